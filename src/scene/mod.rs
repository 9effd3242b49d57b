//! TOML scenes: the format (every field documented in `scenes/README.md`) and its
//! validation. Material coordinates in scenes are fractions of the rest length in
//! `[0, 1]`; the library works in rest arclength (m).
//!
//! Unknown fields and tables are rejected, missing ones and values of the wrong type
//! named, all of them at once (each a [`Problem`]), and every value is range-checked by
//! [`Scene::validate`], which names the field in its error.

pub(crate) mod adapt;
mod auto_form;
pub(crate) mod bodies;
mod build;
pub(crate) mod closed;
mod coarse_start;
pub(crate) mod contact;
pub(crate) mod ensemble;
mod found;
pub mod limits;
mod load;
pub(crate) mod loads;
pub(crate) mod obstacles;
mod output_probe;
mod pin_offsets;
pub(crate) mod pins;
pub(crate) mod plausible;
mod probe;
pub(crate) mod problems;
pub(crate) mod rods;
pub(crate) mod shape;
pub(crate) mod solver;

pub(crate) use crate::error::{finite_vec, fraction, non_negative, positive};
pub use crate::scene::adapt::{AdaptivitySpec, CutSpec, GrabSpec};
pub use crate::scene::bodies::{BodySpec, InertiaSpec};
pub use crate::scene::closed::RingSpec;
pub use crate::scene::contact::{ContactSpec, DEFAULT_TOLERANCE_RADII};
pub use crate::scene::ensemble::EnsembleSpec;
pub use crate::scene::limits::{Limits, Resources};
pub(crate) use crate::scene::load::parse_error;
pub use crate::scene::loads::LoadSpec;
pub use crate::scene::obstacles::ObstacleSpec;
pub use crate::scene::output_probe::ProbeSpec;
pub use crate::scene::pins::{PinSpec, WorldSpec};
pub use crate::scene::plausible::MIN_START_STRETCH;
pub use crate::scene::problems::Problem;
pub use crate::scene::shape::{OverhandShape, RestShape, StretchFormulationSpec};
use crate::Error;
use serde::Deserialize;

/// A whole scene file.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// The rod; with `[[rods]]`, the first of them (see [`Scene::rods`]).
    #[serde(default = "RodSpec::absent")]
    pub rod: RodSpec,
    /// Several rods in one system (`[[rods]]`, instead of `[rod]`); empty for a scene
    /// with one `[rod]`.
    #[serde(default)]
    pub rods: Vec<RodSpec>,
    /// Pinned material points.
    #[serde(default)]
    pub pins: Vec<PinSpec>,
    /// Gravity.
    #[serde(default)]
    pub world: WorldSpec,
    /// How to solve.
    pub solver: SolverSpec,
    /// What to report.
    #[serde(default)]
    pub output: OutputSpec,
    /// Adaptive resolution; absent: the basis never changes.
    pub adaptivity: Option<AdaptivitySpec>,
    /// Grabs: material points pulled along a path.
    #[serde(default)]
    pub grabs: Vec<GrabSpec>,
    /// Cuts at given times.
    #[serde(default)]
    pub cuts: Vec<CutSpec>,
    /// Many copies of the rod with varied parameters, run together.
    pub ensemble: Option<EnsembleSpec>,
    /// Self-contact, contact between cut pieces, and a floor.
    pub contact: Option<ContactSpec>,
    /// Rigid obstacles (with `[contact]`'s penalty and friction).
    #[serde(default)]
    pub obstacles: Vec<ObstacleSpec>,
    /// Point loads.
    #[serde(default)]
    pub loads: Vec<LoadSpec>,
    /// Rigid bodies the pins may hold (`[[pins]] body`).
    #[serde(default)]
    pub bodies: Vec<BodySpec>,
    /// Set on the one-rod scenes a `[[rods]]` scene builds its rods from
    /// ([`Scene::build_system`]): default quadrature, no contact of their own.
    #[serde(skip)]
    pub(crate) part_of_world: bool,
    /// For a rod of a `[[rods]]` scene: whether all rods take the mixed stretching's
    /// smaller quadrature.
    #[serde(skip)]
    pub(crate) reduced_quadrature: bool,
}

