//! Forward (tangent-linear) sensitivities of a run: the derivatives
//! \\(S_q = \mathrm{d}q/\mathrm{d}p\\), \\(S_v = \mathrm{d}v/\mathrm{d}p\\) of the state by
//! scalar parameters `p`, carried through every step of [`crate::ImplicitEuler`] and
//! [`crate::Bdf2`] (and BDF2's implicit-midpoint start) with the step's own Newton matrix.
//!
//! **The step.** Every one of these steps solves the incremental problem
//! (the crate's `incremental.rs`) for the velocity `x`, with base \\(\hat q, \hat v\\), effective
//! step β and reach ρ: at the solution
//!
//! \\[ r = M\big((1 + \beta\alpha) x - \hat v\big) + \beta \nabla E(q_e; p) = G^T\mu,
//!     \qquad q_e = \hat q + \beta x, \qquad G(\hat q + \rho x) = c. \\]
//!
//! Its derivative by `p`, written for \\(z = \mathrm{d}q_e/\mathrm{d}p = \hat q' +
//! \beta \dot x\\) (so that the Hessian `K` appears only in the Newton matrix
//! \\(A = (1 + \beta\alpha) M + \beta^2 K\\), never as a product), is
//!
//! \\[ A z - G^T (\beta\dot\mu) = (1 + \beta\alpha) M \hat q' - \beta\Big[
//!     M'\big((1 + \beta\alpha)x - \hat v\big) - M \hat v' + \beta\alpha' M x
//!     + \beta\, \partial_p \nabla E \Big], \qquad
//!     G z = G \hat q' + \tfrac{\beta}{\rho}\big(\dot c - G \hat q'\big), \\]
//!
//! with `M' = m_p M` (the mass matrix is linear in the density), `α'` the damping's
//! rate and \\(\partial_p \nabla E\\) at \\(q_e\\) from the caller ([`ParameterRates`]).
//! It is solved by [`crate::newton::tangents`]: `A` assembled and factorised once at
//! \\(q_e\\) (the exact Hessian: a step that needed the definite stand-in at its
//! solution is an error, not an approximate answer), one solve per parameter; the
//! pins' targets' derivatives \\(\dot c\\) come from the caller
//! ([`ParameterRates::target_rate`]: non-zero for a parameter that moves a pin).
//! What the energies froze at the step's start (friction's anchors at \\(q_n\\)) enters
//! \\(\partial_p\nabla E\\) through \\(S_q\\) at the start
//! ([`ParameterRates::add_start_rate`]).
//!
//! **The update.** With \\(\dot x = (z - \hat q')/\beta\\): implicit Euler and BDF2 end
//! at \\(q^+ = q_e\\), \\(v^+ = x\\), so \\(S_q^+ = z\\), \\(S_v^+ = \dot x\\); the
//! midpoint start ends at \\(q^+ = q_0 + h x\\), \\(v^+ = 2x - v_0\\), so
//! \\(S_q^+ = S_q + h\dot x\\), \\(S_v^+ = 2\dot x - S_v\\). The bases: implicit Euler
//! and the midpoint rule \\(\hat q = q_n\\), \\(\hat v = v_n\\); BDF2
//! \\(\hat q = a q_n - b q_{n-1}\\) (`a`, `b` its step-ratio coefficients), so
//! \\(\hat q' = a S_{q,n} - b S_{q,n-1}\\) and the same for `v`. The pins' forces are
//! \\(\mu/\beta\\): their derivatives \\(\beta\dot\mu / \beta^2\\).
//!
//! **Exact, and not.** The derivatives are those of the discrete run (to the Newton
//! tolerance of its steps): the Hessian is exact, every term of the residual is
//! differentiated. What an energy takes from the start of the step (the energies'
//! `begin_step`) is differentiated where the energy says how
//! ([`ParameterRates::add_start_rate`]: friction's anchors), else held fixed (friction's
//! normal forces and normals, a contact barrier's adapted stiffness). Steps handed over by the batched
//! form ([`crate::Batched::preload`]) have no solve here to differentiate: an error.

