//! [`Simulation`]: a [`RodSystem`] advanced by a boxed [`Integrator`].
//!
//! One step is a short list of named, timed stages: integrate (forces, Jacobians, one
//! sparse solve per Newton iteration), then bookkeeping. Adaptivity plugs in after
//! integration (paper §4.1) once its criteria are configured.

use crate::{Error, RodSystem};
use splinerod_core::Real;
use splinerod_integrators::{Integrator, StepStats};
use std::time::Instant;

/// What one step did and how long it took.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepReport {
    /// Solver counters of the integration stage.
    pub solver: StepStats,
    /// Control points after the step.
    pub control_points: usize,
    /// Wall time of the integration stage, s.
    pub integrate_seconds: Real,
}

/// A rod system and the integrator that advances it.
pub struct Simulation {
    /// The mechanical state.
    pub system: RodSystem,
    /// The time integrator (swap it freely between steps).
    pub integrator: Box<dyn Integrator>,
    /// Simulated time, s.
    pub time: Real,
    /// Steps taken.
    pub steps: usize,
}

impl Simulation {
    /// A simulation at time zero.
    pub fn new(system: RodSystem, integrator: Box<dyn Integrator>) -> Self {
        Self {
            system,
            integrator,
            time: 0.0,
            steps: 0,
        }
    }

    /// Advances by `dt`. On error the state is unchanged and time does not advance.
    pub fn step(&mut self, dt: Real) -> Result<StepReport, Error> {
        let start = Instant::now();
        let solver = self.integrator.step(&mut self.system, dt)?;
        let integrate_seconds = start.elapsed().as_secs_f64();
        self.time += dt;
        self.steps += 1;
        Ok(StepReport {
            solver,
            control_points: self.system.rod.len(),
            integrate_seconds,
        })
    }
}

impl std::fmt::Debug for Simulation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulation")
            .field("integrator", &self.integrator.name())
            .field("time", &self.time)
            .field("steps", &self.steps)
            .field("system", &self.system)
            .finish()
    }
}
