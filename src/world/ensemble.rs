//! Ensembles: many independent rods (each with its own basis, energies, pins, integrator
//! workspace and adaptivity, so they may differ in size) stepped together. With the
//! `parallel` feature (default) the rods are spread over rayon's thread pool; every rod
//! is advanced by exactly the same operations whatever the thread count, so results are
//! bit-identical with 1 or many threads.

use crate::{Error, Simulation, StepReport};
use splinerod_core::Real;

/// Independent simulations advanced in lock step.
#[derive(Debug, Default)]
pub struct Ensemble {
    /// The members, in order.
    pub members: Vec<Simulation>,
    /// What each member's last step did (same order).
    pub reports: Vec<StepReport>,
}

impl Ensemble {
    /// An ensemble of `members`.
    pub fn new(members: Vec<Simulation>) -> Self {
        let reports = vec![StepReport::default(); members.len()];
        Self { members, reports }
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
        self.each(|sim| sim.step(dt))
    }

    /// Every member's [`Simulation::settle`] (the static solve), as [`Ensemble::step`].
    pub fn settle(&mut self) -> Result<(), Error> {
        self.each(Simulation::settle)
    }

    /// Runs `stage` on every member, recording the reports.
    fn each(
        &mut self,
        stage: impl Fn(&mut Simulation) -> Result<StepReport, Error> + Sync,
    ) -> Result<(), Error> {
        self.reports
            .resize(self.members.len(), StepReport::default());
        // One member (a single run): no thread pool round trip (tens of µs a step).
        let failed = match (self.members.as_mut_slice(), self.reports.as_mut_slice()) {
            ([sim], [report]) => stage_one(0, sim, report, &stage),
            (members, reports) => stage_all(members, reports, &stage),
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

#[cfg(feature = "parallel")]
fn stage_all(
    members: &mut [Simulation],
    reports: &mut [StepReport],
    stage: &(impl Fn(&mut Simulation) -> Result<StepReport, Error> + Sync),
) -> Option<(usize, Error)> {
    use rayon::prelude::*;
    members
        .par_iter_mut()
        .zip(reports.par_iter_mut())
        .enumerate()
        .filter_map(|(i, (sim, report))| stage_one(i, sim, report, stage))
        .min_by_key(|(i, _)| *i)
}

#[cfg(not(feature = "parallel"))]
fn stage_all(
    members: &mut [Simulation],
    reports: &mut [StepReport],
    stage: &(impl Fn(&mut Simulation) -> Result<StepReport, Error> + Sync),
) -> Option<(usize, Error)> {
    let mut first = None;
    for (i, (sim, report)) in members.iter_mut().zip(reports.iter_mut()).enumerate() {
        if let Some(e) = stage_one(i, sim, report, stage) {
            first.get_or_insert(e);
        }
    }
    first
}
