//! Scene tables for adaptive resolution and interactions: `[adaptivity]`, `[[grabs]]`
//! and `[[cuts]]` (documented in `scenes/README.md`), with their validation. Material
//! coordinates and lengths are fractions of the rest length, as everywhere in scenes.

use crate::scene::{finite_vec, fraction, non_negative, positive};
use crate::Error;
use serde::Deserialize;

/// `[adaptivity]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdaptivitySpec {
    /// Adapt after every step. Default true when the table is present.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Curvature criterion: insert where `c_i` and `c_{i+1}` exceed this (in [0, 1]).
    /// Default 0.05.
    #[serde(default = "default_insert")]
    pub insert_threshold: f64,
    /// Curvature criterion: remove where all influenced `c` are below this. Default 0.005.
    #[serde(default = "default_remove")]
    pub remove_threshold: f64,
    /// Largest curve displacement the removals of one step may cause, m. Default 1e-6.
    #[serde(default = "default_tolerance")]
    pub shape_tolerance: f64,
    /// Upper limit on control points. Default 200.
    #[serde(default = "default_max")]
    pub max_control_points: usize,
    /// Lower limit on control points. Default: `rod.control_points`.
    pub min_control_points: Option<usize>,
    /// Smallest knot span, fraction of the rest length. Default 1e-3.
    #[serde(default = "default_min_span")]
    pub min_span: f64,
    /// Steps during which an inserted knot may not be removed. Default 10.
    #[serde(default = "default_hysteresis")]
    pub hysteresis_steps: usize,
    /// A knot this close (fraction of rest length) to a grab counts as at the grab.
    /// Default 0.01.
    #[serde(default = "default_radius")]
    pub interaction_radius: f64,
    /// Knot multiplicity wanted at a grab (1 as in the paper; up to the degree: a
    /// corner, as a point load makes on a string). Default 1.
    #[serde(default = "default_multiplicity")]
    pub interaction_multiplicity: usize,
}

fn default_multiplicity() -> usize {
    1
}

fn yes() -> bool {
    true
}
fn default_insert() -> f64 {
    0.05
}
fn default_remove() -> f64 {
    0.005
}
fn default_tolerance() -> f64 {
    1e-6
}
fn default_max() -> usize {
    200
}
fn default_min_span() -> f64 {
    1e-3
}
fn default_hysteresis() -> usize {
    10
}
fn default_radius() -> f64 {
    0.01
}

/// `[[grabs]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrabSpec {
    /// Material coordinate, fraction of the rest length in `[0, 1]`.
    pub at: f64,
    /// Target position reached at `end_time`, m.
    pub to: [f64; 3],
    /// Start of the pull, s (≥ 0). Default 0.
    #[serde(default)]
    pub start_time: f64,
    /// End of the pull, s (≥ `start_time`); the target is held afterwards.
    pub end_time: f64,
    /// Spring stiffness, N/m (> 0).
    pub stiffness: f64,
}

/// `[[cuts]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CutSpec {
    /// Material coordinate, fraction of the rest length strictly inside `(0, 1)`.
    pub at: f64,
    /// When to cut, s (≥ 0); the cut happens after the first step ending at or past it.
    pub time: f64,
}

/// Range checks of the adaptivity, grab and cut tables; `initial` is the initial number
/// of control points.
pub(crate) fn validate(
    adaptivity: Option<&AdaptivitySpec>,
    grabs: &[GrabSpec],
    cuts: &[CutSpec],
    initial: usize,
) -> Result<(), Error> {
    if let Some(a) = adaptivity {
        validate_adaptivity(a, initial)?;
    }
    for (i, g) in grabs.iter().enumerate() {
        fraction(&format!("grabs[{i}].at"), g.at)?;
        finite_vec(&format!("grabs[{i}].to"), g.to)?;
        non_negative(&format!("grabs[{i}].start_time"), g.start_time)?;
        non_negative(&format!("grabs[{i}].end_time"), g.end_time)?;
        if g.end_time < g.start_time {
            let reason = format!("must not be before start_time = {}", g.start_time);
            return Err(Error::field(
                format!("grabs[{i}].end_time"),
                g.end_time,
                reason,
            ));
        }
        positive(&format!("grabs[{i}].stiffness"), g.stiffness)?;
    }
    for (i, c) in cuts.iter().enumerate() {
        if !(c.at > 0.0 && c.at < 1.0) {
            let reason = "must be strictly inside (0, 1)";
            return Err(Error::field(format!("cuts[{i}].at"), c.at, reason));
        }
        non_negative(&format!("cuts[{i}].time"), c.time)?;
    }
    Ok(())
}

fn validate_adaptivity(a: &AdaptivitySpec, initial: usize) -> Result<(), Error> {
    fraction("adaptivity.insert_threshold", a.insert_threshold)?;
    fraction("adaptivity.remove_threshold", a.remove_threshold)?;
    if a.remove_threshold > a.insert_threshold {
        let reason = format!("must not exceed insert_threshold = {}", a.insert_threshold);
        return Err(Error::field(
            "adaptivity.remove_threshold",
            a.remove_threshold,
            reason,
        ));
    }
    positive("adaptivity.shape_tolerance", a.shape_tolerance)?;
    positive("adaptivity.min_span", a.min_span)?;
    fraction("adaptivity.min_span", a.min_span)?;
    positive("adaptivity.interaction_radius", a.interaction_radius)?;
    if a.interaction_multiplicity == 0 {
        let reason = "must be at least 1 (it is capped at the degree)";
        return Err(Error::field(
            "adaptivity.interaction_multiplicity",
            0,
            reason,
        ));
    }
    let min = a.min_control_points.unwrap_or(initial);
    if a.max_control_points < initial {
        let reason = format!("must be at least rod.control_points = {initial}");
        return Err(Error::field(
            "adaptivity.max_control_points",
            a.max_control_points,
            reason,
        ));
    }
    if min > a.max_control_points || min < 2 {
        let reason = "must be at least 2 and at most max_control_points";
        return Err(Error::field("adaptivity.min_control_points", min, reason));
    }
    Ok(())
}
