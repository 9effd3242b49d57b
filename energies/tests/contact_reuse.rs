//! What Newton's method sees of contact between iterates: the exact Hessian (with the
//! turning of the normal) is the derivative of the gradient, and a detection that reuses
//! its Verlet list along a trajectory finds what a fresh detector finds — energy,
//! gradient, Hessian, contact summary and closest points — for small moves (list kept)
//! and large ones (list rebuilt). A state saved after a cut, before the next detection
//! (a checkpoint on the step of a cut), loads on the cut rod and detects alike.
use nalgebra::{DMatrix, Vector3};
use splinerod_core::{BSplineSpace, BlockBanded, HessianKind, Material, Real, Rod, SavedState};
use splinerod_energies::Lifecycle;
use splinerod_energies::{Contact, ContactParams, Energy};

const R: Real = 0.003;

/// A helix of two turns whose turns overlap by 0.2 r, wiggled: many crossing samples.
fn coil() -> Rod {
    let (radius, pitch, n) = (0.02, 1.8 * R, 30);
    let length = 2.0 * (std::f64::consts::TAU * radius).hypot(pitch);
    let material = Material {
        rest_length: length,
        linear_density: 0.01,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, length).expect("basis");
    let mut rod = Rod::straight(
        material,
        Box::new(basis),
        Vector3::zeros(),
        Vector3::x() * length,
    )
    .expect("rod");
    let turns = |i: usize| 2.0 * std::f64::consts::TAU * i as Real / (n - 1) as Real;
    for (i, q) in rod.positions.iter_mut().enumerate() {
        let a = turns(i);
        let wobble = 1e-4 * (7.0 * a).sin();
        *q = Vector3::new(
            (radius + wobble) * a.cos(),
            (radius + wobble) * a.sin(),
            pitch * a / std::f64::consts::TAU,
        );
    }
    rod
}

fn contact() -> Contact {
    Contact::new(ContactParams::new(R, 1e4).expect("params")).expect("contact")
}

/// Contact with samples `spacing` apart: finely sampled, the curve strays little from
/// its samples and the Verlet list certifies the closest-point searches too; with the
/// default spacing they run a broad phase of their own.
fn contact_sampled(spacing: Real) -> Contact {
    let mut params = ContactParams::new(R, 1e4).expect("params");
    params.spacing = spacing;
    Contact::new(params).expect("contact")
}

fn gradient(e: &dyn Energy, rod: &Rod) -> Vec<Vector3<Real>> {
    let mut g = vec![Vector3::zeros(); rod.len()];
    e.add_gradient(rod, &mut g);
    g
}

fn hessian(e: &dyn Energy, rod: &Rod, kind: HessianKind) -> DMatrix<Real> {
    let mut h = BlockBanded::zeros(rod.len(), rod.basis().degree());
    e.add_hessian(rod, kind, &mut h);
    h.to_dense()
}

fn flat(v: &[Vector3<Real>]) -> DMatrix<Real> {
    DMatrix::from_iterator(3 * v.len(), 1, v.iter().flat_map(|x| x.iter().copied()))
}

#[test]
fn the_exact_hessian_is_the_derivative_of_the_gradient() {
    let (c, rod) = (contact(), coil());
    assert!(
        c.summary(&rod).expect("summary").pairs > 0,
        "the coil touches"
    );
    let exact = hessian(&c, &rod, HessianKind::Exact);
    let definite = hessian(&c, &rod, HessianKind::Definite);
    let step = 1e-7;
    let (mut worst, mut dropped): (Real, Real) = (0.0, 0.0);
    for k in 0..4 {
        // Smooth directions, so that no sample pair crosses the onset within a step.
        let v: Vec<Vector3<Real>> = (0..rod.len())
            .map(|i| {
                let x = 0.37 * (i + 3 * k) as Real;
                Vector3::new(x.sin(), (1.3 * x).cos(), (0.7 * x + k as Real).sin())
            })
            .collect();
        let moved = |t: Real| {
            let mut r = rod.clone();
            r.positions
                .iter_mut()
                .zip(&v)
                .for_each(|(q, d)| *q += d * t);
            flat(&gradient(&c, &r))
        };
        let fd = (moved(step) - moved(-step)) / (2.0 * step);
        let x = flat(&v);
        let scale = fd.amax().max(1e-12);
        worst = worst.max((&exact * &x - &fd).amax() / scale);
        dropped = dropped.max((&definite * &x - &fd).amax() / scale);
    }
    assert!(worst < 1e-5, "exact Hessian against differences: {worst:e}");
    // The definite form drops the turning term: visibly different.
    assert!(
        dropped > 10.0 * worst,
        "definite {dropped:e}, exact {worst:e}"
    );
}

