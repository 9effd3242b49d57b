//! Closest points of two straight segments (capsule axes, polyline edges).

use crate::Real;
use nalgebra::Vector3;

/// The parameters `(s, t) ∈ [0, 1]²` of the closest points \\(p_0 + s(p_1 - p_0)\\) and
/// \\(q_0 + t(q_1 - q_0)\\) of the segments `p0`–`p1` and `q0`–`q1`, with their distance:
/// the unconstrained minimiser of the squared distance clamped to the square, then each
/// edge of the square (one end fixed, the other parameter clamped); the least distance
/// of those candidates. A segment of length zero is a point.
pub fn closest_on_segments(
    (p0, p1): (Vector3<Real>, Vector3<Real>),
    (q0, q1): (Vector3<Real>, Vector3<Real>),
) -> (Real, Real, Real) {
    let (u, v, w) = (p1 - p0, q1 - q0, p0 - q0);
    let (a, b, c, d, e) = (u.dot(&u), u.dot(&v), v.dot(&v), u.dot(&w), v.dot(&w));
    let at = |s: Real, t: Real| (s, t, (w + u * s - v * t).norm());
    let clamp = |x: Real| {
        if x.is_finite() {
            x.clamp(0.0, 1.0)
        } else {
            0.0
        }
    };
    let least = |x: (Real, Real, Real), y: (Real, Real, Real)| {
        if y.2 < x.2 || x.2.is_nan() {
            y
        } else {
            x
        }
    };
    let det = a * c - b * b;
    let mut best = if det > 1e-14 * a * c {
        at(clamp((b * e - c * d) / det), clamp((a * e - b * d) / det))
    } else {
        (0.0, 0.0, Real::INFINITY)
    };
    for s in [0.0, 1.0] {
        best = least(best, at(s, clamp((b * s + e) / c)));
    }
    for t in [0.0, 1.0] {
        best = least(best, at(clamp((b * t - d) / a), t));
    }
    best
}
