//! Adaptive sub-stepping: one call of [`Simulation::step`] covers its `dt` (the output
//! interval and the largest step) with as many integrator steps as it takes.
//!
//! A sub-step whose Newton solve fails — stops at the iteration limit, diverges, meets
//! a non-finite value or an indefinite matrix — is rolled back by the integrator and
//! retried at half the length (but not below [`StepControl::min_dt`]); when a sub-step
//! of `min_dt` fails the whole step fails and the state is restored. The length tried
//! never goes below `min_dt`; only a rest of the step under twice that length is cut
//! into two equal pieces (no sliver at the end), each at least half of it. After a
//! success the length doubles again, but not back to a length that just failed until
//! [`RECOVERY_STEPS`] sub-steps in a row succeeded (so that a step length on the edge
//! does not fail every other time). The next call starts from the length the last one
//! reached.
//!
//! **Time error control** (optional, [`StepControl::time_tolerance`] = τ, metres): after
//! each sub-step of length `h` the local error of implicit Euler,
//!
//! \\[ e = \tfrac h2 \max_i \lVert v_i^+ - v_i^0 \rVert \\]
//!
//! (the gap between its end point and the trapezoidal one; the control-point bound holds
//! for every material point, the basis being a partition of unity), is compared with τ:
//! `e > τ` rejects the sub-step, and the next length is \\(h \min(2, \max(0.2,
//! 0.9\sqrt{\tau / e}))\\) (the error is \\(O(h^2)\\) per step), never below `min_dt`;
//! a sub-step of `min_dt` with `e > τ` fails the step ([`Error::MinDtReached`], naming
//! `solver.min_dt`: a tolerance too tight for the shortest step allowed), as does one
//! that fails the energy guard below. For the
//! second-order schemes it overestimates the local error, so τ is then a conservative
//! bound.
//!
//! **Interruption.** Every sub-step first polls the system's [`splinerod_core::Cancel`]
//! (as Newton does every iteration): an abandoned step returns
//! [`IntegratorError::Interrupted`] and the caller restores the state.
//!
//! **Energy guard.** A scheme that conserves energy ([`Integrator::conserves_energy`]:
//! the implicit midpoint rule) is not unconditionally stable for nonlinear elasticity:
//! at long steps it can pump energy into the stiff modes until it blows up. The total
//! energy `H` (kinetic `K` plus potential) may only grow by the work `W` of the grabs'
//! moving targets `p` and of driven pins (the only forces that do work on a
//! [`crate::RodSystem`] during a step; damping and fixed pins take energy out or do
//! none): for the grabs estimated by the trapezoidal rule in the state,
//! \\(W \approx \tfrac12\big[E(q^0, p^1) - E(q^0, p^0) + E(q^+, p^1) -
//! E(q^+, p^0)\big]\\), for a driven pin its force during the step times its
//! displacement. A sub-step with \\(H^+ - H^0 - W > 10^{-2} (K^0 + K^+)\\)
//! ([`ENERGY_GAIN`]) is rejected and halved like a failed solve.
//!
//! [`Integrator::conserves_energy`]: splinerod_integrators::Integrator::conserves_energy

use crate::{Error, Simulation};
use nalgebra::Vector3;
use splinerod_core::Real;
use splinerod_integrators::Role;
use splinerod_integrators::{IntegratorError, StepStats};
use std::time::Instant;

/// After a rejection, sub-steps in a row that must succeed before the length may grow
/// back to the rejected one.
pub const RECOVERY_STEPS: usize = 8;

/// Energy an energy-conserving scheme may gain in one sub-step without forces doing
/// work, relative to the kinetic energy: beyond it the step is rejected as unstable.
pub const ENERGY_GAIN: Real = 1e-2;

/// Default smallest sub-step, as a fraction of the step.
pub const DEFAULT_MIN_DT_FRACTION: Real = 1e-6;

/// Settings of the sub-stepping controller.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepControl {
    /// Smallest sub-step, s; `None`: `dt · 1e-6` ([`DEFAULT_MIN_DT_FRACTION`]).
    pub min_dt: Option<Real>,
    /// Local time-discretisation error allowed per sub-step, m; `None`: no time error
    /// control (only failed solves shorten the step).
    pub time_tolerance: Option<Real>,
}

/// What the sub-steps of one step did.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SubstepCounts {
    /// Accepted sub-steps (1 when the step was taken whole).
    pub substeps: usize,
    /// Sub-steps rolled back and retried shorter.
    pub rejected: usize,
    /// Shortest accepted sub-step, s.
    pub smallest_dt: Real,
}