#[test]
fn a_reused_detection_finds_what_a_fresh_one_finds() {
    for spacing in [0.2 * R, 0.05 * R] {
        reused_equals_fresh(spacing);
    }
}

/// Closest points are computed on the curve, between contact segments, whatever the
/// samples: the search certified by the Verlet list (fine samples) and the one with a
/// broad phase of its own (default samples) must find the same points.
#[test]
fn both_closest_point_searches_find_the_same_points() {
    let rod = coil();
    let points = |c: &Contact| {
        let mut out = Vec::new();
        c.energy(&rod);
        c.interaction_points(&rod, &mut out).expect("points");
        out.sort_by(Real::total_cmp);
        out
    };
    let (coarse, fine) = (
        points(&contact_sampled(0.2 * R)),
        points(&contact_sampled(0.05 * R)),
    );
    assert!(!coarse.is_empty());
    assert_eq!(coarse, fine);
}

fn reused_equals_fresh(spacing: Real) {
    let reused = contact_sampled(spacing);
    let mut rod = coil();
    let n = rod.len();
    // Small moves (the list is kept), then a jump of a third of the radius (rebuilt).
    for (k, size) in [1e-5, 2e-5, 3e-5, 1e-3, 2e-5, 1e-5].into_iter().enumerate() {
        for (i, q) in rod.positions.iter_mut().enumerate() {
            let x = (i * 7 + k * 13) as Real;
            *q += Vector3::new(x.sin(), (0.5 * x).cos(), (0.3 * x).sin()) * size;
        }
        let fresh = contact_sampled(spacing);
        let (e0, e1) = (fresh.energy(&rod), reused.energy(&rod));
        assert!(e0 > 0.0, "step {k}: in contact");
        assert!(
            (e0 - e1).abs() <= 1e-12 * e0,
            "step {k}: energy {e0} vs {e1}"
        );
        let (g0, g1) = (
            flat(&gradient(&fresh, &rod)),
            flat(&gradient(&reused, &rod)),
        );
        assert!(
            (&g0 - &g1).amax() <= 1e-12 * g0.amax(),
            "step {k}: gradient"
        );
        let (h0, h1) = (
            hessian(&fresh, &rod, HessianKind::Exact),
            hessian(&reused, &rod, HessianKind::Exact),
        );
        assert!((&h0 - &h1).amax() <= 1e-12 * h0.amax(), "step {k}: Hessian");
        let (s0, s1) = (
            fresh.summary(&rod).expect("fresh"),
            reused.summary(&rod).expect("reused"),
        );
        assert_eq!(s0, s1, "step {k}: summary");
        let points = |c: &Contact| {
            let mut out = Vec::new();
            c.interaction_points(&rod, &mut out).expect("points");
            out.sort_by(Real::total_cmp);
            out
        };
        assert_eq!(points(&fresh), points(&reused), "step {k}: closest points");
        assert_eq!(n, rod.len());
    }
}

#[test]
fn a_state_saved_after_a_cut_loads_on_the_cut_rod() {
    let (mut c, mut rod) = (contact(), coil());
    assert!(
        c.summary(&rod).expect("summary").pairs > 0,
        "detected uncut"
    );
    let at = 0.883 * rod.material().rest_length;
    rod.cut_with(at, &mut |r, map| c.on_knot_change(r, map))
        .expect("cut");
    let mut saved = SavedState::default();
    c.save_state(&mut saved);
    let mut restored = contact();
    let mut reader = saved.reader();
    restored
        .load_state(&rod, &mut reader)
        .expect("loads on the cut rod");
    reader.finish().expect("read to its end");
    assert!(c.summary(&rod).expect("summary") == restored.summary(&rod).expect("summary"));
    assert!(gradient(&c, &rod) == gradient(&restored, &rod));
}
