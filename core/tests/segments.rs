//! Joined rods (`Rod::join`): each part keeps its curve, motion, mass and damping, and
//! knot changes inside one part leave the others untouched.
use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, Material, Real, Rod};

fn part(n: usize, length: Real, density: Real, damping: Real, lift: Real) -> Rod {
    let material = Material {
        rest_length: length,
        linear_density: density,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, length).expect("basis");
    let mut rod = Rod::straight(
        material,
        Box::new(basis),
        Vector3::new(0.0, lift, 0.0),
        Vector3::new(length, lift + 0.3, 0.1),
    )
    .expect("rod");
    for (i, (q, v)) in rod
        .positions
        .iter_mut()
        .zip(rod.velocities.iter_mut())
        .enumerate()
    {
        let x = i as Real;
        *q += Vector3::new(0.0, 0.05 * (1.7 * x).sin(), 0.02 * x.cos());
        *v = Vector3::new(0.1 * x, -0.2, 0.3 * (0.5 * x).sin());
    }
    rod.damping = damping;
    rod
}

fn parts() -> Vec<Rod> {
    vec![
        part(7, 1.0, 0.1, 0.5, 0.0),
        part(9, 0.6, 0.4, 2.0, 1.0),
        part(5, 1.3, 0.02, 0.0, -1.0),
    ]
}

#[test]
fn each_part_keeps_its_curve_motion_mass_and_damping() {
    let parts = parts();
    let joined = Rod::join(&parts).expect("join");
    assert_eq!(joined.segments().len(), 3);
    assert_eq!(joined.pieces(), 3);
    assert_eq!(joined.damping, parts[0].damping);
    assert_eq!(joined.uniform_damping(), None);
    let mut offset = 0.0;
    for (k, p) in parts.iter().enumerate() {
        let range = joined.segment_points(k);
        assert_eq!(range.len(), p.len(), "part {k}");
        for s in [0.0, 0.17, 0.5, 0.93, 1.0].map(|f| f * p.material().rest_length) {
            let t = (offset + s).min(joined.material().rest_length);
            let a = if s == p.material().rest_length && k + 1 < parts.len() {
                // On a junction the joined rod takes the next part's start.
                continue;
            } else {
                joined.point(t).expect("point")
            };
            assert!(
                (a - p.point(s).expect("part point")).norm() < 1e-14,
                "{k} {s}"
            );
            let v = joined.velocity(t).expect("velocity") - p.velocity(s).expect("v");
            assert!(v.norm() < 1e-14);
        }
        let first = range.start;
        for i in 0..p.len() {
            assert_eq!(joined.damping_at(first + i), p.damping);
            assert!((joined.lumped_masses()[first + i] - p.lumped_masses()[i]).abs() < 1e-15);
            for j in 0..p.len() {
                let m = joined.mass_matrix().get(first + i, first + j);
                assert!((m - p.mass_matrix().get(i, j)).abs() < 1e-15, "{k} {i} {j}");
            }
        }
        offset += p.material().rest_length;
    }
    let mass: Real = parts.iter().map(Rod::total_mass).sum();
    assert!((joined.total_mass() - mass).abs() < 1e-14);
    assert_eq!(joined.segment_at(1.3), 1);
    assert_eq!(joined.segment_at(1.0), 1);
    assert_eq!(joined.segment_at(0.99), 0);
}

#[test]
fn knot_changes_inside_a_part_match_the_part_alone() {
    let mut parts = parts();
    let mut joined = Rod::join(&parts).expect("join");
    joined.insert_knot(1.0 + 0.37).expect("insert");
    parts[1].insert_knot(0.37).expect("insert");
    let index = joined
        .basis()
        .knots()
        .iter()
        .position(|&t| t == 1.0 + 0.6 / 6.0 * 2.0)
        .expect("knot");
    joined.remove_knot(index, 1.0).expect("remove");
    let local = parts[1]
        .basis()
        .knots()
        .iter()
        .position(|&t| t == 0.6 / 6.0 * 2.0)
        .expect("knot");
    parts[1].remove_knot(local, 1.0).expect("remove");
    let mut first = 0;
    for (k, p) in parts.iter().enumerate() {
        assert_eq!(joined.segment_points(k), first..first + p.len());
        for i in 0..p.len() {
            assert!((joined.positions[first + i] - p.positions[i]).norm() < 1e-14);
            for j in 0..p.len() {
                let m = joined.mass_matrix().get(first + i, first + j);
                assert!((m - p.mass_matrix().get(i, j)).abs() < 1e-14, "{k} {i} {j}");
            }
            assert_eq!(joined.damping_at(first + i), p.damping);
        }
        first += p.len();
    }
}

#[test]
fn joining_refuses_mixed_degrees_and_nothing() {
    assert!(Rod::join(&[]).is_err());
    let cubic = part(6, 1.0, 0.1, 0.0, 0.0);
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let quadratic = BSplineSpace::clamped_uniform(2, 6, 1.0).expect("basis");
    let quadratic = Rod::straight(
        material,
        Box::new(quadratic),
        Vector3::zeros(),
        Vector3::x(),
    )
    .expect("rod");
    let err = Rod::join(&[cubic, quadratic]).expect_err("degrees differ");
    assert!(err.to_string().contains("degree"), "{err}");
}