/// `[rod]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RodSpec {
    /// Name of the rod, for `rod = "…"` in pins, grabs, loads and cuts (`[[rods]]`).
    pub name: Option<String>,
    /// Set when the scene has no `[rod]` table (it has `[[rods]]`).
    #[serde(skip)]
    pub absent: bool,
    /// Rest length `L`, m (> 0): as given, or set by `overhand` ([`Scene::resolve_shape`]).
    #[serde(skip)]
    pub rest_length: f64,
    /// `rest_length` as written in the file (required unless `overhand` is given).
    #[serde(rename = "rest_length")]
    pub given_rest_length: Option<f64>,
    /// Mass per unit rest length, kg/m (> 0).
    pub linear_density: f64,
    /// Axial stiffness `EA = Y·r`, N (> 0), or `"inextensible"` (read as `+∞`).
    #[serde(deserialize_with = "shape::stiffness_or_inextensible")]
    pub stretch_stiffness: f64,
    /// Bending stiffness `EI`, N·m² (> 0; needs degree ≥ 2). Default: no bending energy.
    pub bending_stiffness: Option<f64>,
    /// Torsional stiffness `GJ`, N·m² (> 0; needs clamps at both ends and
    /// `bending_stiffness`). Default: no twisting energy.
    pub twist_stiffness: Option<f64>,
    /// Total twist a closed rod starts with, rad (needs `twist_stiffness`; an open rod is
    /// twisted by turning its clamps). Default 0.
    pub twist: Option<f64>,
    /// Mass-proportional damping, 1/s (≥ 0). Default 0.
    #[serde(default)]
    pub damping: f64,
    /// Number of control points (≥ degree + 1).
    pub control_points: usize,
    /// Polynomial degree, 1 to 9. Default 3.
    #[serde(default = "shape::default_degree")]
    pub degree: usize,
    /// `"clamped"` (default), `"uniform"`, or an explicit non-decreasing knot vector of
    /// `control_points + degree + 1` values (any units; the domain is mapped to `[0, L]`).
    /// A closed rod's are periodic ([`RingSpec`]). Read it through [`RodSpec::knot_layout`].
    pub knots: Option<KnotsSpec>,
    /// A closed rod: the curve wraps from the end back to the start ([`RingSpec`]).
    #[serde(default)]
    pub closed: bool,
    /// `[rod.ring]`: a closed rod's initial circle (makes the rod closed).
    pub ring: Option<RingSpec>,
    /// Start of the initial straight shape, m. Default the origin.
    pub start: Option<[f64; 3]>,
    /// End of the initial straight shape, m. Default `start + (L, 0, 0)`.
    pub end: Option<[f64; 3]>,
    /// Explicit initial control points (instead of `start`/`end`), m.
    pub initial_control_points: Option<Vec<[f64; 3]>>,
    /// Radius of the rod's cross-section, m (> 0). Needed by `[contact]`.
    pub radius: Option<f64>,
    /// Friction coefficient of its surface in contacts (≥ 0); a contact takes the smaller
    /// of its two surfaces' coefficients. Default `[contact] friction`.
    pub friction: Option<f64>,
    /// Initial shape: a loose overhand knot (sets `rest_length` and the control points).
    pub overhand: Option<OverhandShape>,
    /// Stress-free state of stretching: `"arclength"` (default: `s` is rest arclength)
    /// or `"initial"` (the initial curve, the paper's I₀).
    #[serde(default)]
    pub rest_shape: RestShape,
    /// How the strain enters the stretching energy: `"mixed"` (default, free of membrane
    /// locking), `"mixed-consistent"` (mixed with the consistent Gram matrix: also
    /// accurate where the strain varies) or `"pointwise"` (the paper's eq. 12).
    #[serde(default)]
    pub stretch_formulation: StretchFormulationSpec,
}

impl RodSpec {
    /// `knots` as given, `"clamped"` when not.
    pub fn knot_layout(&self) -> KnotsSpec {
        self.knots.clone().unwrap_or_default()
    }
}

/// `rod.knots`: a named layout or an explicit vector.
#[derive(Debug, Clone, PartialEq)]
pub enum KnotsSpec {
    /// `"clamped"` or `"uniform"`.
    Named(String),
    /// Explicit knot values.
    Explicit(Vec<f64>),
}

