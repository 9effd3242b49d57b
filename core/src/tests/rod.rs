use super::all_test_spaces;
use crate::{BSplineSpace, BasisSpace, CoreError, Material, Real, Rod};
use nalgebra::Vector3;

fn material(length: Real) -> Material {
    Material {
        rest_length: length,
        linear_density: 0.37,
    }
}

fn bent_rod(space: &BSplineSpace) -> Rod {
    let l = space.domain().1;
    let mut rod = Rod::straight(
        material(l),
        Box::new(space.clone()),
        Vector3::zeros(),
        Vector3::new(l, 0.0, 0.0),
    )
    .unwrap();
    for (i, (q, v)) in rod
        .positions
        .iter_mut()
        .zip(rod.velocities.iter_mut())
        .enumerate()
    {
        let x = i as Real;
        q.y += 0.1 * (1.3 * x).sin();
        *v = Vector3::new((0.7 * x).cos(), 0.3 * x, -0.2);
    }
    rod
}

#[test]
fn straight_rod_is_the_uniform_line() {
    for space in all_test_spaces() {
        let l = space.domain().1;
        let (a, b) = (Vector3::new(0.1, 0.2, 0.3), Vector3::new(1.0, -0.5, 0.7));
        let rod = Rod::straight(material(l), Box::new(space.clone()), a, b).unwrap();
        for k in 0..=50 {
            let s = l * k as Real / 50.0;
            let expected = a + (b - a) * (s / l);
            assert!((rod.point(s).unwrap() - expected).norm() < 1e-13);
            assert!((rod.tangent(s).unwrap() - (b - a) / l).norm() < 1e-12);
        }
    }
}

#[test]
fn mass_matrix_integrates_the_density() {
    // Total mass μL, rigid translation kinetic energy ½ μ L |v|², exact to round-off.
    for space in all_test_spaces() {
        let l = space.domain().1;
        let mut rod = bent_rod(&space);
        assert!((rod.total_mass() - 0.37 * l).abs() < 1e-14 * l);
        let v = Vector3::new(0.3, -1.2, 2.0);
        rod.velocities.iter_mut().for_each(|x| *x = v);
        let expected = 0.5 * 0.37 * l * v.norm_squared();
        assert!((rod.kinetic_energy() - expected).abs() < 1e-13 * expected);
        assert!((rod.linear_momentum() - v * 0.37 * l).norm() < 1e-13);
        let m = rod.mass_matrix();
        for i in 0..rod.len() {
            let row: Real = (0..rod.len()).map(|j| m.get(i, j)).sum();
            assert!((row - rod.lumped_masses()[i]).abs() < 1e-14);
        }
    }
}

#[test]
fn mass_matrix_entries_match_a_fine_quadrature() {
    // A 40-point rule per span integrates b_i b_j to round-off; the cached rule must agree.
    let space = super::irregular_space(3, 1.5);
    let rod = bent_rod(&space);
    let fine = crate::QuadratureTable::new(&space, 40).unwrap();
    let n = rod.len();
    let mut dense = vec![vec![0.0; n]; n];
    for qp in fine.points() {
        for a in 0..4 {
            for b in 0..4 {
                dense[qp.first + a][qp.first + b] += 0.37 * qp.weight * qp.value[a] * qp.value[b];
            }
        }
    }
    for (i, row) in dense.iter().enumerate() {
        for (j, value) in row.iter().enumerate() {
            assert!((rod.mass_matrix().get(i, j) - value).abs() < 1e-15);
        }
    }
}

#[test]
fn knot_insertion_changes_no_physical_quantity() {
    // The invariant of adaptivity, to round-off (1e-13 relative).
    for space in all_test_spaces() {
        let mut rod = bent_rod(&space);
        let l = space.domain().1;
        let (ke, p, c) = (
            rod.kinetic_energy(),
            rod.linear_momentum(),
            rod.centre_of_mass(),
        );
        let probe: Vec<_> = (0..=20).map(|k| l * k as Real / 20.0).collect();
        let before: Vec<_> = probe
            .iter()
            .map(|&s| (rod.point(s).unwrap(), rod.velocity(s).unwrap()))
            .collect();
        let mut epochs = vec![rod.topology_epoch()];
        for f in [0.3, 0.31, 0.8] {
            rod.insert_knot(f * l).unwrap();
            epochs.push(rod.topology_epoch());
        }
        // Every change of basis gets a new epoch.
        epochs.sort_unstable();
        epochs.dedup();
        assert_eq!(epochs.len(), 4);
        assert!((rod.kinetic_energy() - ke).abs() < 1e-13 * ke);
        assert!((rod.linear_momentum() - p).norm() < 1e-13 * p.norm());
        assert!((rod.centre_of_mass() - c).norm() < 1e-13 * (1.0 + c.norm()));
        for (s, (x, v)) in probe.iter().zip(&before) {
            assert!((rod.point(*s).unwrap() - x).norm() < 1e-13);
            assert!((rod.velocity(*s).unwrap() - v).norm() < 1e-12);
        }
    }
}

