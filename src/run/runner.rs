//! Running a scene to its end and collecting the result that `splinerod run` prints and
//! writes as JSON.

use crate::run::ensemble::MemberSummary;
use crate::run::knot_track::KnotTrack;
use crate::run::observe::{Frame, Observer};
use crate::run::shard::{Shard, ShardInfo};
use crate::run::tally::Tally;
use crate::scene::Scene;
use crate::world::estimate::EstimateOutput;
use crate::{Error, RodSystem, Simulation, StageTimes};
use serde::Serialize;
use splinerod_core::Real;
use splinerod_energies::ContactSummary;
use splinerod_integrators::Role;
use std::collections::BTreeMap;

/// Positions of evenly spaced material points at the end.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Samples {
    /// Material coordinates, fractions of the rest length.
    pub s: Vec<Real>,
    /// Their positions, m.
    pub positions: Vec<[Real; 3]>,
    /// Axial tension there, N (the stretching energy's tension field; absent without one).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub tension: Vec<Real>,
}

/// The trajectory of one material point.
#[derive(Debug, Clone, Serialize, serde::Deserialize, PartialEq)]
pub struct Probe {
    /// Material coordinate, fraction of the rest length.
    pub s: Real,
    /// Times, s (the initial state first).
    pub t: Vec<Real>,
    /// Positions at those times, m.
    pub positions: Vec<[Real; 3]>,
}

pub use crate::run::totals::SolverTotals;

/// Contact over the run (scenes with `[contact]`).
#[derive(Debug, Clone, Copy, Default, Serialize, serde::Deserialize, PartialEq)]
pub struct ContactStats {
    /// Smallest clearance ratio seen at the start or at the end of any step: centre-line
    /// distance between touching parts over `2r`, or from an obstacle's surface over
    /// `r` (below 1: overlap); `null` if nothing came within the penalty's reach.
    pub min_clearance_ratio: Option<Real>,
    /// Most contacts at once.
    pub max_pairs: usize,
    /// Most material samples touching an obstacle at once (0 without obstacles).
    pub max_obstacle_contacts: usize,
    /// The contact stiffness at the end, N/m: the penalty's `k` or the barrier's `κ`,
    /// as the updates left it (`splinerod_energies::contact::stiffness`).
    pub stiffness_used: Option<Real>,
    /// The gap tolerance, m (`null` for a fixed penalty: `stiffness` without
    /// `tolerance`).
    pub tolerance: Option<Real>,
    /// The smallest gap at the end over the contact's sample pairs and surface points,
    /// m (negative: overlap; `null` if nothing is within reach): at rest, how far from
    /// touching the contacts sit.
    pub end_gap: Option<Real>,
}

impl ContactStats {
    /// Folds in one contact summary.
    pub(crate) fn add(&mut self, summary: &ContactSummary) {
        self.max_pairs = self.max_pairs.max(summary.pairs);
        self.max_obstacle_contacts = self.max_obstacle_contacts.max(summary.obstacle_contacts);
        self.stiffness_used = Some(summary.stiffness);
        self.tolerance = summary.tolerance;
        self.end_gap = summary.min_gap;
        if let Some(ratio) = summary.min_clearance_ratio {
            self.min_clearance_ratio =
                Some(self.min_clearance_ratio.map_or(ratio, |r| r.min(ratio)));
        }
    }
}

pub use crate::run::twist::TwistOutput;

/// How a rod was modelled (JSON `rod`).
#[derive(Debug, Clone, Serialize, PartialEq, Eq)]
pub struct RodModel {
    /// The stretching form the run used (`"mixed"`, `"mixed-consistent"` or
    /// `"pointwise"`): the scene's, or what `"auto"` chose (`scene/auto_form.rs`).
    pub stretch_formulation_used: String,
}

