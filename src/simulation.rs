//! [`Simulation`]: a [`RodSystem`] advanced by a boxed [`Integrator`], with optional
//! adaptive resolution.
//!
//! One step (paper §4.1): move the grabs' targets to the end of the step, integrate
//! (forces, Jacobians, one sparse solve per Newton iteration; contact is detected at
//! every Newton iterate, as part of the forces), then adapt — insert and remove knots
//! through the exact maps, telling every energy about each map, with the grabs and the
//! contact points as interactions — and record what happened. Cutting goes through [`Simulation::cut`] for the same reason.

use crate::estimate::ErrorEstimation;
use crate::substep::{StepControl, SubstepCounts, SubstepMemory, SubstepState};
use crate::{Error, RodSystem};
use splinerod_adaptivity::{AdaptReport, Adapter, ErrorEstimate};
use splinerod_core::{KnotMap, Real, Rod};
use splinerod_energies::{ContactSummary, Energy};
use splinerod_integrators::{Integrator, StepStats};
use std::time::Instant;

/// Most times one step is recomputed on a finer basis because its error estimate was
/// rejected.
const MAX_REDONE_STEPS: usize = 3;

/// What one step did and how long it took.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Solver counters of the integration stage.
    pub solver: StepStats,
    /// Knots inserted and removed by the adapt stage.
    pub adapt: AdaptReport,
    /// Control points after the step.
    pub control_points: usize,
    /// Wall time of the integration stage, s (recomputed steps included).
    pub integrate_seconds: Real,
    /// Wall time of the adapt stage, s: error estimate, marks and knot maps (of rejected
    /// steps too).
    pub adapt_seconds: Real,
    /// Sub-steps taken, rejected and the shortest one (see [`crate::substep`]).
    pub substeps: SubstepCounts,
    /// Contacts at the end of the step (`None` without contact).
    pub contact: Option<ContactSummary>,
    /// The error estimate made at this step, m (`None` when none was due).
    pub error_estimate: Option<Real>,
}

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
    /// Length of the last step, s (the inertial load of the error estimate).
    last_dt: Real,
    saved_time: Real,
    saved_substep: SubstepMemory,
    interactions: Vec<Real>,
    saved: (Vec<nalgebra::Vector3<Real>>, Vec<nalgebra::Vector3<Real>>),
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
            last_dt: 0.0,
            saved_time: 0.0,
            saved_substep: SubstepMemory::default(),
            interactions: Vec::new(),
            saved: (Vec::new(), Vec::new()),
        }
    }

    /// Adds adaptive resolution (builder style); an adapter whose criteria read an error
    /// estimate turns the estimator on.
    pub fn with_adapter(mut self, adapter: Adapter) -> Self {
        if adapter.wants_estimate() {
            self.estimation.get_or_insert_with(ErrorEstimation::default);
        }
        self.adapter = Some(adapter);
        self
    }

    /// Turns the error estimate on after every step (builder style), with or without
    /// adaptivity: [`Simulation::error_estimate`] then says how accurate the run is.
    pub fn estimate_errors(mut self) -> Self {
        self.estimation.get_or_insert_with(ErrorEstimation::default);
        self
    }

    /// The latest error estimate (after a step), if the estimator is on.
    pub fn error_estimate(&self) -> Option<&ErrorEstimate> {
        self.estimation.as_ref().map(|e| e.latest())
    }

    /// Advances by `dt`, in as many sub-steps as the solver needs (see
    /// [`crate::substep`]). On an integration error the state is unchanged and time does
    /// not advance.
    pub fn step(&mut self, dt: Real) -> Result<StepReport, Error> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::field("dt", dt, "must be finite and positive"));
        }
        let start = Instant::now();
        let mut redone = 0;
        let mut adapt_seconds = 0.0;
        let (solver, substeps, fresh) = loop {
            let (solver, substeps) = self.integrate_or_restore(dt)?;
            self.last_dt = dt;
            let stage = Instant::now();
            let fresh = self.estimate_if_due()?;
            let rejected = fresh && redone < MAX_REDONE_STEPS && self.rejected();
            let inserted = if rejected {
                self.restore();
                self.refine_for_redo()?
            } else {
                0
            };
            adapt_seconds += stage.elapsed().as_secs_f64();
            if inserted > 0 {
                redone += 1;
                continue;
            }
            if rejected {
                // Nothing could be inserted: the same step again, accepted.
                let (solver, substeps) = self.integrate_or_restore(dt)?;
                break (solver, substeps, fresh);
            }
            break (solver, substeps, fresh);
        };
        let integrate_seconds = start.elapsed().as_secs_f64() - adapt_seconds;
        self.time += dt;
        self.system.time = self.time;
        self.steps += 1;
        // A multiplier update moves the constrained energy's minimum: a dissipative scheme
        // absorbs the jump, an energy-conserving one (the midpoint rule) would keep the
        // axial ringing it starts, so there the penalty alone holds the constraint.
        if !self.integrator.conserves_energy() {
            self.system.update_multipliers(false);
        }
        let stage = Instant::now();
        let mut adapt = self.apply_adapter(fresh)?;
        adapt_seconds += stage.elapsed().as_secs_f64();
        adapt.redone_steps = redone;
        let error_estimate = fresh
            .then(|| self.error_estimate().map(|e| e.max()))
            .flatten();
        let contact = self.system.contact.as_ref();
        let contact = contact.map(|c| c.summary(&self.system.rod)).transpose()?;
        Ok(StepReport {
            solver,
            adapt,
            control_points: self.system.rod.len(),
            integrate_seconds,
            adapt_seconds,
            substeps,
            contact,
            error_estimate,
        })
    }

    /// Runs the error estimate (if on) and the adapt step (if any) now.
    pub fn adapt(&mut self) -> Result<AdaptReport, Error> {
        let fresh = self.estimate_now()?.is_some();
        self.apply_adapter(fresh)
    }

    /// Runs the error estimate now (if on), whatever the schedule, and returns it.
    pub fn estimate_now(&mut self) -> Result<Option<&ErrorEstimate>, Error> {
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
        self.integrate(dt).inspect_err(|_| self.restore())
    }

    /// Puts back the state saved before the last integration.
    fn restore(&mut self) {
        self.system.time = self.saved_time;
        self.substep.restore(self.saved_substep);
        let rod = &mut self.system.rod;
        rod.positions.clone_from(&self.saved.0);
        rod.velocities.clone_from(&self.saved.1);
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
        let RodSystem { rod, energies, .. } = &mut self.system;
        let mut follow = |rod: &Rod, map: &KnotMap| notify(energies, rod, map);
        Ok(adapter.refine(rod, &self.interactions, e.latest(), &mut follow)?)
    }

    /// The material coordinates where something acts on the rod now: active grabs and
    /// contacts.
    fn gather_interactions(&mut self) -> Result<(), Error> {
        self.interactions.clear();
        let t = self.system.time;
        let grabs = self.system.grabs.iter().filter(|g| g.active(t));
        self.interactions.extend(grabs.map(|g| g.spring.at));
        if let Some(contact) = &self.system.contact {
            contact.interaction_points(&self.system.rod, &mut self.interactions)?;
        }
        Ok(())
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
        let RodSystem { rod, energies, .. } = &mut self.system;
        let mut follow = |rod: &Rod, map: &KnotMap| notify(energies, rod, map);
        Ok(adapter.adapt(rod, &self.interactions, estimate, &mut follow)?)
    }

    /// Cuts the rod at material coordinate `s` (m; see [`Rod::cut`]).
    pub fn cut(&mut self, s: Real) -> Result<(), Error> {
        let RodSystem { rod, energies, .. } = &mut self.system;
        rod.cut_with(s, &mut |rod, map| notify(energies, rod, map))?;
        Ok(())
    }
}

fn notify(energies: &mut [Box<dyn Energy>], rod: &Rod, map: &KnotMap) {
    for e in energies.iter_mut() {
        e.on_knot_change(rod, map);
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
