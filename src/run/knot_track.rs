//! Tightness of a knot over a run (scenes with `[rod.overhand]`): the knot length and
//! radius of [`crate::knot::knot_diagram`], seen from above (`+y`, the direction the
//! initial knot is laid out for), sampled every [`KnotTrack::EVERY`] seconds and at the
//! end, for the JSON result.

use crate::{Error, RodSystem};
use nalgebra::Vector3;
use serde::Serialize;
use splinerod_core::Real;

/// Samples along the rod for the projection.
const SAMPLES: usize = 400;

/// Tightness of the knot over time. A missing knot (no crossings seen) is recorded as
/// `null` entries.
#[derive(Debug, Clone, Default, Serialize, serde::Deserialize, PartialEq)]
pub struct KnotTrack {
    /// Times, s.
    pub t: Vec<Real>,
    /// Rest arclength between the first and last crossing, m (smaller is tighter).
    pub knot_length: Vec<Option<Real>>,
    /// Radius of the ball around the knot section, m.
    pub radius: Vec<Option<Real>>,
    /// Crossings of the projection seen from above (3 for the overhand knot's diagram).
    pub crossings: Vec<usize>,
    /// Knot determinant of that diagram ([`crate::knot::knot_determinant`]): 3 while the
    /// overhand knot is intact.
    pub determinant: Vec<i64>,
}

impl KnotTrack {
    /// Sampling interval, s.
    pub const EVERY: Real = 0.05;

    /// Records the knot of `system` at time `t` if `EVERY` has passed since the last
    /// record (or `force`).
    pub(crate) fn record(&mut self, system: &RodSystem, t: Real, force: bool) -> Result<(), Error> {
        let due = self
            .t
            .last()
            .is_none_or(|&last| t >= last + Self::EVERY * (1.0 - 1e-9));
        if !(due || force) || self.t.last() == Some(&t) {
            return Ok(());
        }
        let diagram = crate::knot::knot_diagram(&system.rod, Vector3::y(), SAMPLES)?;
        let tight = diagram.tightness;
        self.determinant
            .push(crate::knot::knot_determinant(&diagram.crossings));
        self.t.push(t);
        self.knot_length.push(tight.map(|k| k.knot_length));
        self.radius.push(tight.map(|k| k.radius));
        self.crossings.push(tight.map_or(0, |k| k.crossings));
        Ok(())
    }
}