impl<'de> Deserialize<'de> for KnotsSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Knots;
        impl<'de> serde::de::Visitor<'de> for Knots {
            type Value = KnotsSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("\"clamped\", \"uniform\" or a list of knots")
            }
            fn visit_str<E: serde::de::Error>(self, name: &str) -> Result<KnotsSpec, E> {
                Ok(KnotsSpec::Named(name.to_string()))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                seq: A,
            ) -> Result<KnotsSpec, A::Error> {
                let knots =
                    Deserialize::deserialize(serde::de::value::SeqAccessDeserializer::new(seq))?;
                Ok(KnotsSpec::Explicit(knots))
            }
        }
        d.deserialize_any(Knots)
    }
}

impl Default for KnotsSpec {
    fn default() -> Self {
        Self::Named("clamped".into())
    }
}

/// `solver.method`.
#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Implicit Euler time stepping.
    ImplicitEuler,
    /// Implicit midpoint: second order, conserves the energy of linear systems.
    ImplicitMidpoint,
    /// Second-order backward differentiation (dissipative).
    Bdf2,
    /// Static equilibrium (no time).
    Static,
}

/// `[solver]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// `"implicit-euler"`, `"implicit-midpoint"`, `"bdf2"` or `"static"`.
    pub method: Method,
    /// Time step, s (> 0; required for time stepping).
    pub dt: Option<f64>,
    /// Simulated duration, s (> 0; required for time stepping).
    pub duration: Option<f64>,
    /// Most Newton iterations per step (≥ 1). Default 10 (200 for `static`).
    pub newton_iterations: Option<usize>,
    /// Newton tolerance on the step, relative to the rest length (> 0). Default 1e-10
    /// (1e-12 for `static`).
    pub tolerance: Option<f64>,
    /// Line search on the incremental potential. Default true.
    #[serde(default = "default_true")]
    pub line_search: bool,
    /// `"banded"` (default) or `"sparse"` (faer): the factorisation of Newton matrices.
    #[serde(default)]
    pub linear_solver: LinearSolverSpec,
    /// Largest move of a material point per Newton iteration, m (> 0). Default: no limit.
    pub max_step: Option<f64>,
    /// Smallest sub-step, s (> 0, at most `dt`): a step whose Newton solve fails is
    /// retried in halves down to this length. Default `dt · 1e-6`.
    pub min_dt: Option<f64>,
    /// Local time-discretisation error allowed per sub-step, m (> 0): sub-steps are
    /// shortened until the implicit-Euler error estimate is below it. Default: off.
    pub time_tolerance: Option<f64>,
    /// Accept a step that reached `newton_iterations` without converging (counted in
    /// `solver.unconverged_steps`) instead of splitting it. Default false.
    #[serde(default)]
    pub accept_unconverged: bool,
}

/// `solver.linear_solver`.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum LinearSolverSpec {
    /// Dense 3×3-block band Cholesky.
    #[default]
    Banded,
    /// faer's sparse Cholesky.
    Sparse,
}

fn default_true() -> bool {
    true
}

/// `[output]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Material points reported at the end, evenly spaced in `[0, 1]` (≥ 2). Default 41.
    #[serde(default = "default_samples")]
    pub samples: usize,
    /// Material points whose positions are recorded every step: fractions in `[0, 1]`
    /// of the first rod, or `{ rod = "name", at = fraction }` on any rod.
    #[serde(default)]
    pub probes: Vec<ProbeSpec>,
    /// Estimate the discretisation error after every step (on without asking when the
    /// adaptivity is tolerance-driven): JSON `adaptivity.estimated_error` and `history`.
    #[serde(default)]
    pub error_estimate: bool,
}

fn default_samples() -> usize {
    41
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            samples: default_samples(),
            probes: Vec::new(),
            error_estimate: false,
        }
    }
}

