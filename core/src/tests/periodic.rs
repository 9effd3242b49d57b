//! Periodic spaces: closed curves, and knot maps that are exact across the seam.
use super::max_curve_difference;
use crate::{
    BasisSpace, BasisValues, CoreError, Material, PeriodicBSplineSpace, Real, RefinementOperator,
    Rod,
};
use nalgebra::Vector3;
use proptest::prelude::*;

/// Breakpoints with uneven gaps (and one repeated value) on a period of 1.7.
fn irregular(degree: usize) -> PeriodicBSplineSpace {
    let breaks = vec![0.0, 0.11, 0.3, 0.31, 0.7, 0.7, 0.95, 1.2, 1.42, 1.69];
    PeriodicBSplineSpace::new(degree, breaks, 1.7).unwrap()
}

fn spaces() -> Vec<PeriodicBSplineSpace> {
    (1..=5)
        .flat_map(|d| {
            [
                PeriodicBSplineSpace::uniform(d, d + 3, 2.0).unwrap(),
                irregular(d),
            ]
        })
        .collect()
}

/// A closed wiggly control polygon: `m` distinct points, then the first `d` again.
fn closed_points(space: &dyn BasisSpace) -> Vec<Vector3<Real>> {
    let m = space.periodic_count().unwrap();
    (0..space.count())
        .map(|i| {
            let x = (i % m) as Real;
            Vector3::new((0.9 * x).cos() + x, (1.7 * x).sin(), (0.3 * x * x).cos())
        })
        .collect()
}

fn curve(space: &dyn BasisSpace, q: &[Vector3<Real>], s: Real, derivative: usize) -> Vector3<Real> {
    let mut b = BasisValues::default();
    space.evaluate(s, &mut b).unwrap();
    let w = [&b.value, &b.d1, &b.d2][derivative];
    b.combine(w, q)
}

/// The copies across the seam are bit-equal to what they copy.
fn assert_tied(space: &dyn BasisSpace, q: &[Vector3<Real>]) {
    let m = space.periodic_count().unwrap();
    assert_eq!(q.len(), space.count());
    for i in m..q.len() {
        assert_eq!(
            q[i],
            q[i - m],
            "copy {i} of {} (degree {})",
            i - m,
            space.degree()
        );
    }
}

#[test]
fn a_closed_curve_joins_smoothly_at_the_seam() {
    for space in spaces() {
        let q = closed_points(&space);
        let (d, l) = (space.degree(), space.period());
        assert_eq!(space.domain(), (0.0, l));
        assert_eq!(space.count(), space.breaks().len() + d);
        // Continuous up to derivative d - 1 across s = 0 ≡ L (d - 1 ≥ 0).
        for k in 0..d.min(3) {
            let gap = curve(&space, &q, 0.0, k) - curve(&space, &q, l, k);
            let scale = curve(&space, &q, 0.0, k).norm().max(1.0);
            assert!(
                gap.norm() < 1e-11 * scale,
                "degree {d}, derivative {k}: {gap:?}"
            );
        }
    }
}

#[test]
fn insertion_anywhere_is_exact_and_keeps_the_copies() {
    for space in spaces() {
        let q = closed_points(&space);
        let l = space.period();
        let near_seam = [1e-3, 0.02, 0.05, 0.1, 0.5, 0.8, 0.95, 0.98, 0.999];
        for f in near_seam {
            let mut fine = space.clone();
            let mut q1 = q.clone();
            let map = fine.insert_knot(f * l).unwrap();
            map.apply_in_place(&mut q1);
            assert_tied(&fine, &q1);
            assert!(max_curve_difference((&space, &q), (&fine, &q1)) < 1e-12);
            // The knots are the periodic ones of the new breakpoints.
            let again = PeriodicBSplineSpace::new(space.degree(), fine.breaks().to_vec(), l);
            assert_eq!(again.unwrap().knots(), fine.knots());
            // The weights describe the map, ties included.
            for (i, qi) in q1.iter().enumerate() {
                let via: Vector3<Real> = (0..q.len()).map(|j| q[j] * map.weight(i, j)).sum();
                assert!((via - qi).norm() < 1e-13, "row {i}");
            }
        }
    }
}

