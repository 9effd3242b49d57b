//! Exact sensitivities of a static scene's equilibrium to its scalar parameters (issue
//! #48, item 1, the static part): for the equilibrium `q(p)` of
//! \\(\nabla E(q; p) + G^T \mu = 0\\), `G q = c(p)`, the implicit-function theorem gives
//!
//! \\[ K\, \frac{\mathrm{d}q}{\mathrm{d}p} - G^T\frac{\mathrm{d}\mu}{\mathrm{d}p}
//! = -\frac{\partial \nabla E}{\partial p}, \qquad
//! G\, \frac{\mathrm{d}q}{\mathrm{d}p} = \frac{\mathrm{d}c}{\mathrm{d}p}, \\]
//!
//! one solve with the factorised exact Hessian `K` per parameter
//! ([`splinerod_integrators::StaticSolver::sensitivities`]). Each energy gives
//! \\(\partial \nabla E / \partial p\\) through its
//! [`Parameters`](splinerod_energies::Parameters) capability; a point
//! load's is \\(-b_i(s)\, e_c\\). The pins' targets move only with a pin's position:
//! for `pins[i].position[c]`, \\(\mathrm{d}c/\mathrm{d}p = e_c\\) on the entry's pin
//! (and on an exact clamp's tangent pin, whose line is translated with it; of a driven
//! pin the whole path is), zero on the others, and \\(\partial\nabla E/\partial p = 0\\).
//! The derivative of a material point is then
//! \\(\sum_i b_i(s)\, \mathrm{d}q_i/\mathrm{d}p\\).
//!
//! **Parameters**, named by their scene path ([`paths`]): `rod.stretch_stiffness`,
//! `rod.bending_stiffness`, `rod.twist_stiffness`, `rod.linear_density` (through the
//! weight), the same on `rods[k].…` of a `[[rods]]` scene, `world.gravity[c]`,
//! `loads[i].force[c]`, `pins[i].position[c]` and `rod.rest_length` (the domain
//! `[0, L]` scaled with every material coordinate at its fraction:
//! `sensitivity/rest_length.rs`). Anything else — an unknown path, a
//! vector without its index, a parameter no energy of the scene depends on — is an
//! error naming the path. `rod.damping` and `contact.friction` are parameters of runs
//! (friction acts only through the lags a time step freezes: an equilibrium does not
//! depend on it); a `[[rods]]` entry's rest length is refused (`paths::REST_LENGTH`).
//!
//! Outputs: the samples' positions (at fixed fractions of the rest length) and every
//! `[[pins]]` entry's force (the derivative of the multipliers, from the same solve).
//! Runs (implicit Euler, BDF2) have theirs from [`dynamic_sensitivities`] (forward
//! sensitivities through every step, see `sensitivity/dynamic.rs`).

mod dynamic;
pub mod paths;
pub(crate) mod rest_length;
mod step_view;

pub use paths::{parameter_value, set_parameter};
pub(crate) use paths::{target, target_value, Target};
pub use step_view::StepView;

pub use dynamic::{
    dynamic_sensitivities, observed_sensitivities, DynamicSensitivities, StepObserver,
    TimeSensitivities,
};

use crate::{Error, RodSystem, Scene};
use nalgebra::Vector3;
use splinerod_core::Real;
use splinerod_core::Rod;
use splinerod_integrators::newton::Tangent;
use splinerod_integrators::StaticSolver;

/// The sensitivities of a static scene's equilibrium.
#[derive(Debug, Clone, serde::Serialize)]
pub struct StaticSensitivities {
    /// The parameters, by scene path, with their values.
    pub parameters: Vec<(String, Real)>,
    /// The output samples' material coordinates (fractions of the first rod's length).
    pub s: Vec<Real>,
    /// Per parameter, the derivative of each sample's equilibrium position, m per unit.
    pub positions: Vec<Vec<[Real; 3]>>,
    /// The equilibrium positions of the samples, m.
    pub at: Vec<[Real; 3]>,
    /// Per parameter, the derivative of the rod's force on each `[[pins]]` entry's
    /// support, N per unit (as the run's `pin_forces`).
    pub pin_forces: Vec<Vec<[Real; 3]>>,
    /// The rod's force on each `[[pins]]` entry's support at equilibrium, N (as the
    /// run's `pin_forces`).
    pub forces: Vec<[Real; 3]>,
    /// Per parameter, the derivative of every control point.
    #[serde(skip)]
    pub control_points: Vec<Vec<Vector3<Real>>>,
    /// The rod at equilibrium.
    #[serde(skip)]
    pub rod: Rod,
}