/// Everything `splinerod run` reports.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RunResult {
    /// The kernel set that computed it (`"portable"` or `"avx2-fma"`,
    /// [`splinerod_core::kernels`]): results are bit-identical only under one set.
    pub kernels: &'static str,
    /// Simulated time at the end, s.
    pub time: Real,
    /// Time steps taken (0 for a static solve).
    pub steps: usize,
    /// Control points at the end.
    pub control_points: usize,
    /// Wall time of the solve, s.
    pub wall_seconds: Real,
    /// End positions of evenly spaced material points.
    pub samples: Samples,
    /// Trajectories of the probed material points.
    pub probes: Vec<Probe>,
    /// Final energies, J: `kinetic` and one entry per energy term (`stretch`, `gravity`).
    pub energy: BTreeMap<String, Real>,
    /// Final knot vector, fractions of the rest length.
    pub knots: Vec<Real>,
    /// Solver counters.
    pub solver: SolverTotals,
    /// Forces the pins exert on the rod at the end, N (static solves only).
    pub pin_forces: Vec<[Real; 3]>,
    /// Torques the pins exert on the rod at the end, N·m, one per pin, about the pinned
    /// point: an exact clamp's bending moment plus, with `rod.twist_stiffness`, the
    /// twisting moment about the end clamps' axes (absent when no pin carries a torque).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub pin_torques: Vec<[Real; 3]>,
    /// The twist between the end clamps at the end (with `rod.twist_stiffness` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub twist: Option<TwistOutput>,
    /// Mechanically independent pieces at the end (rods + cuts).
    pub pieces: usize,
    /// How the rod was modelled (for a `[[rods]]` scene, its first rod; `rods[k]` has
    /// each rod's).
    pub rod: RodModel,
    /// Each rod of a `[[rods]]` scene: name, control points, samples, energies. Empty
    /// for a one-rod scene (whose rod is the top-level result).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub rods: Vec<crate::run::rods::RodOutput>,
    /// The force the rod exerts on each `[[obstacles]]` entry at the end, N (penalty and
    /// friction); absent without obstacles.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub obstacle_forces: Vec<[Real; 3]>,
    /// For a `--shard` run: which shard of which scene ([`crate::run::shard`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub shard: Option<ShardInfo>,
    /// `[t, n]`: the initial number of control points and every change of it.
    pub control_points_history: Vec<[Real; 2]>,
    /// Recorded states (steps) that ended with a hinge: a knot of multiplicity `d` (a
    /// corner) on a rod with bending or twist. Adaptivity never makes one (its corners
    /// are for strings); only a knot inserted by hand can.
    pub hinge_steps: usize,
    /// Median wall time of one step (integration and adaptivity), s; 0 for a static solve.
    /// For an ensemble: of one step of the whole ensemble.
    pub median_step_seconds: Real,
    /// Per-member summaries of an `[ensemble]` run (absent otherwise); the other fields
    /// then describe member 0, except `wall_seconds` and `solver` (the whole ensemble).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ensemble: Vec<MemberSummary>,
    /// Contact statistics (absent without `[contact]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactStats>,
    /// Tightness of the knot over time (scenes with `[rod.overhand]` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub knot: Option<KnotTrack>,
    /// Wall time of each stage of the steps (drivers, setup, integrate, adapt, record),
    /// summed over the run, s (member 0's for an ensemble).
    pub stage_seconds: StageTimes,
    /// The error estimate (tolerance-driven `[adaptivity]`, or `output.error_estimate`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adaptivity: Option<EstimateOutput>,
    /// Whether the run stopped before its duration ([`RunControl`]: a signal, a stop
    /// request or `--max-steps`); absent from the JSON when it ran to its end.
    #[serde(skip_serializing_if = "is_false")]
    pub interrupted: bool,
    /// Whether the stop abandoned a step under way, rolled back to the last completed
    /// step ([`crate::run::control`]); not in the JSON.
    #[serde(skip)]
    pub abandoned_step: bool,
    /// Whether a checkpoint was written where the run stopped (with a checkpoint plan;
    /// not after an abandoned step that could not be undone exactly); not in the JSON.
    #[serde(skip)]
    pub checkpoint_at_stop: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

pub use crate::run::control::RunControl;

/// Runs `scene` to its end.
pub fn run(scene: &Scene) -> Result<RunResult, Error> {
    run_observed(scene, &mut [])
}

