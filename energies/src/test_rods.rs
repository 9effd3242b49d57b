//! Rods the unit tests of several energies share.

use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, Material, Real, Rod};

/// A 12-point rod of `degree` with `points` quadrature points per span, unevenly
/// stretched along x and bent out of it by waves of amplitudes `(y, z)`.
pub(crate) fn wavy_rod(degree: usize, points: usize, (y, z): (Real, Real)) -> Rod {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(degree, 12, 1.0).expect("basis");
    let end = Vector3::new(0.9, 0.0, 0.0);
    let mut rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end)
        .expect("rod")
        .with_quadrature_points(points)
        .expect("quadrature");
    for (i, p) in rod.positions.iter_mut().enumerate() {
        let t = i as Real;
        *p = *p * (1.0 + 0.2 * (0.7 * t).sin())
            + Vector3::new(0.0, y * (1.3 * t).sin(), z * t.cos());
    }
    rod
}
