//! Scene tables for adaptive resolution and interactions: `[adaptivity]`, `[[grabs]]`
//! and `[[cuts]]` (documented in `scenes/README.md`), with their validation. Material
//! coordinates and lengths are fractions of the rest length, as everywhere in scenes.

use crate::scene::{finite_vec, fraction, non_negative, positive};
use crate::Error;
use serde::Deserialize;
use splinerod_adaptivity::{
    AdaptParams, Adapter, CurvatureCriterion, InteractionCriterion, ToleranceCriterion,
};

/// `[adaptivity]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AdaptivitySpec {
    /// Adapt after every step. Default true when the table is present.
    #[serde(default = "yes")]
    pub enabled: bool,
    /// Error tolerance, m: refine where the estimated error exceeds it, coarsen far below
    /// it (`ToleranceCriterion`). The default criterion, with `1e-4 · rest_length`
    /// unless the curvature thresholds below are given instead.
    pub tolerance: Option<f64>,
    /// Curvature criterion (the paper's; chosen by giving a threshold): insert where
    /// `c_i` and `c_{i+1}` exceed this (in [0, 1]). Default 0.05.
    pub insert_threshold: Option<f64>,
    /// Curvature criterion: remove where all influenced `c` are below this. Default 0.005.
    pub remove_threshold: Option<f64>,
    /// Largest curve displacement the removals of one step may cause, m. Default a
    /// quarter of the tolerance (1e-6 with the curvature criterion).
    pub shape_tolerance: Option<f64>,
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

impl AdaptivitySpec {
    /// Whether the curvature thresholds select the paper's criterion (a threshold given
    /// and no tolerance).
    pub fn uses_curvature(&self) -> bool {
        self.tolerance.is_none()
            && (self.insert_threshold.is_some() || self.remove_threshold.is_some())
    }

    /// The curvature thresholds (insert, remove), defaults filled in.
    pub fn thresholds(&self) -> (f64, f64) {
        (
            self.insert_threshold.unwrap_or(0.05),
            self.remove_threshold.unwrap_or(0.005),
        )
    }

    /// The adapt step this table describes for a rod of `rest_length` (m) starting with
    /// `initial` control points: the interaction criterion and either the tolerance
    /// criterion (default) or the paper's curvature criterion. Fields as in the scene:
    /// `min_span` and `interaction_radius` are fractions of the rest length.
    pub fn adapter(&self, rest_length: f64, initial: usize) -> Result<Adapter, Error> {
        let l = rest_length;
        let tolerance = self.tolerance_for(l);
        let default_shape = if self.uses_curvature() {
            1e-6
        } else {
            0.25 * tolerance
        };
        let params = AdaptParams {
            max_control_points: self.max_control_points,
            min_control_points: self.min_control_points.unwrap_or(initial),
            min_span: self.min_span * l,
            shape_tolerance: self.shape_tolerance.unwrap_or(default_shape),
            hysteresis_steps: self.hysteresis_steps,
            ..AdaptParams::default()
        };
        let interaction = InteractionCriterion::new(self.interaction_radius * l)?
            .with_multiplicity(self.interaction_multiplicity)?;
        let adapter = Adapter::new(params)?.with(interaction);
        Ok(if self.uses_curvature() {
            let (insert, remove) = self.thresholds();
            adapter.with(CurvatureCriterion::new(insert, remove)?)
        } else {
            adapter.with(ToleranceCriterion::new(tolerance)?.with_budget(self.max_control_points))
        })
    }

    /// An `[adaptivity]` table from TOML text that holds it (the header and its keys), as
    /// in a scene file: defaults filled in, errors naming `adaptivity.<field>`. Not
    /// range-checked: see [`AdaptivitySpec::validate`].
    pub fn from_toml(text: &str) -> Result<Self, Error> {
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Table {
            adaptivity: AdaptivitySpec,
        }
        let table: Table = crate::scene::problems::read(text, |_| Vec::new())?;
        Ok(table.adaptivity)
    }

    /// Range checks of the table (errors name `adaptivity.<field>`); `initial` is the
    /// rod's initial number of control points.
    pub fn validate(&self, initial: usize) -> Result<(), Error> {
        validate_adaptivity(self, initial)
    }

    /// The error tolerance, m, for a rod of `rest_length` (default `1e-4 · rest_length`).
    pub fn tolerance_for(&self, rest_length: f64) -> f64 {
        self.tolerance
            .unwrap_or(DEFAULT_RELATIVE_TOLERANCE * rest_length)
    }

    /// The error a run with this adapter aims at, m: the tolerance of a tolerance-driven
    /// adapter, 0 for the curvature thresholds (what `"auto"` stretching may spend,
    /// [`splinerod_energies::AutoInputs::model_error`]).
    pub fn aimed_error(&self, rest_length: f64) -> f64 {
        match self.insert_threshold.is_none() && self.remove_threshold.is_none() {
            true => self.tolerance_for(rest_length),
            false => 0.0,
        }
    }
}

/// Default error tolerance as a fraction of the rest length.
pub const DEFAULT_RELATIVE_TOLERANCE: f64 = 1e-4;

/// `[[grabs]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GrabSpec {
    /// The rod (its `name` in `[[rods]]`) this acts on; needed when the scene has
    /// several rods.
    pub rod: Option<String>,
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
    /// The rod (its `name` in `[[rods]]`) this acts on; needed when the scene has
    /// several rods.
    pub rod: Option<String>,
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
    closed: bool,
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
        // A closed rod may be cut at its seam, 0 ≡ 1.
        let seam = closed && (c.at == 0.0 || c.at == 1.0);
        let inside = c.at > 0.0 && c.at < 1.0;
        if !(inside || seam) {
            let reason = match closed {
                true => "must be in [0, 1] (0 and 1 are the seam of a closed rod)",
                false => "must be strictly inside (0, 1)",
            };
            return Err(Error::field(format!("cuts[{i}].at"), c.at, reason));
        }
        non_negative(&format!("cuts[{i}].time"), c.time)?;
    }
    Ok(())
}

fn validate_adaptivity(a: &AdaptivitySpec, initial: usize) -> Result<(), Error> {
    if let Some(t) = a.tolerance {
        positive("adaptivity.tolerance", t)?;
        let threshold = [
            ("insert", a.insert_threshold),
            ("remove", a.remove_threshold),
        ];
        if let Some((which, Some(v))) = threshold.into_iter().find(|(_, v)| v.is_some()) {
            let reason = format!(
                "selects the curvature criterion, which contradicts tolerance = {t}: give one or the other"
            );
            return Err(Error::field(
                format!("adaptivity.{which}_threshold"),
                v,
                reason,
            ));
        }
    }
    let (insert, remove) = a.thresholds();
    fraction("adaptivity.insert_threshold", insert)?;
    fraction("adaptivity.remove_threshold", remove)?;
    if remove > insert {
        let reason = format!("must not exceed insert_threshold = {insert}");
        return Err(Error::field("adaptivity.remove_threshold", remove, reason));
    }
    if let Some(t) = a.shape_tolerance {
        positive("adaptivity.shape_tolerance", t)?;
    }
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
