//! The convergence decisions of Newton's method, one [`ConvergenceTracker`] per solve:
//! the scalar solver ([`crate::newton::solve`]) owns one, and the batched solver
//! ([`crate::lane_euler`]) one per lane, so that a fix to a rule lands in both.
//!
//! **The rules.** With the tolerance \\(\tau = \texttt{tolerance} \cdot L\\) (m, `L` the
//! rod's rest length), an iteration's full step \\(s_k\\) (the largest move of a material
//! point, m, after any `max_step` shortening; \\(s_{-1} = s_{-2} = \infty\\)), the taken
//! step \\(t\, s_k\\) (`t` the line search's length) and the round-off band
//! \\(B = \\) [`ROUND_OFF_BAND`] \\(= 10^3\\):
//!
//! | Rule | Condition | Decision |
//! |---|---|---|
//! | iteration limit | `k = max_iterations` iterations done | stop, unconverged |
//! | divergence | \\(s_k > \\) [`DIVERGENCE_LENGTHS`] \\(\cdot L = 10^3 L\\) | the solve fails ([`IntegratorError::Diverged`]) |
//! | searched | \\(s_k > \tau\\) | the line search may shorten the step; a shorter one is taken whole (its merit change is rounding) |
//! | converging | \\(s_k \le B\tau\\) and \\(s_k < \tfrac12 s_{k-1}\\) | taken whole, without the merit test |
//! | stalled | \\(s_k \le B\tau\\), \\(s_k \ge \tfrac12 s_{k-1}\\) and \\(s_{k-1} \ge \tfrac12 s_{k-2}\\) | the tolerance widens to \\(B\tau\\) for this step |
//! | converged | \\(t\, s_k \le \tau\\) (\\(\le B\tau\\) if stalled) | stop, converged |
//! | accepted | converged, or `accept_unconverged`, or `max_iterations = 1` | the step stands ([`NewtonParams::accepts`]) |
//!
//! **Why a step test, and its round-off floor.** The unknowns are positions (or
//! velocities times the step), so the step length is the error that matters to a user,
//! in metres, relative to the rod: near a solution Newton's step is the distance to it
//! (quadratic convergence makes the next one negligible). The residual, the other
//! candidate, mixes stiff and soft directions: for EA = 1e7 N a force of 1e-7 N is a
//! 1e-14 m axial error but a 1e-8 m transverse one. But a step cannot shrink below what
//! round-off in the residual allows, `‖A⁻¹ η‖` for a residual noise `η`, which grows
//! with the conditioning (the stiff-to-soft ratio: about 1e-12 m for that cable, at a
//! 1e-12 · L tolerance). Rather than guess `η`, the tracker watches for it: when two full
//! steps in a row fail to halve while already inside the band, quadratic convergence has
//! stopped at the floor, and the step is compared with the widened tolerance instead.
//! (A definite Hessian converging linearly at rate `c` would be stopped there too, with
//! an error of at most `step / (1 − c)`.)
//!
//! **Why a converging step is taken whole.** Inside the band and at most half the step
//! before, the merit's change, about \\(\tfrac12 r \cdot \Delta x\\), can sit below the
//! merit's own rounding (the merit is a sum of terms far larger than their sum, e.g.
//! gravity's), so the line search would halve the step on noise — and a halved step
//! that then passes the step test stops Newton short of the solution by the part left
//! out (a round-off difference then moves the result by up to the tolerance). Such a
//! step is taken whole (if admissible): the next iteration measures it.

use crate::{IntegratorError, NewtonParams};
use splinerod_core::Real;

/// A Newton step moving a material point by more than this many rest lengths is taken
/// as divergence (a safety net against numerical explosion, e.g. a linearised step on a
/// rod too stiff for its time step), not as motion.
pub const DIVERGENCE_LENGTHS: Real = 1e3;

/// Width of the round-off band, in tolerances: once two full steps in a row fail to
/// halve while the step is below `ROUND_OFF_BAND · tolerance`, the iterates sit at the
/// floor that round-off sets for the problem's conditioning (see the module docs).
pub const ROUND_OFF_BAND: Real = 1e3;

/// How an iteration ended ([`ConvergenceTracker::verdict`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NewtonVerdict {
    /// The taken step is within the tolerance: the solve is done.
    Converged,
    /// The taken step is within the widened tolerance of a stalled solve (module docs):
    /// the solve is done, at the round-off floor.
    Stalled,
    /// Iterate again (if the iteration limit allows).
    Continue,
}

impl NewtonVerdict {
    /// Whether the solve is done ([`Self::Converged`] or [`Self::Stalled`]).
    pub fn done(self) -> bool {
        self != NewtonVerdict::Continue
    }
}

/// The state of one Newton solve's convergence decisions (module docs): its tolerance
/// and divergence limit, the iterations done and the last two full steps. Small and
/// `Copy`: no allocation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConvergenceTracker {
    /// \\(\tau\\), m.
    tolerance: Real,
    /// The divergence limit, m.
    limit: Real,
    /// Iterations started.
    iterations: usize,
    /// The iteration limit.
    max_iterations: usize,
    /// \\(s_{k-1}, s_{k-2}\\), m.
    previous: [Real; 2],
}

impl Default for ConvergenceTracker {
    /// A tracker for a rod of unit length with the default [`NewtonParams`].
    fn default() -> Self {
        Self::new(&NewtonParams::default(), 1.0)
    }
}

impl ConvergenceTracker {
    /// A fresh solve's tracker with `params`' tolerance and iteration limit, for a rod
    /// of rest length `rest_length` (m).
    pub fn new(params: &NewtonParams, rest_length: Real) -> Self {
        Self {
            tolerance: params.tolerance * rest_length,
            limit: DIVERGENCE_LENGTHS * rest_length,
            iterations: 0,
            max_iterations: params.max_iterations,
            previous: [Real::INFINITY; 2],
        }
    }

