//! The implicit midpoint rule, symplectic and second order:
//!
//! \\[ q^+ = q_0 + h\, v_m, \qquad M (v^+ - v_0) = h\, f(q_m, v_m), \qquad
//! q_m = \tfrac12 (q_0 + q^+),\; v_m = \tfrac12 (v_0 + v^+), \\]
//!
//! with \\(f(q, v) = -\nabla E(q) - \alpha M v + G^T\lambda\\). The Newton unknown is the
//! midpoint velocity \\(x = v_m\\): then \\(q_m = q_0 + \tfrac h2 x\\) and, halving the
//! momentum equation, the residual
//!
//! \\[ r(x) = M (x - v_0) + \tfrac h2 \nabla E(q_0 + \tfrac h2 x) + \tfrac{h\alpha}{2} M x \\]
//!
//! is the gradient of the merit
//! \\(\Phi(x) = \tfrac12 (x - v_0)^T M (x - v_0) + E(q_0 + \tfrac h2 x) + \tfrac{h\alpha}{4} x^T M x\\),
//! with Newton matrix \\((1 + \tfrac{h\alpha}{2}) M + \tfrac{h^2}{4} K(q_m)\\): the shared
//! incremental problem ([`crate::incremental`]) with β = h/2. Pins hold at the end of the
//! step, \\(G q^+ = p \iff G x = (p - G q_0)/h\\) (reach ρ = h). After Newton,
//! \\(q^+ = q_0 + h x\\) and \\(v^+ = 2x - v_0\\).
//!
//! For a quadratic energy (a linear system) and no damping the rule conserves the
//! energy exactly (up to the Newton tolerance); for nonlinear energies it is symplectic,
//! so the energy error stays bounded instead of drifting. Linear momentum is conserved
//! exactly by translation-invariant internal forces.

use crate::incremental::{Increment, Stepper};
use crate::newton::NewtonParams;
use crate::{Integrator, IntegratorError, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::Real;

/// Implicit midpoint rule with Newton iterations (an [`Integrator`]).
#[derive(Debug, Default)]
pub struct ImplicitMidpoint {
    /// Newton settings.
    pub params: NewtonParams,
    stepper: Stepper,
}

impl ImplicitMidpoint {
    /// An implicit midpoint integrator with the given Newton settings.
    pub fn new(params: NewtonParams) -> Result<Self, IntegratorError> {
        params.validate()?;
        Ok(Self {
            params,
            ..Self::default()
        })
    }
}

/// One midpoint step on a prepared stepper (base = start state); shared with BDF2's start.
pub(crate) fn midpoint_step(
    stepper: &mut Stepper,
    system: &mut dyn System,
    params: &NewtonParams,
    dt: Real,
) -> Result<StepStats, IntegratorError> {
    let step = Increment {
        beta: 0.5 * dt,
        reach: dt,
    };
    let stats = stepper.solve(system, params, step)?;
    let rod = system.rod_mut();
    for (((q, v), x), (q0, v0)) in rod
        .positions
        .iter_mut()
        .zip(rod.velocities.iter_mut())
        .zip(&stepper.x)
        .zip(stepper.q0.iter().zip(&stepper.v0))
    {
        *q = q0 + x * dt;
        *v = x * 2.0 - v0;
    }
    Ok(stats)
}

impl Integrator for ImplicitMidpoint {
    fn name(&self) -> &str {
        "implicit-midpoint"
    }

    /// An unconverged Newton solve is an error (the step is rolled back) unless
    /// [`NewtonParams::accept_unconverged`]: an energy-conserving scheme fed unconverged
    /// iterates can gain energy without bound (seen on a compressed cable released at
    /// dt = 10 ms).
    fn step(&mut self, system: &mut dyn System, dt: Real) -> Result<StepStats, IntegratorError> {
        self.stepper.begin(system, dt)?;
        let result = midpoint_step(&mut self.stepper, system, &self.params, dt);
        self.stepper.finish(system, result)
    }

    fn conserves_energy(&self) -> bool {
        true
    }

    fn pin_forces(&self) -> Vec<Vector3<Real>> {
        self.stepper.pin_forces()
    }
}
