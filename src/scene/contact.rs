//! The `[contact]` scene table (documented in `scenes/README.md`): self-contact of the
//! rod (and between the pieces of its cuts) and an optional floor, through the
//! [`Contact`] energy. Unlike other scene lengths, contact lengths are in metres, like
//! `rod.radius`.
//!
//! **The law** (`splinerod_energies::ContactLaw`, `splinerod_energies::contact::stiffness`): without
//! `stiffness` the barrier, acting within the gap `tolerance` (default
//! [`DEFAULT_TOLERANCE_RADII`] of the thinnest radius), so that every contact rests at
//! a gap inside the tolerance; `stiffness` alone is the fixed penalty of earlier
//! versions (onset `0.1 r` by default); both together the penalty of least stiffness
//! `stiffness`, its onset at the tolerance, stiffened between steps to keep the deepest
//! contact within half the tolerance.
//!
//! **The barrier's stiffness** `κ` carries a line load `w` at half the tolerance
//! (`barrier_stiffness_for`), with `w` the largest over the rods of
//!
//! \\[ w = \mu |g| + \frac{T}{r}, \qquad T = \mu |g| L + \sum |F_{load}| + \sum
//! k_{grab} d_{grab} + EA\, \max(\varepsilon_{pins}, \varepsilon_{start}) + \frac{EI +
//! GJ}{L^2} \\]
//!
//! (the weight per length, and a tension scale — the strain scale of `auto_form.rs`
//! times `EA`, plus the bending and twisting stiffnesses over the length squared —
//! bent around the rod's own radius, the tightest a contact can bend it; an
//! overestimate, which the barrier tolerates, see its docs). Without any of these, `w`
//! is the weight at `1 m/s²`.

use crate::scene::{non_negative, positive, Scene};
use crate::Error;
use serde::Deserialize;
use splinerod_core::Real;
use splinerod_energies::contact::stiffness::barrier_stiffness_for;
use splinerod_energies::{Contact, ContactParams};

/// The default gap tolerance, in radii of the thinnest rod (`contact.tolerance`).
pub const DEFAULT_TOLERANCE_RADII: f64 = 0.05;

/// `[contact]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    /// Contact on. Default true when the table is present.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Penalty stiffness `k`, N/m (> 0): a contact pushes with `k` per metre of overlap.
    /// Optional: without it, the barrier (module docs).
    pub stiffness: Option<f64>,
    /// Gap tolerance, m (> 0): how far from touching a contact may rest. Default
    /// [`DEFAULT_TOLERANCE_RADII`] of the thinnest radius without `stiffness`; with
    /// `stiffness`, none (the fixed penalty) unless given.
    pub tolerance: Option<f64>,
    /// Coulomb friction coefficient (≥ 0). Default 0.
    #[serde(default)]
    pub friction: f64,
    /// Sliding speed below which friction sticks (smoothed), m/s (> 0). Default 1e-3.
    pub slip_speed: Option<f64>,
    /// Height of a static floor plane `y = floor`, m. Default: no floor.
    pub floor: Option<f64>,
    /// Onset layer, m (> 0): the penalty starts when centre lines are `2r + onset` apart.
    /// Default `0.1 · rod.radius`, or the tolerance; only with `stiffness`, and at most
    /// the tolerance.
    pub onset: Option<f64>,
    /// Points closer than this along the rod never touch, m (≥ 0). Default `π` times the
    /// thickest rod's radius.
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
        if let Some(k) = self.stiffness {
            positive("contact.stiffness", k)?;
        }
        if let Some(t) = self.tolerance {
            positive("contact.tolerance", t)?;
        }
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
            if self.stiffness.is_none() {
                let reason = "the barrier (no contact.stiffness) acts within contact.tolerance: set that instead";
                return Err(Error::field("contact.onset", o, reason));
            }
            if let Some(t) = self.tolerance.filter(|&t| o > t) {
                let reason = format!("must be at most contact.tolerance = {t} m: the onset layer would hold contacts further apart than the tolerance");
                return Err(Error::field("contact.onset", o, reason));
            }
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
        let tolerance = spec.tolerance.unwrap_or(DEFAULT_TOLERANCE_RADII * radius);
        let mut params = match (spec.stiffness, spec.tolerance) {
            (Some(k), None) => ContactParams::new(radius, k)?,
            (Some(k), Some(t)) => ContactParams::adaptive(radius, k, t)?,
            (None, _) => {
                let kappa = barrier_stiffness_for(self.contact_line_load()?, radius, tolerance);
                ContactParams::barrier(radius, tolerance, kappa)?
            }
        };
        if let Some(h) = spec.floor {
            params = params.with_floor(h)?;
        }
        params.onset = spec.onset.unwrap_or(params.onset);
        // A rod bent to its radius first touches itself π r along: the thickest rod's.
        let thickest = (0..self.rod_count())
            .filter_map(|k| self.rod_spec(k).radius)
            .fold(radius, Real::max);
        params.exclusion = spec.exclusion.unwrap_or(std::f64::consts::PI * thickest);
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
        if self.obstacles.iter().any(|o| o.friction().is_some()) {
            let mu: Vec<Real> = self
                .obstacles
                .iter()
                .map(|o| o.friction().unwrap_or(spec.friction))
                .collect();
            contact = contact.with_obstacle_friction(&mu)?;
        }
        if self.rods.is_empty() {
            if let Some(mu) = self.rod.friction {
                contact = contact.with_segment_friction(&[0.0], &[mu])?;
            }
        }
        Ok(Some(contact))
    }
}

impl Scene {
    /// The gap the contact's layer spans, m: the tolerance (barrier, adaptive penalty)
    /// or the onset (fixed penalty); `None` without contact.
    pub(crate) fn contact_layer(&self) -> Option<f64> {
        let spec = self.contact.as_ref().filter(|c| c.enabled)?;
        let r = self.contact_radius()?;
        let tolerance = spec.tolerance.unwrap_or(DEFAULT_TOLERANCE_RADII * r);
        Some(match spec.stiffness {
            Some(_) => spec.onset.unwrap_or(spec.tolerance.unwrap_or(0.1 * r)),
            None => tolerance,
        })
    }

    /// The line load `w` (N/m) the barrier's default stiffness carries at half the
    /// tolerance (module docs): the largest over the rods.
    fn contact_line_load(&self) -> Result<Real, Error> {
        let g = nalgebra::Vector3::from(self.world.gravity).norm();
        let mut w: Real = 0.0;
        let mut fallback: Real = 0.0;
        for k in 0..self.rod_count() {
            let sub = match self.rods.is_empty() {
                true => self.clone(),
                false => self.rod_scene(k)?.0,
            };
            let r = &sub.rod;
            let Some(radius) = r.radius else { continue };
            let rod = sub.build_rod()?;
            let ea = r.stretch_stiffness;
            let strain = sub.pin_strain(&rod)?.max(sub.start_strain(&rod).0);
            let stretch = if ea.is_finite() { ea * strain } else { 0.0 };
            let bend = r.bending_stiffness.unwrap_or(0.0) + r.twist_stiffness.unwrap_or(0.0);
            let tension =
                sub.load_tension(&rod)? + stretch + bend / (r.rest_length * r.rest_length);
            w = w.max(r.linear_density * g + tension / radius);
            fallback = fallback.max(r.linear_density);
        }
        Ok(if w > 0.0 && w.is_finite() {
            w
        } else {
            fallback.max(Real::MIN_POSITIVE)
        })
    }
}
