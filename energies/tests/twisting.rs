//! Twisting: conformance (exact derivatives of the discrete holonomy), uniform torsion.

use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, Material, Rod};
use splinerod_energies::conformance::{check_energy, Expectations, RigidInvariance};
use splinerod_energies::Lifecycle;
use splinerod_energies::{Energy, Frame, Twisting};

fn straight(n: usize, degree: usize) -> Rod {
    let material = Material {
        rest_length: 1.3,
        linear_density: 0.2,
    };
    let basis = BSplineSpace::clamped_uniform(degree, n, 1.3).unwrap();
    Rod::straight(
        material,
        Box::new(basis),
        Vector3::zeros(),
        Vector3::new(1.3, 0.0, 0.0),
    )
    .unwrap()
}

#[test]
fn twisting_passes_the_conformance_harness() {
    let rod = straight(8, 3);
    let mut twisting =
        Twisting::between_ends(0.7, &rod, Frame::along(Vector3::x()).unwrap()).unwrap();
    twisting.turn = 0.4;
    let report = check_energy(
        &twisting,
        Expectations {
            zero_at_rest: false,
            rigid: RigidInvariance::None,
            knot_insertion: 5e-2,
        },
    )
    .unwrap();
    println!("{report:?}");
}

#[test]
fn uniform_torsion_has_the_exact_energy_and_moment() {
    for degree in [2, 3, 5] {
        let rod = straight(12, degree);
        let mut twisting =
            Twisting::between_ends(0.7, &rod, Frame::along(Vector3::x()).unwrap()).unwrap();
        for phi in [0.3, 2.0, -5.0] {
            twisting.turn = phi;
            let exact = 0.7 * phi * phi / (2.0 * 1.3);
            let e = twisting.energy(&rod);
            assert!((e - exact).abs() <= 1e-12 * exact, "{e} vs {exact}");
            let m = twisting.moment(&rod);
            assert!((m - 0.7 * phi / 1.3).abs() <= 1e-12 * m.abs());
        }
    }
}

/// On a resolved smooth rod the sampling error is small: the twist changes under knot
/// insertion by far less than on the harness's crumpled rods.
#[test]
fn knot_insertion_barely_changes_the_twist_of_a_resolved_rod() {
    let mut rod = straight(16, 3);
    for (i, q) in rod.positions.iter_mut().enumerate() {
        let s = i as f64 / 15.0;
        q.y += 0.08 * (std::f64::consts::PI * s).sin();
        q.z += 0.05 * (2.0 * std::f64::consts::PI * s).sin();
    }
    let frame = Frame::along(rod.tangent(0.0).unwrap()).unwrap();
    let mut twisting = Twisting::between_ends(0.7, &straight(16, 3), frame).unwrap();
    twisting.turn = 2.0;
    let before = twisting.twist(&rod);
    let mut refined = rod.clone();
    for s in [0.17, 0.6, 1.01] {
        refined.insert_knot(s).unwrap();
    }
    let after = twisting.twist(&refined);
    println!("twist {before:.9} → {after:.9} rad after three insertions");
    assert!(
        (after - before).abs() < 1e-4 * before.abs(),
        "{before} → {after}"
    );
}

/// The twist of a closed rod: the conformance harness runs it on the closed test rods
/// (it refuses open ones), including the coupling across the seam.
#[test]
fn the_twist_of_a_loop_passes_the_conformance_harness() {
    use splinerod_core::PeriodicBSplineSpace;
    let material = Material {
        rest_length: 1.3,
        linear_density: 0.2,
    };
    let space = PeriodicBSplineSpace::uniform(3, 10, 1.3).unwrap();
    let ring = Rod::ring(
        material,
        Box::new(space),
        Vector3::zeros(),
        Vector3::z(),
        0.2,
    )
    .unwrap();
    let twisting = Twisting::around_loop(0.7, &ring, 0.4).unwrap();
    assert!(twisting.supports(&straight(8, 3)).is_err());
    let report = check_energy(
        &twisting,
        Expectations {
            zero_at_rest: false,
            rigid: RigidInvariance::Full,
            // The sampling error of the holonomy on the harness's coarse rings (8 control
            // points of degree 3 around a wiggled loop): measured 8.2e-2.
            knot_insertion: 0.1,
        },
    )
    .unwrap();
    println!("{report:?}");
    // A planar ring keeps the twist it was given: Tw = Φ, E = GJ Φ² / (2L).
    let e = twisting.energy(&ring);
    assert!((e - 0.7 * 0.16 / 2.6).abs() < 1e-12, "{e}");
}
