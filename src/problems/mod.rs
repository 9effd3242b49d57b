//! Problems with known answers, shared by the tests, the benchmarks and the
//! speed-vs-error report (`splinerod report`): the elastic catenary and the taut string
//! of `tests/data/` (embedded here, so the binary needs no data files).
//!
//! * Catenary: L = 1 m, ends pinned 0.8 m apart, μ = 0.1 kg/m, EA = 100 N, g = 9.81 m/s²;
//!   the reference gives the equilibrium of 41 material points.
//! * Taut string: the same rod stretched to 1.2 m between pins, no gravity; the first
//!   transverse mode is f = 1/(2L)·√(T0/(γ0 μ)) and the first longitudinal
//!   f = 1/(2L)·√(T'(γ0)/μ).
//! * Crossing ([`crossing`]): two pinned ropes with bending, the upper resting on the
//!   lower; the share of the upper rope's weight the lower one carries.
//! * Capstan ([`capstan`]): a rope wound a full turn around a capsule slips when its
//!   load ratio passes e^{2πμ}.

pub mod capstan;
pub mod crossing;
pub mod elastic_catenary;
pub mod hard_cases;
pub mod locking;

use crate::integrators::modal::{self, Mode};
use crate::{Error, RodSystem, RunResult, Scene, Simulation};
use nalgebra::Vector3;
use serde::Deserialize;
use splinerod_core::{BSplineSpace, Material, Pin, Real, Rod};
use splinerod_energies::{Gravity, StretchFormulation, Stretching};
use splinerod_integrators::Integrator;

const CATENARY_JSON: &str = include_str!("../../tests/data/catenary_L1_D0.8_mu0.1_EA100.json");
const STRING_JSON: &str = include_str!("../../tests/data/string_L1_D1.2_mu0.1_EA100.json");

/// The reference catenary: material fractions `s` and equilibrium positions `xy`.
#[derive(Debug, Clone, Deserialize)]
pub struct CatenaryReference {
    /// Material coordinates, fractions of the rest length.
    pub s: Vec<Real>,
    /// Equilibrium positions, m.
    pub xy: Vec<[Real; 2]>,
    /// Horizontal tension, N.
    #[serde(rename = "H")]
    pub h: Real,
    /// Midpoint sag, m.
    pub sag: Real,
}

/// The reference string frequencies, Hz.
#[derive(Debug, Clone, Deserialize)]
pub struct StringReference {
    /// First transverse frequencies.
    pub transverse_hz: Vec<Real>,
    /// First longitudinal frequencies.
    pub longitudinal_hz: Vec<Real>,
}

fn parse<T: for<'de> Deserialize<'de>>(text: &str, what: &str) -> Result<T, Error> {
    serde_json::from_str(text).map_err(|e| Error::study(what, format!("embedded data: {e}")))
}

/// The embedded catenary reference.
pub fn catenary_reference() -> Result<CatenaryReference, Error> {
    parse(CATENARY_JSON, "catenary reference")
}

/// The embedded string reference.
pub fn string_reference() -> Result<StringReference, Error> {
    parse(STRING_JSON, "string reference")
}

/// The catenary as a scene with `n` clamped cubic control points, mass-proportional
/// `damping`, 41 samples (the reference's material points) and the given `[solver]`
/// table body.
pub fn catenary_scene(n: usize, damping: Real, solver: &str) -> Result<Scene, Error> {
    catenary_scene_with(n, damping, solver, "mixed")
}

/// [`catenary_scene`] with `rod.stretch_formulation = formulation`.
pub fn catenary_scene_with(
    n: usize,
    damping: Real,
    solver: &str,
    formulation: &str,
) -> Result<Scene, Error> {
    Scene::from_toml(&format!(
        "[rod]\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 100.0\n\
         stretch_formulation = \"{formulation}\"\n\
         damping = {damping}\ncontrol_points = {n}\nstart = [0.0, 0.0, 0.0]\n\
         end = [0.8, 0.0, 0.0]\n[[pins]]\nat = 0.0\n[[pins]]\nat = 1.0\n\
         [solver]\n{solver}\n[output]\nsamples = 41\n"
    ))
}

/// Largest distance between a run's 41 samples and the reference material points, m.
pub fn catenary_error(result: &RunResult) -> Result<Real, Error> {
    let reference = catenary_reference()?;
    if result.samples.positions.len() != reference.xy.len() {
        return Err(Error::study("catenary", "the run needs 41 samples"));
    }
    let pairs = result.samples.positions.iter().zip(&reference.xy);
    Ok(pairs
        .map(|(p, r)| ((p[0] - r[0]).powi(2) + (p[1] - r[1]).powi(2) + p[2].powi(2)).sqrt())
        .fold(0.0, Real::max))
}

/// The taut string with `n` clamped cubic control points, at rest, straight.
pub fn taut_string(n: usize) -> Result<RodSystem, Error> {
    taut_string_with(n, StretchFormulation::default())
}

/// [`taut_string`] with the given stretching formulation.
pub fn taut_string_with(n: usize, formulation: StretchFormulation) -> Result<RodSystem, Error> {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, 1.0)?;
    let end = Vector3::new(1.2, 0.0, 0.0);
    let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end)?
        .with_quadrature_points(formulation.points_per_span(3))?
        .without_second_derivatives();
    let pins = [Pin::here(&rod, 0.0)?, Pin::here(&rod, 1.0)?];
    let mut stretching = Stretching::new(100.0)?;
    stretching.formulation = formulation;
    Ok(RodSystem::new(rod)
        .with_energy(stretching)
        .with_pin(pins[0])
        .with_pin(pins[1]))
}