#[test]
fn removal_beyond_tolerance_changes_nothing() {
    let space = BSplineSpace::clamped_uniform(3, 10, 1.0).unwrap();
    let mut rod = bent_rod(&space);
    let knots = rod.basis().knots().to_vec();
    let positions = rod.positions.clone();
    let result = rod.remove_knot(5, 1e-9);
    assert!(matches!(
        result,
        Err(CoreError::RemovalNotWithinTolerance { index: 5, .. })
    ));
    assert_eq!(rod.basis().knots(), &knots[..]);
    assert_eq!(rod.positions, positions);
}

#[test]
fn bad_rods_are_rejected() {
    let space = BSplineSpace::clamped_uniform(3, 6, 1.0).unwrap();
    let bad =
        |m: Material| Rod::straight(m, Box::new(space.clone()), Vector3::zeros(), Vector3::x());
    let e = bad(Material {
        rest_length: 1.0,
        linear_density: -1.0,
    })
    .unwrap_err();
    assert!(matches!(
        e,
        CoreError::InvalidParameter {
            name: "linear_density",
            ..
        }
    ));
    let e = bad(Material {
        rest_length: Real::NAN,
        linear_density: 1.0,
    })
    .unwrap_err();
    assert!(matches!(
        e,
        CoreError::InvalidParameter {
            name: "rest_length",
            ..
        }
    ));
    let e = bad(Material {
        rest_length: 2.0,
        linear_density: 1.0,
    })
    .unwrap_err();
    assert!(matches!(e, CoreError::DomainMismatch { .. }));
    let m = material(1.0);
    let e = Rod::new(m, Box::new(space.clone()), vec![Vector3::zeros(); 5]).unwrap_err();
    assert!(matches!(
        e,
        CoreError::CountMismatch {
            expected: 6,
            found: 5,
            ..
        }
    ));
    let mut pts = vec![Vector3::zeros(); 6];
    pts[2].x = Real::INFINITY;
    let e = Rod::new(m, Box::new(space), pts).unwrap_err();
    assert!(matches!(e, CoreError::NonFiniteState { index: 2, .. }));
}

/// A rod without second derivatives tabulates the same values and first derivatives,
/// keeps leaving the second ones out through knot insertion, removal and refined copies,
/// and says so.
#[test]
fn a_lean_table_keeps_everything_but_the_second_derivatives() {
    let space = BSplineSpace::clamped_uniform(3, 12, 1.0).unwrap();
    let full = bent_rod(&space).with_quadrature_points(4).unwrap();
    let mut lean = bent_rod(&space)
        .with_quadrature_points(4)
        .unwrap()
        .without_second_derivatives();
    let same = |a: &Rod, b: &Rod| {
        assert_eq!(a.quadrature().len(), b.quadrature().len());
        for (p, q) in a.quadrature().points().zip(b.quadrature().points()) {
            assert_eq!((p.s, p.weight, p.first), (q.s, q.weight, q.first));
            assert_eq!((p.value, p.d1, p.lower), (q.value, q.d1, q.lower));
        }
        assert_eq!(a.mass_matrix().get(3, 4), b.mass_matrix().get(3, 4));
    };
    same(&full, &lean);
    assert!(full.quadrature().has_second_derivatives());
    let lean_everywhere = |rod: &Rod| {
        assert!(!rod.quadrature().has_second_derivatives());
        assert!(rod.quadrature().points().all(|p| p.d2.is_empty()));
    };
    lean_everywhere(&lean);
    let mut full = full;
    full.insert_knot(0.37).unwrap();
    lean.insert_knot(0.37).unwrap();
    same(&full, &lean);
    lean_everywhere(&lean);
    let mut op = crate::RefinementOperator::default();
    let refined = lean.refined(&[0.5, 0.61], &mut op).unwrap();
    lean_everywhere(&refined);
    let knot = lean
        .basis()
        .knots()
        .iter()
        .position(|&t| t == 0.37)
        .unwrap();
    lean.remove_knot(knot, 1.0).unwrap();
    lean_everywhere(&lean);
    let lean = lean.with_quadrature_points(5).unwrap();
    lean_everywhere(&lean);
}
