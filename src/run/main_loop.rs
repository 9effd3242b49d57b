//! The one run loop behind [`crate::run`]: single runs, ensembles and static solves.
//!
//! A run is a list of members — one simulation, or the `[ensemble]`'s — advanced
//! together ([`Ensemble`], in parallel with the `parallel` feature) through the same
//! stages: a static scene is one [`Simulation::settle`] (the equilibrium under the
//! grabs' final targets, re-solved while adaptivity changes the knots), a dynamic one
//! `step_count` calls of [`Simulation::step`]. After each stage every member records in
//! its own tally (`tally.rs`: solver counters, energy summaries (contacts), error
//! estimates, knot tracking, due cuts, the control-point history, probes) and observers
//! see member 0. Cuts due at the start (all of them for a static scene) are made first.
//! The run's members and counters are a `state::Run`; at the end the loop reads the
//! result off it ([`crate::run::result`]).
//!
//! This file owns the loop: it calls the observers, the tallies, the undo
//! ([`crate::run::control`]) and the checkpoint writer, and none of them calls back.
//!
//! A [`RunControl`] may stop the loop before a stage (a signal, `max_steps`), or inside
//! one (the solvers abandon it; [`crate::run::control`] puts the run back as it stood
//! before it); the result is then complete up to there and marked interrupted. With a
//! checkpoint plan the loop writes the run's state (members, tallies, observers)
//! periodically and where it stops, and [`resume_scene`] continues such a run from the
//! stage after it ([`crate::run::checkpoint`]).

use crate::run::checkpoint::{Checkpoint, CheckpointPlan, MemberState};
use crate::run::control::{RunControl, Undo};
use crate::run::ensemble::summarize;
use crate::run::observe::{Frame, Observer};
use crate::run::result::{finish, median, RunResult};
use crate::run::state::{
    check_memory, fresh_run, mismatched_checkpoint, restored_run, Member, Run,
};
use crate::run::totals::SolverTotals;
use crate::scene::{Method, Scene};
use crate::{Ensemble, Error, RodSystem, Simulation};
use splinerod_core::{Cancel, Real};
use std::ops::Range;
use std::time::Instant;

/// Runs `scene` to its end (only the ensemble members of `only`, if given), showing
/// every stage of its first member to `observers`.
pub(crate) fn run_scene(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
    only: Option<&Range<usize>>,
    control: &RunControl,
) -> Result<RunResult, Error> {
    check_memory(scene, only)?;
    let mut run = fresh_run(scene, only, &control.cancel)?;
    run.set_cancel(&control.cancel);
    let lead = &run.ensemble.members[0];
    for o in observers.iter_mut() {
        o.start(&frame(scene, &lead.system, lead.time, 0))?;
    }
    advance(scene, run, observers, control)
}

/// Continues the run of `checkpoint` (of `scene`, its scene text parsed).
pub(crate) fn resume_scene(
    scene: &Scene,
    checkpoint: Checkpoint,
    observers: &mut [&mut dyn Observer],
    control: &RunControl,
) -> Result<RunResult, Error> {
    let only = checkpoint.only.map(|(a, b)| a..b);
    check_memory(scene, only.as_ref())?;
    if observers.len() != checkpoint.observers.len() {
        return Err(mismatched_checkpoint(checkpoint.members.len()));
    }
    let states = checkpoint.members.into_iter();
    let states = states.map(|m| (m.simulation, m.tally));
    let mut run = restored_run(scene, only, states, checkpoint.stage)?;
    run.set_cancel(&control.cancel);
    run.wall_before = checkpoint.wall_seconds;
    let lead = &run.ensemble.members[0];
    let now = frame(scene, &lead.system, lead.time, lead.steps);
    for (o, state) in observers.iter_mut().zip(&checkpoint.observers) {
        o.resume(&now, state.as_deref())?;
    }
    advance(scene, run, observers, control)
}

