//! The `[contact]` scene table (documented in `scenes/README.md`): self-contact of the
//! rod (and between the pieces of its cuts) and an optional floor, through the penalty
//! [`Contact`] energy. Unlike other scene lengths, contact lengths are in metres, like
//! `rod.radius`.

use crate::scene::{non_negative, positive, Scene};
use crate::Error;
use serde::Deserialize;
use splinerod_core::Real;
use splinerod_energies::{Contact, ContactParams};

/// `[contact]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Contact on. Default true when the table is present.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Penalty stiffness `k`, N/m (> 0): a contact pushes with `k` per metre of overlap.
    pub stiffness: f64,
    /// Coulomb friction coefficient (≥ 0). Default 0.
    #[serde(default)]
    pub friction: f64,
    /// Sliding speed below which friction sticks (smoothed), m/s (> 0). Default 1e-3.
    pub slip_speed: Option<f64>,
    /// Height of a static floor plane `y = floor`, m. Default: no floor.
    pub floor: Option<f64>,
    /// Onset layer, m (> 0): the penalty starts when centre lines are `2r + onset` apart.
    /// Default `0.1 · rod.radius`.
    pub onset: Option<f64>,
    /// Points closer than this along the rod never touch, m (≥ 0). Default `π · rod.radius`.
    pub exclusion: Option<f64>,
}

fn yes() -> bool {
    true
}

impl ContactSpec {
    /// Checks the table against the rod's radius (which it needs).
    pub fn validate(&self, radius: Option<f64>) -> Result<(), Error> {
        if !self.enabled {
            return Ok(());
        }
        let Some(r) = radius else {
            let reason = "contact needs the rod's thickness: set rod.radius";
            return Err(Error::field("contact.enabled", true, reason));
        };
        positive("rod.radius", r)?;
        positive("contact.stiffness", self.stiffness)?;
        non_negative("contact.friction", self.friction)?;
        if let Some(s) = self.slip_speed {
            positive("contact.slip_speed", s)?;
        }
        if let Some(h) = self.floor {
            if !h.is_finite() {
                return Err(Error::field("contact.floor", h, "must be finite"));
            }
        }
        if let Some(o) = self.onset {
            positive("contact.onset", o)?;
        }
        if let Some(x) = self.exclusion {
            non_negative("contact.exclusion", x)?;
        }
        Ok(())
    }
}

impl Scene {
    /// The contact energy of `[contact]`, if enabled.
    pub fn contact(&self) -> Result<Option<Contact>, Error> {
        let Some(spec) = self.contact.as_ref().filter(|c| c.enabled) else {
            return Ok(None);
        };
        spec.validate(self.rod.radius)?;
        // The thinnest rod's radius sets the sampling and the onset layer.
        let radius = (0..self.rod_count())
            .filter_map(|k| self.rod_spec(k).radius)
            .fold(Real::INFINITY, Real::min);
        let radius = if radius.is_finite() { radius } else { 0.0 };
        let mut params = ContactParams::new(radius, spec.stiffness)?;
        if let Some(h) = spec.floor {
            params = params.with_floor(h)?;
        }
        params.onset = spec.onset.unwrap_or(params.onset);
        params.exclusion = spec.exclusion.unwrap_or(params.exclusion);
        params.friction = spec.friction;
        params.slip_speed = spec.slip_speed.unwrap_or(params.slip_speed);
        let mut contact = Contact::new(params)?;
        for (i, o) in self.obstacles.iter().enumerate() {
            contact = match o.motion() {
                (Some(keyframes), interpolation) => {
                    let field = format!("obstacles[{i}].path");
                    let path = crate::world::path::Path::new(keyframes, interpolation, &field)?;
                    contact.with_moving_obstacle(o.obstacle(), path.keyframes().clone())?
                }
                (None, _) => contact.with_obstacles([o.obstacle()])?,
            };
        }
        Ok(Some(contact))
    }
}
