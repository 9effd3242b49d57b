//! Ensembles: many independent rods (each with its own basis, energies, pins, integrator
//! workspace and adaptivity, so they may differ in size) stepped together. With the
//! `parallel` feature (default) the rods are spread over rayon's thread pool; every rod
//! is advanced by exactly the same operations whatever the thread count, so results are
//! bit-identical with 1 or many threads.

//!
//! Members that share a shape are solved [`LANES`] at a time by the batched implicit
//! Euler step (see [`crate::world::lanes`]; [`Ensemble::batched`], on by default): each
//! still takes its own step through every stage, with the same result up to round-off,
//! and a member's bits depend neither on the grouping nor on its lane-mates (a member
//! alone is solved in the lanes too), so results stay bit-identical for any thread
//! count and any split into shards (under one kernel set, [`splinerod_core::kernels`]).
//! [`Ensemble::advance`] takes many steps in one call, a group at a time, keeping the
//! lanes' state between the steps of a group that can (`world/kept.rs`).

use crate::world::kept::advance_group;
use crate::world::lanes::preload_group;
use crate::world::unbatched::Unbatched;
use crate::{Error, Simulation, StepReport};
use splinerod_core::{Real, LANES};

/// Independent simulations advanced in lock step.
#[derive(Debug)]
pub struct Ensemble {
    /// The members, in order.
    pub members: Vec<Simulation>,
    /// What each member's last step did (same order).
    pub reports: Vec<StepReport>,
    /// Solve the steps of members that share a shape [`LANES`] at a time (the batched
    /// step, `world/lanes.rs`). Default true; false steps every member alone.
    pub batched: bool,
    /// Index of the first member in the whole ensemble (a shard's first member): the
    /// groups of [`LANES`] start at multiples of [`LANES`] in that numbering, so a
    /// shard groups, and computes, its members exactly as a run of the whole ensemble
    /// does. Default 0.
    pub first_index: usize,
}

impl Default for Ensemble {
    fn default() -> Self {
        Self::new(Vec::new())
    }
}

impl Ensemble {
    /// An ensemble of `members`.
    pub fn new(members: Vec<Simulation>) -> Self {
        let reports = vec![StepReport::default(); members.len()];
        Self {
            members,
            reports,
            batched: true,
            first_index: 0,
        }
    }

    /// Number of members.
    pub fn len(&self) -> usize {
        self.members.len()
    }

    /// Whether there are no members.
    pub fn is_empty(&self) -> bool {
        self.members.is_empty()
    }

    /// Advances every member by `dt` (in parallel with the `parallel` feature). Members
    /// whose step fails keep their state; the error of the first failing member (by
    /// index) is returned after all members have been tried. Each member's report says
    /// why its step was solved alone, if it was ([`StepReport::unbatched`]).
    pub fn step(&mut self, dt: Real) -> Result<(), Error> {
        let batched = self.batched;
        self.groups(|first, members, reports| step_group(first, members, reports, dt, batched))
    }

    /// `steps` steps of `dt`: the same results, bit for bit, as [`Ensemble::step`]
    /// called `steps` times under the same kernel set, for any thread count and shard
    /// (a member whose step fails keeps its state at that step's start and tries the
    /// next step from there; the error of the first failing member by index is
    /// returned at the end), faster. Each group of [`LANES`] members takes
    /// all its steps before the next group starts (so its data stays in the caches),
    /// and a group whose members are all batched with nothing to do between steps but
    /// the solve keeps its state in the lanes from one step to the next and writes it
    /// back into the members once, at the end (`world/kept.rs`). Members' public
    /// fields are current when the call returns; [`Ensemble::reports`] are the last
    /// step's.
    pub fn advance(&mut self, dt: Real, steps: usize) -> Result<(), Error> {
        let batched = self.batched;
        self.groups(|first, members, reports| {
            advance_group(first, members, reports, (dt, steps), batched)
        })
    }

    /// Every member's [`Simulation::settle`] (the static solve), as [`Ensemble::step`].
    pub fn settle(&mut self) -> Result<(), Error> {
        let prepare = |_: &mut [Simulation], _: &mut [Option<Unbatched>]| {};
        self.each(prepare, Simulation::settle, false)
    }

    /// Runs `prepare` on every group of [`LANES`] consecutive members, then `stage` on
    /// each of its members, recording the reports (and, for a time step (`timed`), why
    /// each member's step was solved alone).
    fn each(
        &mut self,
        prepare: impl Fn(&mut [Simulation], &mut [Option<Unbatched>]) + Sync,
        stage: impl Fn(&mut Simulation) -> Result<StepReport, Error> + Sync,
        timed: bool,
    ) -> Result<(), Error> {
        let steps = Stages {
            prepare: &prepare,
            stage: &stage,
            timed,
        };
        self.groups(|first, members, reports| steps.group(first, members, reports))
    }

