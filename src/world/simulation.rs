//! [`Simulation`]: a [`RodSystem`] advanced by a boxed [`Integrator`], with optional
//! adaptive resolution.
//!
//! One step (paper §4.1): move the grabs' targets to the end of the step, start every
//! energy's step ([`splinerod_energies::Lifecycle::begin_step`]), integrate (forces,
//! Jacobians, one sparse solve per Newton iteration), then adapt — insert and remove
//! knots through the exact maps, with the grabs and every energy's interaction points
//! as interactions — and report what happened, stage by stage ([`StepReport`]). Every
//! knot change goes through [`RodSystem::change_knots`], so the energies hear of it.
//!
//! An equilibrium solver ([`Role::Equilibrium`], the static solver) runs
//! through the same stages: [`Simulation::step`] then gives a quasi-static sequence
//! (the equilibrium under the loads at the end of each step), and
//! [`Simulation::settle`] the equilibrium at the current time, re-solved after every
//! adapt stage that changed the knots.

use crate::world::estimate::ErrorEstimation;
use crate::world::step_report::{StageTimes, StepReport};
use crate::world::substep::{StepControl, SubstepCounts, SubstepMemory, SubstepState};
use crate::{Error, RodSystem};
use splinerod_adaptivity::{AdaptReport, Adapter, ErrorEstimate};
use splinerod_core::{Real, Rod};
use splinerod_integrators::Role;
use splinerod_integrators::{Integrator, IntegratorError, StepStats};
use std::time::Instant;

/// Most times one step is recomputed on a finer basis because its error estimate was
/// rejected.
const MAX_REDONE_STEPS: usize = 3;

/// Most solve-and-adapt rounds of [`Simulation::settle`] with adaptivity.
pub const MAX_SETTLE_ROUNDS: usize = 12;

/// A rod system, the integrator that advances it and, optionally, the adapt step.
pub struct Simulation {
    /// The mechanical state.
    pub system: RodSystem,
    /// The time integrator (swap it freely between steps).
    pub integrator: Box<dyn Integrator>,
    /// Adaptive resolution after each step; `None` keeps the basis fixed.
    pub adapter: Option<Adapter>,
    /// Simulated time, s.
    pub time: Real,
    /// Steps taken.
    pub steps: usize,
    /// Sub-stepping settings (smallest sub-step, optional time error tolerance).
    pub control: StepControl,
    pub(crate) substep: SubstepState,
    /// The error estimator: run after every step when a criterion reads it or when set
    /// (`Some`) on request; see [`Simulation::estimate_errors`].
    pub estimation: Option<ErrorEstimation>,
    /// Stage times of the step under way.
    pub(crate) clock: StageTimes,
    /// Length of the last step, s (the inertial load of the error estimate).
    pub(crate) last_dt: Real,
    saved_time: Real,
    saved_substep: SubstepMemory,
    interactions: Vec<Real>,
    pub(crate) saved: (Vec<nalgebra::Vector3<Real>>, Vec<nalgebra::Vector3<Real>>),
    /// The rigid bodies before the last integration.
    saved_bodies: Vec<splinerod_core::RigidBody>,
}

impl Simulation {
    /// A simulation at time zero, without adaptivity.
    pub fn new(system: RodSystem, integrator: Box<dyn Integrator>) -> Self {
        Self {
            system,
            integrator,
            adapter: None,
            time: 0.0,
            steps: 0,
            control: StepControl::default(),
            substep: SubstepState::default(),
            estimation: None,
            clock: StageTimes::default(),
            last_dt: 0.0,
            saved_time: 0.0,
            saved_substep: SubstepMemory::default(),
            interactions: Vec::new(),
            saved: (Vec::new(), Vec::new()),
            saved_bodies: Vec::new(),
        }
    }

    /// Adds adaptive resolution (builder style); an adapter whose criteria read an error
    /// estimate turns the estimator on.
    pub fn with_adapter(mut self, adapter: Adapter) -> Self {
        if adapter.wants_estimate() {
            self.estimation.get_or_insert_with(ErrorEstimation::default);
        }
        if let Some(e) = &mut self.estimation {
            e.set_continuity(&adapter.continuity);
        }
        self.adapter = Some(adapter);
        self
    }

    /// Turns the error estimate on after every step (builder style), with or without
    /// adaptivity: [`Simulation::error_estimate`] then says how accurate the run is.
    pub fn estimate_errors(mut self) -> Self {
        let e = self.estimation.get_or_insert_with(ErrorEstimation::default);
        if let Some(adapter) = &self.adapter {
            e.set_continuity(&adapter.continuity);
        }
        self
    }

    /// The latest error estimate (after a step), if the estimator is on.
    pub fn error_estimate(&self) -> Option<&ErrorEstimate> {
        self.estimation.as_ref().map(|e| e.latest())
    }

