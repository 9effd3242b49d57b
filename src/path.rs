//! Keyframed paths for driven points (`[[pins]] path`): positions given at times, and
//! a point that is there at those times and moves between them.
//!
//! With keyframes \\((t_k, p_k)\\), `t` strictly increasing, the path is \\(p_0\\)
//! before \\(t_0\\) and \\(p_{last}\\) after the last time; in between
//!
//! * **linear**: \\(p(t) = p_k + \tfrac{t - t_k}{t_{k+1} - t_k} (p_{k+1} - p_k)\\)
//!   (continuous, the velocity jumps at keyframes);
//! * **smooth**: the cubic Hermite curve through the keyframes with Catmull–Rom
//!   velocities \\(v_k = \tfrac{p_{k+1} - p_{k-1}}{t_{k+1} - t_{k-1}}\\) inside and zero
//!   velocity at the first and last keyframe (continuous velocity; a start and a stop
//!   without a jerk of speed).

use crate::Error;
use nalgebra::Vector3;
use splinerod_core::Real;

/// How a [`Path`] moves between keyframes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Interpolation {
    /// Straight lines at constant speed (the default).
    #[default]
    Linear,
    /// Cubic Hermite with Catmull–Rom velocities, at rest at both ends.
    Smooth,
}

/// Positions at increasing times (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Path {
    times: Vec<Real>,
    points: Vec<Vector3<Real>>,
    interpolation: Interpolation,
}

impl Path {
    /// A path through `keyframes` `[t, x, y, z]`; `field` names them in errors: they
    /// must be finite, at least one, with strictly increasing times.
    pub fn new(
        keyframes: &[[Real; 4]],
        interpolation: Interpolation,
        field: &str,
    ) -> Result<Self, Error> {
        if keyframes.is_empty() {
            return Err(Error::field(field, "[]", "needs at least one [t, x, y, z]"));
        }
        for (k, f) in keyframes.iter().enumerate() {
            if !f.iter().all(|x| x.is_finite()) {
                return Err(Error::field(
                    format!("{field}[{k}]"),
                    format!("{f:?}"),
                    "must be finite",
                ));
            }
            if k > 0 && f[0] <= keyframes[k - 1][0] {
                let reason = format!(
                    "times must increase (the one before is {})",
                    keyframes[k - 1][0]
                );
                return Err(Error::field(
                    format!("{field}[{k}]"),
                    format!("{f:?}"),
                    reason,
                ));
            }
        }
        Ok(Self {
            times: keyframes.iter().map(|f| f[0]).collect(),
            points: keyframes
                .iter()
                .map(|f| Vector3::new(f[1], f[2], f[3]))
                .collect(),
            interpolation,
        })
    }

    /// The first keyframe's time and position.
    pub fn start(&self) -> (Real, Vector3<Real>) {
        (self.times[0], self.points[0])
    }

    /// The last keyframe's time.
    pub fn end_time(&self) -> Real {
        self.times[self.times.len() - 1]
    }

    /// The position at time `t`.
    pub fn at(&self, t: Real) -> Vector3<Real> {
        let (times, points) = (&self.times, &self.points);
        let last = times.len() - 1;
        if t <= times[0] {
            return points[0];
        }
        if t >= times[last] {
            return points[last];
        }
        let k = times.partition_point(|&tk| tk <= t) - 1;
        let h = times[k + 1] - times[k];
        let u = (t - times[k]) / h;
        match self.interpolation {
            Interpolation::Linear => points[k] + (points[k + 1] - points[k]) * u,
            Interpolation::Smooth => {
                let (v0, v1) = (self.velocity(k), self.velocity(k + 1));
                let (u2, u3) = (u * u, u * u * u);
                points[k] * (2.0 * u3 - 3.0 * u2 + 1.0)
                    + v0 * (h * (u3 - 2.0 * u2 + u))
                    + points[k + 1] * (-2.0 * u3 + 3.0 * u2)
                    + v1 * (h * (u3 - u2))
            }
        }
    }

    /// Catmull–Rom velocity at keyframe `k` (zero at the ends).
    fn velocity(&self, k: usize) -> Vector3<Real> {
        if k == 0 || k + 1 >= self.times.len() {
            return Vector3::zeros();
        }
        let dt = self.times[k + 1] - self.times[k - 1];
        (self.points[k + 1] - self.points[k - 1]) / dt
    }
}