    /// Runs `group` on every group of at most [`LANES`] consecutive members (with the
    /// index of its first member and its reports); the error of the first failing member.
    fn groups(
        &mut self,
        group: impl Fn(usize, &mut [Simulation], &mut [StepReport]) -> Failure + Sync,
    ) -> Result<(), Error> {
        self.reports
            .resize(self.members.len(), StepReport::default());
        let failed = match (self.members.as_mut_slice(), self.reports.as_mut_slice()) {
            // One member (a single run, or a shard of one): no thread pool round trip
            // (tens of µs a step); batched all the same, its lanes repeated.
            (members @ [_], reports) => group(0, members, reports),
            (members, reports) => {
                // The first group ends at the next multiple of LANES (in the whole
                // ensemble's numbering): the grouping of a shard is the whole run's.
                let head = (LANES - self.first_index % LANES) % LANES;
                let head = head.min(members.len());
                let (first, rest) = members.split_at_mut(head);
                let (first_reports, rest_reports) = reports.split_at_mut(head);
                let failed = group(0, first, first_reports);
                let later = stage_all(head, rest, rest_reports, &group);
                failed.or(later)
            }
        };
        match failed {
            Some((index, e)) => Err(Error::Member {
                index,
                source: Box::new(e),
            }),
            None => Ok(()),
        }
    }
}

/// A group's first failing member (its index in the ensemble) and its error, if any.
pub(crate) type Failure = Option<(usize, Error)>;

/// One step of `dt` of the group of members starting at `first` ([`Ensemble::step`]'s
/// stages: the batched solve with the ensemble's setting `batched`, then each member's
/// step); the error of its first failing member.
pub(crate) fn step_group(
    first: usize,
    members: &mut [Simulation],
    reports: &mut [StepReport],
    dt: Real,
    batched: bool,
) -> Failure {
    let prepare = move |group: &mut [Simulation], alone: &mut [Option<Unbatched>]| {
        preload_group(group, dt, batched, alone);
    };
    let stage = |sim: &mut Simulation| sim.step(dt);
    let steps = Stages {
        prepare: &prepare,
        stage: &stage,
        timed: true,
    };
    steps.group(first, members, reports)
}

/// What [`Ensemble::each`] runs on each group: `prepare`, then `stage` on every member.
struct Stages<'a, P, S> {
    prepare: &'a P,
    stage: &'a S,
    timed: bool,
}

impl<P, S> Stages<'_, P, S>
where
    P: Fn(&mut [Simulation], &mut [Option<Unbatched>]) + Sync,
    S: Fn(&mut Simulation) -> Result<StepReport, Error> + Sync,
{
    /// The stages of the group of members (at most [`LANES`]) starting at `first`; the
    /// error of its first failing member.
    fn group(
        &self,
        first: usize,
        members: &mut [Simulation],
        reports: &mut [StepReport],
    ) -> Option<(usize, Error)> {
        let mut alone = [None; LANES];
        let alone = &mut alone[..members.len().min(LANES)];
        (self.prepare)(&mut members[..alone.len()], alone);
        let mut failed = None;
        for (j, (sim, report)) in members.iter_mut().zip(reports).enumerate() {
            if let Some(e) = stage_one(first + j, sim, report, self.stage) {
                failed.get_or_insert(e);
                continue;
            }
            if self.timed {
                let why = alone.get(j).copied().flatten();
                report.unbatched = Unbatched::of_step(why, report.solver.batched > 0);
            }
        }
        failed
    }
}

/// The stage of one member, recording its report; the error with the member's index.
fn stage_one(
    i: usize,
    sim: &mut Simulation,
    report: &mut StepReport,
    stage: &(impl Fn(&mut Simulation) -> Result<StepReport, Error> + Sync),
) -> Option<(usize, Error)> {
    match stage(sim) {
        Ok(r) => {
            *report = r;
            None
        }
        Err(e) => Some((i, e)),
    }
}

/// `group` on every group of [`LANES`] members, the first being member `offset`; the
/// error of the first failing member.
#[cfg(feature = "parallel")]
fn stage_all(
    offset: usize,
    members: &mut [Simulation],
    reports: &mut [StepReport],
    group: &(impl Fn(usize, &mut [Simulation], &mut [StepReport]) -> Failure + Sync),
) -> Failure {
    use rayon::prelude::*;
    members
        .par_chunks_mut(LANES)
        .zip(reports.par_chunks_mut(LANES))
        .enumerate()
        .filter_map(|(g, (sims, reports))| group(offset + g * LANES, sims, reports))
        .min_by_key(|(i, _)| *i)
}

/// `group` on every group of [`LANES`] members, the first being member `offset`; the
/// error of the first failing member.
#[cfg(not(feature = "parallel"))]
fn stage_all(
    offset: usize,
    members: &mut [Simulation],
    reports: &mut [StepReport],
    group: &(impl Fn(usize, &mut [Simulation], &mut [StepReport]) -> Failure + Sync),
) -> Failure {
    let groups = members.chunks_mut(LANES).zip(reports.chunks_mut(LANES));
    let mut first = None;
    for (g, (sims, reports)) in groups.enumerate() {
        if let Some(e) = group(offset + g * LANES, sims, reports) {
            first.get_or_insert(e);
        }
    }
    first
}
