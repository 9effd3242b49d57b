//! The contact penalty: counted once per crossing (also at knots), gradient against
//! finite differences, Hessian along the normal exact and positive semi-definite,
//! floor, self-contact on one piece.

use nalgebra::{DMatrix, Vector3};
use splinerod_core::{BSplineSpace, BlockBanded, HessianKind, Material, Real, Rod};
use splinerod_energies::{Contact, ContactParams, Energy};

const R: Real = 0.01;
const K: Real = 1e4;

/// Penalty value, as documented in `contact::penalty`, for the default onset `0.1 r`.
fn phi(g: Real) -> Real {
    let d = 0.1 * R;
    if g >= d {
        0.0
    } else if g >= 0.0 {
        K * (d - g).powi(3) / (6.0 * d)
    } else {
        0.5 * K * g * g - 0.5 * K * d * g + K * d * d / 6.0
    }
}

/// A rod of length 2 cut at s = 1: piece one along x, piece two along y at height `h`,
/// crossing piece one at x = `x`.
fn crossing(h: Real, x: Real) -> Rod {
    let material = Material {
        rest_length: 2.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, 12, 2.0).unwrap();
    let mut rod = Rod::straight(
        material,
        Box::new(basis),
        Vector3::zeros(),
        Vector3::new(2.0, 0.0, 0.0),
    )
    .unwrap();
    rod.cut(1.0).unwrap();
    let knots = rod.basis().knots().to_vec();
    for (i, q) in rod.positions.iter_mut().enumerate() {
        if knots[i] >= 1.0 {
            *q = Vector3::new(x, q.x - 1.5, h);
        }
    }
    rod
}

fn contact() -> Contact {
    Contact::new(ContactParams::new(R, K).unwrap()).unwrap()
}

fn gradient(e: &dyn Energy, rod: &Rod) -> Vec<Vector3<Real>> {
    let mut g = vec![Vector3::zeros(); rod.len()];
    e.add_gradient(rod, &mut g);
    g
}

fn hessian(e: &dyn Energy, rod: &Rod) -> DMatrix<Real> {
    let mut h = BlockBanded::zeros(rod.len(), rod.basis().degree());
    e.add_hessian(rod, HessianKind::Definite, &mut h);
    h.to_dense()
}

#[test]
fn a_crossing_is_found_on_the_curve_and_slides_smoothly() {
    let c = contact();
    let h = 1.9 * R;
    let mut energies = Vec::new();
    // Offsets inside spans and exactly on knots (2/9 = span length before the cut).
    for x in [0.5, 2.0 / 9.0 * 2.0, 2.0 / 9.0 * 3.0, 0.3, 0.61, 0.7] {
        let rod = crossing(h, x);
        let summary = c.summary(&rod).unwrap();
        assert!(summary.pairs >= 1, "x = {x}");
        assert!((summary.min_distance.unwrap() - h).abs() < 1e-12, "x = {x}");
        c.for_each_contact(&rod, |p| {
            assert!(p.distance < c.params().reach());
            assert!((p.s - x).abs() < 2.0 * c.params().segment, "{p:?}");
        })
        .unwrap();
        energies.push(c.energy(&rod));
    }
    // Sliding along the other strand changes only the sampling of the double integral.
    let mean = energies.iter().sum::<Real>() / energies.len() as Real;
    for e in &energies {
        assert!((e - mean).abs() <= 0.02 * mean, "{energies:?}");
    }
    // The double integral of a perpendicular crossing at height h: with
    // d ≈ h + ρ²/(2h), ∬ φ du dv = 2πh ∫_{-p}^{δ} φ(g) dg, divided by (2r)².
    let p = 2.0 * R - h;
    let n = 2000;
    let integral: Real = (0..n)
        .map(|i| {
            let g = -p + (i as Real + 0.5) * (p + 0.1 * R) / n as Real;
            phi(g) * (p + 0.1 * R) / n as Real
        })
        .sum();
    let expected = std::f64::consts::PI * h / (2.0 * R * R) * integral;
    assert!(
        (mean - expected).abs() <= 0.05 * expected,
        "{mean} vs {expected}"
    );
}

#[test]
fn apart_means_no_contact_and_no_force() {
    let c = contact();
    let rod = crossing(2.2 * R, 0.5);
    assert_eq!(c.summary(&rod).unwrap().pairs, 0);
    assert_eq!(c.energy(&rod), 0.0);
    assert!(gradient(&c, &rod).iter().all(|g| g.norm() == 0.0));
}

/// The crossing with every control point moved by a smooth deterministic wiggle.
fn wiggled(h: Real) -> Rod {
    let mut rod = crossing(h, 0.47);
    for (i, q) in rod.positions.iter_mut().enumerate() {
        let f = i as Real;
        *q += Vector3::new((1.3 * f).sin(), (0.7 * f).cos(), (2.1 * f).sin()) * 2e-3;
    }
    rod
}

