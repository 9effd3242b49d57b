//! What a Python `Simulation` advances: a scene's run or a simulation built in code.

use splinerod::core::Cancel;
use splinerod::integrators::Role;
use splinerod::{Error, Real, SceneRun};

/// What advances: a scene's run, or one simulation built in code with its step.
pub enum Driver {
    /// A scene's run (every member).
    Scene(Box<SceneRun>),
    /// A simulation built in code, stepped by `dt`.
    Code {
        /// The simulation.
        sim: Box<splinerod::Simulation>,
        /// Its time step, s (0 for the static solver).
        dt: Real,
        /// Calls made (steps, or solves of the static solver, whose `steps` stay 0).
        calls: usize,
    },
}

impl Driver {
    /// Makes `n` steps (static: solves), stopping when `cancel` asks to: between steps,
    /// or inside one (abandoned and rolled back, see [`splinerod::run::control`]), with
    /// an interrupted error ([`Error::is_interrupted`]).
    pub fn advance(&mut self, n: usize, cancel: &Cancel) -> Result<(), Error> {
        match self {
            Self::Scene(run) => {
                run.set_cancel(cancel.clone());
                run.advance(n)
            }
            Self::Code { sim, dt, calls } => {
                sim.system.cancel = cancel.clone();
                for _ in 0..n {
                    if cancel.check() {
                        return Err(Error::Interrupted("between steps"));
                    }
                    match sim.integrator.role() {
                        Role::Equilibrium => sim.settle()?,
                        Role::Dynamic => sim.step(*dt)?,
                    };
                    *calls += 1;
                }
                Ok(())
            }
        }
    }

    /// The simulations: a scene's members, or the one built in code.
    pub fn sims(&self) -> &[splinerod::Simulation] {
        match self {
            Self::Scene(run) => run.members(),
            Self::Code { sim, .. } => std::slice::from_ref(sim),
        }
    }

    /// Member `index`, to change its state; `None` past the last.
    pub fn sim_mut(&mut self, index: usize) -> Option<&mut splinerod::Simulation> {
        match self {
            Self::Scene(run) => run.member_mut(index),
            Self::Code { sim, .. } => (index == 0).then_some(sim.as_mut()),
        }
    }

    /// Whether the integrator solves for equilibrium (the static solver).
    pub fn is_static(&self) -> bool {
        self.sims()[0].integrator.role() == Role::Equilibrium
    }
}