impl StaticSensitivities {
    /// The JSON of `splinerod sensitivities`: `parameters` (`name`, `value`), `s`,
    /// `positions` (per parameter name, one `[dx, dy, dz]` per sample), `pin_forces` (per
    /// parameter name, one per `[[pins]]` entry) and `at` (the samples' equilibrium
    /// positions).
    pub fn json(&self) -> serde_json::Value {
        let derivatives = (&self.positions[..], &self.pin_forces[..]);
        shared_json(&self.parameters, &self.s, derivatives, &self.at)
    }

    /// One line per parameter: its value and the largest derivative of a sample.
    pub fn summary(&self) -> Vec<String> {
        let lines = self.parameters.iter().zip(&self.positions);
        lines
            .map(|((name, value), d)| {
                format!(
                    "{name} = {value}: samples move by up to {:.3e} m per unit",
                    largest(d)
                )
            })
            .collect()
    }
}

/// One parameter's derivatives of a list of points or forces.
type PerParameter = Vec<[Real; 3]>;

/// The JSON keys static and run sensitivities share: `parameters` (`name`, `value`),
/// `s`, `positions` and `pin_forces` (per parameter name) and `at`.
pub(crate) fn shared_json(
    parameters: &[(String, Real)],
    s: &[Real],
    (positions, pin_forces): (&[PerParameter], &[PerParameter]),
    at: &[[Real; 3]],
) -> serde_json::Value {
    let names = parameters
        .iter()
        .map(|(name, value)| serde_json::json!({ "name": name, "value": value }));
    serde_json::json!({
        "parameters": names.collect::<Vec<_>>(),
        "s": s,
        "positions": by_name(parameters, positions),
        "pin_forces": by_name(parameters, pin_forces),
        "at": at,
    })
}

/// Each parameter's entry of `d`, keyed by its name.
pub(crate) fn by_name(
    parameters: &[(String, Real)],
    d: &[Vec<[Real; 3]>],
) -> serde_json::Map<String, serde_json::Value> {
    let pairs = parameters.iter().zip(d);
    pairs
        .map(|((name, _), d)| (name.clone(), serde_json::json!(d)))
        .collect()
}

/// The output samples' fractions and their basis rows on `rod`.
pub(crate) fn sample_rows(
    scene: &Scene,
    rod: &Rod,
) -> Result<(Vec<Real>, Vec<splinerod_core::BasisValues>), Error> {
    let samples = scene.output.samples;
    let s: Vec<Real> = (0..samples)
        .map(|k| k as Real / (samples - 1) as Real)
        .collect();
    let rows = s
        .iter()
        .map(|&f| rod.basis_at(scene.material_coordinate(f)))
        .collect::<Result<Vec<_>, _>>()?;
    Ok((s, rows))
}

/// The curve of control points (or of their derivatives) `q` at the basis rows `rows`.
pub(crate) fn points_at(
    rows: &[splinerod_core::BasisValues],
    q: &[Vector3<Real>],
) -> Vec<[Real; 3]> {
    rows.iter().map(|b| b.combine(&b.value, q).into()).collect()
}

/// The largest component of the derivatives `d`.
pub(crate) fn largest(d: &[[Real; 3]]) -> Real {
    d.iter().flatten().fold(0.0, |m: Real, x| m.max(x.abs()))
}