#[test]
fn some_insertions_next_to_the_seam_rewrite_both_sides() {
    let mut space = PeriodicBSplineSpace::uniform(3, 6, 1.0).unwrap();
    let map = space.insert_knot(0.05).unwrap();
    assert!(map.wraps());
    let ties: Vec<_> = map.tied_new().collect();
    assert!(ties.iter().all(|&(j, w)| j == w + 7));
    let map = space.insert_knot(0.5).unwrap();
    assert!(!map.wraps());
}

#[test]
fn removal_inverts_insertion_across_the_seam() {
    for space in spaces() {
        let q = closed_points(&space);
        for f in [0.004, 0.03, 0.43, 0.97, 0.996] {
            let mut fine = space.clone();
            let mut q1 = q.clone();
            let ins = fine.insert_knot(f * space.period()).unwrap();
            ins.apply_in_place(&mut q1);
            let rem = fine.removal(ins.knot_index()).unwrap();
            assert!(rem.shape_error(&q1) < 1e-12);
            fine.remove_knot(ins.knot_index())
                .unwrap()
                .apply_in_place(&mut q1);
            assert_eq!(fine, space);
            assert_tied(&fine, &q1);
            for (x, y) in q.iter().zip(&q1) {
                assert!(
                    (x - y).norm() < 1e-12 * (1.0 + x.norm()),
                    "degree {}",
                    space.degree()
                );
            }
        }
    }
}

#[test]
fn removing_a_needed_knot_reports_a_bound_on_the_change() {
    for space in spaces().into_iter().filter(|s| s.degree() >= 2) {
        let m = space.breaks().len();
        if m <= space.degree() + 1 {
            continue; // one knot fewer would leave too few control points
        }
        let q = closed_points(&space);
        let d = space.degree();
        for index in d + 1..d + m {
            let map = space.removal(index).unwrap();
            let bound = map.shape_error(&q);
            let mut coarse = space.clone();
            coarse.remove_knot(index).unwrap();
            let mut q1 = q.clone();
            map.apply_in_place(&mut q1);
            assert_tied(&coarse, &q1);
            let actual = max_curve_difference((&space, &q), (&coarse, &q1));
            assert!(
                actual <= bound * (1.0 + 1e-9),
                "knot {index}: {actual} > {bound}"
            );
        }
    }
}

#[test]
fn refining_many_knots_at_once_equals_one_at_a_time() {
    // Degree 1 allows a value at most twice; the list inserts 0.5 L twice.
    for space in spaces().into_iter().filter(|s| s.degree() >= 2) {
        let q = closed_points(&space);
        let l = space.period();
        let values: Vec<Real> = [0.001, 0.04, 0.26, 0.5, 0.5, 0.93, 0.9995]
            .iter()
            .map(|f| f * l)
            .collect();
        let mut op = RefinementOperator::default();
        let fine = space.refined(&values, &mut op).unwrap();
        let mut q1 = Vec::new();
        op.apply(&q, &mut q1);
        assert_tied(fine.as_ref(), &q1);
        let mut one_by_one = space.clone();
        for &v in &values {
            one_by_one.insert_knot(v).unwrap();
        }
        assert_eq!(fine.knots(), one_by_one.knots());
        assert!(max_curve_difference((&space, &q), (fine.as_ref(), &q1)) < 1e-12);
    }
}

#[test]
fn bad_periodic_spaces_are_errors() {
    let bad = |breaks: Vec<Real>, period: Real| PeriodicBSplineSpace::new(3, breaks, period);
    assert!(matches!(
        bad(vec![0.0, 0.5, 0.7], 1.0),
        Err(CoreError::TooFewControlPoints { .. })
    ));
    assert!(matches!(
        bad(vec![0.1, 0.2, 0.5, 0.7], 1.0),
        Err(CoreError::InvalidParameter { .. })
    ));
    // The seam may repeat (a cut there), up to degree + 1.
    assert!(bad(vec![0.0, 0.0, 0.5, 0.7], 1.0).is_ok());
    assert!(matches!(
        bad(vec![0.0; 5].into_iter().chain([0.5, 0.7]).collect(), 1.0),
        Err(CoreError::MultiplicityTooHigh { .. })
    ));
    assert!(matches!(
        bad(vec![0.0, 0.5, 0.2, 0.7], 1.0),
        Err(CoreError::KnotsNotSorted { .. })
    ));
    assert!(matches!(
        bad(vec![0.0, 0.2, 0.5, 1.0], 1.0),
        Err(CoreError::OutsideDomain { .. })
    ));
    assert!(matches!(
        bad(vec![0.0, 0.2, Real::NAN, 0.7], 1.0),
        Err(CoreError::NonFiniteKnot { .. })
    ));
    assert!(matches!(
        bad(vec![0.0, 0.2, 0.5, 0.7], 0.0),
        Err(CoreError::InvalidParameter { .. })
    ));
    let five = vec![0.0, 0.5, 0.5, 0.5, 0.5, 0.5, 0.7];
    assert!(matches!(
        bad(five, 1.0),
        Err(CoreError::MultiplicityTooHigh { .. })
    ));
    let mut space = PeriodicBSplineSpace::uniform(3, 5, 1.0).unwrap();
    // Outside the loop is an error; its seam, 0 or 1, may be inserted (a cut there).
    for s in [-0.1, 1.1, Real::NAN] {
        assert!(space.insert_knot(s).is_err(), "inserting {s}");
    }
    // Removing down to fewer than degree + 1 control points is refused.
    let before = space.clone();
    assert!(space.remove_knot(4).is_ok());
    assert!(matches!(
        space.remove_knot(4),
        Err(CoreError::TooFewControlPoints { .. })
    ));
    assert_eq!(space.breaks().len(), before.breaks().len() - 1);
}