/// The controller's memory between steps.
#[derive(Debug, Clone, Default)]
pub(crate) struct SubstepState {
    /// Length to try first at the next step.
    next: Option<Real>,
    /// A length that failed recently: growth stays below it for a while.
    ceiling: Option<Real>,
    /// Sub-steps accepted since the last rejection.
    streak: usize,
    /// Start of the current sub-step (for a rejection by the time error test).
    saved_q: Vec<Vector3<Real>>,
    saved_v: Vec<Vector3<Real>>,
    saved_bodies: Vec<splinerod_core::RigidBody>,
    /// The grabs' targets at the start of the sub-step.
    targets: Vec<Vector3<Real>>,
    /// The pins' positions at the start of the sub-step.
    pins: Vec<Vector3<Real>>,
    /// The loads' forces at the start of the sub-step.
    loads: Vec<Vector3<Real>>,
}

/// The controller's memory without its scratch buffers: what a recomputed step must
/// start from again.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct SubstepMemory {
    pub(crate) next: Option<Real>,
    pub(crate) ceiling: Option<Real>,
    pub(crate) streak: usize,
}

impl SubstepState {
    /// The memory to restore a step from.
    pub(crate) fn memory(&self) -> SubstepMemory {
        SubstepMemory {
            next: self.next,
            ceiling: self.ceiling,
            streak: self.streak,
        }
    }

    /// Puts back a saved memory.
    pub(crate) fn restore(&mut self, m: SubstepMemory) {
        (self.next, self.ceiling, self.streak) = (m.next, m.ceiling, m.streak);
    }
}

/// Whether a shorter step may cure `e`.
fn retryable(e: &Error) -> bool {
    matches!(e, Error::Integrator(e) if e.is_recoverable())
}

/// The length to retry a sub-step of `length` with: `factor · length`, but not below
/// `min_dt`; `None` when `length` is `min_dt` already (to round-off) or shorter.
fn shorter(length: Real, factor: Real, min_dt: Real) -> Option<Real> {
    (length > min_dt * (1.0 + 1e-9)).then(|| (factor * length).max(min_dt))
}

impl Simulation {
    /// Covers `[time, time + dt]` with sub-steps (see the module docs). On error the rod
    /// may hold an intermediate state: the caller restores it.
    pub(crate) fn integrate(&mut self, dt: Real) -> Result<(StepStats, SubstepCounts), Error> {
        if self.integrator.role() == Role::Equilibrium {
            // One solve for the loads at the end of the step: no time error to control.
            let (stats, _) = self.try_substep(self.time + dt, dt)?;
            let counts = SubstepCounts {
                substeps: 1,
                rejected: 0,
                smallest_dt: dt,
            };
            return Ok((stats, counts));
        }
        let min_dt = self.control.min_dt.unwrap_or(dt * DEFAULT_MIN_DT_FRACTION);
        let mut h = self.substep.next.unwrap_or(dt).max(min_dt).min(dt);
        let mut total = StepStats {
            converged: true,
            ..StepStats::default()
        };
        let mut counts = SubstepCounts {
            smallest_dt: dt,
            ..SubstepCounts::default()
        };
        let mut done = 0.0;
        while done < dt {
            if self.system.cancel.abandon() {
                return Err(IntegratorError::Interrupted.into());
            }
            let rest = dt - done;
            // The rest in one piece if it fits, in two equal ones if it is under 2h (no
            // sliver of a step at the end); never longer than h.
            let length = if rest <= h * (1.0 + 1e-12) {
                rest
            } else if rest < 2.0 * h {
                0.5 * rest
            } else {
                h
            };
            let end = if length == rest {
                self.time + dt
            } else {
                self.time + done + length
            };
            match self.try_substep(end, length) {
                Ok((stats, error_ratio)) => {
                    total.add_counts(&stats);
                    total.converged &= stats.converged;
                    if error_ratio > 1.0 {
                        let factor = (0.9 / error_ratio.sqrt()).max(0.2);
                        let Some(shorter) = shorter(length, factor, min_dt) else {
                            self.reject_for_time_error();
                            return Err(self.time_error_at_min_dt(min_dt, error_ratio));
                        };
                        self.reject_for_time_error();
                        counts.rejected += 1;
                        h = shorter;
                        continue;
                    }
                    done = if length == rest { dt } else { done + length };
                    counts.substeps += 1;
                    counts.smallest_dt = counts.smallest_dt.min(length);
                    h = self.grow(length, error_ratio).max(min_dt).min(dt);
                }
                Err(e) if retryable(&e) && shorter(length, 0.5, min_dt).is_some() => {
                    if let Error::Integrator(IntegratorError::NotConverged { iterations, .. }) = e {
                        total.newton_iterations += iterations;
                    }
                    self.restore_targets();
                    counts.rejected += 1;
                    self.substep.ceiling = Some(length);
                    self.substep.streak = 0;
                    h = shorter(length, 0.5, min_dt).unwrap_or(min_dt);
                }
                Err(e) => return Err(e),
            }
        }
        self.substep.next = Some(h);
        Ok((total, counts))
    }

