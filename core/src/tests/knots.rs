use super::{all_test_spaces, irregular_space, max_curve_difference};
use crate::{BSplineSpace, BasisSpace, BasisValues, CoreError, KnotOperation, Real};
use nalgebra::Vector3;
use proptest::prelude::*;

fn wiggly_points(n: usize) -> Vec<Vector3<Real>> {
    (0..n)
        .map(|i| {
            let x = i as Real;
            Vector3::new(x, (1.7 * x).sin(), (0.3 * x * x).cos())
        })
        .collect()
}

#[test]
fn insertion_preserves_the_curve_for_every_degree() {
    // Boehm's algorithm is exact: only round-off of O(10 eps · |q|) remains.
    for space in all_test_spaces() {
        let q = wiggly_points(space.count());
        let (a, b) = space.domain();
        for f in [0.01, 0.25, 0.5, 0.5, 0.77, 0.999] {
            let mut refined = space.clone();
            let mut q1 = q.clone();
            let map = refined.insert_knot(a + f * (b - a)).unwrap();
            map.apply_in_place(&mut q1);
            assert_eq!(map.operation(), KnotOperation::Insert);
            assert_eq!(q1.len(), q.len() + 1);
            assert!(max_curve_difference((&space, &q), (&refined, &q1)) < 1e-12);
        }
    }
}

#[test]
fn map_weights_reproduce_applied_map() {
    let mut space = irregular_space(3, 1.0);
    let q = wiggly_points(space.count());
    let map = space.insert_knot(0.55).unwrap();
    let mut q1 = q.clone();
    map.apply_in_place(&mut q1);
    for (i, qi) in q1.iter().enumerate() {
        let via_weights: Vector3<Real> = (0..q.len()).map(|j| q[j] * map.weight(i, j)).sum();
        assert!((via_weights - qi).norm() < 1e-14);
    }
    // Each row of β sums to one (affine invariance).
    for i in 0..q1.len() {
        let sum: Real = (0..q.len()).map(|j| map.weight(i, j)).sum();
        assert!((sum - 1.0).abs() < 1e-15);
    }
}

#[test]
fn removal_inverts_insertion_exactly() {
    for space in all_test_spaces() {
        let q = wiggly_points(space.count());
        let (a, b) = space.domain();
        let mut refined = space.clone();
        let mut q1 = q.clone();
        let ins = refined.insert_knot(a + 0.4321 * (b - a)).unwrap();
        ins.apply_in_place(&mut q1);
        let rem = refined.removal(ins.knot_index()).unwrap();
        assert!(rem.shape_error(&q1) < 1e-12, "degree {}", space.degree());
        let rem = refined.remove_knot(ins.knot_index()).unwrap();
        rem.apply_in_place(&mut q1);
        assert_eq!(refined.knots(), space.knots());
        for (x, y) in q.iter().zip(&q1) {
            assert!((x - y).norm() < 1e-12 * (1.0 + x.norm()));
        }
    }
}

#[test]
fn removing_a_needed_knot_reports_a_bounded_shape_error() {
    // The error returned bounds the curve's actual displacement (convex hull property).
    for space in all_test_spaces().into_iter().filter(|s| s.degree() >= 2) {
        let q = wiggly_points(space.count());
        let (a, b) = space.domain();
        let interior: Vec<usize> = (0..space.knots().len())
            .filter(|&i| space.knots()[i] > a && space.knots()[i] < b)
            .collect();
        for &index in &interior {
            let map = space.removal(index).unwrap();
            let bound = map.shape_error(&q);
            let mut coarse = space.clone();
            coarse.remove_knot(index).unwrap();
            let mut q1 = q.clone();
            map.apply_in_place(&mut q1);
            let actual = max_curve_difference((&space, &q), (&coarse, &q1));
            assert!(bound > 1e-6, "a wiggly curve needs its knots");
            assert!(
                actual <= bound * (1.0 + 1e-9),
                "actual {actual} > bound {bound}"
            );
        }
    }
}

#[test]
fn cut_by_full_multiplicity_separates_the_curve() {
    let mut space = BSplineSpace::clamped_uniform(3, 8, 1.0).unwrap();
    let mut q = wiggly_points(8);
    for _ in 0..4 {
        space.insert_knot(0.5).unwrap().apply_in_place(&mut q);
    }
    assert_eq!(space.multiplicity(0.5), 4);
    assert!(matches!(
        space.insert_knot(0.5),
        Err(CoreError::MultiplicityTooHigh { .. })
    ));
    // Left of the cut, no basis function reaches past it.
    let mut b = BasisValues::default();
    space.evaluate(0.4999, &mut b).unwrap();
    let last_left = b.first + b.order - 1;
    space.evaluate(0.5, &mut b).unwrap();
    assert_eq!(b.first, last_left + 1);
}

#[test]
fn bad_knot_operations_are_errors() {
    let mut space = BSplineSpace::clamped_uniform(3, 6, 1.0).unwrap();
    assert!(matches!(
        space.insert_knot(0.0),
        Err(CoreError::OutsideDomain { .. })
    ));
    assert!(matches!(
        space.insert_knot(1.2),
        Err(CoreError::OutsideDomain { .. })
    ));
    assert!(matches!(
        space.insert_knot(Real::NAN),
        Err(CoreError::OutsideDomain { .. })
    ));
    assert!(matches!(
        space.removal(0),
        Err(CoreError::NotInteriorKnot { index: 0, .. })
    ));
    assert!(matches!(
        space.removal(99),
        Err(CoreError::NotInteriorKnot { index: 99, .. })
    ));
}

proptest! {
    #[test]
    fn random_insertions_preserve_the_curve(fractions in prop::collection::vec(0.001f64..0.999, 1..20), degree in 1usize..=5) {
        let space = BSplineSpace::uniform(degree, degree + 5, 1.0).unwrap();
        let q = wiggly_points(space.count());
        let mut refined = space.clone();
        let mut q1 = q.clone();
        for f in &fractions {
            if refined.multiplicity(*f) < degree + 1 {
                refined.insert_knot(*f).unwrap().apply_in_place(&mut q1);
            }
        }
        prop_assert!(max_curve_difference((&space, &q), (&refined, &q1)) < 1e-11);
    }
}
