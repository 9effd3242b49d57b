//! Writhe of a rod between two clamps, for checking Călugăreanu's theorem
//! \\(\mathrm{Lk} = \mathrm{Tw}/2\pi + \mathrm{Wr}\\) on twisted rods.
//!
//! The centreline is sampled into a polyline and closed "at infinity" by straight
//! extensions along the clamp axes (backwards from the start, forwards from the end),
//! each `EXTENSION` rest lengths long: the usual convention for an open rod whose ends
//! are held on a common axis (e.g. a twisted molecule or cable between clamps). The
//! writhe of the polyline is the exact double sum of Klenin & Langowski (2000):
//! \\(\mathrm{Wr} = \tfrac{1}{2\pi}\sum_{i<j} \Omega_{ij}\\), with \\(\Omega_{ij}\\)
//! the signed solid angle segment `j` subtends seen from all points of segment `i`.
//! O(N²) in the samples: an analysis at output time, never in a step. A closed rod's
//! polyline closes on itself, with no extensions.

use crate::Error;
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};

/// Length of each straight extension, in rest lengths.
pub const EXTENSION: Real = 1e3;

/// Writhe (turns) of `rod` sampled at `samples` points, closed by extensions along
/// `axes` (unit tangents of the start and end clamps).
pub fn writhe(rod: &Rod, samples: usize, axes: [Vector3<Real>; 2]) -> Result<Real, Error> {
    let l = rod.material().rest_length;
    if rod.is_closed() {
        // A closed rod needs no closure: its own polyline, back to the start.
        let points: Vec<Vector3<Real>> = (0..samples)
            .map(|k| rod.point(l * k as Real / samples as Real))
            .collect::<Result<_, _>>()?;
        return Ok(closed_polyline_writhe(&points));
    }
    let mut points = Vec::with_capacity(samples + 2);
    let start = rod.point(0.0)?;
    points.push(start - axes[0] * (EXTENSION * l));
    for k in 0..samples {
        // `l k / (n − 1)` can round above `l` at the end (l = 1.49925, 25 samples).
        let s = (l * k as Real / (samples - 1) as Real).min(l);
        points.push(rod.point(s)?);
    }
    let end = points[points.len() - 1];
    points.push(end + axes[1] * (EXTENSION * l));
    Ok(polyline_writhe(&points))
}

/// Writhe of an open polyline (turns).
pub fn polyline_writhe(points: &[Vector3<Real>]) -> Real {
    let segments = points.len().saturating_sub(1);
    let mut sum = 0.0;
    for i in 0..segments {
        for j in i + 2..segments {
            sum += solid_angle(points[i], points[i + 1], points[j], points[j + 1]);
        }
    }
    sum / (2.0 * std::f64::consts::PI)
}

/// Writhe of the closed polyline through `points` and back to the first (turns).
pub fn closed_polyline_writhe(points: &[Vector3<Real>]) -> Real {
    let n = points.len();
    let segment = |i: usize| (points[i], points[(i + 1) % n]);
    let mut sum = 0.0;
    for i in 0..n {
        // Not with itself nor its neighbours (around the loop: the last and the first).
        for j in i + 2..n - usize::from(i == 0) {
            let ((p1, p2), (p3, p4)) = (segment(i), segment(j));
            sum += solid_angle(p1, p2, p3, p4);
        }
    }
    sum / (2.0 * std::f64::consts::PI)
}

/// Signed solid angle of segment `p3 p4` seen from segment `p1 p2` (Klenin & Langowski).
fn solid_angle(p1: Vector3<Real>, p2: Vector3<Real>, p3: Vector3<Real>, p4: Vector3<Real>) -> Real {
    let (r13, r14, r23, r24) = (p3 - p1, p4 - p1, p3 - p2, p4 - p2);
    let unit = |v: Vector3<Real>| {
        let n = v.norm();
        if n > 0.0 {
            v / n
        } else {
            Vector3::zeros()
        }
    };
    let n = [
        unit(r13.cross(&r14)),
        unit(r14.cross(&r24)),
        unit(r24.cross(&r23)),
        unit(r23.cross(&r13)),
    ];
    let omega: Real = (0..4)
        .map(|k| n[k].dot(&n[(k + 1) % 4]).clamp(-1.0, 1.0).asin())
        .sum();
    let sign = (p4 - p3).cross(&(p2 - p1)).dot(&r13);
    omega * sign.signum()
}
