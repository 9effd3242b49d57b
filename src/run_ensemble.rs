//! Running an `[ensemble]` scene: every member built from the scene with its own
//! variations, stepped together (in parallel with the `parallel` feature), cut on the
//! same schedule, and summarised one by one. Observers see member 0.

use crate::observe::Observer;
use crate::runner::{finish, frame, notify_finish, probes_at_start, CutSchedule, Tally};
use crate::scene::{MemberSummary, Scene};
use crate::scene_ensemble::summarize;
use crate::{Ensemble, Error, RunResult};
use std::time::Instant;

/// Runs the ensemble of `scene` (which must have an `[ensemble]` table) to its end.
pub(crate) fn run_ensemble(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
) -> Result<RunResult, Error> {
    let spec = scene
        .ensemble
        .as_ref()
        .ok_or_else(|| Error::Scene("no [ensemble] table".into()))?;
    let mut scenes = Vec::with_capacity(spec.count);
    let mut sims = Vec::with_capacity(spec.count);
    for i in 0..spec.count {
        let (member_scene, sim) = spec.member(scene, i)?;
        scenes.push(member_scene);
        sims.push(sim);
    }
    let mut ensemble = Ensemble::new(sims);
    let dt = scene.solver.dt.unwrap_or_default();
    let first = &ensemble.members[0].system;
    let mut tally = Tally::new(first, probes_at_start(scene, first)?);
    let mut cuts = CutSchedule::new(scene);
    for o in observers.iter_mut() {
        o.start(&frame(scene, &ensemble.members[0].system, 0.0, 0))?;
    }
    let start = Instant::now();
    for _ in 0..scene.step_count() {
        let step_start = Instant::now();
        ensemble.step(dt)?;
        ensemble.reports.iter().for_each(|r| tally.add(r));
        let time = ensemble.members[0].time;
        cuts.apply(time, dt, |s| {
            ensemble.members.iter_mut().try_for_each(|m| m.cut(s))
        })?;
        let wall = step_start.elapsed().as_secs_f64();
        tally.step_seconds.push(wall);
        let lead = &ensemble.members[0];
        tally.count(time, lead.system.rod.len());
        tally.probe(scene, &lead.system, time)?;
        let now = frame(scene, &lead.system, time, lead.steps);
        for o in observers.iter_mut() {
            o.step(&now, &ensemble.reports[0], wall)?;
        }
    }
    tally.wall = start.elapsed().as_secs_f64();
    let lead = &ensemble.members[0];
    (tally.time, tally.steps) = (lead.time, lead.steps);
    let mut result = finish(scene, &lead.system, tally)?;
    result.ensemble = summaries(&scenes, &ensemble)?;
    notify_finish(
        observers,
        &frame(scene, &lead.system, lead.time, lead.steps),
        result,
    )
}

fn summaries(scenes: &[Scene], ensemble: &Ensemble) -> Result<Vec<MemberSummary>, Error> {
    let members = scenes.iter().zip(&ensemble.members).enumerate();
    members.map(|(i, (s, m))| summarize(i, s, m)).collect()
}
