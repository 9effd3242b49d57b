//! Places where the rod is closer to itself or to a surface than asked
//! ([`Contact::for_each_close`]): what a start that overlaps only because its fit is
//! coarse needs to be told apart from a genuinely overlapping one and pushed out (the
//! scene's coarse start, issue #46).
//!
//! Besides its gap and the direction that opens it, each place carries the same gap
//! measured on the **control polygon** of the basis rows involved: for a surface, the
//! smallest gap of the row's control points, \\(\min_i d(q_i) - r\\); for a sample pair,
//! the distance between the two rows' control polygons (their consecutive points joined
//! by segments) minus \\(r_a + r_b\\). A curve lies in the convex hull of its row's
//! control points and approaches its control polygon as knots are inserted, so where
//! the curve overlaps but the polygon does not, the overlap is the spline's smoothing
//! of a coarse polygon, not the polygon's own.

use super::Contact;
use nalgebra::Vector3;
use splinerod_core::{CoreError, Real, Rod};

/// One side of a close place: a material point and its basis row.
#[derive(Debug, Clone, Copy)]
pub struct Side<'a> {
    /// Material coordinate, m.
    pub s: Real,
    /// First control point of the basis row.
    pub first: usize,
    /// Basis values at `s` for control points `first..`.
    pub row: &'a [Real],
}

/// A place where the rod is closer than asked (module docs).
#[derive(Debug, Clone, Copy)]
pub struct Close<'a> {
    /// Gap, m (negative: overlap).
    pub gap: Real,
    /// The contact distance there: `r_a + r_b` between strands, `r` from a surface, m.
    pub distance: Real,
    /// Unit vector along which moving side `a` (and `b` the other way) opens the gap.
    pub normal: Vector3<Real>,
    /// The point of the rod (the first of a pair).
    pub a: Side<'a>,
    /// The other point of a pair (`None`: a surface).
    pub b: Option<Side<'a>>,
    /// The gap measured on the control polygon, m (module docs).
    pub polygon_gap: Real,
}

impl Contact {
    /// Calls `f` at every sample pair and surface point within reach whose gap is below
    /// `below` (m; at most the onset: nothing farther is detected).
    pub fn for_each_close(
        &self,
        rod: &Rod,
        below: Real,
        mut f: impl FnMut(&Close<'_>),
    ) -> Result<(), CoreError> {
        let d = self.detected(rod)?;
        let q = &rod.positions;
        for c in &d.pairs {
            let gap = self.gap(&d, c);
            if gap >= below {
                continue;
            }
            let side = |k: u32| {
                let k = k as usize;
                let first = d.samples.first[k] as usize;
                let row = d.samples.row(k);
                (
                    Side {
                        s: d.samples.s[k],
                        first,
                        row,
                    },
                    &q[first..first + row.len()],
                )
            };
            let ((a, pa), (b, pb)) = (side(c.a), side(c.b));
            let distance = self.sum_of_radii(&d, c);
            f(&Close {
                gap,
                distance,
                normal: c.normal,
                a,
                b: Some(b),
                polygon_gap: polygon_distance(pa, pb) - distance,
            });
        }
        drop(d);
        let floor = self.params.floor;
        self.for_each_surface_point(rod, |p| {
            if p.gap >= below {
                return;
            }
            let points = &q[p.first..p.first + p.row.len()];
            let surface_gap = |x: &Vector3<Real>| match p.obstacle {
                Some(i) => self.obstacles[i].distance(x).0 - p.radius,
                None => floor.map_or(Real::INFINITY, |(n, h)| n.dot(x) - h - p.radius),
            };
            let polygon_gap = points
                .iter()
                .map(surface_gap)
                .fold(Real::INFINITY, Real::min);
            f(&Close {
                gap: p.gap,
                distance: p.radius,
                normal: p.normal,
                a: Side {
                    s: p.s,
                    first: p.first,
                    row: p.row,
                },
                b: None,
                polygon_gap,
            });
        })
    }
}

/// The distance between two control polygons (consecutive points joined).
fn polygon_distance(a: &[Vector3<Real>], b: &[Vector3<Real>]) -> Real {
    // Consecutive points; a single point is a segment of length zero.
    let edge = |p: &[Vector3<Real>], k: usize| [p[k], p[(k + 1).min(p.len() - 1)]];
    let count = |p: &[Vector3<Real>]| p.len().saturating_sub(1).max(1);
    let mut least = Real::INFINITY;
    for i in 0..count(a) {
        let [a0, a1] = edge(a, i);
        for k in 0..count(b) {
            let [b0, b1] = edge(b, k);
            least = least.min(segment_distance(a0, a1, b0, b1));
        }
    }
    least
}

/// The distance between the segments `p0`–`p1` and `q0`–`q1`.
fn segment_distance(
    p0: Vector3<Real>,
    p1: Vector3<Real>,
    q0: Vector3<Real>,
    q1: Vector3<Real>,
) -> Real {
    splinerod_core::proximity::closest_on_segments((p0, p1), (q0, q1)).2
}

#[cfg(test)]
mod tests {
    use super::segment_distance;
    use nalgebra::Vector3;

    #[test]
    fn segment_distances() {
        let v = Vector3::new;
        let d = segment_distance(
            v(0., 0., 0.),
            v(1., 0., 0.),
            v(0.5, 1., -1.),
            v(0.5, 1., 1.),
        );
        assert!((d - 1.0).abs() < 1e-15, "{d}");
        // Parallel, overlapping: 2 apart.
        let d = segment_distance(v(0., 0., 0.), v(1., 0., 0.), v(0.5, 2., 0.), v(3., 2., 0.));
        assert!((d - 2.0).abs() < 1e-15, "{d}");
        // End to end.
        let d = segment_distance(v(0., 0., 0.), v(1., 0., 0.), v(2., 0., 0.), v(3., 0., 0.));
        assert!((d - 1.0).abs() < 1e-15, "{d}");
        // Degenerate (points).
        let d = segment_distance(v(0., 0., 0.), v(0., 0., 0.), v(0., 3., 4.), v(0., 3., 4.));
        assert!((d - 5.0).abs() < 1e-15, "{d}");
    }
}