use crate::newton::Tangent;
use crate::{IntegratorError, NewtonParams, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::Real;

use crate::incremental::Stepper;

/// The derivatives of a run's state by one parameter.
#[derive(Debug, Clone, Default)]
pub struct ForwardState {
    /// \\(S_q\\): the control points' derivative, m per unit.
    pub positions: Vec<Vector3<Real>>,
    /// \\(S_v\\): the control points' velocities' derivative, m/s per unit.
    pub velocities: Vec<Vector3<Real>>,
    /// The derivative of each pin's force during the last step, N per unit.
    pub pin_forces: Vec<Vector3<Real>>,
    /// \\(S_q\\) one step back (BDF2's history).
    previous_positions: Vec<Vector3<Real>>,
    /// \\(S_v\\) one step back.
    previous_velocities: Vec<Vector3<Real>>,
}

impl ForwardState {
    /// Zero derivatives for a rod of `n` control points (a start that does not depend on
    /// the parameter).
    pub fn new(n: usize) -> Self {
        let zeros = vec![Vector3::zeros(); n];
        Self {
            positions: zeros.clone(),
            velocities: zeros.clone(),
            pin_forces: Vec::new(),
            previous_positions: zeros.clone(),
            previous_velocities: zeros,
        }
    }
}

/// What a step's residual takes from the parameters, given by the caller per parameter
/// `k` (its index in the states handed to [`Forward::propagate`]).
pub trait ParameterRates {
    /// Writes \\(\partial \nabla E / \partial p_k\\) (every energy's, and any load's) at
    /// the system's current state into `out` (overwritten, one entry per control point).
    fn gradient_rate(
        &mut self,
        system: &dyn System,
        k: usize,
        out: &mut [Vector3<Real>],
    ) -> Result<(), IntegratorError>;
    /// \\(m_k\\) with \\(\partial M / \partial p_k = m_k M\\) (`1/μ` for the density μ, else 0).
    fn mass_rate(&self, k: usize) -> Real;
    /// \\(\partial\alpha / \partial p_k\\) (1 for the damping rate itself, else 0).
    fn damping_rate(&self, k: usize) -> Real;
    /// Adds to `out` the derivative of the gradient through what the energies froze at
    /// the step's start, whose positions have the derivative `start_rate` (\\(S_q\\) at
    /// the step's start; e.g. friction's anchors). Default: nothing frozen.
    fn add_start_rate(
        &mut self,
        system: &dyn System,
        start_rate: &[Vector3<Real>],
        out: &mut [Vector3<Real>],
    ) -> Result<(), IntegratorError> {
        let _ = (system, start_rate, out);
        Ok(())
    }
    /// \\(\dot c\\): the derivative by \\(p_k\\) of pin `pin`'s target (a parameter that
    /// moves the pin). Default zero.
    fn target_rate(&self, k: usize, pin: usize) -> Vector3<Real> {
        let _ = (k, pin);
        Vector3::zeros()
    }
}

/// A scheme that carries forward sensitivities through its last step
/// ([`crate::Integrator::forward`]).
pub trait Forward {
    /// After a successful step: advances each state of `states` (one per parameter,
    /// sized for the rod) through it, see the module docs. `rates` gives the residual's
    /// parameter derivatives. An error if the last step cannot be differentiated (not
    /// solved by this integrator, or its matrix not the exact Hessian).
    fn propagate(
        &mut self,
        system: &mut dyn System,
        rates: &mut dyn ParameterRates,
        states: &mut [ForwardState],
    ) -> Result<StepStats, IntegratorError>;
}

/// What the last step was, for its derivative.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum StepKind {
    /// Implicit Euler: base = start state, end at the solve's iterate.
    Euler,
    /// BDF2: base = `a · now − b · previous`, end at the solve's iterate.
    Bdf2 {
        /// Weight of the current state.
        a: Real,
        /// Weight of the previous state.
        b: Real,
    },
    /// The implicit midpoint rule (BDF2's start step).
    Midpoint,
}

