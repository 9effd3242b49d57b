//! Helpers shared by the energies' integration tests.

use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, Material, Real, Rod};

/// A cubic rod of `n` control points and rest length `length`, along x at height
/// `lift`, bent a little out of line.
pub fn part(n: usize, length: Real, lift: Real) -> Rod {
    let material = Material {
        rest_length: length,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, length).expect("basis");
    let (a, b) = (
        Vector3::new(0.0, lift, 0.0),
        Vector3::new(0.9 * length, lift, 0.2),
    );
    let mut rod = Rod::straight(material, Box::new(basis), a, b).expect("rod");
    for (i, q) in rod.positions.iter_mut().enumerate() {
        let x = i as Real;
        *q += Vector3::new(0.0, 0.04 * (1.9 * x).sin(), 0.03 * (0.7 * x).cos());
    }
    rod
}
