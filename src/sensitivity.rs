//! Exact sensitivities of a static scene's equilibrium to its scalar parameters (issue
//! #48, item 1, the static part): for the equilibrium `q(p)` of
//! \\(\nabla E(q; p) + G^T \mu = 0\\), `G q = c`, the implicit-function theorem gives
//!
//! \\[ K\, \frac{\mathrm{d}q}{\mathrm{d}p} = -\frac{\partial \nabla E}{\partial p}, \qquad
//! G\, \frac{\mathrm{d}q}{\mathrm{d}p} = 0, \\]
//!
//! one solve with the factorised exact Hessian `K` per parameter
//! ([`splinerod_integrators::StaticSolver::sensitivities`]). Each energy gives
//! \\(\partial \nabla E / \partial p\\) through its
//! [`Parameters`](splinerod_energies::Parameters) capability; a point
//! load's is \\(-b_i(s)\, e_c\\). The derivative of a material point is then
//! \\(\sum_i b_i(s)\, \mathrm{d}q_i/\mathrm{d}p\\).
//!
//! **Parameters**, named by their scene path: `rod.stretch_stiffness`,
//! `rod.bending_stiffness`, `rod.twist_stiffness`, `rod.linear_density` (through the
//! weight), the same on `rods[k].…` of a `[[rods]]` scene, `world.gravity[c]` and
//! `loads[i].force[c]`. Anything else — an unknown path, a vector without its index, a
//! parameter no energy of the scene depends on — is an error naming the path.
//!
//! Outputs: the samples' positions and every `[[pins]]` entry's force (the derivative of
//! the multipliers, from the same solve). Runs (implicit Euler, BDF2) have theirs from
//! [`dynamic_sensitivities`] (forward sensitivities through every step, see
//! `sensitivity/dynamic.rs`), which also take `rod.damping`. Not yet: pin positions as
//! parameters.

mod dynamic;

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
    /// Per parameter, the derivative of each `[[pins]]` entry's force on the rod, N per
    /// unit (as the run's `pin_forces`).
    pub pin_forces: Vec<Vec<[Real; 3]>>,
    /// Each `[[pins]]` entry's force on the rod at equilibrium, N.
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

/// What a parameter path names.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Target {
    /// An energy parameter: its name and the segment (`None`: any energy of the rod).
    Energy(&'static str, Option<usize>),
    /// Component `c` of load `i`'s force.
    Load(usize, usize),
    /// The mass-proportional damping rate of the rod (`None`) or of `[[rods]]` entry `k`:
    /// a parameter of dynamic runs only.
    Damping(Option<usize>),
}