    /// The tolerance \\(\tau\\), m.
    pub fn tolerance(&self) -> Real {
        self.tolerance
    }

    /// The iterations started so far.
    pub fn iterations(&self) -> usize {
        self.iterations
    }

    /// Starts an iteration if the iteration limit allows one (and counts it); false
    /// once `max_iterations` have been started.
    pub fn next_iteration(&mut self) -> bool {
        let more = self.iterations < self.max_iterations;
        self.iterations += usize::from(more);
        more
    }

    /// The divergence rule: an error if the full step `full` (m) exceeds the limit.
    pub fn check_divergence(&self, full: Real) -> Result<(), IntegratorError> {
        if full > self.limit {
            return Err(IntegratorError::Diverged {
                step: full,
                limit: self.limit,
            });
        }
        Ok(())
    }

    /// Whether the full step `full` (m) is long enough for the line search to judge:
    /// longer than the tolerance (a shorter one is taken whole).
    pub fn searches(&self, full: Real) -> bool {
        full > self.tolerance
    }

    /// The converging rule: whether the full step `full` (m) is Newton converging near
    /// its solution — inside the round-off band and less than half the step before —
    /// and is to be taken whole (module docs).
    pub fn converging(&self, full: Real) -> bool {
        full <= ROUND_OFF_BAND * self.tolerance && full < 0.5 * self.previous[0]
    }

    /// Ends an iteration whose full step was `full` and whose taken step `taken` (m):
    /// converged if `taken` is within the tolerance, widened when the steps stall.
    pub fn verdict(&mut self, full: Real, taken: Real) -> NewtonVerdict {
        self.verdict_with(full, taken, |step, tolerance| step <= tolerance)
    }

    /// [`Self::verdict`] with the comparison `within(taken, tolerance)` of a problem
    /// that adds conditions to it ([`crate::newton::NewtonProblem::converged`]).
    pub fn verdict_with(
        &mut self,
        full: Real,
        taken: Real,
        within: impl FnOnce(Real, Real) -> bool,
    ) -> NewtonVerdict {
        let band = ROUND_OFF_BAND * self.tolerance;
        let [p0, p1] = self.previous;
        let stalled = full <= band && full >= 0.5 * p0 && p0 >= 0.5 * p1;
        self.previous = [full, p0];
        let reach = if stalled { band } else { self.tolerance };
        match (within(taken, reach), stalled) {
            (false, _) => NewtonVerdict::Continue,
            (true, false) => NewtonVerdict::Converged,
            (true, true) => NewtonVerdict::Stalled,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn tracker(max_iterations: usize) -> ConvergenceTracker {
        let params = NewtonParams {
            max_iterations,
            tolerance: 1e-10,
            ..NewtonParams::default()
        };
        ConvergenceTracker::new(&params, 2.0)
    }

    #[test]
    fn the_iteration_limit_counts_started_iterations() {
        let mut t = tracker(2);
        assert!(t.next_iteration() && t.next_iteration());
        assert!(!t.next_iteration());
        assert_eq!(t.iterations(), 2);
    }

    #[test]
    fn a_step_beyond_a_thousand_rest_lengths_diverges() {
        let t = tracker(10);
        assert!(t.check_divergence(2e3).is_ok());
        let err = t.check_divergence(2.1e3).unwrap_err();
        assert!(matches!(err, IntegratorError::Diverged { limit, .. } if limit == 2e3));
    }

    #[test]
    fn quadratic_convergence_stops_at_the_tolerance() {
        let mut t = tracker(10);
        let tol = t.tolerance();
        assert_eq!(tol, 2e-10);
        assert!(t.searches(1.0) && !t.converging(1.0));
        assert_eq!(t.verdict(1.0, 1.0), NewtonVerdict::Continue);
        assert!(t.converging(1e-8) && !t.converging(1e-6));
        assert_eq!(t.verdict(1e-8, 1e-8), NewtonVerdict::Continue);
        assert!(!t.searches(tol) && t.converging(tol));
        assert_eq!(t.verdict(tol, tol), NewtonVerdict::Converged);
        // A taken step shortened below the tolerance ends the solve too.
        let mut t = tracker(10);
        assert_eq!(t.verdict(1.0, 0.5 * tol), NewtonVerdict::Converged);
    }

    #[test]
    fn steps_that_stop_halving_in_the_band_widen_the_tolerance() {
        let mut t = tracker(10);
        let tol = t.tolerance();
        assert_eq!(t.verdict(40.0 * tol, 40.0 * tol), NewtonVerdict::Continue);
        // Halving: not stalled, not converged.
        assert_eq!(t.verdict(30.0 * tol, 30.0 * tol), NewtonVerdict::Continue);
        // The second step in a row that fails to halve: stalled within B τ.
        assert!(!t.converging(20.0 * tol));
        assert_eq!(t.verdict(20.0 * tol, 20.0 * tol), NewtonVerdict::Stalled);
        // Outside the band no step stalls.
        let mut t = tracker(10);
        for _ in 0..3 {
            assert_eq!(t.verdict(2e3 * tol, 2e3 * tol), NewtonVerdict::Continue);
        }
        // A problem's own test decides with the widened tolerance.
        let mut t = tracker(10);
        t.verdict(5.0 * tol, 5.0 * tol);
        t.verdict(4.0 * tol, 4.0 * tol);
        let verdict = t.verdict_with(4.0 * tol, 4.0 * tol, |_, reach| {
            assert_eq!(reach, ROUND_OFF_BAND * tol);
            false
        });
        assert_eq!(verdict, NewtonVerdict::Continue);
    }
}
