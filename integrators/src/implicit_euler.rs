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
//!
//! Its [`Forward`] form carries forward sensitivities through each solved step
//! ([`crate::forward`]).

use crate::forward::{Forward, ForwardState, ForwardWork, ParameterRates, StepKind};
use crate::incremental::{Increment, Stepper};
use crate::lane_euler::LaneOutcome;
use crate::newton::NewtonParams;
use crate::{Batched, Integrator, IntegratorError, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::Real;

/// Implicit Euler with Newton iterations (an [`Integrator`]).
#[derive(Debug, Default)]
pub struct ImplicitEuler {
    /// Newton settings.
    pub params: NewtonParams,
    stepper: Stepper,
    preloaded: Preloaded,
    forward: ForwardWork,
}

/// A step the batched form took ([`Batched::preload`]), waiting for the step it is.
///
/// The step is recognised by its `dt` and a copy of its start state, compared with the
/// rod's state bit for bit ([`same_bits`]): exact by construction, where a hash of the
/// state (which this replaced, #47) could take another state for the start, and where a
/// write counter on the rod would be exact only if every writer of its public fields
/// counted. The copy reuses its buffers: no allocation once sized.
#[derive(Debug, Default)]
struct Preloaded {
    live: bool,
    dt: Real,
    /// The start state (positions, velocities) the step was taken from.
    start: (Vec<Vector3<Real>>, Vec<Vector3<Real>>),
    end: (Vec<Vector3<Real>>, Vec<Vector3<Real>>),
    stats: StepStats,
    forces: Vec<Vector3<Real>>,
}

impl Preloaded {
    /// Whether it is the step of `dt` from the system's current state.
    fn fits(&self, system: &dyn System, dt: Real) -> bool {
        let rod = system.rod();
        self.dt.to_bits() == dt.to_bits()
            && rod.positions.len() == self.end.0.len()
            && rod.velocities.len() == self.end.1.len()
            && same_bits(&rod.positions, &self.start.0)
            && same_bits(&rod.velocities, &self.start.1)
    }
}

/// Whether two fields are equal bit for bit: the same length and every coordinate's
/// [`f64::to_bits`] equal (so `-0.0` is not `0.0`, and a NaN is only itself).
fn same_bits(a: &[Vector3<Real>], b: &[Vector3<Real>]) -> bool {
    a.len() == b.len()
        && a.iter().zip(b).all(|(x, y)| {
            x.iter()
                .zip(y.iter())
                .all(|(p, q)| p.to_bits() == q.to_bits())
        })
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
        // A preloaded step is used once, and only for the step it was taken as.
        self.forward.kind = None;
        if std::mem::take(&mut self.preloaded.live) && self.preloaded.fits(system, dt) {
            let p = &mut self.preloaded;
            return self
                .stepper
                .accept(system, &mut p.end, (p.stats, &p.forces), dt);
        }
        self.stepper.bodies = true;
        self.stepper.begin(system, dt)?;
        let step = Increment {
            beta: dt,
            reach: dt,
        };
        let result = self.stepper.solve(system, &self.params, step);
        let result = self.stepper.finish(system, result);
        if result.is_ok() {
            self.forward.kind = Some(StepKind::Euler);
        }
        result
    }

    fn pin_forces(&self) -> Vec<Vector3<Real>> {
        self.stepper.pin_forces()
    }

    fn batched(&mut self) -> Option<&mut dyn Batched> {
        Some(self)
    }

    fn forward(&mut self) -> Option<&mut dyn Forward> {
        Some(self)
    }
}

impl Forward for ImplicitEuler {
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

impl Batched for ImplicitEuler {
    fn lane_params(&self) -> NewtonParams {
        self.params
    }

    fn preload(
        &mut self,
        start: (&[Vector3<Real>], &[Vector3<Real>]),
        outcome: &LaneOutcome<'_>,
        dt: Real,
    ) {
        let p = &mut self.preloaded;
        p.start.0.clear();
        p.start.0.extend_from_slice(start.0);
        p.start.1.clear();
        p.start.1.extend_from_slice(start.1);
        p.end.0.clear();
        p.end.0.extend_from_slice(outcome.positions);
        p.end.1.clear();
        p.end.1.extend_from_slice(outcome.velocities);
        p.forces.clear();
        p.forces.extend_from_slice(outcome.pin_forces);
        (p.stats, p.dt, p.live) = (outcome.stats, dt, true);
    }
}