    /// Advances by `dt`, in as many sub-steps as the solver needs (see
    /// [`crate::world::substep`]). On an integration error the state is unchanged and time does
    /// not advance.
    pub fn step(&mut self, dt: Real) -> Result<StepReport, Error> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::field("dt", dt, "must be finite and positive"));
        }
        self.system.check_knots_heard()?;
        self.system.take_non_finite_energy();
        let result = self.advance(dt);
        result.map_err(|e| self.name_non_finite_energy(e))
    }

    /// `e`, naming the energy that returned a non-finite value if that is what failed.
    fn name_non_finite_energy(&self, e: Error) -> Error {
        match (e, self.system.take_non_finite_energy()) {
            (
                Error::Integrator(source @ IntegratorError::NonFinite { .. }),
                Some((what, energy)),
            ) => Error::EnergyNotFinite {
                energy,
                what,
                source,
            },
            (e, _) => e,
        }
    }

    /// Solves for the equilibrium at the current time (the integrator must be an
    /// equilibrium solver, [`Role::Equilibrium`]), then adapts; while the
    /// adapt stage changes the knots the equilibrium is solved again, at most
    /// [`MAX_SETTLE_ROUNDS`] times. Time and the step count do not advance. The report
    /// sums the rounds.
    pub fn settle(&mut self) -> Result<StepReport, Error> {
        if self.integrator.role() == Role::Dynamic {
            let name = self.integrator.name().to_string();
            return Err(Error::NotAnEquilibriumSolver(name));
        }
        self.system.check_knots_heard()?;
        let mut total = StepReport::default();
        for _ in 0..MAX_SETTLE_ROUNDS {
            let report = self.advance(0.0)?;
            let changed = report.adapt.inserted + report.adapt.removed > 0;
            total.solver += report.solver;
            total.adapt += report.adapt;
            total.stages += report.stages;
            total.substeps = report.substeps;
            (total.control_points, total.energies) = (report.control_points, report.energies);
            total.error_estimate = report.error_estimate.or(total.error_estimate);
            if !changed {
                break;
            }
        }
        Ok(total)
    }

    /// One step of `dt` (0: an equilibrium at the current time) through every stage.
    fn advance(&mut self, dt: Real) -> Result<StepReport, Error> {
        self.clock = StageTimes::default();
        // Steps redone on a finer basis, and the knots their refinement inserted.
        let (mut redone, mut redo_inserted) = (0, 0);
        let start = Instant::now();
        let (solver, substeps, fresh) = loop {
            let (solver, substeps) = self.integrate_or_restore(dt)?;
            self.last_dt = dt;
            // Only stages with work are timed (see `try_substep`).
            let stage = self.estimation.is_some().then(Instant::now);
            let fresh = self.estimate_if_due()?;
            let rejected = fresh && redone < MAX_REDONE_STEPS && self.rejected();
            let inserted = if rejected {
                self.restore();
                self.refine_for_redo()?
            } else {
                0
            };
            if let Some(stage) = stage {
                self.clock.adapt += stage.elapsed().as_secs_f64();
            }
            if inserted > 0 {
                redone += 1;
                redo_inserted += inserted;
                continue;
            }
            if rejected {
                // Nothing could be inserted: the same step again, accepted.
                let (solver, substeps) = self.integrate_or_restore(dt)?;
                break (solver, substeps, fresh);
            }
            break (solver, substeps, fresh);
        };
        let c = &mut self.clock;
        c.integrate = start.elapsed().as_secs_f64() - c.adapt - c.drivers - c.setup;
        self.time += dt;
        self.system.time = self.time;
        self.steps += usize::from(dt > 0.0);
        // A multiplier update moves the constrained energy's minimum: a dissipative scheme
        // absorbs the jump, an energy-conserving one (the midpoint rule) would keep the
        // axial ringing it starts, so there the penalty alone holds the constraint. An
        // equilibrium solver updates them itself until the constraint holds.
        let integrator = &self.integrator;
        if !integrator.conserves_energy() && integrator.role() == Role::Dynamic {
            self.system.update_multipliers(false);
        }
        let stage = self.adapter.is_some().then(Instant::now);
        let mut adapt = self.apply_adapter(fresh)?;
        if let Some(stage) = stage {
            self.clock.adapt += stage.elapsed().as_secs_f64();
        }
        adapt.redone_steps = redone;
        adapt.inserted += redo_inserted;
        let error_estimate = fresh
            .then(|| self.error_estimate().map(|e| e.max()))
            .flatten();
        Ok(StepReport {
            solver,
            adapt,
            control_points: self.system.rod.distinct_len(),
            stages: self.clock,
            substeps,
            energies: self.system.summary()?,
            error_estimate,
            unbatched: None,
        })
    }

    /// Runs the error estimate (if on) and the adapt step (if any) now.
    pub fn adapt(&mut self) -> Result<AdaptReport, Error> {
        self.system.check_knots_heard()?;
        let fresh = self.estimate_now()?.is_some();
        self.apply_adapter(fresh)
    }

    /// Runs the error estimate now (if on), whatever the schedule, and returns it.
    pub fn estimate_now(&mut self) -> Result<Option<&ErrorEstimate>, Error> {
        self.system.check_knots_heard()?;
        self.gather_interactions()?;
        match &mut self.estimation {
            Some(e) => Ok(Some(e.run(
                &self.system,
                &self.interactions,
                &self.saved.1,
                self.last_dt,
            )?)),
            None => Ok(None),
        }
    }

    /// Integrates one step of `dt` from a saved state, restoring it on error.
    fn integrate_or_restore(&mut self, dt: Real) -> Result<(StepStats, SubstepCounts), Error> {
        self.saved_time = self.system.time;
        self.saved.0.clone_from(&self.system.rod.positions);
        self.saved.1.clone_from(&self.system.rod.velocities);
        self.saved_substep = self.substep.memory();
        self.saved_bodies.clone_from(&self.system.bodies.bodies);
        let result = self.integrate(dt).inspect_err(|_| self.restore());
        self.system.follow_bodies();
        result
    }

    /// Puts back the state saved before the last integration.
    fn restore(&mut self) {
        self.system.time = self.saved_time;
        self.substep.restore(self.saved_substep);
        let rod = &mut self.system.rod;
        rod.positions.clone_from(&self.saved.0);
        rod.velocities.clone_from(&self.saved.1);
        self.system.bodies.bodies.clone_from(&self.saved_bodies);
        self.system.follow_bodies();
    }

    /// Whether the step just estimated must be recomputed on a finer basis: its error
    /// estimate is far above what the adapter's criteria accept.
    fn rejected(&self) -> bool {
        match (&self.adapter, &self.estimation) {
            (Some(adapter), Some(e)) => adapter.rejects(&self.system.rod, e.latest()),
            _ => false,
        }
    }

    /// Refines the restored start of a rejected step where the estimate asks for it;
    /// returns the knots inserted.
    fn refine_for_redo(&mut self) -> Result<usize, Error> {
        let (Some(adapter), Some(e)) = (self.adapter.as_mut(), &self.estimation) else {
            return Ok(0);
        };
        let (interactions, estimate) = (&self.interactions, e.latest());
        let refine = |rod: &mut Rod, heard: &mut dyn FnMut(&Rod, &splinerod_core::KnotMap)| {
            adapter.refine(rod, interactions, estimate, heard)
        };
        Ok(self.system.change_knots(refine)?)
    }

    /// The material coordinates where something acts on the rod now
    /// ([`RodSystem::interaction_points`]).
    fn gather_interactions(&mut self) -> Result<(), Error> {
        self.interactions.clear();
        Ok(self.system.interaction_points(&mut self.interactions)?)
    }

    /// Runs the estimator on the state just integrated if it is on and an estimate is
    /// due ([`ErrorEstimation::due`]); whether it ran.
    fn estimate_if_due(&mut self) -> Result<bool, Error> {
        if self.estimation.is_none() {
            return Ok(false);
        }
        self.gather_interactions()?;
        let Some(e) = &mut self.estimation else {
            return Ok(false);
        };
        if !e.due(&self.system.rod, &self.interactions) {
            return Ok(false);
        }
        let estimate = e.run(
            &self.system,
            &self.interactions,
            &self.saved.1,
            self.last_dt,
        )?;
        let content = self.adapter.as_ref().map(|a| a.content(estimate));
        e.schedule(&self.system.rod, &self.interactions, content);
        Ok(true)
    }

    /// The adapter's insertions and removals, with the latest estimate if `fresh` (the
    /// interactions were then gathered with it).
    fn apply_adapter(&mut self, fresh: bool) -> Result<AdaptReport, Error> {
        if self.adapter.is_none() {
            return Ok(AdaptReport::default());
        }
        if !fresh {
            self.gather_interactions()?;
        }
        let estimate = self
            .estimation
            .as_ref()
            .filter(|_| fresh)
            .map(|e| e.latest());
        let Some(adapter) = self.adapter.as_mut() else {
            return Ok(AdaptReport::default());
        };
        let interactions = &self.interactions;
        let adapt = |rod: &mut Rod, heard: &mut dyn FnMut(&Rod, &splinerod_core::KnotMap)| {
            adapter.adapt(rod, interactions, estimate, heard)
        };
        Ok(self.system.change_knots(adapt)?)
    }

    /// Cuts the rod at material coordinate `s` (m; see [`RodSystem::cut`]).
    pub fn cut(&mut self, s: Real) -> Result<(), Error> {
        self.system.check_knots_heard()?;
        self.system.cut(s)?;
        Ok(())
    }
}

impl std::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("integrator", &self.integrator.name())
            .field("adapter", &self.adapter)
            .field("time", &self.time)
            .field("steps", &self.steps)
            .field("system", &self.system)
            .finish()
    }
}
