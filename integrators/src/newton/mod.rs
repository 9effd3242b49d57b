//! Newton's method with linear equality constraints and a backtracking line search,
//! shared by every implicit scheme and the static solver.
//!
//! A [`NewtonProblem`] is the minimisation of a merit \\(\Phi(x)\\) whose gradient is the
//! residual `r(x)` and whose (positive definite) Newton matrix is `A(x)`, subject to the
//! pins \\(G x = c\\). Each iteration assembles `r` and `A`, factorises `A` (numeric
//! only, unless the basis or the far block pattern changed; far blocks select the sparse
//! path, see [`crate::linear`]), solves the KKT system by a Schur complement
//! (the private `kkt` module), and takes the step — first shortened to
//! [`NewtonParams::max_step`] if longer — halving it while the Armijo condition
//! \\(\Phi(x + t\Delta x) \le \Phi(x) + 10^{-4}\, t\, r \cdot \Delta x\\) fails —
//! except a step already converging (at most half the one before, within the round-off
//! band), taken whole: its merit change can be below the merit's own rounding.
//! It stops when the step moves no material point by more than
//! `tolerance · rest_length` (see [`NewtonProblem::length_per_unknown`]), or by the
//! widened tolerance once the steps stall at round-off. These per-iteration decisions
//! (iteration limit, divergence, stall band, converging steps) are one
//! [`ConvergenceTracker`]'s, the type each lane of the batched solver
//! ([`crate::lane_euler`]) owns too; [`crate::convergence`] states the rules and why.

mod bodies;
mod carried;
mod curvature;
mod fallback;
mod line_search;
mod tangent;

use crate::convergence::ConvergenceTracker;
pub use crate::convergence::{DIVERGENCE_LENGTHS, ROUND_OFF_BAND};
use crate::kkt::Constraints;
use crate::linear::{LinearSolver, LinearSolverKind};
use crate::remainder::{RemainderCg, MOTION_FRACTION, REMAINDER_FLOOR};
use crate::{IntegratorError, StepStats, System};
pub use bodies::BodyForm;
use bodies::{couple_bodies, set_targets};
pub(crate) use curvature::negative_curvature;
use fallback::{indefinite_fallback, Fallback};
use line_search::{line_search, Trial};
use nalgebra::Vector3;
use splinerod_core::{BasisValues, BlockBanded, Pin, Real, RigidBody, Rod};
pub use tangent::{tangents, Tangent};

/// Settings of Newton's method.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NewtonParams {
    /// Most iterations per solve (≥ 1). Default 10; 1 gives the classic linearised
    /// ("fast") implicit Euler.
    pub max_iterations: usize,
    /// Stop when the largest position change of a step is below
    /// `tolerance · rest_length`. Default 1e-10.
    pub tolerance: Real,
    /// Backtrack on the merit function when a full step does not decrease it. Default on.
    pub line_search: bool,
    /// The factorisation of the Newton matrix. Default banded.
    pub linear_solver: LinearSolverKind,
    /// Largest move of a material point in one Newton iteration, m; a longer step is
    /// shortened to it (along the same direction) before the line search, so that the
    /// iterates follow the path of the step instead of jumping (e.g. over a contact).
    /// Default `None` (no limit).
    pub max_step: Option<Real>,
    /// Accept a time step whose Newton iterations stopped at `max_iterations` without
    /// converging (it is then counted as unconverged). Default false: such a step is an
    /// error ([`IntegratorError::NotConverged`]) and is rolled back, so that a caller can
    /// retry it with a shorter step. One iteration (`max_iterations = 1`, the linearised
    /// scheme) is always accepted.
    pub accept_unconverged: bool,
}

impl Default for NewtonParams {
    fn default() -> Self {
        Self {
            max_iterations: 10,
            tolerance: 1e-10,
            line_search: true,
            linear_solver: LinearSolverKind::Banded,
            max_step: None,
            accept_unconverged: false,
        }
    }
}

impl NewtonParams {
    /// Checks the ranges of the settings.
    pub fn validate(&self) -> Result<(), IntegratorError> {
        if self.max_iterations == 0 {
            return Err(IntegratorError::InvalidParameter {
                name: "max_iterations",
                value: 0.0,
                reason: "must be at least 1",
            });
        }
        crate::error::positive("tolerance", self.tolerance)?;
        match self.max_step {
            Some(limit) => crate::error::positive("max_step", limit),
            None => Ok(()),
        }
    }

