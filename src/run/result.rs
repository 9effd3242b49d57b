//! The result of a run, [`RunResult`]: what `splinerod run` prints and writes as JSON.
//! The run loop reads it off a finished run with `finish` (the lead member's final
//! state and tally, with the per-rod results of [`crate::run::rods`], the pins' forces
//! and torques and the twist) and adds the ensemble's summaries.

use crate::run::bodies::BodyTrack;
use crate::run::ensemble::MemberSummary;
use crate::run::knot_track::KnotTrack;
use crate::run::pins::{pin_torques, scene_pin_forces};
use crate::run::rods::{RodOutput, Samples};
use crate::run::shard::ShardInfo;
use crate::run::tally::{Probe, Tally};
use crate::run::totals::{ContactStats, SolverTotals};
use crate::run::twist::TwistOutput;
use crate::scene::Scene;
use crate::world::estimate::EstimateOutput;
use crate::{Error, RodSystem, Simulation, StageTimes};
use serde::Serialize;
use splinerod_core::Real;
use splinerod_integrators::Role;
use std::collections::BTreeMap;

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
    /// The rigid bodies' tracks (`[[bodies]]`); absent from the JSON without bodies.
    #[serde(skip_serializing_if = "Vec::is_empty", default)]
    pub bodies: Vec<BodyTrack>,
    /// Final energies, J: `kinetic` and one entry per energy term (`stretch`, `gravity`).
    pub energy: BTreeMap<String, Real>,
    /// Final knot vector, fractions of the rest length.
    pub knots: Vec<Real>,
    /// Solver counters.
    pub solver: SolverTotals,
    /// Forces the rod puts on its pins' supports (grippers, bodies, fixed points) at the
    /// end, N, one per `[[pins]]` entry: the negative of the pins' forces on the rod.
    pub pin_forces: Vec<[Real; 3]>,
    /// Torques the rod puts on its pins' supports at the end, N·m, one per pin, about
    /// the pinned point: an exact clamp's bending moment plus, with
    /// `rod.twist_stiffness`, the twisting moment about the end clamps' axes, as the
    /// gripper feels them (absent when no pin carries a torque).
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
    pub rods: Vec<RodOutput>,
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
    /// Whether the run stopped before its duration ([`crate::run::control::RunControl`]: a signal, a stop
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
    let samples = end_samples(scene, system)?;
    let mut energy = BTreeMap::from([("kinetic".to_string(), rod.kinetic_energy())]);
    energy.extend(system.energy_breakdown());
    energy.extend(crate::run::bodies::energies(system));
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
        samples,
        probes: tally.probes,
        bodies: tally.bodies,
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

/// The positions of `scene`'s `output.samples` evenly spaced material points of `system`
/// and the axial tension there.
fn end_samples(scene: &Scene, system: &RodSystem) -> Result<Samples, Error> {
    let m = scene.output.samples;
    let s: Vec<Real> = (0..m).map(|k| k as Real / (m - 1) as Real).collect();
    let positions = s
        .iter()
        .map(|&f| {
            system
                .rod
                .point(scene.material_coordinate(f))
                .map(Into::into)
        })
        .collect::<Result<_, _>>()?;
    let tension = system.tension(
        &s.iter()
            .map(|&f| scene.material_coordinate(f))
            .collect::<Vec<_>>(),
    );
    Ok(Samples {
        s,
        positions,
        tension,
    })
}

/// Median of `values` (0 if empty); reorders them.
pub(crate) fn median(values: &mut [Real]) -> Real {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, Real::total_cmp).1
}
