//! Twisting: conformance (exact derivatives of the discrete holonomy), uniform torsion.

use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, Material, Rod};
use splinerod_energies::conformance::{check_energy, Expectations, RigidInvariance};
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
            knot_insertion: 3e-2,
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