    /// Whether a solve that ended `converged` (or not) stands: converged, or unconverged
    /// with [`accept_unconverged`](Self::accept_unconverged), or a single iteration (the
    /// linearised scheme). The scalar and the batched implicit Euler both ask this.
    pub fn accepts(&self, converged: bool) -> bool {
        converged || self.accept_unconverged || self.max_iterations == 1
    }
}

/// A problem Newton's method can drive. The unknown `x` has one 3-vector per control point.
pub trait NewtonProblem {
    /// Writes the iterate `x` into the rod (positions and velocities).
    fn apply(&self, rod: &mut Rod, x: &[Vector3<Real>]);
    /// Writes the residual \\(r = \nabla\Phi\\) at the applied iterate.
    fn residual(&mut self, system: &dyn System, r: &mut [Vector3<Real>]);
    /// Writes the Newton matrix at the applied iterate (symmetric positive definite).
    fn matrix(&mut self, system: &dyn System, a: &mut BlockBanded);
    /// Writes the residual and the Newton matrix at the applied iterate: the two calls
    /// above (the default), or one pass where the problem can share it. Newton's method
    /// calls this once per iteration, and [`matrix`](Self::matrix) alone for a retry.
    fn residual_and_matrix(
        &mut self,
        system: &dyn System,
        r: &mut [Vector3<Real>],
        a: &mut BlockBanded,
    ) {
        self.residual(system, r);
        self.matrix(system, a);
    }
    /// The merit \\(\Phi\\) at the applied iterate (used by the line search).
    fn merit(&mut self, system: &dyn System) -> Real;
    /// Right-hand side `c` of pin `pin`'s constraint \\(\sum_k b_k x_{first+k} = c\\).
    fn target(&self, row: &BasisValues, pin: &Pin) -> Vector3<Real>;
    /// Length moved by a material point per unit of `x` (`h` for velocities, 1 for positions).
    fn length_per_unknown(&self) -> Real;
    /// Weight ρ of the augmented Lagrangian term \\(\rho G^T G\\) added to `A` (with
    /// \\(\rho G^T (c - G x)\\) on the right), which leaves the constrained solution
    /// unchanged but makes `A` definite where only the pins remove rigid motions. Default 0.
    fn augmentation(&self) -> Real {
        0.0
    }
    /// Called when `A` is not positive definite; return true after adjusting to retry.
    fn on_not_positive_definite(&mut self) -> bool {
        false
    }
    /// Whether an indefinite but nonsingular `A` (the exact Hessian under compression) may
    /// give the step, factorised by [`crate::banded_ldlt::BandedLdlt`]; its step is used
    /// only if it descends the merit, otherwise
    /// [`on_not_positive_definite`](Self::on_not_positive_definite) is called. Default false.
    fn indefinite_allowed(&self) -> bool {
        false
    }
    /// Whether a step whose exact matrix factorised indefinite while a remainder needs
    /// the correction carries the difference to the definite matrix with it (`carried.rs`:
    /// the exact step, quadratic convergence) instead of leaving the remainder out.
    /// Default false (time steps); static solves say true.
    fn carries_indefinite(&self) -> bool {
        false
    }
    /// Whether a step moving material points by at most `step` (m) ends the solve; the
    /// default compares it with `tolerance` (m).
    fn converged(&self, step: Real, tolerance: Real) -> bool {
        step <= tolerance
    }
    /// The factor of the potential's Hessian in the Newton matrix (`β²` for an
    /// incremental potential, 1 for statics), which the Hessian's remainder
    /// ([`System::add_hessian_remainder`]) is applied with; 0 (the default) leaves the
    /// remainder out of the step (Newton then converges linearly).
    fn hessian_scale(&self) -> Real {
        0.0
    }

    /// How the problem moves rigid bodies ([`crate::System::bodies`]); `None` (the
    /// default): it cannot, and a system with bodies is refused.
    fn body_form(&self) -> Option<BodyForm> {
        None
    }