#[test]
fn gradient_matches_finite_differences() {
    let c = contact();
    for h in [1.5 * R, 1.95 * R, 2.05 * R] {
        let rod = wiggled(h);
        assert!(c.summary(&rod).unwrap().pairs >= 1);
        let g = gradient(&c, &rod);
        let scale = g.iter().map(|v| v.amax()).fold(0.0, Real::max);
        assert!(scale > 0.0);
        let step = 1e-7;
        for i in 0..rod.len() {
            for a in 0..3 {
                let mut plus = rod.clone();
                let mut minus = rod.clone();
                plus.positions[i][a] += step;
                minus.positions[i][a] -= step;
                let fd = (c.energy(&plus) - c.energy(&minus)) / (2.0 * step);
                let err = (fd - g[i][a]).abs();
                assert!(
                    err <= 1e-5 * scale,
                    "h {h}, point {i}.{a}: {fd} vs {}",
                    g[i][a]
                );
            }
        }
    }
}

/// Second difference of the energy along a displacement field `v`.
fn second_difference(c: &Contact, rod: &Rod, v: &[Vector3<Real>], step: Real) -> Real {
    let at = |t: Real| {
        let mut r = rod.clone();
        r.positions.iter_mut().zip(v).for_each(|(q, d)| *q += d * t);
        c.energy(&r)
    };
    (at(step) - 2.0 * at(0.0) + at(-step)) / (step * step)
}

#[test]
fn hessian_is_semidefinite_and_matches_along_the_normal() {
    let c = contact();
    let rod = crossing(1.9 * R, 0.5);
    let h = hessian(&c, &rod);
    assert!((&h - h.transpose()).amax() <= 1e-12 * h.amax());
    let min_eig = h.clone().symmetric_eigenvalues().min();
    assert!(min_eig >= -1e-9 * h.amax(), "{min_eig}");
    let knots = rod.basis().knots().to_vec();
    let flat = |v: &[Vector3<Real>]| {
        DMatrix::from_iterator(3 * v.len(), 1, v.iter().flat_map(|x| x.iter().copied()))
    };
    // Rigid translation of piece two along the normal, then along each strand.
    let mut quadratic = [0.0; 3];
    let mut fd = [0.0; 3];
    for (k, dir) in [Vector3::z(), Vector3::x(), Vector3::y()]
        .iter()
        .enumerate()
    {
        let v: Vec<_> = (0..rod.len())
            .map(|i| {
                if knots[i] >= 1.0 {
                    *dir
                } else {
                    Vector3::zeros()
                }
            })
            .collect();
        let x = flat(&v);
        quadratic[k] = (x.transpose() * &h * &x)[(0, 0)];
        fd[k] = second_difference(&c, &rod, &v, 1e-6);
    }
    // Along the normal the dropped curvature term is small: the overlap patch is narrow.
    assert!(
        (quadratic[0] - fd[0]).abs() <= 0.1 * fd[0],
        "{quadratic:?} vs {fd:?}"
    );
    // Sliding along a strand: both are small next to the normal stiffness.
    for k in 1..3 {
        assert!(quadratic[k].abs() <= 0.05 * quadratic[0], "{quadratic:?}");
        assert!(fd[k].abs() <= 0.1 * fd[0], "{fd:?}");
    }
}

#[test]
fn floor_pushes_up_with_the_documented_line_density() {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, 8, 1.0).unwrap();
    let depth = 0.2 * R;
    let y = -1.0 + R - depth;
    let rod = Rod::straight(
        material,
        Box::new(basis),
        Vector3::new(0.0, y, 0.0),
        Vector3::new(1.0, y, 0.0),
    )
    .unwrap();
    let params = ContactParams::new(R, K).unwrap().with_floor(-1.0).unwrap();
    let c = Contact::new(params).unwrap();
    let expected = phi(-depth) / (2.0 * R);
    assert!((c.energy(&rod) - expected).abs() <= 1e-9 * expected);
    let g = gradient(&c, &rod);
    let total: Vector3<Real> = g.iter().sum();
    // Force per unit length φ'/(2r) along −y in the gradient (the push is +y).
    let slope = -(K * depth + 0.5 * K * 0.1 * R) / (2.0 * R);
    assert!((total.y - slope).abs() <= 1e-9 * slope.abs(), "{total:?}");
    let h = hessian(&c, &rod);
    assert!(h.clone().symmetric_eigenvalues().min() >= -1e-9 * h.amax());
}

