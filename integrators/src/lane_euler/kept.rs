//! Steps kept in the lanes (#47): a run of batched steps whose state stays in the lanes
//! from one step to the next, so that the rods are read once at the run's start and
//! written once at its end ([`LaneEuler::step_kept`], [`LaneEuler::kept`]).
//!
//! A kept step is the batched step of [`LaneEuler::step`] with its first and last stages
//! changed: it starts from the lanes' end state of the previous kept step instead of the
//! rods' (the rods are still read for their shape, pins, damping and tolerances, which a
//! run of kept steps holds fixed), and it leaves its end state in the lanes,
//! \\(q_0 \leftarrow q_0 + h\,x\\), \\(v_0 \leftarrow x\\) — the same expressions, in the
//! same order, as the positions and velocities [`LaneEuler::step`] writes out and the
//! next step reads back, so a run of kept steps computes the same bits as the steps taken
//! one by one. The start state, counters and pin forces of the last step are kept beside
//! it for the write-back.

use super::{LaneEuler, LaneFallback, LaneOutcome, LaneStep};
use crate::convergence::ConvergenceTracker;
use crate::newton::NewtonParams;
use crate::StepStats;
use nalgebra::Vector3;
use splinerod_core::lanes::ZERO;
use splinerod_core::{Lanes, Real, Rod, LANES};

/// A step's start state: positions and velocities.
pub type StartState<'a> = (&'a [Vector3<Real>], &'a [Vector3<Real>]);

/// Where a batched step reads its start state and leaves its end state.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Keep {
    /// From the rods, to the outcomes ([`LaneEuler::step`]).
    No,
    /// From the rods, kept in the lanes (the first step of a run).
    First,
    /// From the lanes, kept in the lanes.
    Next,
}

/// The last kept step's start state, counters and pin multipliers.
#[derive(Debug, Default)]
pub(super) struct Kept {
    /// Whether a step of the current run completed in every lane (its results are kept).
    valid: bool,
    /// Whether the last call of [`LaneEuler::step_kept`] completed in every lane.
    complete: bool,
    /// Start positions and velocities of the last completed step, lane form.
    q0: Vec<Lanes>,
    v0: Vec<Lanes>,
    stats: [StepStats; LANES],
    multipliers: Vec<[Lanes; 3]>,
    dt: Real,
    start_q: [Vec<Vector3<Real>>; LANES],
    start_v: [Vec<Vector3<Real>>; LANES],
}

impl LaneEuler {
    /// One implicit Euler step for each lane, as [`Self::step`] (same arguments, same
    /// results bit for bit), with its state kept in the lanes: the `first` step of a run
    /// reads the rods' states, a later one starts from the lanes' end state of the
    /// previous call — the rods must then be the same (read only for their shape, pins,
    /// damping and tolerance) and the previous call complete (it returned `true`).
    /// Returns whether every lane completed the step. [`Self::kept`] gives each lane's
    /// result of the run's last complete step: an incomplete step leaves it as it was.
    pub fn step_kept(&mut self, step: &LaneStep<'_>, first: bool) -> Result<bool, LaneFallback> {
        if !first && !self.kept.complete {
            return Err(LaneFallback("kept state"));
        }
        if first {
            self.kept.valid = false;
        }
        self.kept.complete = false;
        self.dispatch(step, if first { Keep::First } else { Keep::Next })?;
        Ok(self.kept.complete)
    }

    /// Lane `l`'s last completed kept step of the run: its start state (positions,
    /// velocities) and its outcome, as [`Self::outcome`] gives a step's. An error if no
    /// step of the run completed.
    pub fn kept(&mut self, l: usize) -> Result<(StartState<'_>, LaneOutcome<'_>), LaneFallback> {
        if !self.kept.valid || l >= LANES {
            return Err(LaneFallback("kept state"));
        }
        let (n, dt) = (self.n, self.kept.dt);
        let k = &mut self.kept;
        let (q, v) = (&mut self.out_q[l], &mut self.out_v[l]);
        let (sq, sv) = (&mut k.start_q[l], &mut k.start_v[l]);
        for out in [&mut *q, &mut *v, &mut *sq, &mut *sv] {
            out.resize(n, Vector3::zeros());
        }
        for i in 0..n {
            for c in 0..3 {
                q[i][c] = self.q0[3 * i + c][l];
                v[i][c] = self.v0[3 * i + c][l];
                sq[i][c] = k.q0[3 * i + c][l];
                sv[i][c] = k.v0[3 * i + c][l];
            }
        }
        let forces = &mut self.forces[l];
        forces.clear();
        let mu = k.multipliers.iter();
        forces.extend(mu.map(|m| Vector3::new(m[0][l], m[1][l], m[2][l]) / dt));
        let outcome = LaneOutcome {
            positions: &self.out_q[l],
            velocities: &self.out_v[l],
            stats: k.stats[l],
            pin_forces: &self.forces[l],
        };
        Ok(((&k.start_q[l], &k.start_v[l]), outcome))
    }

