//! What an observer of a differentiated run sees after each step ([`StepView`]): the
//! time, the rod, the forward states, and the `[[pins]]` entries' forces with their
//! derivatives (an exact clamp's tangent pin folded into its clamp, as the run's
//! `pin_forces`): \\(F_j = \mu_j/\beta\\) of the step and
//! \\(\mathrm{d}F_j/\mathrm{d}p_k\\) from the step's tangent solve.

use crate::run::pins::pin_force_of;
use crate::{Error, Scene, Simulation};
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};
use splinerod_integrators::ForwardState;

/// A run after one of its steps, as an observer sees it.
pub struct StepView<'a> {
    /// The time at the step's end, s.
    pub t: Real,
    /// The rod at the step's end.
    pub rod: &'a Rod,
    /// Per parameter, the forward state (the derivatives of the control points and
    /// their velocities, and of the pins' forces in the step).
    pub states: &'a [ForwardState],
    scene: &'a Scene,
    sim: &'a Simulation,
}

impl<'a> StepView<'a> {
    /// The view of `sim` (of `scene`) after a step, with the forward `states`.
    pub(crate) fn new(scene: &'a Scene, sim: &'a Simulation, states: &'a [ForwardState]) -> Self {
        Self {
            t: sim.time,
            rod: &sim.system.rod,
            states,
            scene,
            sim,
        }
    }

    /// The force the rod put on `[[pins]]` entry `pin`'s support during the step, N (as
    /// the run's `pin_forces`); an error naming `pin` beyond the scene's pins.
    pub fn pin_force(&self, pin: usize) -> Result<Vector3<Real>, Error> {
        self.check(pin)?;
        let forces = self.sim.integrator.pin_forces();
        Ok(pin_force_of(
            self.scene,
            &self.sim.system.pins,
            &forces,
            pin,
        ))
    }

    /// The derivative of [`Self::pin_force`] by parameter `k`, N per unit.
    pub fn pin_force_rate(&self, k: usize, pin: usize) -> Result<Vector3<Real>, Error> {
        self.check(pin)?;
        let forces = &self.states[k].pin_forces;
        Ok(pin_force_of(self.scene, &self.sim.system.pins, forces, pin))
    }

    /// An error naming `pin` unless the scene has it.
    fn check(&self, pin: usize) -> Result<(), Error> {
        let count = self.scene.pins.len();
        if pin < count {
            return Ok(());
        }
        let reason = format!("the scene has {count} [[pins]]");
        Err(Error::field("pin", pin, reason))
    }
}