    /// One integrator step of length `h` ending at `end`: grabs move to their targets at
    /// `end`, the energies start their step (not for an equilibrium solver: no time passes),
    /// the integrator solves. Returns its counters and the
    /// step's error relative to what is allowed (≤ 1: accept; see the module docs).
    fn try_substep(&mut self, end: Real, h: Real) -> Result<(StepStats, Real), Error> {
        let tolerance = self.control.time_tolerance;
        let guard = self.integrator.conserves_energy();
        let before = if guard {
            self.total_energy()
        } else {
            (0.0, 0.0)
        };
        if tolerance.is_some() || guard {
            let rod = &self.system.rod;
            self.substep.saved_q.clone_from(&rod.positions);
            self.substep.saved_v.clone_from(&rod.velocities);
            let bodies = &self.system.bodies.bodies;
            self.substep.saved_bodies.clone_from(bodies);
        }
        // Only stages with work are timed (a clock read costs as much as a small step's
        // bookkeeping); an idle stage stays at zero.
        let drivers = self.system.is_driven().then(Instant::now);
        self.system.time = end;
        self.substep.pins.clear();
        let pins = self.system.pins.iter().map(|p| p.position);
        self.substep.pins.extend(pins);
        self.substep.loads.clear();
        let loads = self.system.loads.iter().map(|l| l.force.force);
        self.substep.loads.extend(loads);
        self.system.drive(end);
        self.substep.targets.clear();
        let rod = &self.system.rod;
        for g in self.system.grabs.iter_mut() {
            self.substep.targets.push(g.spring.target);
            g.update(end, rod)?;
        }
        if let Some(drivers) = drivers {
            self.clock.drivers += drivers.elapsed().as_secs_f64();
        }
        // Work of the grabs' moving targets on the start state (first half of the rule).
        let work_start = if guard {
            self.total_energy().0 - before.0
        } else {
            0.0
        };
        let setup = Instant::now();
        if self.integrator.role() == Role::Dynamic {
            self.system.begin_step(h)?;
        } else {
            // A static solve has no step to slip over: no friction on the bodies.
            self.system.bodies.contact.lags.clear();
        }
        self.clock.setup += setup.elapsed().as_secs_f64();
        let stats = self.integrator.step(&mut self.system, h)?;
        let mut ratio: Real = 0.0;
        if let Some(tau) = tolerance {
            let v = &self.system.rod.velocities;
            let dv = v.iter().zip(&self.substep.saved_v);
            let jump = dv.map(|(a, b)| (a - b).amax()).fold(0.0, Real::max);
            ratio = 0.5 * h * jump / tau;
        }
        if guard {
            let after = self.total_energy();
            let work = 0.5 * (work_start + self.target_swap_energy_gap(end - h)) + self.pin_work();
            let gain = after.0 - before.0 - work;
            let allowed =
                ENERGY_GAIN * (before.1 + after.1) + 1e-12 * (before.0.abs() + after.0.abs());
            if gain > allowed {
                ratio = ratio.max(4.0);
            }
        }
        Ok((stats, ratio))
    }

    /// `E(q, p₁) − E(q, p₀)` at the rod's current positions `q`: the energy the grabs'
    /// targets add by moving from their start-of-step positions `p₀` (saved in
    /// `substep.targets`) to their current ones `p₁`, the time-dependent energies (a
    /// turning clamp) by going from `start` to the step's end, and the loads' forces by
    /// changing (`−(F₁ − F₀)·C(s)`). Zero without grabs, such energies or keyframed loads.
    fn target_swap_energy_gap(&mut self, start: Real) -> Real {
        use splinerod_integrators::System;
        let rod = &self.system.rod;
        let changed = self.system.loads.iter().zip(&self.substep.loads);
        let loads: Real = changed
            .map(|(l, f0)| match rod.point(l.force.at) {
                Ok(x) => -(l.force.force - f0).dot(&x),
                Err(_) => Real::NAN,
            })
            .sum();
        let driven = self.system.has_posed_grippers()
            || self.system.energies.iter().any(|e| {
                let lifecycle = e.capabilities().lifecycle;
                lifecycle.is_some_and(|l| l.time_dependent())
            });
        if self.system.grabs.is_empty() && !driven {
            return loads;
        }
        let end = self.system.time;
        let now = self.system.potential_energy();
        let swap = |grabs: &mut [crate::Grab], targets: &mut [Vector3<Real>]| {
            for (g, t) in grabs.iter_mut().zip(targets.iter_mut()) {
                std::mem::swap(&mut g.spring.target, t);
            }
        };
        swap(&mut self.system.grabs, &mut self.substep.targets);
        let energies = self.system.energies.iter_mut();
        energies
            .filter_map(|e| e.lifecycle_mut())
            .for_each(|l| l.drive(start));
        self.system.drive_grippers(start);
        let then = self.system.potential_energy();
        swap(&mut self.system.grabs, &mut self.substep.targets);
        let energies = self.system.energies.iter_mut();
        energies
            .filter_map(|e| e.lifecycle_mut())
            .for_each(|l| l.drive(end));
        self.system.drive_grippers(end);
        now - then + loads
    }