fn ring(space: PeriodicBSplineSpace) -> Rod {
    let l = space.period();
    let positions = closed_points(&space);
    let material = Material {
        rest_length: l,
        linear_density: 0.3,
    };
    Rod::new(material, Box::new(space), positions).unwrap()
}

#[test]
fn a_closed_rod_keeps_mass_and_momentum_through_knot_changes() {
    for space in spaces() {
        let mut rod = ring(space);
        let m = rod.basis().periodic_count().unwrap();
        for (i, v) in rod.velocities.iter_mut().enumerate() {
            *v = Vector3::new(0.1, -0.2, 0.05) * (i % m) as Real;
        }
        assert!(rod.is_closed());
        let (mass, momentum, kinetic) = (
            rod.total_mass(),
            rod.linear_momentum(),
            rod.kinetic_energy(),
        );
        assert!((mass - 0.3 * rod.material().rest_length).abs() < 1e-14);
        for s in [0.002, 0.9, 1.69] {
            rod.insert_knot(s).unwrap();
            let fresh = Rod::new(
                *rod.material(),
                rod.basis().clone_box(),
                rod.positions.clone(),
            )
            .unwrap();
            let n = rod.len();
            for i in 0..n {
                for j in i..(i + rod.basis().degree() + 1).min(n) {
                    let (a, b) = (rod.mass_matrix().get(i, j), fresh.mass_matrix().get(i, j));
                    assert!((a - b).abs() < 1e-15, "mass ({i}, {j}) after inserting {s}");
                }
            }
            assert!((rod.total_mass() - mass).abs() < 1e-14);
            assert!((rod.linear_momentum() - momentum).norm() < 1e-13);
            assert!((rod.kinetic_energy() - kinetic).abs() < 1e-13 * kinetic);
        }
    }
}

#[test]
fn a_closed_rod_needs_equal_copies_across_the_seam() {
    let space = PeriodicBSplineSpace::uniform(3, 6, 1.0).unwrap();
    let mut positions = closed_points(&space);
    positions[7].x += 1e-9;
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let err = Rod::new(material, Box::new(space), positions).unwrap_err();
    assert!(err.to_string().contains("seam"), "{err}");
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn any_sequence_of_insertions_keeps_a_closed_curve(
        degree in 2usize..=5,
        fractions in prop::collection::vec(0.0005f64..0.9995, 1..12),
    ) {
        let space = PeriodicBSplineSpace::uniform(degree, degree + 2, 1.3).unwrap();
        let q = closed_points(&space);
        let (mut fine, mut q1) = (space.clone(), q.clone());
        for f in fractions {
            fine.insert_knot(f * 1.3).unwrap().apply_in_place(&mut q1);
        }
        assert_tied(&fine, &q1);
        prop_assert!(max_curve_difference((&space, &q), (&fine, &q1)) < 1e-12);
    }
}

/// Largest relative deviation of a ring's radius from `radius`, and its length.
fn ring_fit(rod: &Rod, center: Vector3<Real>, radius: Real) -> (Real, Real) {
    let l = rod.material().rest_length;
    let samples = 2000;
    let (mut worst, mut length) = (0.0, 0.0);
    for k in 0..samples {
        let s = l * (k as Real + 0.5) / samples as Real;
        let r = (rod.point(s).unwrap() - center).norm();
        worst = Real::max(worst, (r / radius - 1.0).abs());
        length += rod.tangent(s).unwrap().norm() * l / samples as Real;
    }
    (worst, length)
}