/// The lowest transverse and longitudinal modes of the taut string with `n` control
/// points (told apart by the share of motion along the string).
pub fn string_modes(n: usize) -> Result<(Mode, Mode), Error> {
    string_modes_with(n, StretchFormulation::default())
}

/// [`string_modes`] with the given stretching formulation.
pub fn string_modes_with(n: usize, formulation: StretchFormulation) -> Result<(Mode, Mode), Error> {
    let modes = modal::modes(&taut_string_with(n, formulation)?, 12)?;
    let axial = |m: &Mode| {
        let along: Real = m.shape.iter().map(|v| v.x * v.x).sum();
        along / m.shape.iter().map(|v| v.norm_squared()).sum::<Real>()
    };
    let find = |want_axial: bool| {
        let found = modes.iter().find(|m| (axial(m) > 0.5) == want_axial);
        found
            .cloned()
            .ok_or_else(|| Error::study("string modes", "mode not found"))
    };
    Ok((find(false)?, find(true)?))
}

/// The midpoint's transverse displacement over time after releasing the 16-point string
/// from its first transverse mode (10⁻⁴ m at most).
#[derive(Debug, Clone)]
pub struct Pluck {
    /// Times, s.
    pub t: Vec<Real>,
    /// Midpoint displacement along the mode, m.
    pub y: Vec<Real>,
    /// Angular frequency of the discrete mode, rad/s.
    pub omega: Real,
}

/// Plucks the string and steps it with `integrator` for `periods` periods of step `dt`.
pub fn pluck(integrator: Box<dyn Integrator>, dt: Real, periods: Real) -> Result<Pluck, Error> {
    let mut system = taut_string(16)?;
    let (mode, _) = string_modes(16)?;
    let biggest = mode.shape.iter().map(|v| v.norm()).fold(0.0, Real::max);
    for (q, v) in system.rod.positions.iter_mut().zip(&mode.shape) {
        *q += v * (1e-4 / biggest);
    }
    let axis = mode.shape[mode.shape.len() / 2].normalize();
    let mut sim = Simulation::new(system, integrator);
    let steps = (periods / mode.frequency / dt).ceil() as usize;
    let mut out = Pluck {
        t: vec![0.0],
        y: vec![sim.system.rod.point(0.5)?.dot(&axis)],
        omega: mode.omega,
    };
    for _ in 0..steps {
        sim.step(dt)?;
        out.t.push(sim.time);
        out.y.push(sim.system.rod.point(0.5)?.dot(&axis));
    }
    Ok(out)
}

impl Pluck {
    /// Frequency from the mean period between upward zero crossings (linearly
    /// interpolated), Hz; `None` with fewer than two crossings.
    pub fn frequency(&self) -> Option<Real> {
        let (t, y) = (&self.t, &self.y);
        let crossings: Vec<Real> = (1..y.len())
            .filter(|&k| y[k - 1] < 0.0 && y[k] >= 0.0)
            .map(|k| t[k - 1] + (t[k] - t[k - 1]) * y[k - 1] / (y[k - 1] - y[k]))
            .collect();
        let (first, last) = (crossings.first()?, crossings.last()?);
        (crossings.len() >= 2).then(|| (crossings.len() - 1) as Real / (last - first))
    }

    /// Fraction of the amplitude lost per period, from the positive peaks; `None` with
    /// fewer than two peaks.
    pub fn amplitude_loss_per_period(&self) -> Option<Real> {
        let y = &self.y;
        let peaks: Vec<Real> = (1..y.len().saturating_sub(1))
            .filter(|&k| y[k] > y[k - 1] && y[k] >= y[k + 1] && y[k] > 0.0)
            .map(|k| y[k])
            .collect();
        let (first, last) = (peaks.first()?, peaks.last()?);
        (peaks.len() >= 2).then(|| 1.0 - (last / first).powf(1.0 / (peaks.len() - 1) as Real))
    }
}

/// A cable of `n` clamped cubic control points (L = 1 m, μ = 0.1 kg/m, axial stiffness
/// `ea`), straight between pins `span` metres apart along x, under gravity: the
/// benchmark rod (span > L starts it stretched, < L compressed).
pub fn pinned_cable(n: usize, span: Real, ea: Real) -> Result<RodSystem, Error> {
    pinned_cable_with(n, span, ea, StretchFormulation::default())
}

/// [`pinned_cable`] with the given stretching formulation.
pub fn pinned_cable_with(
    n: usize,
    span: Real,
    ea: Real,
    formulation: StretchFormulation,
) -> Result<RodSystem, Error> {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, 1.0)?;
    let end = Vector3::new(span, 0.0, 0.0);
    let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end)?
        .with_quadrature_points(formulation.points_per_span(3))?
        .without_second_derivatives();
    let pins = [Pin::here(&rod, 0.0)?, Pin::here(&rod, 1.0)?];
    let mut stretching = Stretching::new(ea)?;
    stretching.formulation = formulation;
    Ok(RodSystem::new(rod)
        .with_energy(stretching)
        .with_energy(Gravity::new(Vector3::new(0.0, -9.81, 0.0))?)
        .with_pin(pins[0])
        .with_pin(pins[1]))
}
