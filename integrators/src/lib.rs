//! # splinerod-integrators
//!
//! Time integrators and solvers for a rod with energies and pins, seen through the small
//! [`System`] view: three [`Integrator`]s — [`ImplicitEuler`] (first order, dissipative),
//! [`ImplicitMidpoint`] (second order, symplectic) and [`Bdf2`] (second order,
//! dissipative) — the [`StaticSolver`] for equilibria, and [`modal::modes`] for natural
//! frequencies. Newton's method ([`newton`]) and the sparse Cholesky solve ([`linear`])
//! are shared by all of them; the [`conformance`] suite checks any integrator.
//!
//! Equations of motion, with mass matrix `M`, potential `E` (elastic + gravity),
//! mass-proportional damping `α` and pins \\(G q = p\\) enforced by multipliers `λ`:
//!
//! \\[ M \ddot q = -\nabla E(q) - \alpha M \dot q + G^T \lambda. \\]
//!
//! Implicit Euler with step `h` finds \\(v^+\\) minimising the incremental potential
//! \\(\Phi(v) = \tfrac12 (v - v_0)^T M (v - v_0) + E(q_0 + h v) + \tfrac{h\alpha}{2} v^T M v\\)
//! subject to \\(G (q_0 + h v) = p\\): Newton on \\(\nabla\Phi = 0\\) with matrix
//! \\(A = (1 + h\alpha) M + h^2 K\\), `K` the positive semi-definite Hessian.
//!
//! ```
//! use splinerod_integrators::{ImplicitEuler, Integrator, NewtonParams};
//! let mut euler: Box<dyn Integrator> = Box::new(ImplicitEuler::new(NewtonParams::default())?);
//! assert_eq!(euler.name(), "implicit-euler");
//! # Ok::<(), splinerod_integrators::IntegratorError>(())
//! ```
#![warn(missing_docs)]

mod banded_cholesky;
pub mod banded_ldlt;
pub mod batched;
mod bdf2;
mod bdf2_bodies;
mod block_pattern;
pub mod block_sparse;
#[cfg(test)]
mod cholesky_variants;
pub mod conformance;
pub mod convergence;
mod error;
pub mod forward;
mod implicit_euler;
mod incremental;
mod kkt;
pub mod lane_euler;
pub mod linear;
mod low_rank;
mod midpoint;
pub mod modal;
pub mod newton;
mod periodic;
mod point_pins;
pub mod remainder;
mod statics;

pub use banded_cholesky::BandedCholesky;
pub use bdf2::Bdf2;
pub use convergence::{ConvergenceTracker, NewtonVerdict};
pub use error::IntegratorError;
pub use forward::{Forward, ForwardState, ParameterRates};
pub use implicit_euler::ImplicitEuler;
pub use linear::LinearSolverKind;
pub use midpoint::ImplicitMidpoint;
pub use newton::NewtonParams;
pub use statics::{StaticParams, StaticSolver, CONSTRAINT_TOLERANCE, MAX_MULTIPLIER_UPDATES};

use nalgebra::{Matrix6, UnitQuaternion, Vector3, Vector6};
use splinerod_core::{
    Attachment, BlockBanded, HessianKind, Pin, Real, RigidBody, Rod, SavedState, StateReader,
};