/// Runs `scene` to its end, showing every step to `observers` (in order).
pub fn run_observed(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
) -> Result<RunResult, Error> {
    run_controlled(scene, observers, &RunControl::default())
}

/// [`run_observed`], stopping early as `control` says.
pub fn run_controlled(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
    control: &RunControl,
) -> Result<RunResult, Error> {
    crate::run::main_loop::run_scene(scene, observers, None, control)
}

/// Continues the run checkpointed in `dir` (see [`crate::run::checkpoint`]) to its end,
/// showing every step to `observers` (built from the checkpoint's command line, in the
/// same order) and stopping early as `control` says. The result equals, bit for bit but
/// for wall-clock times, that of the run never stopped.
pub fn resume(
    dir: &std::path::Path,
    observers: &mut [&mut dyn Observer],
    control: &RunControl,
) -> Result<RunResult, Error> {
    let checkpoint = crate::run::checkpoint::read(dir)?;
    let scene = Scene::from_toml_cancellable(&checkpoint.scene, &control.cancel)?;
    let (only, shard) = (checkpoint.only, checkpoint.shard);
    let mut result = crate::run::main_loop::resume_scene(&scene, checkpoint, observers, control)?;
    if let (Some((a, b)), Some((index, count))) = (only, shard) {
        result.shard = Some(Shard { index, count }.info(&scene, &(a..b)));
    }
    Ok(result)
}

/// Runs shard `shard` of the `[ensemble]` of `scene` (see [`crate::run::shard`]): its
/// members only, the result recording which.
pub fn run_shard(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
    shard: Shard,
    control: &RunControl,
) -> Result<RunResult, Error> {
    let members = shard.members(scene)?;
    let mut result = crate::run::main_loop::run_scene(scene, observers, Some(&members), control)?;
    result.shard = Some(shard.info(scene, &members));
    Ok(result)
}

pub(crate) fn frame<'a>(
    scene: &'a Scene,
    system: &'a RodSystem,
    time: Real,
    step: usize,
) -> Frame<'a> {
    let total_steps = scene.step_count();
    Frame {
        scene,
        system,
        time,
        step,
        total_steps,
    }
}

pub(crate) fn notify_finish(
    observers: &mut [&mut dyn Observer],
    frame: &Frame<'_>,
    result: RunResult,
) -> Result<RunResult, Error> {
    for o in observers.iter_mut() {
        o.finish(frame, &result)?;
    }
    Ok(result)
}

pub(crate) fn probes_at_start(scene: &Scene, system: &RodSystem) -> Result<Vec<Probe>, Error> {
    scene
        .output
        .probes
        .iter()
        .map(|&s| {
            let p = system.rod.point(scene.material_coordinate(s))?;
            Ok(Probe {
                s,
                t: vec![0.0],
                positions: vec![p.into()],
            })
        })
        .collect()
}