/// Buffers of the forward sensitivities, sized once.
#[derive(Debug, Default)]
pub(crate) struct ForwardWork {
    /// What the last step was (`None`: nothing to differentiate).
    pub kind: Option<StepKind>,
    base_q: Vec<Vector3<Real>>,
    base_v: Vec<Vector3<Real>>,
    rate: Vec<Vector3<Real>>,
    scratch: Vec<Vector3<Real>>,
    inner: Vec<Vector3<Real>>,
    cases: Vec<Tangent>,
    /// The rod's end state while it holds the midpoint's iterate.
    end: (Vec<Vector3<Real>>, Vec<Vector3<Real>>),
}

/// [`Forward::propagate`] for a scheme built on `stepper`.
pub(crate) fn propagate(
    stepper: &mut Stepper,
    work: &mut ForwardWork,
    params: &NewtonParams,
    (system, rates): (&mut dyn System, &mut dyn ParameterRates),
    states: &mut [ForwardState],
) -> Result<StepStats, IntegratorError> {
    let kind = work.kind.ok_or(IntegratorError::SolverState(
        "forward sensitivities need the last step solved by implicit Euler or BDF2",
    ))?;
    let step = stepper.step.ok_or(IntegratorError::SolverState(
        "forward sensitivities need a step solved first",
    ))?;
    let n = system.rod().len();
    if states
        .iter()
        .any(|s| s.positions.len() != n || s.previous_positions.len() != n)
    {
        return Err(IntegratorError::SolverState(
            "forward sensitivities sized for another number of control points",
        ));
    }
    let midpoint = kind == StepKind::Midpoint;
    if midpoint {
        hold_iterate(stepper, work, system);
    }
    let result = tangent_solves(stepper, work, params, (&*system, rates), states, kind);
    if midpoint {
        let rod = system.rod_mut();
        std::mem::swap(&mut rod.positions, &mut work.end.0);
        std::mem::swap(&mut rod.velocities, &mut work.end.1);
    }
    let stats = result?;
    for (state, case) in states.iter_mut().zip(&work.cases) {
        advance(state, case, kind, step.beta, step.reach);
    }
    Ok(stats)
}

/// Puts the midpoint step's solve iterate \\((q_0 + \beta x, x)\\) in the rod, its end
/// state in `work.end`.
fn hold_iterate(stepper: &Stepper, work: &mut ForwardWork, system: &mut dyn System) {
    let beta = stepper.step.map_or(0.0, |s| s.beta);
    let rod = system.rod_mut();
    work.end.0.clone_from(&rod.positions);
    work.end.1.clone_from(&rod.velocities);
    for ((q, v), (x, b)) in rod
        .positions
        .iter_mut()
        .zip(rod.velocities.iter_mut())
        .zip(stepper.x.iter().zip(&stepper.base_q))
    {
        *q = b + x * beta;
        *v = *x;
    }
}

/// Sets up one tangent problem per state and solves them all.
fn tangent_solves(
    stepper: &mut Stepper,
    work: &mut ForwardWork,
    params: &NewtonParams,
    (system, rates): (&dyn System, &mut dyn ParameterRates),
    states: &[ForwardState],
    kind: StepKind,
) -> Result<StepStats, IntegratorError> {
    let n = system.rod().len();
    let pins = system.pins().len();
    for v in [
        &mut work.base_q,
        &mut work.base_v,
        &mut work.rate,
        &mut work.scratch,
    ] {
        v.resize(n, Vector3::zeros());
    }
    work.cases.resize_with(states.len(), Tangent::default);
    for (k, state) in states.iter().enumerate() {
        base_rates(work, state, kind);
        rates.gradient_rate(system, k, &mut work.rate)?;
        rates.add_start_rate(system, &state.positions, &mut work.rate)?;
        let case = &mut work.cases[k];
        case.residual_rate.resize(n, Vector3::zeros());
        case.target_rates.resize(pins, Vector3::zeros());
        let (m, a) = (rates.mass_rate(k), rates.damping_rate(k));
        residual_rate(stepper, (m, a), system, work);
        let case = &mut work.cases[k];
        case.residual_rate.copy_from_slice(&work.scratch);
        let step = stepper
            .step
            .ok_or(IntegratorError::SolverState("a solved step"))?;
        let ratio = step.beta / step.reach;
        let keep = 1.0 - ratio;
        for (p, (t, pin)) in case.target_rates.iter_mut().zip(system.pins()).enumerate() {
            *t = rates.target_rate(k, p) * ratio;
            if keep == 0.0 {
                continue;
            }
            let row = pin
                .row(system.rod())
                .map_err(|_| IntegratorError::SolverState("a pin's row"))?;
            *t += row.combine(&row.value, &work.base_q) * keep;
        }
    }
    stepper.tangents(system, params, &mut work.cases)
}