/// The stages of `run` from where it stands to the end (or until `control` stops it,
/// writing a checkpoint there if asked), then the result.
fn advance(
    scene: &Scene,
    mut run: Run,
    observers: &mut [&mut dyn Observer],
    control: &RunControl,
) -> Result<RunResult, Error> {
    let statics = scene.solver.method == Method::Static;
    let (stages, dt) = if statics {
        (1, 0.0)
    } else {
        (scene.step_count(), scene.solver.dt.unwrap_or_default())
    };
    let (mut interrupted, mut abandoned, mut saved) = (false, false, false);
    let start = Instant::now();
    let mut last_checkpoint = Instant::now();
    let plan = control.checkpoint.as_ref();
    let mut undo = Undo::new(&control.cancel);
    while run.stage < stages {
        if control.stops_before(run.stage) {
            interrupted = true;
            if let Some(plan) = plan {
                save(plan, &run, observers, start)?;
                saved = true;
            }
            break;
        }
        undo.before(&run);
        match stage(scene, &mut run, observers, statics, dt) {
            Ok(()) => {}
            Err(e) if e.is_interrupted() => {
                (interrupted, abandoned) = (true, true);
                let exact = undo.restore(scene, &mut run, &control.cancel)?;
                if let (Some(plan), true) = (plan, exact) {
                    save(plan, &run, observers, start)?;
                    saved = true;
                }
                break;
            }
            Err(e) => return Err(e),
        }
        if let Some(plan) = &control.checkpoint {
            if last_checkpoint.elapsed().as_secs_f64() >= plan.every_seconds {
                save(plan, &run, observers, start)?;
                last_checkpoint = Instant::now();
            }
        }
    }
    let wall = run.wall_before + start.elapsed().as_secs_f64();
    let result = conclude(scene, run, observers, wall, interrupted)?;
    Ok(RunResult {
        abandoned_step: abandoned,
        checkpoint_at_stop: saved,
        ..result
    })
}

/// One stage of every member, recorded, shown to the observers.
pub(crate) fn stage(
    scene: &Scene,
    run: &mut Run,
    observers: &mut [&mut dyn Observer],
    statics: bool,
    dt: Real,
) -> Result<(), Error> {
    let stage_start = Instant::now();
    let advanced = if statics {
        run.ensemble.settle()
    } else {
        run.ensemble.step(dt)
    };
    // A single run's error is its own, not an ensemble member's.
    advanced.map_err(|e| match e {
        Error::Member { source, .. } if scene.ensemble.is_none() => *source,
        e => e,
    })?;
    let Ensemble {
        members: sims,
        reports,
        ..
    } = &mut run.ensemble;
    if scene.ensemble.is_none() {
        // A single run is no ensemble member: nothing to count as stepped alone.
        reports.iter_mut().for_each(|r| r.unbatched = None);
    }
    for ((m, sim), report) in run
        .members
        .iter_mut()
        .zip(sims.iter_mut())
        .zip(reports.iter_mut())
    {
        report.stages.record = m.tally.record(&m.scene, sim, report, dt)?;
        m.tally.stages += report.stages;
    }
    let wall = stage_start.elapsed().as_secs_f64();
    run.step_seconds.push(wall);
    run.stage += 1;
    let lead = &run.ensemble.members[0];
    let now = frame(scene, &lead.system, lead.time, lead.steps);
    for o in observers.iter_mut() {
        o.step(&now, &run.ensemble.reports[0], wall)?;
    }
    Ok(())
}

/// Writes the checkpoint of `run` as it stands.
fn save(
    plan: &CheckpointPlan,
    run: &Run,
    observers: &mut [&mut dyn Observer],
    start: Instant,
) -> Result<(), Error> {
    let members = run.members.iter().zip(&run.ensemble.members);
    let checkpoint = Checkpoint {
        kernels: splinerod_core::kernels::name().to_string(),
        scene: plan.scene.clone(),
        scene_hash: crate::run::checkpoint::fnv1a64(plan.scene.as_bytes()),
        args: plan.args.clone(),
        only: run.only.as_ref().map(|r| (r.start, r.end)),
        shard: plan.shard,
        stage: run.stage,
        members: members
            .map(|(m, sim)| MemberState {
                simulation: sim.save_state(),
                tally: m.tally.clone(),
            })
            .collect(),
        wall_seconds: run.wall_before + start.elapsed().as_secs_f64(),
        observers: observers
            .iter_mut()
            .map(|o| o.checkpoint())
            .collect::<Result<_, _>>()?,
    };
    crate::run::checkpoint::write(&plan.dir, &checkpoint)
}

