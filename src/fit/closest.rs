//! The point of a rod's curve nearest to an observed point: what an unlabelled
//! observation (a point of a point cloud or a photograph, `t,x,y,z` rows) is compared
//! with. Its residual is the distance
//!
//! \\[ d(p) = \lVert x - C(s^*; p) \rVert, \qquad s^* = \arg\min_s \lVert x - C(s; p) \rVert, \\]
//!
//! whose derivative needs no derivative of `s*` (at an interior minimum
//! \\((x - C) \cdot C' = 0\\); at an end of the rod `s*` stays there):
//! \\(\partial d / \partial p = -n \cdot \partial C(s^*) / \partial p\\) with
//! \\(n = (x - C)/d\\).
//!
//! The search samples the curve at [`SAMPLES_PER_POINT`] material coordinates per
//! control point, then minimises the squared distance between the samples either side
//! of the nearest one by Brent's method (argmin's `BrentOpt`: parabolic steps safeguarded
//! by golden sections; Gauss–Newton on \\((C - x) \cdot C'\\) was tried and stalls
//! where the distance exceeds the curve's radius of curvature).

use crate::Error;
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::brent::BrentOpt;
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};

/// Samples of the coarse search per control point.
pub const SAMPLES_PER_POINT: usize = 8;
/// Most iterations of Brent's method.
const BRENT_ITERATIONS: u64 = 200;

/// The material coordinate of the point of `rod`'s curve nearest to `x`, and that point.
pub fn closest_point(rod: &Rod, x: &Vector3<Real>) -> Result<(Real, Vector3<Real>), Error> {
    let (a, b) = rod.basis().domain();
    let samples = SAMPLES_PER_POINT * rod.len().max(2);
    let h = (b - a) / samples as Real;
    let mut best = (a, Real::INFINITY);
    for k in 0..=samples {
        let s = (a + k as Real * h).min(b);
        let d = (rod.point(s)? - x).norm_squared();
        if d < best.1 {
            best = (s, d);
        }
    }
    let (lo, hi) = ((best.0 - h).max(a), (best.0 + h).min(b));
    let solver = BrentOpt::new(lo, hi).set_tolerance(Real::EPSILON.sqrt(), 1e-12 * (b - a));
    let found = Executor::new(SquaredDistance { rod, x }, solver)
        .configure(|state| state.max_iters(BRENT_ITERATIONS))
        .run()
        .map_err(|e| Error::field("observations", format!("{x:?}"), e.to_string()))?;
    let s = match found.state().get_best_param() {
        Some(&s) if found.state().get_best_cost() <= best.1 => s,
        _ => best.0,
    };
    Ok((s, rod.point(s)?))
}

/// The squared distance of `x` to the rod's curve point at a material coordinate.
struct SquaredDistance<'a> {
    rod: &'a Rod,
    x: &'a Vector3<Real>,
}

impl CostFunction for SquaredDistance<'_> {
    type Param = Real;
    type Output = Real;

    fn cost(&self, s: &Real) -> Result<Real, argmin::core::Error> {
        Ok((self.rod.point(*s)? - self.x).norm_squared())
    }
}