/// The bases' derivatives \\(\hat q', \hat v'\\) of a step of `kind` into `work`.
fn base_rates(work: &mut ForwardWork, state: &ForwardState, kind: StepKind) {
    let (a, b) = match kind {
        StepKind::Bdf2 { a, b } => (a, b),
        _ => (1.0, 0.0),
    };
    let q = state.positions.iter().zip(&state.previous_positions);
    for (out, (now, before)) in work.base_q.iter_mut().zip(q) {
        *out = now * a - before * b;
    }
    let v = state.velocities.iter().zip(&state.previous_velocities);
    for (out, (now, before)) in work.base_v.iter_mut().zip(v) {
        *out = now * a - before * b;
    }
}

/// The tangent problem's residual rate (the negated right-hand side of the module
/// docs' equation for `z`) into `work.scratch`, from the bases' rates and the gradient
/// rate in `work`, and the mass and damping rates `(m, a)`.
fn residual_rate(
    stepper: &Stepper,
    (m, a): (Real, Real),
    system: &dyn System,
    work: &mut ForwardWork,
) {
    let rod = system.rod();
    let beta = stepper.step.map_or(0.0, |s| s.beta);
    let x = &rod.velocities;
    work.inner.resize(x.len(), Vector3::zeros());
    // t_i = β[m((1 + βα_i) x_i − v̂_i) − v̂'_i + βα' x_i] − (1 + βα_i) q̂'_i, then M t.
    for (i, t) in work.inner.iter_mut().enumerate() {
        let c = 1.0 + beta * stepper.damping_at(i);
        let v0 = stepper.base_v[i];
        let inner = (x[i] * c - v0) * m - work.base_v[i] + x[i] * (beta * a);
        *t = inner * beta - work.base_q[i] * c;
    }
    rod.mass_matrix().mul_vec3(&work.inner, &mut work.scratch);
    for (s, g) in work.scratch.iter_mut().zip(&work.rate) {
        *s += g * (beta * beta);
    }
}

/// Advances `state` by the solved `case` of a step of `kind`, β and ρ.
fn advance(state: &mut ForwardState, case: &Tangent, kind: StepKind, beta: Real, reach: Real) {
    let (a, b) = match kind {
        StepKind::Bdf2 { a, b } => (a, b),
        _ => (1.0, 0.0),
    };
    std::mem::swap(&mut state.previous_positions, &mut state.positions);
    std::mem::swap(&mut state.previous_velocities, &mut state.velocities);
    // Now `previous` holds S_n and `positions` S_{n−1}: the new state overwrites the latter.
    let rows = state
        .positions
        .iter_mut()
        .zip(state.velocities.iter_mut())
        .zip(
            state
                .previous_positions
                .iter()
                .zip(&state.previous_velocities),
        )
        .zip(&case.positions);
    for (((q, v), (q_n, v_n)), z) in rows {
        let base_q = q_n * a - *q * b;
        let rate = (z - base_q) / beta;
        let v_base = v_n * a - *v * b;
        *q = base_q + rate * reach;
        *v = match kind {
            StepKind::Midpoint => rate * 2.0 - v_base,
            _ => rate,
        };
    }
    let scale = 1.0 / (beta * beta);
    state.pin_forces.clear();
    let forces = case.multipliers.iter().map(|mu| mu * scale);
    state.pin_forces.extend(forces);
}
