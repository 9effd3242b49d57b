//! The contact barrier (#46): on a crossing of two strands and on a rod lying on the
//! floor, inside the tolerance layer and in the barrier's quadratic continuation, the
//! gradient matches central differences of the energy, the exact Hessian central
//! differences of the gradient; nothing acts beyond the tolerance; and the floor's
//! force per unit length falls as the gap opens, from unbounded to zero at the
//! tolerance.

use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, BlockBanded, HessianKind, Material, Real, Rod};
use splinerod_energies::{Contact, ContactParams, Energy};

const R: Real = 0.01;
const TAU: Real = 0.05 * R;
const KAPPA: Real = 300.0;

/// A rod of length 2 cut at s = 1: piece one along x, piece two along y at height `h`,
/// crossing piece one at x = 0.47, every control point wiggled slightly.
fn crossing(h: Real) -> Rod {
    let material = Material {
        rest_length: 2.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, 12, 2.0).expect("basis");
    let end = Vector3::new(2.0, 0.0, 0.0);
    let mut rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
    rod.cut(1.0).expect("cut");
    let knots = rod.basis().knots().to_vec();
    for (i, q) in rod.positions.iter_mut().enumerate() {
        if knots[i] >= 1.0 {
            *q = Vector3::new(0.47, q.x - 1.5, h);
        }
        let f = i as Real;
        *q += Vector3::new((1.3 * f).sin(), (0.7 * f).cos(), (2.1 * f).sin()) * 2e-5;
    }
    rod
}

/// A straight rod of radius `R` at height `y` over the floor `y = 0`, tilted by 1e-8.
fn lying(y: Real) -> Rod {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, 8, 1.0).expect("basis");
    let (a, b) = (Vector3::new(0.0, y, 0.0), Vector3::new(1.0, y + 1e-8, 0.0));
    Rod::straight(material, Box::new(basis), a, b).expect("rod")
}

/// The barrier between strands (`floor: false`) or against the floor `y = 0`.
fn barrier(floor: bool) -> Contact {
    let params = ContactParams::barrier(R, TAU, KAPPA).expect("params");
    let params = if floor {
        params.with_floor(0.0).expect("floor")
    } else {
        params
    };
    Contact::new(params).expect("contact")
}

fn gradient(e: &dyn Energy, rod: &Rod) -> Vec<Vector3<Real>> {
    let mut g = vec![Vector3::zeros(); rod.len()];
    e.add_gradient(rod, &mut g);
    g
}

/// Largest difference between `gradient` and central differences of the energy, and
/// between the exact Hessian and central differences of the gradient, each relative
/// to the largest entry.
fn derivative_errors(c: &Contact, rod: &Rod) -> (Real, Real) {
    let g = gradient(c, rod);
    let mut h = BlockBanded::zeros(rod.len(), rod.basis().degree());
    c.add_hessian(rod, HessianKind::Exact, &mut h);
    let h = h.to_dense();
    let step = 1e-9;
    let (mut eg, mut eh) = (0.0_f64, 0.0_f64);
    for i in 0..rod.len() {
        for a in 0..3 {
            let (mut plus, mut minus) = (rod.clone(), rod.clone());
            plus.positions[i][a] += step;
            minus.positions[i][a] -= step;
            let fd = (c.energy(&plus) - c.energy(&minus)) / (2.0 * step);
            eg = eg.max((fd - g[i][a]).abs());
            let (gp, gm) = (gradient(c, &plus), gradient(c, &minus));
            for j in 0..rod.len() {
                for b in 0..3 {
                    let fd = (gp[j][b] - gm[j][b]) / (2.0 * step);
                    eh = eh.max((fd - h[(3 * j + b, 3 * i + a)]).abs());
                }
            }
        }
    }
    let gs = g.iter().map(|v| v.amax()).fold(0.0, Real::max);
    (eg / gs, eh / h.amax())
}

#[test]
fn derivatives_match_finite_differences_in_the_layer_and_its_continuation() {
    // Gaps 0.6 τ, 0.1 τ, 0.005 τ (continuation) and −0.5 τ (overlap).
    for gap in [0.6, 0.1, 0.005, -0.5] {
        let cases = [
            (barrier(false), crossing(2.0 * R + gap * TAU)),
            (barrier(true), lying(R + gap * TAU)),
        ];
        for (c, rod) in cases {
            assert!(c.summary(&rod).expect("summary").min_gap.is_some());
            let (eg, eh) = derivative_errors(&c, &rod);
            assert!(eg < 1e-5 && eh < 1e-4, "gap {gap} τ: {eg:e}, {eh:e}");
        }
    }
}

#[test]
fn nothing_acts_beyond_the_tolerance() {
    let cases = [
        (barrier(false), crossing(2.0 * R + 1.01 * TAU)),
        (barrier(true), lying(R + 1.01 * TAU)),
    ];
    for (c, rod) in cases {
        assert_eq!(c.energy(&rod), 0.0);
        assert!(gradient(&c, &rod).iter().all(|g| g.norm() == 0.0));
    }
}

#[test]
fn the_floor_pushes_harder_the_closer_the_rod_without_bound() {
    let c = barrier(true);
    let force = |x: Real| -> Real {
        -gradient(&c, &lying(R + x * TAU))
            .iter()
            .map(|g| g.y)
            .sum::<Real>()
    };
    let mut last = Real::INFINITY;
    for x in [0.02, 0.05, 0.1, 0.25, 0.5, 0.75, 0.95] {
        let f = force(x);
        assert!(f > 0.0 && f < last, "x {x}: {f} after {last}");
        last = f;
    }
    // Per metre of rod, κ τ (−b̃'(x)) / (2r), b̃'(x) = −2(x − 1) ln x − (x − 1)²/x
    // (about κ τ² / g near contact).
    let x: Real = 0.02;
    let slope = -2.0 * (x - 1.0) * x.ln() - (x - 1.0).powi(2) / x;
    let (near, expected) = (force(x), -KAPPA * TAU * slope / (2.0 * R));
    // The tilt of 1e-8 m moves the gap by up to 1e-3 of 0.02 τ along the rod.
    assert!((near / expected - 1.0).abs() < 2e-3, "{near} vs {expected}");
}
