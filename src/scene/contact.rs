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

/// With `[contact]` and no `solver.max_step`, the largest move of a material point in
/// one Newton iteration, in radii of the thinnest rod: below half the radius, two
/// strands cannot pass through each other within one iteration whatever the time step
/// (the line search refuses states closer than `r`), so a knot cannot untie by a long
/// step (measured: `knot_pulled.toml` with the consistent stretching lost its knot at
/// t = 1.75 s without it, and kept it with it at 6.5 % more Newton iterations).
pub const CONTACT_STEP_RADII: f64 = 0.4;

impl Scene {
    /// The thinnest radius among the rods with `[contact]` enabled (`None` without
    /// contact or radius).
    pub(crate) fn contact_radius(&self) -> Option<f64> {
        self.contact.as_ref().filter(|c| c.enabled)?;
        let radius = (0..self.rod_count())
            .filter_map(|k| self.rod_spec(k).radius)
            .fold(Real::INFINITY, Real::min);
        radius.is_finite().then_some(radius)
    }

    /// `solver.max_step`, or with contact [`CONTACT_STEP_RADII`] radii.
    pub(crate) fn max_step(&self) -> Option<f64> {
        self.solver
            .max_step
            .or_else(|| Some(CONTACT_STEP_RADII * self.contact_radius()?))
    }

    /// The contact energy of `[contact]`, if enabled.
    pub fn contact(&self) -> Result<Option<Contact>, Error> {
        let Some(spec) = self.contact.as_ref().filter(|c| c.enabled) else {
            return Ok(None);
        };
        spec.validate(self.rod.radius)?;
        // The thinnest rod's radius sets the sampling and the onset layer.
        let radius = self.contact_radius().unwrap_or(0.0);
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
