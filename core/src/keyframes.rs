//! [`Keyframes`]: a value given at increasing times, and in between.
//!
//! With keyframes \\((t_k, p_k)\\), `t` strictly increasing, the value is \\(p_0\\)
//! before \\(t_0\\) and \\(p_{last}\\) after the last time; in between
//!
//! * **linear**: \\(p(t) = p_k + \tfrac{t - t_k}{t_{k+1} - t_k} (p_{k+1} - p_k)\\)
//!   (continuous, the rate jumps at keyframes);
//! * **smooth**: the cubic Hermite curve through the keyframes with Catmull–Rom rates
//!   \\(v_k = \tfrac{p_{k+1} - p_{k-1}}{t_{k+1} - t_{k-1}}\\) inside and zero rate at the
//!   first and last keyframe (continuous rate; a start and a stop without a jerk).
//!
//! Driven pins move along `Keyframes<Vector3>`, clamps turn along `Keyframes<Real>`.

use crate::{CoreError, Real};
use std::ops::{Add, Mul, Sub};

/// How [`Keyframes`] interpolate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Interpolation {
    /// Straight lines at constant rate (the default).
    #[default]
    Linear,
    /// Cubic Hermite with Catmull–Rom rates, at rest at both ends.
    Smooth,
}

/// Values at strictly increasing times (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Keyframes<V> {
    times: Vec<Real>,
    values: Vec<V>,
    interpolation: Interpolation,
}

impl<V> Keyframes<V>
where
    V: Copy + Add<Output = V> + Sub<Output = V> + Mul<Real, Output = V>,
{
    /// Keyframes `(t, value)`: at least one, finite times strictly increasing (values are
    /// the caller's to check).
    pub fn new(
        keyframes: impl IntoIterator<Item = (Real, V)>,
        interpolation: Interpolation,
    ) -> Result<Self, CoreError> {
        let (times, values): (Vec<Real>, Vec<V>) = keyframes.into_iter().unzip();
        if times.is_empty() {
            return Err(CoreError::InvalidParameter {
                name: "keyframes",
                value: 0.0,
                reason: "needs at least one keyframe",
            });
        }
        for (k, &t) in times.iter().enumerate() {
            if !t.is_finite() || (k > 0 && t <= times[k - 1]) {
                return Err(CoreError::InvalidParameter {
                    name: "keyframe time",
                    value: t,
                    reason: "times must be finite and strictly increasing",
                });
            }
        }
        Ok(Self {
            times,
            values,
            interpolation,
        })
    }

    /// The first keyframe's time and value.
    pub fn start(&self) -> (Real, V) {
        (self.times[0], self.values[0])
    }

    /// The keyframes' times, increasing.
    pub fn times(&self) -> &[Real] {
        &self.times
    }

    /// The last keyframe's time.
    pub fn end_time(&self) -> Real {
        self.times[self.times.len() - 1]
    }

    /// The value at time `t`.
    pub fn at(&self, t: Real) -> V {
        let (times, values) = (&self.times, &self.values);
        let last = times.len() - 1;
        if t <= times[0] {
            return values[0];
        }
        if t >= times[last] {
            return values[last];
        }
        let k = times.partition_point(|&tk| tk <= t) - 1;
        let h = times[k + 1] - times[k];
        let u = (t - times[k]) / h;
        let (p0, p1) = (values[k], values[k + 1]);
        match self.interpolation {
            Interpolation::Linear => p0 + (p1 - p0) * u,
            Interpolation::Smooth => {
                let (u2, u3) = (u * u, u * u * u);
                let mut p = p0 * (2.0 * u3 - 3.0 * u2 + 1.0) + p1 * (-2.0 * u3 + 3.0 * u2);
                if let Some(v0) = self.rate(k) {
                    p = p + v0 * (h * (u3 - 2.0 * u2 + u));
                }
                if let Some(v1) = self.rate(k + 1) {
                    p = p + v1 * (h * (u3 - u2));
                }
                p
            }
        }
    }

    /// Catmull–Rom rate at keyframe `k` (`None`: zero, at the ends).
    fn rate(&self, k: usize) -> Option<V> {
        if k == 0 || k + 1 >= self.times.len() {
            return None;
        }
        let dt = self.times[k + 1] - self.times[k - 1];
        Some((self.values[k + 1] - self.values[k - 1]) * (1.0 / dt))
    }
}