#[test]
fn coils_of_one_piece_touch_each_other_but_not_their_neighbours() {
    // Two turns of a helix of radius 0.05 m and pitch 1.8 r: turns overlap by 0.2 r.
    let (radius, pitch, turns) = (0.05, 1.8 * R, 2.0);
    let n = 40;
    let length = turns * (std::f64::consts::TAU * radius).hypot(pitch);
    let material = Material {
        rest_length: length,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, length).unwrap();
    let positions = (0..n)
        .map(|i| {
            let a = std::f64::consts::TAU * turns * i as Real / (n - 1) as Real;
            Vector3::new(
                radius * a.cos(),
                radius * a.sin(),
                pitch * a / std::f64::consts::TAU,
            )
        })
        .collect();
    let rod = Rod::new(material, Box::new(basis), positions).unwrap();
    let c = contact();
    let summary = c.summary(&rod).unwrap();
    assert!(summary.pairs >= 10, "{summary:?}");
    assert!(c.energy(&rod) > 0.0);
    let turn = length / turns;
    c.for_each_contact(&rod, |p| {
        assert!(((p.t - p.s).abs() - turn).abs() < 0.2 * turn, "{p:?}");
        assert!(p.distance < 2.0 * R);
    })
    .unwrap();
    // Bad parameters are named.
    let err = ContactParams::new(-1.0, K).unwrap_err().to_string();
    assert!(err.contains("radius"), "{err}");
    let err = ContactParams::new(R, K)
        .unwrap()
        .with_floor(Real::NAN)
        .unwrap_err()
        .to_string();
    assert!(err.contains("floor"), "{err}");
}

#[test]
fn friction_gradient_matches_finite_differences_sticking_and_sliding() {
    let mut params = ContactParams::new(R, K).unwrap();
    params.friction = 0.5;
    let c = Contact::new(params).unwrap();
    let base = wiggled(1.9 * R);
    c.begin_step(&base, 1e-3).unwrap();
    // ε = slip_speed · dt = 1e-6 m: slides of 1e-7 m stick, 1e-4 m slide.
    for slide in [1e-7, 1e-4] {
        let mut rod = base.clone();
        let knots = rod.basis().knots().to_vec();
        for (i, q) in rod.positions.iter_mut().enumerate() {
            if knots[i] >= 1.0 {
                q.x += slide;
            }
        }
        let g = gradient(&c, &rod);
        let scale = g.iter().map(|v| v.amax()).fold(0.0, Real::max);
        let h = 1e-9;
        for i in 0..rod.len() {
            for a in 0..3 {
                let (mut p, mut m) = (rod.clone(), rod.clone());
                p.positions[i][a] += h;
                m.positions[i][a] -= h;
                let fd = (c.energy(&p) - c.energy(&m)) / (2.0 * h);
                let err = (fd - g[i][a]).abs();
                assert!(
                    err <= 1e-4 * scale,
                    "slide {slide}, {i}.{a}: {fd} vs {}",
                    g[i][a]
                );
            }
        }
    }
    assert!(c.begin_step(&base, 0.0).is_err());
}

/// Pieces of radii r₁ = R and r₂ = 0.4 R (`with_segment_radii`, the second piece
/// starting at s = 1): the penalty starts at centre distance r₁ + r₂ + δ, matches the
/// one-radius penalty of a pair with the same sum, and clearance is d / (r₁ + r₂).
#[test]
fn pieces_of_different_radii_keep_the_sum_of_their_radii_apart() {
    let r2 = 0.4 * R;
    let two = contact()
        .with_segment_radii(&[0.0, 1.0], &[R, r2])
        .expect("radii");
    let sum = R + r2;
    let far = crossing(sum + 0.11 * R, 0.5);
    assert_eq!(two.energy(&far), 0.0, "beyond r₁ + r₂ + δ");
    let near = crossing(0.9 * sum, 0.5);
    let summary = two.summary(&near).expect("summary");
    let ratio = summary.min_clearance_ratio.expect("touching");
    assert!((ratio - 0.9).abs() < 1e-9, "clearance {ratio}");
    // The same gap between two pieces of radius (r₁ + r₂)/2 gives the same energy.
    let mean = Contact::new(ContactParams::new(0.5 * sum, K).expect("params")).expect("c");
    let mut params = *mean.params();
    params.onset = 0.1 * R;
    params.spacing = 0.2 * R;
    params.segment = 2.1 * R;
    let mean = Contact::new(params).expect("contact");
    let (a, b) = (two.energy(&near), mean.energy(&near));
    assert!(a > 0.0 && (a - b).abs() < 1e-9 * b, "{a} vs {b}");
    assert!(contact().with_segment_radii(&[0.0], &[R, r2]).is_err());
    assert!(contact()
        .with_segment_radii(&[0.0, 1.0], &[R, -1.0])
        .is_err());
}