/// The result of a run whose stages are done (or stopped).
pub(crate) fn conclude(
    scene: &Scene,
    run: Run,
    observers: &mut [&mut dyn Observer],
    wall: Real,
    interrupted: bool,
) -> Result<RunResult, Error> {
    let Run {
        mut members,
        mut ensemble,
        mut step_seconds,
        only,
        ..
    } = run;
    close(&mut members, &mut ensemble.members)?;
    let first_index = only.map_or(0, |r| r.start);
    let sims = &ensemble.members;
    let result = report(scene, members, sims, first_index, wall, &mut step_seconds)?;
    let result = RunResult {
        interrupted,
        ..result
    };
    let lead = &ensemble.members[0];
    notify_finish(
        observers,
        &frame(scene, &lead.system, lead.time, lead.steps),
        result,
    )
}

/// Makes every member's final records (the error estimate of the final state, the
/// knot's last record) in its tally.
pub(crate) fn close(members: &mut [Member], sims: &mut [Simulation]) -> Result<(), Error> {
    for (m, sim) in members.iter_mut().zip(sims) {
        m.tally.close(sim)?;
    }
    Ok(())
}

/// The result of a run from its closed `members`' tallies and the simulations `sims`
/// (read only), the first member being the scene's member `first_index`.
pub(crate) fn report(
    scene: &Scene,
    mut members: Vec<Member>,
    sims: &[Simulation],
    first_index: usize,
    wall: Real,
    step_seconds: &mut [Real],
) -> Result<RunResult, Error> {
    let summaries = if scene.ensemble.is_some() {
        let all = members.iter().zip(sims).enumerate();
        all.map(|(i, (m, sim))| summarize(first_index + i, &m.scene, sim, &m.tally))
            .collect::<Result<Vec<_>, _>>()?
    } else {
        Vec::new()
    };
    let solver = ensemble_totals(&members);
    let mut tally = members.swap_remove(0).tally;
    tally.solver = solver;
    let mut result = finish(scene, &sims[0], tally, wall, step_seconds)?;
    result.ensemble = summaries;
    Ok(result)
}

/// Solver counters summed over every member.
fn ensemble_totals(members: &[Member]) -> SolverTotals {
    let mut total = SolverTotals::default();
    for m in members {
        total += m.tally.solver;
    }
    total
}

fn frame<'a>(scene: &'a Scene, system: &'a RodSystem, time: Real, step: usize) -> Frame<'a> {
    let total_steps = scene.step_count();
    Frame {
        scene,
        system,
        time,
        step,
        total_steps,
    }
}

fn notify_finish(
    observers: &mut [&mut dyn Observer],
    frame: &Frame<'_>,
    result: RunResult,
) -> Result<RunResult, Error> {
    for o in observers.iter_mut() {
        o.finish(frame, &result)?;
    }
    Ok(result)
}

/// The cost of a checkpoint (`bench` key `checkpoint_us_16`): `scene` run for `steps`
/// steps, then its checkpoint written into `plan.dir` `repeats` times; the median
/// write's wall time (s, encoding, writing, `fsync` and rename) and the file's size.
pub(crate) fn checkpoint_cost(
    scene: &Scene,
    steps: usize,
    plan: &CheckpointPlan,
    repeats: usize,
) -> Result<(Real, u64), Error> {
    let mut run = fresh_run(scene, None, &Cancel::none())?;
    let dt = scene.solver.dt.unwrap_or_default();
    for _ in 0..steps {
        stage(scene, &mut run, &mut [], false, dt)?;
    }
    let mut times = Vec::with_capacity(repeats);
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        save(plan, &run, &mut [], start)?;
        times.push(start.elapsed().as_secs_f64());
    }
    let path = plan.dir.join(crate::run::checkpoint::FILE);
    let bytes = std::fs::metadata(&path).map_err(|source| Error::Io {
        path: path.display().to_string(),
        source,
    })?;
    Ok((median(&mut times), bytes.len()))
}
