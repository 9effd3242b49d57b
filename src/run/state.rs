//! A run under way ([`Run`]): its members, each a scene and the [`Tally`] it records
//! into, their simulations advanced together as one [`Ensemble`], and the loop's
//! counters. A run is built fresh from a scene ([`fresh_run`]: every member built and
//! prepared for its first stage) or rebuilt from saved states ([`restored_run`]: a
//! checkpoint, an undone stage, a copy to conclude).

use crate::run::tally::{CutSchedule, Tally};
use crate::scene::{Method, Scene};
use crate::world::saved::SimulationState;
use crate::{Ensemble, Error, Simulation};
use splinerod_core::{Cancel, Real};
use std::ops::Range;

/// Step times reserved up front (more grow the vector as the run goes).
const STEP_TIMES_RESERVED: usize = 1 << 16;

/// One member of a run.
pub(crate) struct Member {
    pub(crate) scene: Scene,
    pub(crate) tally: Tally,
}

/// The members of `scene`: the ensemble's (those of `only`, if given), or the scene
/// itself.
pub(crate) fn build_members(
    scene: &Scene,
    only: Option<&Range<usize>>,
) -> Result<Vec<(Scene, Simulation)>, Error> {
    match &scene.ensemble {
        Some(spec) => {
            let all = 0..spec.count;
            let range = only.cloned().unwrap_or(all);
            range.map(|i| spec.member(scene, i)).collect()
        }
        None => Ok(vec![(scene.clone(), scene.build()?)]),
    }
}

/// Prepares a member for its first stage: a static solve starts at the time the grabs,
/// driven pins, turning clamps, grippers, moving obstacles and keyframed loads reach their final
/// targets, with every cut made; a dynamic one with the cuts due at time zero.
pub(crate) fn prepare(
    scene: &Scene,
    sim: &mut Simulation,
    cuts: &mut CutSchedule,
) -> Result<(), Error> {
    if scene.solver.method == Method::Static {
        let grabs = scene.grabs.iter().map(|g| g.end_time);
        let paths = sim.system.drivers.iter().map(|d| d.path.end_time());
        let grippers = sim.system.grippers.iter();
        let poses = grippers.filter_map(|g| Some(g.path.as_ref()?.end_time()));
        let loads = sim.system.loads.iter().filter_map(|l| l.path.as_ref());
        let loads = loads.map(|p| p.end_time());
        let turns = scene
            .pins
            .iter()
            .filter_map(|p| p.turn.as_ref()?.last().map(|k| k[0]));
        let moving = scene
            .obstacles
            .iter()
            .filter_map(|o| o.motion().0?.last().map(|k| k[0]));
        let t = grabs
            .chain(paths)
            .chain(loads)
            .chain(moving)
            .chain(turns)
            .chain(poses)
            .fold(0.0, Real::max);
        cuts.apply(Real::INFINITY, 0.0, |s| sim.cut(s))?;
        settle_along_poses(sim, t)?;
        (sim.time, sim.system.time) = (t, t);
        Ok(())
    } else {
        cuts.apply(0.0, 0.0, |s| sim.cut(s))
    }
}

/// Most a gripper turns between two equilibria of a static solve, rad.
const STATIC_TURN: Real = 0.5;

/// A static solve whose grippers turn by more than [`STATIC_TURN`] on their way to time
/// `t`: the equilibria at evenly spaced times before `t` first, each gripper turning by
/// at most that from one to the next. The tangent pin holds a line, and one jump by 90°
/// or more would start the control point next to the clamp on the clamp point itself or
/// beyond it; in stages the rod follows the gripper on its side (a quasi-static path:
/// the counters of these solves are not in the run's totals).
fn settle_along_poses(sim: &mut Simulation, t: Real) -> Result<(), Error> {
    let paths = sim.system.grippers.iter().filter_map(|g| g.path.as_ref());
    let turn = paths.map(|p| p.turning(t)).fold(0.0, Real::max);
    let stages = (turn / STATIC_TURN).ceil() as usize;
    for k in 1..stages {
        let time = t * k as Real / stages as Real;
        (sim.time, sim.system.time) = (time, time);
        sim.settle()?;
    }
    Ok(())
}

