//! Refinement by many knots at once (`BasisSpace::refined`, `Rod::refined`) against one
//! insertion at a time.
use nalgebra::Vector3;
use splinerod_core::{
    BSplineSpace, BasisSpace, BasisValues, Material, Real, RefinementOperator, Rod,
};

/// Clamped, uniform (paper) and irregular spaces of degrees 1 to 5.
fn all_test_spaces() -> Vec<BSplineSpace> {
    let mut v = Vec::new();
    for d in 1..=5 {
        v.push(BSplineSpace::clamped_uniform(d, d + 7, 1.3).expect("clamped"));
        v.push(BSplineSpace::uniform(d, d + 6, 0.7).expect("uniform"));
        let mut irregular = BSplineSpace::clamped_uniform(d, d + 4, 2.0).expect("clamped");
        for f in [0.13, 0.37, 0.38, 0.61, 0.9] {
            irregular.insert_knot(f * 2.0).expect("insert");
        }
        v.push(irregular);
    }
    v
}

fn wiggly(n: usize) -> Vec<Vector3<Real>> {
    (0..n)
        .map(|i| Vector3::new(i as Real, (1.3 * i as Real).sin(), (0.4 * i as Real).cos()))
        .collect()
}

/// Every span's midpoint plus a repeat of an existing interior knot (multiplicity +1).
fn values_for(space: &dyn BasisSpace) -> Vec<Real> {
    let mut v: Vec<Real> = splinerod_core::basis::spans(space)
        .map(|s| 0.5 * (s.start + s.end))
        .collect();
    let (a, b) = space.domain();
    if let Some(&t) = space.knots().iter().find(|&&t| t > a && t < b) {
        v.push(t);
    }
    v.sort_by(Real::total_cmp);
    v
}

#[test]
fn batch_refinement_equals_one_insertion_at_a_time() {
    for space in all_test_spaces() {
        let values = values_for(&space);
        let q = wiggly(space.count());
        let mut op = RefinementOperator::default();
        let fine = space.refined(&values, &mut op).expect("valid");
        let mut batch = Vec::new();
        op.apply(&q, &mut batch);
        let (mut one, mut q1) = (space.clone(), q.clone());
        for &v in &values {
            one.insert_knot(v).expect("valid").apply_in_place(&mut q1);
        }
        assert_eq!(fine.knots(), one.knots(), "degree {}", space.degree());
        let gap = batch
            .iter()
            .zip(&q1)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, Real::max);
        assert!(gap < 1e-13, "degree {}: {gap:e}", space.degree());
        // And the curve itself is unchanged.
        let (mut b0, mut b1) = (BasisValues::default(), BasisValues::default());
        let (s0, s1) = space.domain();
        for k in 0..=97 {
            let s = s0 + (s1 - s0) * k as Real / 97.0;
            space.evaluate(s, &mut b0).expect("valid");
            fine.evaluate(s, &mut b1).expect("valid");
            let e = (b0.combine(&b0.value, &q) - b1.combine(&b1.value, &batch)).norm();
            assert!(e < 1e-13, "degree {} at {s}: {e:e}", space.degree());
        }
    }
}

#[test]
fn refined_rod_keeps_curve_mass_and_motion() {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.2,
    };
    let basis = BSplineSpace::clamped_uniform(3, 9, 1.0).expect("valid");
    let mut rod = Rod::new(material, Box::new(basis), wiggly(9)).expect("valid");
    rod.velocities = wiggly(9).iter().map(|v| v * 0.5).collect();
    let values = values_for(rod.basis());
    let mut op = RefinementOperator::default();
    let fine = rod.refined(&values, &mut op).expect("valid");
    assert_eq!(fine.len(), rod.len() + values.len());
    assert!((fine.kinetic_energy() - rod.kinetic_energy()).abs() < 1e-13);
    assert!((fine.total_mass() - rod.total_mass()).abs() < 1e-14);
    for s in [0.0, 0.1, 0.33, 0.5, 0.91, 1.0] {
        assert!((fine.point(s).expect("valid") - rod.point(s).expect("valid")).norm() < 1e-13);
        assert!(
            (fine.velocity(s).expect("valid") - rod.velocity(s).expect("valid")).norm() < 1e-13
        );
    }
    assert!(rod.refined(&[1.5], &mut op).is_err(), "outside the domain");
}