    /// The bodies a time step starts from when that is not the system's state (a
    /// two-step scheme's blend of its last two states: poses and velocities, the
    /// system's loads and mass properties); `None` (the default): the system's bodies.
    fn body_base(&self) -> Option<&[RigidBody]> {
        None
    }

    /// Called after each step with the accepted step length `t ∈ (0, 1]`.
    fn on_step(&mut self, step_length: Real) {
        let _ = step_length;
    }
}

/// Buffers and factorisation reused across solves (no allocation once sized).
#[derive(Debug, Default)]
pub struct NewtonWorkspace {
    r: Vec<Vector3<Real>>,
    base: Vec<Vector3<Real>>,
    dx: Vec<Vector3<Real>>,
    flat: Vec<Real>,
    /// The linear solver, which owns the Newton matrix.
    solver: LinearSolver,
    constraints: Constraints,
    multipliers: Vec<Vector3<Real>>,
    /// The correction of steps for a Hessian remainder.
    remainder: RemainderCg,
    /// Scratch multipliers of the correction's solves.
    scratch_mu: Vec<Vector3<Real>>,
    /// Step entries below this end the correction (unknowns' units).
    floor: Real,
    /// Largest entry of the solve's first step from the banded matrix (unknowns' units),
    /// which bounds the correction's floor from above ([`MOTION_FRACTION`]).
    motion: Option<Real>,
    /// Zeros, the iterate of the tangent solves ([`tangents`]).
    origin: Vec<Vector3<Real>>,
    /// The problem's matrix, unfactorised, for the tangent solves' multipliers.
    spare: BlockBanded,
    /// A tangent solve's exact and definite matrices when the exact one was indefinite
    /// ([`carried`]): their difference rides with the remainder's correction.
    carried: carried::Carried,
    /// Rigid bodies in the solve ([`bodies`]).
    coupling: bodies::Coupling,
}

impl NewtonWorkspace {
    /// Multipliers `μ` of the pins from the last iteration (pin force × `length_per_unknown`
    /// for dynamics: an impulse; the force itself for statics).
    pub fn multipliers(&self) -> &[Vector3<Real>] {
        &self.multipliers
    }

    /// Sets the multipliers to those of a step taken elsewhere (a batched step).
    pub(crate) fn set_multipliers(&mut self, mu: impl Iterator<Item = Vector3<Real>>) {
        self.multipliers.clear();
        self.multipliers.extend(mu);
    }

    /// Writes the last solve's rigid bodies into the system (nothing without bodies).
    pub(crate) fn write_bodies(&self, system: &mut dyn System) {
        self.coupling.write_back(system);
    }

    /// The Newton matrix buffer (scratch between solves).
    pub(crate) fn matrix_mut(&mut self) -> &mut BlockBanded {
        self.solver.matrix_mut()
    }

    /// Selects the linear solver `kind` for `system`'s rod, as a solve does.
    pub(crate) fn solver_kind(&mut self, kind: LinearSolverKind, system: &dyn System) {
        self.solver.kind = kind;
        self.solver.periodic = system.rod().basis().periodic_count();
    }

    fn resize(&mut self, n: usize, pins: usize) {
        for v in [&mut self.r, &mut self.base, &mut self.dx, &mut self.origin] {
            v.resize(n, Vector3::zeros());
        }
        self.flat.resize(3 * n, 0.0);
        self.multipliers.resize(pins, Vector3::zeros());
        self.scratch_mu.resize(pins, Vector3::zeros());
    }
}

