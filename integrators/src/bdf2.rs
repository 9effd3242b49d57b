//! BDF2, the second-order backward differentiation formula: L-stable and dissipative
//! (it damps high frequencies strongly and low ones weakly, O((ωh)⁴) per step).
//!
//! \\[ q_{n+1} - \tfrac43 q_n + \tfrac13 q_{n-1} = \tfrac23 h\, v_{n+1}, \qquad
//! M\left(v_{n+1} - \tfrac43 v_n + \tfrac13 v_{n-1}\right) = \tfrac23 h\, f(q_{n+1}, v_{n+1}), \\]
//!
//! with \\(f(q, v) = -\nabla E(q) - \alpha M v + G^T\lambda\\). The Newton unknown is
//! \\(x = v_{n+1}\\); with \\(\hat q = \tfrac13(4 q_n - q_{n-1})\\),
//! \\(\hat v = \tfrac13(4 v_n - v_{n-1})\\) and β = 2h/3, \\(q_{n+1} = \hat q + \beta x\\) and
//! the residual
//!
//! \\[ r(x) = M (x - \hat v) + \beta \nabla E(\hat q + \beta x) + \beta\alpha M x \\]
//!
//! is the gradient of the merit
//! \\(\Phi(x) = \tfrac12 (x - \hat v)^T M (x - \hat v) + E(\hat q + \beta x) + \tfrac{\beta\alpha}{2} x^T M x\\),
//! Newton matrix \\((1 + \beta\alpha) M + \beta^2 K\\):
//! implicit Euler's problem with shifted base and step ([`crate::incremental`]). Pins hold
//! at the end of the step: \\(G x = (p - G\hat q)/\beta\\).
//!
//! **Start.** BDF2 needs the previous state. The first step, and any step after the
//! history became invalid, is an implicit midpoint step ([`crate::ImplicitMidpoint`]):
//! second order and exact for constant accelerations, so free flight stays exact. The
//! history is invalid when `dt` changed (fixed-step coefficients), the basis changed
//! (knot insertion or removal: the old state is in another basis) or the rod's state is
//! not bitwise the one this integrator left (someone else moved it).

use crate::incremental::{Increment, Stepper};
use crate::midpoint::midpoint_step;
use crate::newton::NewtonParams;
use crate::{Integrator, IntegratorError, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};

/// BDF2 with Newton iterations and an implicit-midpoint start (an [`Integrator`]).
#[derive(Debug, Default)]
pub struct Bdf2 {
    /// Newton settings.
    pub params: NewtonParams,
    stepper: Stepper,
    history: History,
}

/// The state one step back and the one this integrator left, to validate the history.
#[derive(Debug, Default)]
struct History {
    valid: bool,
    dt: Real,
    epoch: u64,
    previous_q: Vec<Vector3<Real>>,
    previous_v: Vec<Vector3<Real>>,
    left_q: Vec<Vector3<Real>>,
    left_v: Vec<Vector3<Real>>,
}

impl History {
    /// Whether a BDF2 step may use the stored previous state.
    fn usable(&self, rod: &Rod, dt: Real) -> bool {
        self.valid
            && self.dt == dt
            && self.epoch == rod.topology_epoch()
            && self.left_q == rod.positions
            && self.left_v == rod.velocities
    }

    /// Records a successful step from `(q0, v0)` to the rod's state.
    fn record(&mut self, stepper: &Stepper, rod: &Rod, dt: Real) {
        self.previous_q.clone_from(&stepper.q0);
        self.previous_v.clone_from(&stepper.v0);
        self.left_q.clone_from(&rod.positions);
        self.left_v.clone_from(&rod.velocities);
        self.dt = dt;
        self.epoch = rod.topology_epoch();
        self.valid = true;
    }
}

impl Bdf2 {
    /// A BDF2 integrator with the given Newton settings.
    pub fn new(params: NewtonParams) -> Result<Self, IntegratorError> {
        params.validate()?;
        Ok(Self {
            params,
            ..Self::default()
        })
    }

    /// Forgets the previous state: the next step is a midpoint start step.
    pub fn reset(&mut self) {
        self.history.valid = false;
    }

    fn bdf2_step(
        &mut self,
        system: &mut dyn System,
        dt: Real,
    ) -> Result<StepStats, IntegratorError> {
        let s = &mut self.stepper;
        let h = &self.history;
        let third = 1.0 / 3.0;
        for (b, (q, p)) in s.base_q.iter_mut().zip(s.q0.iter().zip(&h.previous_q)) {
            *b = (q * 4.0 - p) * third;
        }
        for (b, (v, p)) in s.base_v.iter_mut().zip(s.v0.iter().zip(&h.previous_v)) {
            *b = (v * 4.0 - p) * third;
        }
        let beta = 2.0 * dt / 3.0;
        let step = Increment { beta, reach: beta };
        s.solve(system, &self.params, step)
    }
}

impl Integrator for Bdf2 {
    fn name(&self) -> &str {
        "bdf2"
    }

    fn step(&mut self, system: &mut dyn System, dt: Real) -> Result<StepStats, IntegratorError> {
        self.stepper.begin(system, dt)?;
        let result = if self.history.usable(system.rod(), dt) {
            self.bdf2_step(system, dt)
        } else {
            midpoint_step(&mut self.stepper, system, &self.params, dt)
        };
        let result = self.stepper.finish(system, result);
        if result.is_ok() {
            self.history.record(&self.stepper, system.rod(), dt);
        }
        result
    }

    fn pin_forces(&self) -> Vec<Vector3<Real>> {
        self.stepper.pin_forces()
    }
}
