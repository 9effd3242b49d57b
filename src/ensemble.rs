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
        self.reports
            .resize(self.members.len(), StepReport::default());
        let first_error = step_all(&mut self.members, &mut self.reports, dt);
        match first_error {
            Some((index, e)) => Err(Error::Scene(format!("ensemble member {index}: {e}"))),
            None => Ok(()),
        }
    }
}

/// Steps one member, recording its report; the error with the member's index.
fn step_one(
    i: usize,
    sim: &mut Simulation,
    report: &mut StepReport,
    dt: Real,
) -> Option<(usize, Error)> {
    match sim.step(dt) {
        Ok(r) => {
            *report = r;
            None
        }
        Err(e) => Some((i, e)),
    }
}

#[cfg(feature = "parallel")]
fn step_all(
    members: &mut [Simulation],
    reports: &mut [StepReport],
    dt: Real,
) -> Option<(usize, Error)> {
    use rayon::prelude::*;
    members
        .par_iter_mut()
        .zip(reports.par_iter_mut())
        .enumerate()
        .filter_map(|(i, (sim, report))| step_one(i, sim, report, dt))
        .min_by_key(|(i, _)| *i)
}

#[cfg(not(feature = "parallel"))]
fn step_all(
    members: &mut [Simulation],
    reports: &mut [StepReport],
    dt: Real,
) -> Option<(usize, Error)> {
    let mut first = None;
    for (i, (sim, report)) in members.iter_mut().zip(reports.iter_mut()).enumerate() {
        if let Some(e) = step_one(i, sim, report, dt) {
            first.get_or_insert(e);
        }
    }
    first
}