/// Runs Newton's method on `problem` from the iterate `x`, leaving the solution in `x` and
/// applied to the system. On error the system holds some iterate: callers restore it.
pub fn solve(
    problem: &mut dyn NewtonProblem,
    system: &mut dyn System,
    x: &mut [Vector3<Real>],
    params: &NewtonParams,
    ws: &mut NewtonWorkspace,
) -> Result<StepStats, IntegratorError> {
    let n = x.len();
    ws.solver_kind(params.linear_solver, system);
    ws.resize(n, system.pins().len());
    let coupled = ws
        .coupling
        .begin(system, problem.body_form(), problem.body_base())?;
    ws.constraints.set_held(ws.coupling.held_pins());
    if coupled {
        ws.multipliers
            .iter_mut()
            .for_each(|m| *m = Vector3::zeros());
    } else {
        set_targets(problem, system.rod(), system.pins(), ws)?;
    }
    let mut tracker = ConvergenceTracker::new(params, system.rod().material().rest_length);
    let tolerance = tracker.tolerance();
    let length = problem.length_per_unknown();
    ws.floor = REMAINDER_FLOOR * tolerance / length;
    ws.motion = None;
    let mut stats = StepStats::default();
    // The merit at the applied iterate, once the line search has measured it.
    let mut merit = None;
    problem.apply(system.rod_mut(), x);
    while tracker.next_iteration() {
        if system.interrupted() {
            return Err(IntegratorError::Interrupted);
        }
        stats.newton_iterations = tracker.iterations();
        problem.residual_and_matrix(system, &mut ws.r, ws.solver.matrix_mut());
        if coupled {
            couple_bodies(problem, system, ws)?;
        }
        let mut slope = newton_direction(problem, system, x, ws, true, &mut stats)?;
        let descends = slope < 0.0;
        if ws.solver.is_indefinite() && !descends && problem.on_not_positive_definite() {
            // The exact step climbs the merit: take the definite one instead.
            slope = newton_direction(problem, system, x, ws, false, &mut stats)?;
        }
        let mut full = ws.dx.iter().map(|v| v.amax()).fold(0.0, Real::max) * length;
        full = full.max(ws.coupling.motion());
        tracker.check_divergence(full)?;
        if let Some(cap) = params.max_step.filter(|&cap| full > cap) {
            ws.dx.iter_mut().for_each(|d| *d *= cap / full);
            ws.coupling.scale_step(cap / full);
            full = cap;
        }
        let step = Trial {
            search: params.line_search && tracker.searches(full),
            trust: tracker.converging(full),
            slope,
        };
        let (t, reached) = line_search(problem, system, x, ws, step, merit, &mut stats)?;
        merit = reached;
        problem.on_step(t);
        let within = |step: Real, reach: Real| problem.converged(step, reach);
        if tracker.verdict_with(full, full * t, within).done() {
            stats.converged = true;
            break;
        }
    }
    Ok(stats)
}

/// Assembles and factorises `A` (the exact Hessian by Cholesky, else by the indefinite
/// factorisation if the problem allows, else the problem's definite fallback; with
/// `assembled`, the problem's matrix is in the solver already for the first try), then
/// solves the KKT system into `ws.dx` and the multipliers. Returns the slope
/// \(r \cdot \Delta x\) (negative for a descent direction from a feasible iterate, where
/// \(G\Delta x = 0\) makes it \((r - G^T\mu)\cdot\Delta x\)).
fn newton_direction(
    problem: &mut dyn NewtonProblem,
    system: &dyn System,
    x: &[Vector3<Real>],
    ws: &mut NewtonWorkspace,
    mut assembled: bool,
    stats: &mut StepStats,
) -> Result<Real, IntegratorError> {
    let analyses = ws.solver.analyses();
    loop {
        factor_matrix(problem, system, ws, std::mem::take(&mut assembled))?;
        match ws.constraints.factor(&mut ws.solver) {
            Err(_) if ws.solver.is_indefinite() && problem.on_not_positive_definite() => {}
            result => break result?,
        }
    }
    stats.symbolic_analyses += ws.solver.analyses() - analyses;
    if problem.carries_indefinite() {
        tangent::carry_if_indefinite(problem, system, ws)?;
    }
    let slope = solve_factored(problem, system, x, ws, stats);
    ws.carried.active = false;
    slope
}

