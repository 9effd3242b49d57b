//! [`StepReport`]: what one step of a [`crate::Simulation`] did, stage by stage.
//!
//! A step runs named stages, each timed on its own ([`StageTimes`]): **drivers** (the
//! grabs' targets move to the end of each sub-step), **setup** (every energy's
//! per-step hook, [`splinerod_energies::Lifecycle::begin_step`]), **integrate** (the
//! integrator's Newton solves, recomputed steps included), **adapt** (error estimate,
//! marks, knot maps) and **record** (probes, histories and trackers of a run, filled in
//! by the run loop; observers are not timed).

use serde::Serialize;
use splinerod_adaptivity::AdaptReport;
use splinerod_core::Real;
use splinerod_energies::EnergySummary;
use splinerod_integrators::StepStats;
use std::ops::AddAssign;

use crate::world::substep::SubstepCounts;
use crate::world::unbatched::Unbatched;

/// Wall time of each stage of a step, s.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, serde::Deserialize)]
pub struct StageTimes {
    /// Grabs and other drivers moving to their targets.
    pub drivers: Real,
    /// The energies' per-step setup (contact freezing its friction data).
    pub setup: Real,
    /// The integrator's solves (all sub-steps and recomputed steps).
    pub integrate: Real,
    /// Error estimate and adaptivity (of rejected steps too).
    pub adapt: Real,
    /// Recording by the run loop (probes, histories, knot tracking).
    pub record: Real,
}

impl StageTimes {
    /// Names of the stages, in the order of [`StageTimes::values`] (CSV columns, JSON).
    pub const NAMES: [&'static str; 5] = ["drivers", "setup", "integrate", "adapt", "record"];

    /// The stage times in the order of [`StageTimes::NAMES`].
    pub fn values(&self) -> [Real; 5] {
        [
            self.drivers,
            self.setup,
            self.integrate,
            self.adapt,
            self.record,
        ]
    }

    /// Sum of all stages, s.
    pub fn total(&self) -> Real {
        self.values().iter().sum()
    }
}

impl AddAssign for StageTimes {
    fn add_assign(&mut self, other: StageTimes) {
        self.drivers += other.drivers;
        self.setup += other.setup;
        self.integrate += other.integrate;
        self.adapt += other.adapt;
        self.record += other.record;
    }
}

/// What one step did and how long each stage took.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Solver counters of the integration stage.
    pub solver: StepStats,
    /// Knots inserted and removed by the adapt stage.
    pub adapt: AdaptReport,
    /// Control points after the step.
    pub control_points: usize,
    /// Wall time of each stage, s.
    pub stages: StageTimes,
    /// Sub-steps taken, rejected and the shortest one (see [`crate::world::substep`]).
    pub substeps: SubstepCounts,
    /// What the energies report at the end of the step (contacts, ...).
    pub energies: EnergySummary,
    /// The error estimate made at this step, m (`None` when none was due).
    pub error_estimate: Option<Real>,
    /// For a member of an [`crate::Ensemble`]: why its step was solved alone instead of
    /// in the lanes of the batched step (`None` for a batched step, a static solve or a
    /// simulation stepped on its own).
    pub unbatched: Option<Unbatched>,
}