    /// Work the driven pins did on the rod in the sub-step just solved, J: the forces
    /// they exerted (the integrator's, constant over the step) times their displacement
    /// (0 if the integrator does not report pin forces).
    fn pin_work(&self) -> Real {
        if self.system.drivers.is_empty() && !self.system.has_posed_grippers() {
            return 0.0; // fixed pins do no work
        }
        let forces = self.integrator.pin_forces();
        let moved = self.system.pins.iter().zip(&self.substep.pins);
        let displacement = moved.map(|(p, p0)| p.position - p0);
        forces
            .iter()
            .zip(displacement)
            .map(|(f, d)| f.dot(&d))
            .sum()
    }

    /// The error of a step whose sub-step of `min_dt` still has a time error of
    /// `ratio` times the tolerance (or failed the energy guard).
    fn time_error_at_min_dt(&self, min_dt: Real, ratio: Real) -> Error {
        let tau = self.control.time_tolerance.unwrap_or(Real::INFINITY);
        let reason = if ratio > 1.0 && tau.is_finite() {
            format!(
                "its time error is {ratio:.3e} times `solver.time_tolerance` = {tau:e} m; raise solver.time_tolerance or lower solver.min_dt"
            )
        } else {
            "it still gains energy (the implicit midpoint rule's guard); lower solver.min_dt or use a dissipative method".to_string()
        };
        Error::MinDtReached {
            time: self.time,
            min_dt,
            reason,
        }
    }

    /// Total and kinetic energy of the system now, J.
    fn total_energy(&self) -> (Real, Real) {
        use splinerod_integrators::System;
        let kinetic = self.system.rod.kinetic_energy();
        (kinetic + self.system.potential_energy(), kinetic)
    }

    /// Restores the start of the sub-step just taken (rejected by the time error test or
    /// the energy guard).
    fn reject_for_time_error(&mut self) {
        let rod = &mut self.system.rod;
        if rod.len() == self.substep.saved_q.len() {
            rod.positions.copy_from_slice(&self.substep.saved_q);
            rod.velocities.copy_from_slice(&self.substep.saved_v);
        }
        let bodies = &mut self.system.bodies.bodies;
        if bodies.len() == self.substep.saved_bodies.len() {
            bodies.clone_from_slice(&self.substep.saved_bodies);
        }
        self.restore_targets();
        self.substep.streak = 0;
    }

    /// Puts the grabs' targets back where they were at the start of the sub-step (the
    /// energy guard measures the targets' work from there).
    fn restore_targets(&mut self) {
        let grabs = self.system.grabs.iter_mut();
        for (g, t) in grabs.zip(&self.substep.targets) {
            g.spring.target = *t;
        }
    }

    /// What a whole step of `dt` solved elsewhere in one piece, within the time
    /// tolerance, leaves in the member besides its state (the lanes' kept steps, see
    /// `world/kept.rs`): the clock and step count advanced, the controller's next length
    /// as [`Simulation::integrate`] sets it after an accepted sub-step.
    pub(crate) fn count_solved_step(&mut self, dt: Real) {
        let min_dt = self.control.min_dt.unwrap_or(dt * DEFAULT_MIN_DT_FRACTION);
        let h = self.grow(dt, 0.0).max(min_dt).min(dt);
        self.substep.next = Some(h);
        self.last_dt = dt;
        self.time += dt;
        self.system.time = self.time;
        self.steps += 1;
    }

    /// The next sub-step length after an accepted one of length `h`.
    fn grow(&mut self, h: Real, error_ratio: Real) -> Real {
        let s = &mut self.substep;
        s.streak += 1;
        if s.streak >= RECOVERY_STEPS {
            s.ceiling = None;
        }
        let factor = if error_ratio > 0.0 {
            (0.9 / error_ratio.sqrt()).clamp(0.2, 2.0)
        } else {
            2.0
        };
        let grown = h * factor;
        match s.ceiling {
            Some(c) if grown >= c => h.max(0.5 * c),
            _ => grown,
        }
    }
}