/// The result of a run of `scene` whose (lead) member ended as `sim` with `tally`, in
/// `wall` seconds with stages of `step_seconds`.
pub(crate) fn finish(
    scene: &Scene,
    sim: &Simulation,
    tally: Tally,
    wall: Real,
    step_seconds: &mut [Real],
) -> Result<RunResult, Error> {
    let system = &sim.system;
    let rod = &system.rod;
    let m = scene.output.samples;
    let s: Vec<Real> = (0..m).map(|k| k as Real / (m - 1) as Real).collect();
    let positions = s
        .iter()
        .map(|&f| rod.point(scene.material_coordinate(f)).map(Into::into))
        .collect::<Result<_, _>>()?;
    let tension = system.tension(
        &s.iter()
            .map(|&f| scene.material_coordinate(f))
            .collect::<Vec<_>>(),
    );
    let mut energy = BTreeMap::from([("kinetic".to_string(), rod.kinetic_energy())]);
    energy.extend(system.energy_breakdown());
    let l = rod.material().rest_length;
    let statics = sim.integrator.role() == Role::Equilibrium;
    let pin_forces = scene_pin_forces(scene, sim);
    let forms = scene.stretch_formulations_used()?;
    Ok(RunResult {
        kernels: splinerod_core::kernels::name(),
        time: sim.time,
        steps: sim.steps,
        control_points: rod.distinct_len(),
        wall_seconds: wall,
        samples: Samples {
            s,
            positions,
            tension,
        },
        probes: tally.probes,
        energy,
        knots: rod.basis().knots().iter().map(|k| k / l).collect(),
        solver: tally.solver,
        pin_forces: pin_forces.clone(),
        pin_torques: pin_torques(scene, sim)?,
        twist: crate::run::twist::twist(system)?,
        pieces: rod.pieces(),
        rod: RodModel {
            stretch_formulation_used: forms.first().map_or("", |f| f.name()).to_string(),
        },
        rods: crate::run::rods::rods(scene, system, &pin_forces, &forms)?,
        obstacle_forces: system
            .obstacle_forces()?
            .into_iter()
            .map(Into::into)
            .collect(),
        shard: None,
        control_points_history: tally.history,
        hinge_steps: tally.hinge_steps,
        median_step_seconds: if statics { 0.0 } else { median(step_seconds) },
        ensemble: Vec::new(),
        contact: tally.contact,
        knot: tally.knot,
        stage_seconds: tally.stages,
        adaptivity: tally.estimates,
        interrupted: false,
        abandoned_step: false,
        checkpoint_at_stop: false,
    })
}

/// One force per `[[pins]]` entry: an exact clamp's tangent pin (after them in the
/// system) adds its force to its clamp's (the pair's net force; their moment is the
/// clamp's bending moment).
pub(crate) fn scene_pin_forces(scene: &Scene, sim: &Simulation) -> Vec<[Real; 3]> {
    let mut forces = sim.integrator.pin_forces();
    for (i, j) in clamp_tangents(scene, sim, forces.len()) {
        let extra = forces[i];
        forces[j] += extra;
    }
    forces.truncate(scene.pins.len());
    forces.into_iter().map(Into::into).collect()
}

/// `(i, j)` for every exact clamp: its tangent pin `i` in the system (below `count`) and
/// its `[[pins]]` entry `j`.
fn clamp_tangents<'a>(
    scene: &'a Scene,
    sim: &'a Simulation,
    count: usize,
) -> impl Iterator<Item = (usize, usize)> + 'a {
    let pins = &sim.system.pins;
    (scene.pins.len()..count.min(pins.len())).filter_map(move |i| {
        let pin = &pins[i];
        let clamp = scene.pins.iter().position(|p| {
            p.clamp
                && matches!(scene.entry_coordinate(p.rod.as_deref(), p.at), Ok(s) if s == pin.at)
        });
        clamp.filter(|_| pin.tangent).map(|j| (i, j))
    })
}

/// One torque per `[[pins]]` entry (N·m, about the pinned point): the twisting moment at
/// the end clamps ([`crate::run::twist::pin_torques`]) plus, at an exact clamp, the
/// bending moment of its pin pair, \\((q_1 - q_0) \times F_1\\) with \\(F_1\\) the force on
/// the control point next to the end. Empty when no pin carries a torque.
fn pin_torques(scene: &Scene, sim: &Simulation) -> Result<Vec<[Real; 3]>, Error> {
    let mut torques = crate::run::twist::pin_torques(scene, &sim.system)?;
    let forces = sim.integrator.pin_forces();
    let rod = &sim.system.rod;
    for (i, j) in clamp_tangents(scene, sim, forces.len()) {
        let pin = &sim.system.pins[i];
        let next = pin.row(rod)?.first;
        let points = rod.segment_points(rod.segment_at(pin.at));
        let end = if next == points.start + 1 {
            points.start
        } else {
            points.end - 1
        };
        let moment = (rod.positions[next] - rod.positions[end]).cross(&forces[i]);
        torques.resize(scene.pins.len(), [0.0; 3]);
        torques[j] = (nalgebra::Vector3::from(torques[j]) + moment).into();
    }
    Ok(torques)
}

/// Median of `values` (0 if empty); reorders them.
pub(crate) fn median(values: &mut [Real]) -> Real {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, Real::total_cmp).1
}