/// The equilibrium of the static `scene` and its sensitivities to the parameters
/// `paths` (see the module docs).
pub fn static_sensitivities(scene: &Scene, paths: &[&str]) -> Result<StaticSensitivities, Error> {
    scene.without_bodies("sensitivities")?;
    if scene.solver.method != crate::scene::Method::Static {
        let reason = "a static solve's sensitivities need method = \"static\" \
                      (a run's are dynamic_sensitivities')";
        return Err(Error::field(
            "solver.method",
            format!("{:?}", scene.solver.method),
            reason,
        ));
    }
    let targets: Vec<Target> = paths
        .iter()
        .map(|p| target(scene, p))
        .collect::<Result<_, _>>()?;
    // As the run: the grabs, paths, turns and loads at their ends, every cut made.
    let mut sim = scene.build()?;
    let mut cuts = crate::run::tally::CutSchedule::new(scene)?;
    crate::run::state::prepare(scene, &mut sim, &mut cuts)?;
    sim.settle()?;
    let system = &sim.system;
    let mut parameters = Vec::with_capacity(paths.len());
    let mut rhs = Vec::with_capacity(paths.len());
    for (path, target) in paths.iter().zip(&targets) {
        let (value, mut b) = derivative(system, scene, path, target)?;
        add_barrier_stiffness_derivative(system, scene, target, value, &mut b)?;
        parameters.push((path.to_string(), value));
        rhs.push(b);
    }
    let mut cases: Vec<Tangent> = rhs
        .into_iter()
        .zip(&targets)
        .map(|(b, target)| {
            let mut target_rates = Vec::new();
            paths::target_rates(scene, &system.pins, target, &mut target_rates);
            Tangent {
                residual_rate: b,
                target_rates,
                ..Tangent::default()
            }
        })
        .collect();
    let mut solver = StaticSolver::new(scene.static_params())?;
    solver.sensitivities(system, &mut cases)?;
    let pin_forces = cases
        .iter()
        .map(|c| crate::run::pins::fold_pin_forces(scene, &sim, c.multipliers.clone()))
        .collect();
    let rhs: Vec<Vec<Vector3<Real>>> = cases.into_iter().map(|c| c.positions).collect();
    let rod = &system.rod;
    let (s, rows) = sample_rows(scene, rod)?;
    let point = |q: &[Vector3<Real>]| points_at(&rows, q);
    Ok(StaticSensitivities {
        parameters,
        positions: rhs.iter().map(|d| point(d)).collect(),
        at: point(&rod.positions),
        s,
        pin_forces,
        forces: crate::run::pins::scene_pin_forces(scene, &sim),
        control_points: rhs,
        rod: rod.clone(),
    })
}

/// The parameter's value and \\(\partial \nabla E / \partial p\\) on `system`.
fn derivative(
    system: &RodSystem,
    scene: &Scene,
    path: &str,
    target: &Target,
) -> Result<(Real, Vec<Vector3<Real>>), Error> {
    let rod = &system.rod;
    let mut b = vec![Vector3::zeros(); rod.len()];
    match *target {
        Target::Damping(_) => {
            let reason = "damping does not change an equilibrium (a parameter of runs)";
            Err(Error::field("params", format!("\"{path}\""), reason))
        }
        Target::Friction => {
            let reason = "friction acts only in runs (through the normal forces each time \
                          step freezes): an equilibrium does not depend on it";
            Err(Error::field("params", format!("\"{path}\""), reason))
        }
        Target::Pin { .. } => Ok((target_value(scene, target), b)),
        Target::Load(i, c) => {
            let load = &system.loads[i].force;
            let row = rod.basis_at(load.at)?;
            for k in 0..row.order {
                b[row.first + k][c] -= row.value[k];
            }
            Ok((load.force[c], b))
        }
        Target::Energy(name, segment) => {
            if rest_length::is_rest_length(name) {
                rest_length::check_energies(system, path)?;
            }
            if !energy_rate(system, name, segment, &mut b)? {
                let reason =
                    "no energy of the scene depends on it (is it set, and is it not a constraint?)";
                return Err(Error::field("params", format!("\"{path}\""), reason));
            }
            if rest_length::is_rest_length(name) {
                rest_length::add_derived(system, &mut b);
            }
            Ok((paths::value(scene, name, segment), b))
        }
    }
}