#[test]
fn a_ring_fits_its_circle_to_the_order_of_the_basis() {
    let (center, normal) = (Vector3::new(0.3, -1.0, 2.0), Vector3::new(1.0, 1.0, 0.5));
    let radius = 0.25;
    let material = Material {
        rest_length: std::f64::consts::TAU * radius,
        linear_density: 0.1,
    };
    let mut previous = Real::INFINITY;
    for m in [8, 16, 32] {
        let space = PeriodicBSplineSpace::uniform(3, m, material.rest_length).unwrap();
        let rod = Rod::ring(material, Box::new(space), center, normal, radius).unwrap();
        let (deviation, length) = ring_fit(&rod, center, radius);
        let stretch = length / material.rest_length - 1.0;
        println!("{m} control points: radius within {deviation:.2e}, length {stretch:+.2e}");
        // In the plane, and fourth order (h⁴: 16 times smaller per halving, here ≥ 12).
        for q in &rod.positions {
            assert!((q - center).dot(&normal.normalize()).abs() < 1e-14);
        }
        assert!(deviation < previous / 12.0 && deviation < 3e-3);
        assert!(stretch.abs() < 2.0 * deviation);
        previous = deviation;
    }
    let space = || Box::new(PeriodicBSplineSpace::uniform(3, 8, material.rest_length).unwrap());
    let bad =
        |normal: Vector3<Real>, radius: Real| Rod::ring(material, space(), center, normal, radius);
    assert!(bad(Vector3::zeros(), 0.1).is_err());
    assert!(bad(normal, 0.0).is_err());
    assert!(bad(normal, Real::NAN).is_err());
    assert!(bad(normal, 0.1).is_ok());
    let open = crate::BSplineSpace::clamped_uniform(3, 8, material.rest_length).unwrap();
    assert!(Rod::ring(material, Box::new(open), center, normal, 0.1).is_err());
}

#[test]
fn a_closed_curve_can_be_cut_at_its_seam() {
    for space in spaces().into_iter().filter(|s| s.degree() >= 2) {
        let d = space.degree();
        let q = closed_points(&space);
        let (mut cut, mut q1) = (space.clone(), q.clone());
        // The seam is a simple knot: d more copies make the cut.
        for k in 1..=d {
            let s = if k % 2 == 0 { 0.0 } else { space.period() }; // 0 and L: one point
            cut.insert_knot(s).unwrap().apply_in_place(&mut q1);
            assert_tied(&cut, &q1);
            assert!(
                max_curve_difference((&space, &q), (&cut, &q1)) < 1e-12,
                "degree {d}"
            );
        }
        assert_eq!(cut.seam_multiplicity(), d + 1);
        assert!(cut.insert_knot(0.0).is_err(), "already cut");
        // No basis function straddles the seam any more: the functions at 0+ and at L−
        // are different unknowns (indices mod the distinct count).
        let m = cut.breaks().len();
        let mut b = BasisValues::default();
        cut.evaluate(0.0, &mut b).unwrap();
        let start: Vec<usize> = (0..b.order)
            .filter(|&k| b.value[k] != 0.0)
            .map(|k| (b.first + k) % m)
            .collect();
        cut.evaluate(cut.period() * (1.0 - 1e-12), &mut b).unwrap();
        let end: Vec<usize> = (0..b.order)
            .filter(|&k| b.value[k] != 0.0)
            .map(|k| (b.first + k) % m)
            .collect();
        assert!(
            start.iter().all(|i| !end.contains(i)),
            "degree {d}: {start:?} {end:?}"
        );
    }
}

#[test]
fn a_ring_cut_at_its_seam_is_one_open_piece() {
    let mut rod = ring(PeriodicBSplineSpace::uniform(3, 9, 1.3).unwrap());
    assert_eq!(rod.pieces(), 1);
    assert!(!rod.is_cut_at_seam());
    assert_eq!(rod.cut(1.3).unwrap(), 3, "the seam is a knot already");
    assert!(rod.is_cut_at_seam());
    assert_eq!(rod.pieces(), 1);
    rod.cut(0.5).unwrap();
    assert_eq!(rod.pieces(), 2);
    assert!(rod.cut(0.0).is_err(), "the seam is cut already");
}
