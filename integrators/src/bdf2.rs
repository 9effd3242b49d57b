//! BDF2, the second-order backward differentiation formula: L-stable and dissipative
//! (it damps high frequencies strongly and low ones weakly, O((ωh)⁴) per step).
//!
//! With the step ratio \\(\omega = h_n / h_{n-1}\\) (1 for a constant step) the
//! variable-step formula is
//!
//! \\[ q_{n+1} - \frac{(1+\omega)^2}{1+2\omega} q_n + \frac{\omega^2}{1+2\omega} q_{n-1}
//!     = \frac{1+\omega}{1+2\omega} h_n\, v_{n+1}, \\]
//!
//! and the same for `M v` with \\(h_n f(q_{n+1}, v_{n+1})\\) on the right, where
//! \\(f(q, v) = -\nabla E(q) - \alpha M v + G^T\lambda\\). For ω = 1:
//! \\(q_{n+1} - \tfrac43 q_n + \tfrac13 q_{n-1} = \tfrac23 h v_{n+1}\\). The Newton
//! unknown is \\(x = v_{n+1}\\); with \\(\hat q = \frac{(1+\omega)^2 q_n - \omega^2
//! q_{n-1}}{1+2\omega}\\), \\(\hat v\\) alike and \\(\beta = \frac{1+\omega}{1+2\omega} h_n\\),
//! \\(q_{n+1} = \hat q + \beta x\\) and the residual
//!
//! \\[ r(x) = M (x - \hat v) + \beta \nabla E(\hat q + \beta x) + \beta\alpha M x \\]
//!
//! is the gradient of the merit
//! \\(\Phi(x) = \tfrac12 (x - \hat v)^T M (x - \hat v) + E(\hat q + \beta x) + \tfrac{\beta\alpha}{2} x^T M x\\),
//! Newton matrix \\((1 + \beta\alpha) M + \beta^2 K\\):
//! implicit Euler's problem with shifted base and step ([`crate::incremental`]). Pins hold
//! at the end of the step: \\(G x = (p - G\hat q)/\beta\\).
//!
//! **Rigid bodies** ([`System::bodies`]) take the same formula in the rods' Newton
//! solve, from a base blended on the rotation group ([`crate::bdf2_bodies`]).
//!
//! **Start.** BDF2 needs the previous state. The first step, and any step after the
//! history became invalid, is an implicit midpoint step ([`crate::ImplicitMidpoint`]):
//! second order and exact for constant accelerations, so free flight stays exact; with
//! rigid bodies (which the midpoint rule does not carry) an implicit Euler step. The
//! history is invalid when the step ratio leaves `[1/MAX_STEP_RATIO, MAX_STEP_RATIO]`
//! (variable-step BDF2 is zero-stable for ω < 1 + √2), the basis changed (knot
//! insertion or removal: the old state is in another basis) or the rod's state is not
//! bitwise the one this integrator left (someone else moved it, or a sub-step was
//! rolled back).
//!
//! Its [`Forward`] form carries forward sensitivities through each step, the midpoint
//! start included, with the two-step base's derivative ([`crate::forward`]).