/// Adds \\(\partial \nabla E / \partial p\\) of every acting energy with the
/// parameter `name` (on rod `segment`) to `out`; whether any has it.
fn energy_rate(
    system: &RodSystem,
    name: &str,
    segment: Option<usize>,
    out: &mut [Vector3<Real>],
) -> Result<bool, Error> {
    let mut found = false;
    for energy in system.acting() {
        let caps = energy.capabilities();
        let on = segment.is_none() || caps.segment == segment;
        if let Some(p) = caps.parameters.filter(|_| on) {
            found |= p.add_gradient_derivative(&system.rod, name, out)?;
        }
    }
    Ok(found)
}

/// The contact barrier's default stiffness follows the loads
/// (`scene/contact.rs`: \\(\kappa(w)\\), `w` the largest line load, which depends on the
/// density, gravity, the stiffnesses and the loads), and the barrier is linear in it:
/// adds \\((\mathrm{d}\kappa/\mathrm{d}p) / \kappa\, \nabla E_{contact}\\). `dκ/dp` is
/// the central difference of that scalar function of the scene (relative step 1e-6: it
/// is algebraic in the parameters, so its difference quotient is accurate to ~1e-10);
/// with an explicit `[contact] stiffness` nothing is added.
fn add_barrier_stiffness_derivative(
    system: &RodSystem,
    scene: &Scene,
    target: &Target,
    value: Real,
    b: &mut [Vector3<Real>],
) -> Result<(), Error> {
    if let Some(ratio) = barrier_rate(system, scene, target, value)? {
        add_barrier_rate(system, ratio, b, &mut Vec::new());
    }
    Ok(())
}

/// \\((\mathrm{d}\kappa/\mathrm{d}p) / \kappa\\) of the contact barrier's derived
/// stiffness (see [`add_barrier_stiffness_derivative`]); `None` without a derived one.
fn barrier_rate(
    system: &RodSystem,
    scene: &Scene,
    target: &Target,
    value: Real,
) -> Result<Option<Real>, Error> {
    let derived = scene
        .contact
        .as_ref()
        .is_some_and(|c| c.enabled && c.stiffness.is_none());
    if !derived || !system.acting().any(|e| e.name() == "contact") {
        return Ok(None);
    }
    let kappa = |p: Real| -> Result<Real, Error> {
        let mut s = scene.clone();
        paths::set(&mut s, target, p);
        Ok(s.contact()?.map_or(0.0, |c| c.params().stiffness))
    };
    let h = 1e-6 * value.abs().max(1e-6);
    let here = kappa(value)?;
    let slope = (kappa(value + h)? - kappa(value - h)?) / (2.0 * h);
    if slope == 0.0 || here <= 0.0 {
        return Ok(None);
    }
    Ok(Some(slope / here))
}

/// `b += ratio · ∇E_contact` at the rod's positions (`gradient`: scratch).
fn add_barrier_rate(
    system: &RodSystem,
    ratio: Real,
    b: &mut [Vector3<Real>],
    gradient: &mut Vec<Vector3<Real>>,
) {
    if let Some(contact) = system.acting().find(|e| e.name() == "contact") {
        gradient.clear();
        gradient.resize(system.rod.len(), Vector3::zeros());
        contact.add_gradient(&system.rod, gradient);
        for (b, g) in b.iter_mut().zip(gradient.iter()) {
            *b += g * ratio;
        }
    }
}

/// `splinerod sensitivities`: a static scene's equilibrium's, or a run's (implicit
/// Euler, BDF2) at its end and every recorded time; the summary lines and the JSON.
pub fn report(scene: &Scene, params: &[&str]) -> Result<(Vec<String>, serde_json::Value), Error> {
    if scene.solver.method == crate::scene::Method::Static {
        let found = static_sensitivities(scene, params)?;
        Ok((found.summary(), found.json()))
    } else {
        let found = dynamic_sensitivities(scene, params)?;
        Ok((found.summary(), found.json()))
    }
}