/// With `A` and the pins factorised, solves the KKT system for the residual `ws.r` and
/// the pins' targets into `ws.dx` and the multipliers (with the remainder's correction);
/// returns the slope as [`newton_direction`] does.
fn solve_factored(
    problem: &mut dyn NewtonProblem,
    system: &dyn System,
    x: &[Vector3<Real>],
    ws: &mut NewtonWorkspace,
    stats: &mut StepStats,
) -> Result<Real, IntegratorError> {
    let rho = problem.augmentation();
    ws.base.iter_mut().for_each(|b| *b = Vector3::zeros());
    ws.constraints.add_gram_rhs(rho, x, &mut ws.base);
    for (i, (r, aug)) in ws.r.iter().zip(&ws.base).enumerate() {
        ws.flat[3 * i..3 * i + 3].copy_from_slice((aug - r).as_slice());
    }
    let targets = &ws.constraints.targets;
    ws.constraints
        .points
        .eliminate_rhs(x, Some(targets), &mut ws.flat);
    ws.solver.solve_in_place(&mut ws.flat)?;
    ws.constraints.correct(x, &mut ws.flat, &mut ws.multipliers);
    let scale = problem.hessian_scale();
    // With an indefinite P (LDLT of a compressed rod's exact Hessian) conjugate gradients
    // have no inner product to work in: the step stays P's (measured on a cut rod pulled
    // into compression: fewer Newton iterations than an unguarded correction).
    let remainder = scale > 0.0 && system.has_hessian_remainder();
    if (remainder || ws.carried.active) && !ws.solver.is_indefinite() {
        let first = ws.flat.iter().fold(0.0, |m: Real, x| m.max(x.abs()));
        let floor = ws
            .floor
            .min(MOTION_FRACTION * *ws.motion.get_or_insert(first));
        let (solver, constraints, mu) = (&mut ws.solver, &mut ws.constraints, &mut ws.scratch_mu);
        let carried = &mut ws.carried;
        stats.remainder_iterations += ws.remainder.correct(
            &mut ws.flat,
            floor,
            &mut |v, sign, out| {
                if remainder {
                    system.add_hessian_remainder(v, sign * scale, out);
                }
                carried.add_product(v, sign, out);
            },
            &mut |z| constraints.solve_homogeneous(solver, x, z, mu),
        )?;
    }
    for (i, d) in ws.dx.iter_mut().enumerate() {
        *d = Vector3::new(ws.flat[3 * i], ws.flat[3 * i + 1], ws.flat[3 * i + 2]);
    }
    // Residual with the constraint forces removed: r − Gᵀμ (ws.r keeps r for a retry).
    ws.base.copy_from_slice(&ws.r);
    ws.constraints
        .add_transpose(&ws.multipliers, -1.0, &mut ws.base);
    stats.residual = ws
        .base
        .iter()
        .map(|v| v.norm_squared())
        .sum::<Real>()
        .sqrt();
    if !stats.residual.is_finite() || ws.dx.iter().any(|v| !v.iter().all(|c| c.is_finite())) {
        return Err(IntegratorError::NonFinite {
            what: "Newton step",
        });
    }
    let bodies = match ws.coupling.active() {
        true => ws.coupling.direction(&ws.multipliers),
        false => 0.0,
    };
    Ok(ws
        .base
        .iter()
        .zip(&ws.dx)
        .map(|(r, d)| r.dot(d))
        .sum::<Real>()
        + bodies)
}

/// Assembles the problem's matrix into the solver's (unless `assembled`: it is there)
/// with the pins' augmentation \\(\rho G^T G\\) and the point pins eliminated; returns ρ.
fn assemble(
    problem: &mut dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
    assembled: bool,
) -> Real {
    let matrix = ws.solver.matrix_mut();
    if !assembled {
        problem.matrix(system, matrix);
    }
    let rho = problem.augmentation();
    ws.constraints.add_gram(rho, matrix);
    ws.constraints.points.eliminate_matrix(matrix);
    rho
}

/// Assembles `A` and factorises it, as described at [`newton_direction`]; returns the
/// augmentation weight ρ.
fn factor_matrix(
    problem: &mut dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
    mut assembled: bool,
) -> Result<Real, IntegratorError> {
    let epoch = system.rod().topology_epoch();
    loop {
        let rho = assemble(problem, system, ws, std::mem::take(&mut assembled));
        match ws.solver.factor_assembled(epoch) {
            Ok(()) => return Ok(rho),
            Err(e @ IntegratorError::NotPositiveDefinite { .. }) => {
                match indefinite_fallback(problem, system, ws)? {
                    Fallback::Factored => return Ok(rho),
                    Fallback::Retry => {}
                    Fallback::Fail => return Err(e),
                }
            }
            Err(e) => return Err(e),
        }
    }
}