use crate::bdf2_bodies::BodyHistory;
use crate::forward::{Forward, ForwardState, ForwardWork, ParameterRates, StepKind};
use crate::incremental::{Increment, Stepper};
use crate::midpoint::midpoint_step;
use crate::newton::NewtonParams;
use crate::{Integrator, IntegratorError, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::{Real, Rod, SavedState, StateReader};

/// Largest ratio between consecutive step lengths the history survives (zero stability
/// of variable-step BDF2 needs ω < 1 + √2; sub-stepping changes the step by 2 or ½).
pub const MAX_STEP_RATIO: Real = 2.0;

/// BDF2 with Newton iterations and an implicit-midpoint start (an [`Integrator`]).
#[derive(Debug, Default)]
pub struct Bdf2 {
    /// Newton settings.
    pub params: NewtonParams,
    stepper: Stepper,
    history: History,
    forward: ForwardWork,
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
    bodies: BodyHistory,
}

impl History {
    /// Whether a BDF2 step may use the stored previous state.
    fn usable(&self, system: &dyn System, dt: Real) -> bool {
        let ratio = dt / self.dt;
        let rod = system.rod();
        self.valid
            && (1.0 / MAX_STEP_RATIO..=MAX_STEP_RATIO).contains(&ratio)
            && self.epoch == rod.topology_epoch()
            && self.left_q == rod.positions
            && self.left_v == rod.velocities
            && self.bodies.matches(system.bodies())
    }

    /// Records a successful step from `(q0, v0)` to the system's state.
    fn record(&mut self, stepper: &Stepper, system: &dyn System, dt: Real) {
        let rod = system.rod();
        self.bodies.record(stepper.start_bodies(), system.bodies());
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
        let w = dt / h.dt;
        let (a, b) = ((1.0 + w) * (1.0 + w), w * w);
        let scale = 1.0 / (1.0 + 2.0 * w);
        for (base, (q, p)) in s.base_q.iter_mut().zip(s.q0.iter().zip(&h.previous_q)) {
            *base = (q * a - p * b) * scale;
        }
        for (base, (v, p)) in s.base_v.iter_mut().zip(s.v0.iter().zip(&h.previous_v)) {
            *base = (v * a - p * b) * scale;
        }
        if !system.bodies().is_empty() {
            h.bodies
                .blend(system.bodies(), (a * scale, b * scale), &mut s.body_base);
            s.blend_bodies = true;
        }
        let beta = (1.0 + w) * scale * dt;
        let step = Increment { beta, reach: beta };
        self.forward.kind = Some(StepKind::Bdf2 {
            a: a * scale,
            b: b * scale,
        });
        s.solve(system, &self.params, step)
    }
}

impl Integrator for Bdf2 {
    fn name(&self) -> &str {
        "bdf2"
    }

    fn save_state(&self, out: &mut SavedState) {
        let h = &self.history;
        out.int(u64::from(h.valid));
        out.real(h.dt);
        for field in [&h.previous_q, &h.previous_v, &h.left_q, &h.left_v] {
            out.vectors(field);
        }
        h.bodies.save(out);
    }

    fn load_state(
        &mut self,
        rod: &Rod,
        input: &mut StateReader<'_>,
    ) -> Result<(), IntegratorError> {
        let h = &mut self.history;
        h.valid = input.int()? == 1;
        h.dt = input.real()?;
        for field in [
            &mut h.previous_q,
            &mut h.previous_v,
            &mut h.left_q,
            &mut h.left_v,
        ] {
            input.vectors_into(field)?;
        }
        h.bodies.load(input)?;
        h.epoch = rod.topology_epoch();
        Ok(())
    }

    fn step(&mut self, system: &mut dyn System, dt: Real) -> Result<StepStats, IntegratorError> {
        self.forward.kind = None;
        self.stepper.bodies = true;
        self.stepper.begin(system, dt)?;
        let result = if self.history.usable(system, dt) {
            self.bdf2_step(system, dt)
        } else if !system.bodies().is_empty() {
            self.forward.kind = Some(StepKind::Euler);
            let step = Increment {
                beta: dt,
                reach: dt,
            };
            self.stepper.solve(system, &self.params, step)
        } else {
            self.forward.kind = Some(StepKind::Midpoint);
            midpoint_step(&mut self.stepper, system, &self.params, dt)
        };
        let result = self.stepper.finish(system, result);
        if result.is_ok() {
            self.history.record(&self.stepper, system, dt);
        } else {
            self.forward.kind = None;
        }
        result
    }

    fn forward(&mut self) -> Option<&mut dyn Forward> {
        Some(self)
    }

    fn pin_forces(&self) -> Vec<Vector3<Real>> {
        self.stepper.pin_forces()
    }
}

impl Forward for Bdf2 {
    fn propagate(
        &mut self,
        system: &mut dyn System,
        rates: &mut dyn ParameterRates,
        states: &mut [ForwardState],
    ) -> Result<StepStats, IntegratorError> {
        let (stepper, work) = (&mut self.stepper, &mut self.forward);
        crate::forward::propagate(stepper, work, &self.params, (system, rates), states)
    }
}