impl Scene {
    /// Range checks of every value; the error names the field.
    pub fn validate(&self) -> Result<(), Error> {
        let r = &self.rod;
        plausible::length("rod.rest_length", r.rest_length)?;
        positive("rod.linear_density", r.linear_density)?;
        if r.stretch_stiffness != f64::INFINITY {
            positive("rod.stretch_stiffness", r.stretch_stiffness)?;
        } else if r.stretch_formulation == StretchFormulationSpec::Pointwise {
            let reason = "an inextensible rod needs the mixed formulation (its constraints live on the tension space)";
            return Err(Error::field(
                "rod.stretch_formulation",
                "\"pointwise\"",
                reason,
            ));
        }
        for (field, k) in [
            ("rod.bending_stiffness", r.bending_stiffness),
            ("rod.twist_stiffness", r.twist_stiffness),
        ] {
            self.validate_against_stretch(field, k)?;
        }
        if let Some(ei) = r.bending_stiffness {
            positive("rod.bending_stiffness", ei)?;
            if r.degree < 2 {
                let reason = "bending needs degree ≥ 2 (a degree-1 curve has no curvature)";
                return Err(Error::field("rod.bending_stiffness", ei, reason));
            }
        }
        non_negative("rod.damping", r.damping)?;
        if !(1..=splinerod_core::MAX_DEGREE).contains(&r.degree) {
            return Err(Error::field(
                "rod.degree",
                r.degree,
                format!("must be 1 to {}", splinerod_core::MAX_DEGREE),
            ));
        }
        if r.control_points < r.degree + 1 {
            let reason = format!(
                "a degree-{} rod needs at least {} control points",
                r.degree,
                r.degree + 1
            );
            return Err(Error::field("rod.control_points", r.control_points, reason));
        }
        self.validate_shape()?;
        self.validate_pins()?;
        self.validate_plausible()?;
        finite_vec("world.gravity", self.world.gravity)?;
        self.validate_solver()?;
        if self.output.samples < 2 {
            return Err(Error::field(
                "output.samples",
                self.output.samples,
                "must be at least 2",
            ));
        }
        for i in 0..self.output.probes.len() {
            self.validate_probe(i)?;
        }
        if let Some(e) = &self.ensemble {
            e.validate()?;
        }
        if let Some(radius) = self.rod.radius {
            positive("rod.radius", radius)?;
            if radius > 0.5 * self.rod.rest_length {
                let reason = format!(
                    "must be at most half the rest length ({} m): a rod is thin",
                    self.rod.rest_length
                );
                return Err(Error::field("rod.radius", radius, reason));
            }
            // Contact samples the rod every 0.2 r: keep their number sane.
            let samples = self.rod.rest_length / (0.2 * radius);
            if samples > 1e7 {
                let reason = format!(
                    "too thin for a rod of length {} m: contact would need {samples:.1e} samples (at most 1e7)",
                    self.rod.rest_length
                );
                return Err(Error::field("rod.radius", radius, reason));
            }
        }
        if let Some(c) = &self.contact {
            c.validate(self.rod.radius)?;
        }
        if let Some(mu) = self.rod.friction {
            non_negative("rod.friction", mu)?;
        }
        self.validate_obstacles()?;
        self.validate_bodies()?;
        self.loads()?;
        crate::scene::adapt::validate(
            self.adaptivity.as_ref(),
            &self.grabs,
            &self.cuts,
            self.rod.control_points,
            self.closed(),
        )
    }

    fn validate_shape(&self) -> Result<(), Error> {
        let r = &self.rod;
        if self.closed() {
            return self.validate_closed();
        }
        match &r.knot_layout() {
            KnotsSpec::Named(name) if name == "clamped" || name == "uniform" => {}
            KnotsSpec::Named(name) => {
                return Err(Error::field(
                    "rod.knots",
                    format!("\"{name}\""),
                    "must be \"clamped\", \"uniform\" or a list of knots",
                ))
            }
            KnotsSpec::Explicit(k) => {
                let expected = r.control_points + r.degree + 1;
                if k.len() != expected {
                    let reason = format!("needs control_points + degree + 1 = {expected} values");
                    return Err(Error::field(
                        "rod.knots",
                        format!("{} values", k.len()),
                        reason,
                    ));
                }
            }
        }
        if let Some(points) = &r.initial_control_points {
            if r.start.is_some() || r.end.is_some() {
                return Err(Error::field(
                    "rod.initial_control_points",
                    "given",
                    "give either start/end or initial_control_points, not both",
                ));
            }
            if points.len() != r.control_points {
                let reason = format!("must list rod.control_points = {} points", r.control_points);
                return Err(Error::field(
                    "rod.initial_control_points",
                    format!("{} points", points.len()),
                    reason,
                ));
            }
            for (i, p) in points.iter().enumerate() {
                finite_vec(&format!("rod.initial_control_points[{i}]"), *p)?;
            }
        }
        if let Some(s) = r.start {
            finite_vec("rod.start", s)?;
        }
        if let Some(e) = r.end {
            finite_vec("rod.end", e)?;
        }
        self.validate_start_length()
    }
}
