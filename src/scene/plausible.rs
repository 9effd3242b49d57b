//! Plausibility checks of a scene: values each in range that together describe no thin
//! rod, or a start no rod can have (each made a fuzzed run that could not finish).

use crate::scene::Scene;
use crate::Error;

/// Smallest stretch (initial length over rest length) a scene may start a rod with.
pub const MIN_START_STRETCH: f64 = 0.1;

impl Scene {
    /// A bending or twisting stiffness `k` (N·m²) of a thin rod: at most EA·L² (its
    /// ratio to EA is a radius of gyration squared, which cannot exceed the length).
    /// Beyond it the stiffnesses differ by more than a double resolves in one Newton
    /// matrix (the fuzzer's EI = 9.2e18 made a run that could not finish).
    pub(crate) fn validate_against_stretch(
        &self,
        field: &str,
        k: Option<f64>,
    ) -> Result<(), Error> {
        let r = &self.rod;
        let bound = r.stretch_stiffness * r.rest_length * r.rest_length;
        match k {
            Some(k) if k.is_finite() && bound.is_finite() && k > bound => {
                let reason = format!(
                    "must be at most stretch_stiffness × rest_length² = {bound:e} N·m² for a thin rod"
                );
                Err(Error::field(field, k, reason))
            }
            _ => Ok(()),
        }
    }

    /// The initial curve (the straight `start`–`end` line, or the control polygon, which
    /// is at least as long as the curve) may not be squeezed to less than
    /// [`MIN_START_STRETCH`] of the rest length: a rod cannot be, and with contact such a
    /// start puts thousands of samples within reach of each other.
    pub(crate) fn validate_start_length(&self) -> Result<(), Error> {
        let r = &self.rod;
        let to_vector = |p: [f64; 3]| nalgebra::Vector3::from(p);
        let (field, value, length) = match (&r.initial_control_points, r.start, r.end) {
            (Some(points), ..) => {
                let pairs = points.windows(2);
                let length: f64 = pairs
                    .map(|w| (to_vector(w[1]) - to_vector(w[0])).norm())
                    .sum();
                let value = format!("{} points", points.len());
                ("rod.initial_control_points", value, length)
            }
            (None, Some(a), Some(b)) => {
                let value = format!("{b:?}");
                ("rod.end", value, (to_vector(b) - to_vector(a)).norm())
            }
            _ => return Ok(()),
        };
        let stretch = length / r.rest_length;
        // A relative 1e-12 of slack: `end = 0.1 · L` written as 1 − 0.9 is still allowed.
        if stretch < MIN_START_STRETCH * (1.0 - 1e-12) {
            let reason = format!(
                "the initial curve is at most {length:.4e} m long for a rest length of {} m (stretch {stretch:.3e}, at least {MIN_START_STRETCH} allowed)",
                r.rest_length
            );
            return Err(Error::field(field, value, reason));
        }
        Ok(())
    }
}
