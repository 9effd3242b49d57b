//! Grabs: a material point pulled by a stiff spring ([`PointSpring`]) whose target moves
//! linearly from where the point is at `start_time` to `to` at `end_time`, then stays.
//! Before `start_time` the grab does nothing. A grab is an interaction: the adapt step
//! keeps a knot at its material coordinate while it is active.

use nalgebra::Vector3;
use splinerod_core::{Real, Rod};
use splinerod_energies::PointSpring;

use crate::Error;

/// A scheduled grab.
#[derive(Debug, Clone, PartialEq)]
pub struct Grab {
    /// The spring (material coordinate `at` in m, target, stiffness).
    pub spring: PointSpring,
    /// Final target, m.
    pub to: Vector3<Real>,
    /// When the pull starts, s.
    pub start_time: Real,
    /// When the target reaches `to`, s (≥ `start_time`).
    pub end_time: Real,
    /// Where the point was at `start_time` (set when the grab starts).
    pub from: Option<Vector3<Real>>,
}

impl Grab {
    /// A grab at material coordinate `at` (m) pulling to `to` between the two times.
    pub fn new(
        at: Real,
        to: Vector3<Real>,
        (start_time, end_time): (Real, Real),
        stiffness: Real,
    ) -> Result<Self, Error> {
        if !(start_time.is_finite() && end_time.is_finite() && end_time >= start_time) {
            let reason = "times must be finite with end_time ≥ start_time";
            return Err(Error::field("grab.end_time", end_time, reason));
        }
        Ok(Self {
            spring: PointSpring::new(at, to, stiffness)?,
            to,
            start_time,
            end_time,
            from: None,
        })
    }

    /// Whether the grab acts at time `t`.
    pub fn active(&self, t: Real) -> bool {
        t >= self.start_time
    }

    /// Sets the spring's target for time `t`, recording the start point from `rod` the
    /// first time the grab is active.
    pub fn update(&mut self, t: Real, rod: &Rod) -> Result<(), Error> {
        if !self.active(t) {
            return Ok(());
        }
        let from = match self.from {
            Some(p) => p,
            None => *self.from.insert(rod.point(self.spring.at)?),
        };
        let span = self.end_time - self.start_time;
        let f = if span > 0.0 {
            ((t - self.start_time) / span).clamp(0.0, 1.0)
        } else {
            1.0
        };
        self.spring.target = from + (self.to - from) * f;
        Ok(())
    }
}