/// The equilibrium of the static `scene` and its sensitivities to the parameters
/// `paths` (see the module docs).
pub fn static_sensitivities(scene: &Scene, paths: &[&str]) -> Result<StaticSensitivities, Error> {
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
    let pins = system.pins.len();
    let mut cases: Vec<Tangent> = rhs
        .into_iter()
        .map(|b| Tangent {
            residual_rate: b,
            target_rates: vec![Vector3::zeros(); pins],
            ..Tangent::default()
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

/// Sets the parameter at scene path `path` (as [`static_sensitivities`] reads it) of
/// `scene` to `value`.
pub fn set_parameter(scene: &mut Scene, path: &str, value: Real) -> Result<(), Error> {
    let target = target(scene, path)?;
    set(scene, &target, value);
    Ok(())
}

/// What the parameter `path` names in `scene`, or an error naming it.
fn target(scene: &Scene, path: &str) -> Result<Target, Error> {
    let bad = |reason: String| Error::field("params", format!("\"{path}\""), reason);
    let rod_fields = [
        "stretch_stiffness",
        "bending_stiffness",
        "twist_stiffness",
        "linear_density",
    ];
    let energy = |field: &str, segment: Option<usize>| {
        if field == "damping" {
            return Ok(Target::Damping(segment));
        }
        let name = rod_fields.iter().find(|f| **f == field);
        name.map(|n| Target::Energy(n, segment)).ok_or_else(|| {
            bad(format!(
                "not a rod parameter with sensitivities ({}, damping)",
                rod_fields.join(", ")
            ))
        })
    };
    if let Some(field) = path.strip_prefix("rod.") {
        if !scene.rods.is_empty() {
            return Err(bad("the scene has [[rods]]: name the rod as rods[k]".into()));
        }
        return energy(field, None);
    }
    if let Some((k, field)) =
        indexed(path, "rods[").and_then(|(k, rest)| Some((k, rest.strip_prefix('.')?)))
    {
        if k >= scene.rods.len() {
            return Err(bad(format!(
                "the scene has {} [[rods]] entries",
                scene.rods.len()
            )));
        }
        return energy(field, Some(k));
    }
    if let Some((c, "")) = indexed(path, "world.gravity[") {
        return match c {
            0 => Ok(Target::Energy("gravity[0]", None)),
            1 => Ok(Target::Energy("gravity[1]", None)),
            2 => Ok(Target::Energy("gravity[2]", None)),
            _ => Err(bad("gravity has the components 0, 1, 2".into())),
        };
    }
    if let Some((i, rest)) = indexed(path, "loads[") {
        if let Some((c, "")) = indexed(rest, ".force[") {
            if scene.loads.get(i).is_some_and(|l| l.force.is_none()) {
                return Err(bad("a keyframed load (path) has no one force value".into()));
            }
            if i < scene.loads.len() && c < 3 {
                return Ok(Target::Load(i, c));
            }
            return Err(bad(format!(
                "the scene has {} [[loads]]; a force has 3 components",
                scene.loads.len()
            )));
        }
    }
    Err(bad(
        "not a scalar parameter with sensitivities (rod.<stiffness or linear_density>, \
         rods[k].…, world.gravity[c], loads[i].force[c])"
            .into(),
    ))
}

/// `(n, rest)` for `path = prefix + "n]" + rest`.
fn indexed<'a>(path: &'a str, prefix: &str) -> Option<(usize, &'a str)> {
    let rest = path.strip_prefix(prefix)?;
    let (n, rest) = rest.split_once(']')?;
    Some((n.parse().ok()?, rest))
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
        Target::Load(i, c) => {
            let load = &system.loads[i].force;
            let row = rod.basis_at(load.at)?;
            for k in 0..row.order {
                b[row.first + k][c] -= row.value[k];
            }
            Ok((load.force[c], b))
        }
        Target::Energy(name, segment) => {
            if !energy_rate(system, name, segment, &mut b)? {
                let reason =
                    "no energy of the scene depends on it (is it set, and is it not a constraint?)";
                return Err(Error::field("params", format!("\"{path}\""), reason));
            }
            Ok((value(scene, name, segment), b))
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
        set(&mut s, target, p);
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

/// Sets the parameter `target` of `scene` to `v`.
fn set(scene: &mut Scene, target: &Target, v: Real) {
    match *target {
        Target::Damping(Some(k)) => scene.rods[k].damping = v,
        Target::Damping(None) => scene.rod.damping = v,
        Target::Load(i, c) => {
            if let Some(f) = scene.loads[i].force.as_mut() {
                f[c] = v;
            }
        }
        Target::Energy(name, segment) => {
            let rod = match segment {
                Some(k) => &mut scene.rods[k],
                None => &mut scene.rod,
            };
            match name {
                "stretch_stiffness" => rod.stretch_stiffness = v,
                "bending_stiffness" => rod.bending_stiffness = Some(v),
                "twist_stiffness" => rod.twist_stiffness = Some(v),
                "linear_density" => rod.linear_density = v,
                "gravity[0]" => scene.world.gravity[0] = v,
                "gravity[1]" => scene.world.gravity[1] = v,
                _ => scene.world.gravity[2] = v,
            }
        }
    }
}

/// The scene value of the parameter `target`.
fn target_value(scene: &Scene, target: &Target) -> Real {
    match *target {
        Target::Energy(name, segment) => value(scene, name, segment),
        Target::Load(i, c) => scene.loads[i].force.map_or(0.0, |f| f[c]),
        Target::Damping(segment) => scene.rod_spec(segment.unwrap_or(0)).damping,
    }
}

/// The scene value of the energy parameter `name` (on rod `segment`).
fn value(scene: &Scene, name: &str, segment: Option<usize>) -> Real {
    let rod = scene.rod_spec(segment.unwrap_or(0));
    match name {
        "stretch_stiffness" => rod.stretch_stiffness,
        "bending_stiffness" => rod.bending_stiffness.unwrap_or(0.0),
        "twist_stiffness" => rod.twist_stiffness.unwrap_or(0.0),
        "linear_density" => rod.linear_density,
        "gravity[0]" => scene.world.gravity[0],
        "gravity[1]" => scene.world.gravity[1],
        _ => scene.world.gravity[2],
    }
}

/// The value of the parameter at scene path `path` (as [`set_parameter`] names it) in
/// `scene`.
pub fn parameter_value(scene: &Scene, path: &str) -> Result<Real, Error> {
    Ok(target_value(scene, &target(scene, path)?))
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
