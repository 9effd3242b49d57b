//! Unit tests of the core kernels.
mod basis;
mod block_banded;
mod knots;
mod local_update;
mod periodic;
mod proximity;
mod rod;

use crate::{BSplineSpace, BasisSpace, BasisValues, Real};
use nalgebra::Vector3;

/// The curve of control points `q` on `space` at `s`.
pub(crate) fn curve(space: &dyn BasisSpace, q: &[Vector3<Real>], s: Real) -> Vector3<Real> {
    let mut b = BasisValues::default();
    space.evaluate(s, &mut b).unwrap();
    b.combine(&b.value, q)
}

/// Largest distance between two curves over 401 parameters of the first's domain.
pub(crate) fn max_curve_difference(
    a: (&dyn BasisSpace, &[Vector3<Real>]),
    b: (&dyn BasisSpace, &[Vector3<Real>]),
) -> Real {
    let (s0, s1) = a.0.domain();
    (0..=400)
        .map(|k| s0 + (s1 - s0) * k as Real / 400.0)
        .map(|s| (curve(a.0, a.1, s) - curve(b.0, b.1, s)).norm())
        .fold(0.0, Real::max)
}

/// A clamped or uniform space with some random-ish interior knots, for the tests.
pub(crate) fn irregular_space(degree: usize, length: Real) -> BSplineSpace {
    let mut space = BSplineSpace::clamped_uniform(degree, degree + 4, length).unwrap();
    for f in [0.13, 0.37, 0.38, 0.61, 0.9] {
        space.insert_knot(f * length).unwrap();
    }
    space
}

pub(crate) fn all_test_spaces() -> Vec<BSplineSpace> {
    let mut v = Vec::new();
    for d in 1..=5 {
        v.push(BSplineSpace::clamped_uniform(d, d + 7, 1.3).unwrap());
        v.push(BSplineSpace::uniform(d, d + 6, 0.7).unwrap());
        v.push(irregular_space(d, 2.0));
    }
    v
}

#[test]
fn test_spaces_are_valid() {
    for s in all_test_spaces() {
        assert_eq!(s.knots().len(), s.count() + s.degree() + 1);
    }
}