    /// Ends the run of kept steps (a step not kept overwrites the lanes' state).
    pub(super) fn end_kept_run(&mut self) {
        self.kept.complete = false;
    }

    /// The per-step start of a kept step after the first: the Newton iterate and each
    /// lane's tracker start again from the lanes' state ([`Self::gather`]'s last lines).
    #[inline(always)]
    pub(super) fn restart(&mut self, rods: [&Rod; LANES], params: &NewtonParams) {
        for (tracker, rod) in self.trackers.iter_mut().zip(rods) {
            *tracker = ConvergenceTracker::new(params, rod.material().rest_length);
        }
        // x = v₀ already: the last kept step left both its end velocity (`keep_end`).
    }

    /// The end of a kept step: each lane's end state checked finite (as
    /// [`Self::scatter`]); if every lane completed, the start state, counters and pin
    /// multipliers kept and the end state made the next step's start.
    #[inline(always)]
    pub(super) fn keep_end(&mut self, dt: Real) {
        for ((t, q0), x) in self.trial.iter_mut().zip(&self.q0).zip(&self.x) {
            *t = std::array::from_fn(|l| q0[l] + x[l] * dt);
        }
        let finite = finite_lanes(&self.trial, &self.x);
        for l in 0..LANES {
            if self.failed[l].is_none() && !finite[l] {
                self.failed[l] = Some("non-finite state");
            }
        }
        if self.failed.iter().any(Option::is_some) {
            return;
        }
        let k = &mut self.kept;
        k.q0.resize(self.q0.len(), ZERO);
        k.v0.resize(self.v0.len(), ZERO);
        std::mem::swap(&mut k.q0, &mut self.q0);
        std::mem::swap(&mut self.q0, &mut self.trial);
        std::mem::swap(&mut k.v0, &mut self.v0);
        self.v0.copy_from_slice(&self.x);
        k.multipliers.clone_from(&self.multipliers);
        (k.stats, k.dt, k.complete, k.valid) = (self.stats, dt, true, true);
    }
}

/// Per lane, whether every entry of `a` and `b` is finite: one pass over the lanes, no
/// early exit and no branch. `x − x` is 0 for a finite `x` and NaN for an infinite or
/// NaN one, so a lane's sum of them stays 0 exactly while its entries are finite.
#[inline(always)]
#[allow(
    clippy::eq_op,
    reason = "x − x is the test: 0 for a finite x, NaN otherwise"
)]
fn finite_lanes(a: &[Lanes], b: &[Lanes]) -> [bool; LANES] {
    let mut sum = ZERO;
    for v in a.iter().chain(b) {
        for l in 0..LANES {
            sum[l] += v[l] - v[l];
        }
    }
    sum.map(|s| s == 0.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finite_lanes_are_those_whose_every_entry_is_finite() {
        let mut a = vec![[1.0, -2.0, 0.0, 3.5]; 6];
        let mut b = vec![[0.5; LANES]; 4];
        assert_eq!(finite_lanes(&a, &b), [true; LANES]);
        a[5][1] = Real::NAN;
        b[0][3] = Real::NEG_INFINITY;
        assert_eq!(finite_lanes(&a, &b), [true, false, true, false]);
        b[3][0] = Real::INFINITY;
        assert_eq!(finite_lanes(&a, &b), [false, false, true, false]);
        assert_eq!(finite_lanes(&[], &[]), [true; LANES]);
    }
}
