//! [`Simulation`]: a [`RodSystem`] advanced by a boxed [`Integrator`], with optional
//! adaptive resolution.
//!
//! One step (paper §4.1): move the grabs' targets to the end of the step, integrate
//! (forces, Jacobians, one sparse solve per Newton iteration; contact is detected at
//! every Newton iterate, as part of the forces), then adapt — insert and remove knots
//! through the exact maps, telling every energy about each map, with the grabs and the
//! contact points as interactions — and record what happened. Cutting goes through [`Simulation::cut`] for the same reason.

use crate::substep::{StepControl, SubstepCounts, SubstepState};
use crate::{Error, RodSystem};
use splinerod_adaptivity::{AdaptReport, Adapter};
use splinerod_core::{KnotMap, Real, Rod};
use splinerod_energies::{ContactSummary, Energy};
use splinerod_integrators::{Integrator, StepStats};
use std::time::Instant;

/// What one step did and how long it took.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Solver counters of the integration stage.
    pub solver: StepStats,
    /// Knots inserted and removed by the adapt stage.
    pub adapt: AdaptReport,
    /// Control points after the step.
    pub control_points: usize,
    /// Wall time of the integration stage, s.
    pub integrate_seconds: Real,
    /// Sub-steps taken, rejected and the shortest one (see [`crate::substep`]).
    pub substeps: SubstepCounts,
    /// Contacts at the end of the step (`None` without contact).
    pub contact: Option<ContactSummary>,
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
            interactions: Vec::new(),
            saved: (Vec::new(), Vec::new()),
        }
    }

    /// Adds adaptive resolution (builder style).
    pub fn with_adapter(mut self, adapter: Adapter) -> Self {
        self.adapter = Some(adapter);
        self
    }

    /// Advances by `dt`, in as many sub-steps as the solver needs (see
    /// [`crate::substep`]). On an integration error the state is unchanged and time does
    /// not advance.
    pub fn step(&mut self, dt: Real) -> Result<StepReport, Error> {
        if !(dt.is_finite() && dt > 0.0) {
            return Err(Error::field("dt", dt, "must be finite and positive"));
        }
        let start = Instant::now();
        let saved_time = self.system.time;
        self.saved.0.clone_from(&self.system.rod.positions);
        self.saved.1.clone_from(&self.system.rod.velocities);
        let (solver, substeps) = match self.integrate(dt) {
            Ok(done) => done,
            Err(e) => {
                self.system.time = saved_time;
                let rod = &mut self.system.rod;
                rod.positions.clone_from(&self.saved.0);
                rod.velocities.clone_from(&self.saved.1);
                return Err(e);
            }
        };
        let integrate_seconds = start.elapsed().as_secs_f64();
        self.time += dt;
        self.system.time = self.time;
        self.steps += 1;
        // A multiplier update moves the constrained energy's minimum: a dissipative scheme
        // absorbs the jump, an energy-conserving one (the midpoint rule) would keep the
        // axial ringing it starts, so there the penalty alone holds the constraint.
        if !self.integrator.conserves_energy() {
            self.system.update_multipliers(false);
        }
        let adapt = self.adapt()?;
        let contact = self.system.contact.as_ref();
        let contact = contact.map(|c| c.summary(&self.system.rod)).transpose()?;
        Ok(StepReport {
            solver,
            adapt,
            control_points: self.system.rod.len(),
            integrate_seconds,
            substeps,
            contact,
        })
    }

    /// Runs the adapt step now (no-op without an adapter).
    pub fn adapt(&mut self) -> Result<AdaptReport, Error> {
        let Some(adapter) = self.adapter.as_mut() else {
            return Ok(AdaptReport::default());
        };
        self.interactions.clear();
        let t = self.system.time;
        let grabs = self.system.grabs.iter().filter(|g| g.active(t));
        self.interactions.extend(grabs.map(|g| g.spring.at));
        if let Some(contact) = &self.system.contact {
            contact.interaction_points(&self.system.rod, &mut self.interactions)?;
        }
        let RodSystem { rod, energies, .. } = &mut self.system;
        let mut follow = |rod: &Rod, map: &KnotMap| notify(energies, rod, map);
        Ok(adapter.adapt(rod, &self.interactions, &mut follow)?)
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