/// What an integrator needs of a mechanical system: a rod (state, mass, damping), its
/// pins and its total potential energy with derivatives.
///
/// The facade implements it by summing its energies; tests implement it directly.
pub trait System: Send + Sync {
    /// The rod.
    fn rod(&self) -> &Rod;
    /// The rod, mutably (integrators write positions and velocities).
    fn rod_mut(&mut self) -> &mut Rod;
    /// Pins (their positions are the targets at the end of the step).
    fn pins(&self) -> &[Pin];
    /// Total potential energy at the rod's positions, J.
    fn potential_energy(&self) -> Real;
    /// Adds the gradient of the potential energy.
    fn add_potential_gradient(&self, gradient: &mut [Vector3<Real>]);
    /// Adds the Hessian of the potential energy (see [`HessianKind`]).
    fn add_potential_hessian(&self, kind: HessianKind, hessian: &mut BlockBanded);
    /// Adds the gradient and the Hessian of the potential energy in one call (by default
    /// the two calls above; a system whose energies share a pass over the rod overrides
    /// it). Equal to the two calls up to round-off.
    fn add_potential_gradient_and_hessian(
        &self,
        kind: HessianKind,
        gradient: &mut [Vector3<Real>],
        hessian: &mut BlockBanded,
    ) {
        self.add_potential_gradient(gradient);
        self.add_potential_hessian(kind, hessian);
    }
    /// Whether the potential's Hessian has a part that is not banded, left out of
    /// [`add_potential_hessian`](System::add_potential_hessian) and applied by
    /// [`add_hessian_remainder`](System::add_hessian_remainder). Default: none.
    fn has_hessian_remainder(&self) -> bool {
        false
    }
    /// Adds `scale · R v` for that remainder `R` (symmetric positive semi-definite, the
    /// same for both [`HessianKind`]s). Default: nothing.
    fn add_hessian_remainder(&self, v: &[Vector3<Real>], scale: Real, out: &mut [Vector3<Real>]) {
        let _ = (v, scale, out);
    }
    /// Block bandwidth of the potential's Hessian (the largest over the energies; the
    /// degree by default). Newton matrices are sized with it.
    fn hessian_bandwidth(&self) -> usize {
        self.rod().basis().degree()
    }
    /// Whether the current state is one Newton's line search may move to, from a state
    /// that is: a penalty is a finite barrier, and with long time steps the line search
    /// could otherwise accept strands passing through each other. Default: always.
    fn admissible(&self) -> bool {
        true
    }
    /// Scales the stiffness of every energy that has one to `scale` times its own (`1`
    /// restores it exactly): the static solver's continuation from a soft rod to the
    /// real one ([`StaticSolver`]). Returns whether anything was scaled (the default:
    /// no).
    fn set_stiffness_scale(&mut self, scale: Real) -> bool {
        let _ = scale;
        false
    }
    /// One multiplier update of every constraint held by multipliers (the inextensible
    /// rod), `stiffen`ing penalties that fall too slowly; the largest violation before
    /// it. Default: no constraints, 0.
    fn update_multipliers(&mut self, stiffen: bool) -> Real {
        let _ = stiffen;
        0.0
    }
    /// Whether the solve under way must be abandoned (a stop was asked from outside,
    /// e.g. by a signal: [`splinerod_core::Cancel::abandon`]). Newton's method polls it
    /// once per iteration and then returns [`IntegratorError::Interrupted`], leaving the
    /// rollback to its caller as for any error; it must be as cheap as an atomic load.
    /// Default: never.
    fn interrupted(&self) -> bool {
        false
    }
    /// The concrete system, for a caller's callback handed the system back (a forward
    /// sensitivity's [`ParameterRates`] reads the facade's energies through it).
    /// Default `None`.
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        None
    }
    /// The rigid bodies the rod's pins hold ([`System::attachments`]), solved in the same
    /// Newton system by the schemes that support them. Default: none.
    fn bodies(&self) -> &[RigidBody] {
        &[]
    }
    /// The bodies, to write a solved step's state into.
    fn bodies_mut(&mut self) -> &mut [RigidBody] {
        &mut []
    }
    /// Which pins the bodies hold, and where. Default: none.
    fn attachments(&self) -> &[Attachment] {
        &[]
    }
    /// The potential of body `body`'s own forces that depend on its pose `(x, r)`
    /// (contact of its shapes with the floor and obstacles), J; adds its gradient and a
    /// positive semi-definite Hessian with respect to a translation and a rotation
    /// (`r ← exp([δθ]×) r`) to `grad` and `hess`. Default: none.
    fn add_body_potential(
        &self,
        body: usize,
        pose: (&Vector3<Real>, &UnitQuaternion<Real>),
        grad: &mut Vector6<Real>,
        hess: &mut Matrix6<Real>,
    ) -> Real {
        let _ = (body, pose, grad, hess);
        0.0
    }
}

/// Counters of one step or solve, for statistics and regression snapshots.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// Newton iterations (= numeric factorisations of the Newton matrix).
    pub newton_iterations: usize,
    /// Symbolic analyses (only after the basis or the far block pattern changed).
    pub symbolic_analyses: usize,
    /// Line-search step reductions.
    pub line_search_cuts: usize,
    /// Whether the residual reached the tolerance.
    pub converged: bool,
    /// Norm of the last residual (constraint forces removed), in the problem's units.
    pub residual: Real,
    /// Pseudo-transient continuation steps of an equilibrium solve whose Newton failed.
    pub continuation_steps: usize,
    /// Multiplier updates of an equilibrium solve with constraints.
    pub multiplier_updates: usize,
    /// Conjugate-gradient iterations correcting Newton steps for a Hessian remainder
    /// ([`System::add_hessian_remainder`]).
    pub remainder_iterations: usize,
    /// Steps whose solve the batched ensemble step took ([`lane_euler`]; 1 for such a
    /// step, summed over sequences).
    pub batched: usize,
}

impl StepStats {
    /// Adds the counters of `other` (iterations, analyses, cuts, continuation steps,
    /// multiplier updates, batched steps) and takes its residual; what `converged` means for the sum is
    /// the caller's choice.
    pub fn add_counts(&mut self, other: &StepStats) {
        self.newton_iterations += other.newton_iterations;
        self.symbolic_analyses += other.symbolic_analyses;
        self.line_search_cuts += other.line_search_cuts;
        self.continuation_steps += other.continuation_steps;
        self.multiplier_updates += other.multiplier_updates;
        self.remainder_iterations += other.remainder_iterations;
        self.batched += other.batched;
        self.residual = other.residual;
    }
}