/// A run under way: its members, the loop's counters and what it measured.
pub(crate) struct Run {
    pub(crate) members: Vec<Member>,
    pub(crate) ensemble: Ensemble,
    pub(crate) step_seconds: Vec<Real>,
    /// Stages done.
    pub(crate) stage: usize,
    /// Wall time of the stages a checkpointed run did before this process.
    pub(crate) wall_before: Real,
    pub(crate) only: Option<Range<usize>>,
}

impl Run {
    /// The run of `scene` made of `parts` (each member with its simulation; those of
    /// `only`, if given), `stage` stages in.
    fn assemble(
        scene: &Scene,
        parts: Vec<(Member, Simulation)>,
        only: Option<Range<usize>>,
        stage: usize,
    ) -> Self {
        let (members, sims) = parts.into_iter().unzip();
        Run {
            members,
            ensemble: ensemble_of(scene, sims, only.as_ref()),
            step_seconds: Vec::with_capacity(scene.step_count().min(STEP_TIMES_RESERVED)),
            stage,
            wall_before: 0.0,
            only,
        }
    }

    /// Makes every member's solvers poll `cancel`.
    pub(crate) fn set_cancel(&mut self, cancel: &Cancel) {
        for sim in &mut self.ensemble.members {
            sim.system.cancel = cancel.clone();
        }
    }
}

/// The members of `scene` (of `only`) built, prepared and tallied at their start;
/// [`Error::Interrupted`] if `cancel` asks to stop meanwhile.
pub(crate) fn fresh_run(
    scene: &Scene,
    only: Option<&Range<usize>>,
    cancel: &Cancel,
) -> Result<Run, Error> {
    let mut parts = Vec::new();
    for (member_scene, mut sim) in build_members(scene, only)? {
        if cancel.requested() {
            return Err(Error::Interrupted("while the members were built"));
        }
        let mut cuts = CutSchedule::new(&member_scene)?;
        prepare(&member_scene, &mut sim, &mut cuts)?;
        let mut tally = Tally::new(&member_scene, &sim.system)?;
        tally.cuts = cuts;
        let member = Member {
            scene: member_scene,
            tally,
        };
        parts.push((member, sim));
    }
    Ok(Run::assemble(scene, parts, only.cloned(), 0))
}

/// The members of `scene` (those of `only`) rebuilt and put in the saved `states`
/// (simulation state and tally, one per member), `stages` stages into the run.
pub(crate) fn restored_run(
    scene: &Scene,
    only: Option<Range<usize>>,
    states: impl ExactSizeIterator<Item = (SimulationState, Tally)>,
    stages: usize,
) -> Result<Run, Error> {
    let built = build_members(scene, only.as_ref())?;
    if built.len() != states.len() {
        return Err(mismatched_checkpoint(states.len()));
    }
    let mut parts = Vec::new();
    for ((member_scene, mut sim), (state, tally)) in built.into_iter().zip(states) {
        sim.restore_state(&state)?;
        let member = Member {
            scene: member_scene,
            tally,
        };
        parts.push((member, sim));
    }
    Ok(Run::assemble(scene, parts, only, stages))
}

/// The ensemble of `sims` (batched as `scene`'s `[ensemble]` says; a single run is
/// never batched), numbered from the first member of `only` (a shard's), so that it
/// batches its members as a run of the whole ensemble does.
fn ensemble_of(scene: &Scene, sims: Vec<Simulation>, only: Option<&Range<usize>>) -> Ensemble {
    let mut ensemble = Ensemble::new(sims);
    ensemble.first_index = only.map_or(0, |r| r.start);
    ensemble.batched = scene.ensemble.as_ref().is_some_and(|e| e.batched);
    ensemble
}

/// A checkpoint of `members` members that does not fit the scene and command line.
pub(crate) fn mismatched_checkpoint(members: usize) -> Error {
    Error::field(
        "checkpoint",
        members,
        "members or outputs do not match the scene and command line",
    )
}

/// Refuses a run whose memory could not exist (for a shard: its members only).
pub(crate) fn check_memory(scene: &Scene, only: Option<&Range<usize>>) -> Result<(), Error> {
    match only {
        Some(range) => scene.with_member_count(range.len()).check_memory(),
        None => scene.check_memory(),
    }
}
