//! Ensembles: many independent rods (each with its own basis, energies, pins, integrator
//! workspace and adaptivity, so they may differ in size) stepped together. With the
//! `parallel` feature (default) the rods are spread over rayon's thread pool; every rod
//! is advanced by exactly the same operations whatever the thread count, so results are
//! bit-identical with 1 or many threads.

//!
//! Members that share a shape are solved [`LANES`] at a time by the batched implicit
//! Euler step (see [`crate::world::lanes`]; [`Ensemble::batched`], on by default): each
//! still takes its own step through every stage, with the same result up to round-off,
//! and the grouping depends only on the members' order, so results stay bit-identical
//! for any thread count.

use crate::world::lanes::preload_group;
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
    /// step, [`crate::world::lanes`]). Default true; false steps every member alone.
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
    /// index) is returned after all members have been tried.
    pub fn step(&mut self, dt: Real) -> Result<(), Error> {
        let batched = self.batched;
        let prepare = move |group: &mut [Simulation]| {
            if batched {
                preload_group(group, dt);
            }
        };
        self.each(prepare, |sim| sim.step(dt))
    }

    /// Every member's [`Simulation::settle`] (the static solve), as [`Ensemble::step`].
    pub fn settle(&mut self) -> Result<(), Error> {
        self.each(|_: &mut [Simulation]| {}, Simulation::settle)
    }

    /// Runs `prepare` on every group of [`LANES`] consecutive members, then `stage` on
    /// each of its members, recording the reports.
    fn each(
        &mut self,
        prepare: impl Fn(&mut [Simulation]) + Sync,
        stage: impl Fn(&mut Simulation) -> Result<StepReport, Error> + Sync,
    ) -> Result<(), Error> {
        self.reports
            .resize(self.members.len(), StepReport::default());
        // One member (a single run): no thread pool round trip (tens of µs a step), and
        // nothing to batch.
        let failed = match (self.members.as_mut_slice(), self.reports.as_mut_slice()) {
            ([sim], [report]) => stage_one(0, sim, report, &stage),
            (members, reports) => {
                // The first group ends at the next multiple of LANES (in the whole
                // ensemble's numbering): the grouping of a shard is the whole run's.
                let head = (LANES - self.first_index % LANES) % LANES;
                let head = head.min(members.len());
                let (first, rest) = members.split_at_mut(head);
                let (first_reports, rest_reports) = reports.split_at_mut(head);
                let failed = stage_group(0, first, first_reports, &prepare, &stage);
                let later = stage_all(head, rest, rest_reports, &prepare, &stage);
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

/// [`Ensemble::each`]'s stages of the group of members starting at `first`; the error
/// of its first failing member.
fn stage_group(
    first: usize,
    members: &mut [Simulation],
    reports: &mut [StepReport],
    prepare: &(impl Fn(&mut [Simulation]) + Sync),
    stage: &(impl Fn(&mut Simulation) -> Result<StepReport, Error> + Sync),
) -> Option<(usize, Error)> {
    prepare(members);
    let mut failed = None;
    for (j, (sim, report)) in members.iter_mut().zip(reports).enumerate() {
        if let Some(e) = stage_one(first + j, sim, report, stage) {
            failed.get_or_insert(e);
        }
    }
    failed
}

/// [`stage_group`] on every group of [`LANES`] members, the first being member
/// `offset`; the error of the first failing member.
#[cfg(feature = "parallel")]
fn stage_all(
    offset: usize,
    members: &mut [Simulation],
    reports: &mut [StepReport],
    prepare: &(impl Fn(&mut [Simulation]) + Sync),
    stage: &(impl Fn(&mut Simulation) -> Result<StepReport, Error> + Sync),
) -> Option<(usize, Error)> {
    use rayon::prelude::*;
    members
        .par_chunks_mut(LANES)
        .zip(reports.par_chunks_mut(LANES))
        .enumerate()
        .filter_map(|(g, (sims, reports))| {
            stage_group(offset + g * LANES, sims, reports, prepare, stage)
        })
        .min_by_key(|(i, _)| *i)
}

/// [`stage_group`] on every group of [`LANES`] members, the first being member
/// `offset`; the error of the first failing member.
#[cfg(not(feature = "parallel"))]
fn stage_all(
    offset: usize,
    members: &mut [Simulation],
    reports: &mut [StepReport],
    prepare: &(impl Fn(&mut [Simulation]) + Sync),
    stage: &(impl Fn(&mut Simulation) -> Result<StepReport, Error> + Sync),
) -> Option<(usize, Error)> {
    let groups = members.chunks_mut(LANES).zip(reports.chunks_mut(LANES));
    let mut first = None;
    for (g, (sims, reports)) in groups.enumerate() {
        if let Some(e) = stage_group(offset + g * LANES, sims, reports, prepare, stage) {
            first.get_or_insert(e);
        }
    }
    first
}
