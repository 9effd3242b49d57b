//! Implicit (backward) Euler: \\(v^+ = v_0 + h M^{-1} f(q^+, v^+)\\),
//! \\(q^+ = q_0 + h v^+\\), solved by Newton on the incremental potential
//!
//! \\[ \Phi(v) = \tfrac12 (v - v_0)^T M (v - v_0) + E(q_0 + h v) + \tfrac{h\alpha}{2} v^T M v, \\]
//!
//! whose gradient is the residual \\(M(v - v_0) + h\nabla E + h\alpha M v\\) and whose
//! Newton matrix is \\((1 + h\alpha) M + h^2 K\\). Pins hold \\(C(s_p, t + h) = p\\), i.e.
//! \\(G v = (p - G q_0)/h\\). First order; damps a mode of angular frequency ω by
//! \\(1/\sqrt{1 + (\omega h)^2}\\) per step, so it never gains energy.
//!
//! This is the shared incremental problem ([`crate::incremental`]) with
//! \\(\hat q = q_0\\), \\(\hat v = v_0\\) and β = ρ = h.

use crate::incremental::{Increment, Stepper};
use crate::newton::NewtonParams;
use crate::{Integrator, IntegratorError, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::Real;

/// Implicit Euler with Newton iterations (an [`Integrator`]).
#[derive(Debug, Default)]
pub struct ImplicitEuler {
    /// Newton settings.
    pub params: NewtonParams,
    stepper: Stepper,
}

impl ImplicitEuler {
    /// An implicit Euler integrator with the given Newton settings.
    pub fn new(params: NewtonParams) -> Result<Self, IntegratorError> {
        params.validate()?;
        Ok(Self {
            params,
            ..Self::default()
        })
    }
}

impl Integrator for ImplicitEuler {
    fn name(&self) -> &str {
        "implicit-euler"
    }

    fn step(&mut self, system: &mut dyn System, dt: Real) -> Result<StepStats, IntegratorError> {
        self.stepper.begin(system, dt)?;
        let step = Increment {
            beta: dt,
            reach: dt,
        };
        let result = self.stepper.solve(system, &self.params, step);
        self.stepper.finish(system, result)
    }

    fn pin_forces(&self) -> Vec<Vector3<Real>> {
        self.stepper.pin_forces()
    }
}
