//! What a run folds over its stages and members: [`SolverTotals`], the solver counters
//! (JSON `solver`), and [`ContactStats`], the contact seen (JSON `contact`).

use crate::{StepReport, UnbatchedCounts};
use serde::Serialize;
use splinerod_core::Real;
use splinerod_energies::ContactSummary;
use std::ops::AddAssign;

/// Solver counters summed over the run.
#[derive(Debug, Clone, Copy, Default, Serialize, serde::Deserialize, PartialEq)]
pub struct SolverTotals {
    /// Newton iterations (numeric factorisations).
    pub newton_iterations: usize,
    /// Symbolic analyses.
    pub symbolic_analyses: usize,
    /// Line-search step reductions.
    pub line_search_cuts: usize,
    /// Steps whose Newton iterations did not reach the tolerance (only with
    /// `solver.accept_unconverged = true`; otherwise such a step is split).
    pub unconverged_steps: usize,
    /// Integrator steps accepted (sub-steps; equals `steps` when none was split).
    pub substeps: usize,
    /// Sub-steps rolled back and retried shorter.
    pub rejected_steps: usize,
    /// Shortest accepted sub-step, s (`null` for a static solve).
    pub smallest_dt: Option<Real>,
    /// Pseudo-transient continuation steps of a static solve whose Newton failed.
    pub continuation_steps: usize,
    /// Multiplier updates of an inextensible rod (static: until the mean strain of every
    /// tension function is below 1e-12; dynamic: one per step).
    pub multiplier_updates: usize,
    /// Conjugate-gradient iterations correcting Newton steps for a Hessian remainder
    /// (`stretch_formulation = "mixed-consistent"`; 0 otherwise).
    pub remainder_iterations: usize,
    /// Knots the adapt stage inserted.
    pub knots_inserted: usize,
    /// Knots the adapt stage removed.
    pub knots_removed: usize,
    /// Steps recomputed on a finer basis because their error estimate was rejected.
    pub redone_steps: usize,
    /// Steps whose solve an ensemble batched with other members' (four at a time, see
    /// [`crate::Ensemble::batched`]); 0 for a single run.
    #[serde(default)]
    pub batched_steps: usize,
    /// Steps of `[ensemble]` members solved alone, per reason ([`crate::Unbatched`]):
    /// an object of the nonzero counts (empty for a single run, which is not batched).
    #[serde(default)]
    pub unbatched: UnbatchedCounts,
}

impl SolverTotals {
    /// Adds one stage's counters; `timed`: a time step (a static solve has no sub-steps
    /// or step lengths to count).
    pub(crate) fn add(&mut self, report: &StepReport, timed: bool) {
        let s = &report.solver;
        self.newton_iterations += s.newton_iterations;
        self.symbolic_analyses += s.symbolic_analyses;
        self.line_search_cuts += s.line_search_cuts;
        self.continuation_steps += s.continuation_steps;
        self.multiplier_updates += s.multiplier_updates;
        self.remainder_iterations += s.remainder_iterations;
        self.batched_steps += s.batched;
        if let Some(reason) = report.unbatched {
            self.unbatched.add(reason);
        }
        self.knots_inserted += report.adapt.inserted;
        self.knots_removed += report.adapt.removed;
        self.redone_steps += report.adapt.redone_steps;
        if !timed {
            return;
        }
        self.unconverged_steps += usize::from(!s.converged);
        self.substeps += report.substeps.substeps;
        self.rejected_steps += report.substeps.rejected;
        let h = report.substeps.smallest_dt;
        self.smallest_dt = Some(self.smallest_dt.map_or(h, |s| s.min(h)));
    }
}

/// Totals of several runs (an ensemble's members).
impl AddAssign for SolverTotals {
    fn add_assign(&mut self, o: SolverTotals) {
        self.newton_iterations += o.newton_iterations;
        self.symbolic_analyses += o.symbolic_analyses;
        self.line_search_cuts += o.line_search_cuts;
        self.unconverged_steps += o.unconverged_steps;
        self.substeps += o.substeps;
        self.rejected_steps += o.rejected_steps;
        self.smallest_dt = match (self.smallest_dt, o.smallest_dt) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        self.continuation_steps += o.continuation_steps;
        self.multiplier_updates += o.multiplier_updates;
        self.remainder_iterations += o.remainder_iterations;
        self.batched_steps += o.batched_steps;
        self.unbatched += o.unbatched;
        self.knots_inserted += o.knots_inserted;
        self.knots_removed += o.knots_removed;
        self.redone_steps += o.redone_steps;
    }
}

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
