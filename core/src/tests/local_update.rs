//! The local cache update after knot operations equals a rebuild from scratch.

use super::all_test_spaces;
use crate::{BasisSpace, Material, Real, Rod};
use nalgebra::Vector3;

fn rebuilt(rod: &Rod) -> Rod {
    Rod::new(
        *rod.material(),
        rod.basis().clone_box(),
        rod.positions.clone(),
    )
    .unwrap()
}

fn assert_same_caches(local: &Rod, label: &str) {
    let fresh = rebuilt(local);
    let (a, b) = (local.quadrature(), fresh.quadrature());
    assert_eq!(a.len(), b.len(), "{label}: point count");
    for p in 0..a.len() {
        let (x, y) = (a.point(p), b.point(p));
        assert_eq!(x.first, y.first, "{label}: point {p} first");
        assert!((x.s - y.s).abs() <= 1e-15 && (x.weight - y.weight).abs() <= 1e-15);
        for k in 0..x.value.len() {
            let worst = [
                x.value[k] - y.value[k],
                x.d1[k] - y.d1[k],
                x.d2[k] - y.d2[k],
            ];
            assert!(worst.iter().all(|e| e.abs() <= 1e-9), "{label}: point {p}");
        }
    }
    let n = local.len();
    let (m, f) = (local.mass_matrix(), fresh.mass_matrix());
    assert_eq!(m.dim(), f.dim());
    for i in 0..n {
        for j in i..(i + m.bandwidth() + 1).min(n) {
            assert!(
                (m.get(i, j) - f.get(i, j)).abs() <= 1e-14,
                "{label}: M[{i},{j}]"
            );
        }
        let dl = local.lumped_masses()[i] - fresh.lumped_masses()[i];
        assert!(dl.abs() <= 1e-14, "{label}: lumped {i}");
    }
}

#[test]
fn local_updates_match_a_rebuild() {
    for space in all_test_spaces() {
        let l = space.domain().1;
        let material = Material {
            rest_length: l,
            linear_density: 0.37,
        };
        let end = Vector3::new(l, 0.1, 0.0);
        let mut rod =
            Rod::straight(material, Box::new(space.clone()), Vector3::zeros(), end).unwrap();
        let label = format!("degree {}, {} cps", space.degree(), space.count());
        let mut inserted = Vec::new();
        for f in [0.37, 0.5, 0.5, 0.91, 0.02, 0.5] {
            let s: Real = f * l;
            if let Ok(map) = rod.insert_knot(s) {
                inserted.push(map.knot_index());
                assert_same_caches(&rod, &format!("{label}, insert {s}"));
            }
        }
        for index in inserted.into_iter().rev() {
            rod.remove_knot(index, 1e-9).unwrap();
            assert_same_caches(&rod, &format!("{label}, remove #{index}"));
        }
    }
}

#[test]
fn a_cut_separates_the_rod_into_decoupled_pieces() {
    use crate::BSplineSpace;
    for degree in 1..=4 {
        let space = BSplineSpace::clamped_uniform(degree, 9, 1.0).unwrap();
        let material = Material {
            rest_length: 1.0,
            linear_density: 0.2,
        };
        let end = Vector3::new(1.0, 0.0, 0.0);
        let mut rod = Rod::straight(material, Box::new(space), Vector3::zeros(), end).unwrap();
        let before = rod.point(0.42).unwrap();
        assert_eq!(rod.cut(0.42).unwrap(), degree + 1);
        assert_eq!((rod.pieces(), rod.cuts()), (2, vec![0.42]));
        assert!((rod.point(0.42).unwrap() - before).norm() < 1e-14);
        assert!(rod.cut(0.42).is_err(), "cutting twice at one place");
        assert!(rod.cut(1.0).is_err() && rod.cut(-0.1).is_err());
        // No mass couples a control point of the left piece with one of the right piece.
        let knots = rod.basis().knots();
        let last_left = knots.iter().position(|&t| t == 0.42).unwrap() - 1;
        let m = rod.mass_matrix();
        for i in 0..=last_left {
            for j in last_left + 1..rod.len() {
                assert_eq!(m.get(i, j), 0.0, "degree {degree}: M[{i},{j}]");
            }
        }
        rod.cut(0.8).unwrap();
        assert_eq!(rod.pieces(), 3);
        assert_same_caches(&rod, &format!("degree {degree}, two cuts"));
    }
}