/// The counters of a sequence of steps: sums, the last residual, and converged only if
/// every step was.
impl std::ops::AddAssign for StepStats {
    fn add_assign(&mut self, other: StepStats) {
        let first = *self == StepStats::default();
        self.add_counts(&other);
        self.converged = other.converged && (first || self.converged);
    }
}

/// What an [`Integrator`]'s step is ([`Integrator::role`]).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Role {
    /// A step in time of the given duration, with inertia (the time integrators).
    #[default]
    Dynamic,
    /// An equilibrium solve under the loads at the step's end (the [`StaticSolver`]).
    Equilibrium,
}

/// A scheme whose step the batched ensemble step can take for it ([`lane_euler`]): an
/// ensemble steps the members whose schemes have this form several at once and hands
/// each its result. Reached through [`Integrator::batched`].
pub trait Batched: Send + Sync {
    /// The Newton settings with which this scheme's step is the batched implicit Euler
    /// step.
    fn lane_params(&self) -> NewtonParams;

    /// Hands the scheme the step of `dt` the batched form took from the state `start`
    /// (positions, velocities): the next [`Integrator::step`] of the same `dt` from that
    /// state (recognised exactly: the same bits) takes it instead of solving; any other
    /// step ignores it.
    fn preload(
        &mut self,
        start: (&[Vector3<Real>], &[Vector3<Real>]),
        outcome: &lane_euler::LaneOutcome<'_>,
        dt: Real,
    );
}

/// Advances a [`System`] in time, or solves for its equilibrium ([`Role`]).
///
/// Required: [`name`](Integrator::name) and [`step`](Integrator::step). On error the
/// system is left exactly as before the step. A scheme the batched ensemble step can
/// take says so through [`batched`](Integrator::batched).
///
/// A minimal implementation, the explicit (symplectic) Euler step without pins:
/// ```
/// use splinerod_core::Real;
/// use splinerod_integrators::{Integrator, IntegratorError as Error, StepStats, System};
/// use nalgebra::Vector3;
///
/// struct Explicit;
/// impl Integrator for Explicit {
///     fn name(&self) -> &str { "explicit" }
///     fn step(&mut self, system: &mut dyn System, dt: Real) -> Result<StepStats, Error> {
///         let mut gradient = vec![Vector3::zeros(); system.rod().len()];
///         system.add_potential_gradient(&mut gradient);
///         let rod = system.rod_mut();
///         let masses = rod.lumped_masses().to_vec();
///         for ((v, g), m) in rod.velocities.iter_mut().zip(&gradient).zip(&masses) {
///             *v -= g * (dt / m);
///         }
///         for (q, v) in rod.positions.iter_mut().zip(&rod.velocities) {
///             *q += v * dt;
///         }
///         Ok(StepStats { converged: true, ..StepStats::default() })
///     }
/// }
/// ```
pub trait Integrator: Send + Sync {
    /// Short name, as used in scene files (`"implicit-euler"`).
    fn name(&self) -> &str;
    /// Advances `system` by `dt` seconds; pins must already hold their end-of-step targets.
    fn step(&mut self, system: &mut dyn System, dt: Real) -> Result<StepStats, IntegratorError>;
    /// Whether the scheme conserves the energy of an undamped, unforced system (the
    /// implicit midpoint rule): a step that gains energy is then an error of the step
    /// length (for nonlinear elasticity such a scheme can blow up at long steps), and a
    /// sub-stepping controller may reject it. Default false.
    fn conserves_energy(&self) -> bool {
        false
    }
    /// What a step is: a step in time (the default) or an equilibrium solve (the
    /// [`StaticSolver`]: no duration of its own — no inertia, no sub-steps, no per-step
    /// energy hooks — and the equilibrium under the loads at its end).
    fn role(&self) -> Role {
        Role::Dynamic
    }
    /// Forces the pins exerted on the rod during the last step, N, one per pin (empty if
    /// the integrator does not compute them).
    fn pin_forces(&self) -> Vec<Vector3<Real>> {
        Vec::new()
    }
    /// The scheme's [`Batched`] form, if the batched ensemble step can take its steps
    /// ([`lane_euler`]). Default `None`: the scheme has no batched form.
    fn batched(&mut self) -> Option<&mut dyn Batched> {
        None
    }
    /// The scheme's [`Forward`] form, if it can carry forward sensitivities through its
    /// steps ([`forward`]: implicit Euler and BDF2). Default `None`.
    fn forward(&mut self) -> Option<&mut dyn Forward> {
        None
    }
    /// Appends what the scheme keeps between steps (a multistep scheme's history), for a
    /// checkpoint ([`splinerod_core::state`]). Default: nothing.
    fn save_state(&self, out: &mut SavedState) {
        let _ = out;
    }
    /// Reads back what [`save_state`](Integrator::save_state) wrote, into a scheme built
    /// like this one; `rod` is the restored rod.
    fn load_state(
        &mut self,
        rod: &Rod,
        input: &mut StateReader<'_>,
    ) -> Result<(), IntegratorError> {
        let _ = (rod, input);
        Ok(())
    }
}
