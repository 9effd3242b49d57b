//! Static equilibrium: minimise the potential energy \\(E(q)\\) subject to the pins
//! \\(G q = p\\), by Newton's method with a line search and Levenberg–Marquardt
//! regularisation \\(A = K + \varepsilon M\\).
//!
//! `K` is the positive semi-definite Hessian, singular where the rod is slack (a
//! compressed straight rod has no transverse stiffness), so \\(\varepsilon\\) starts at
//! `1e-3 · max diag K / max diag M`, grows ×4 whenever the line search had to cut the step
//! and shrinks ÷10 after every full step, reaching zero: the last iterations are pure
//! Newton on the exact Hessian (by Cholesky, or by the indefinite block LDLᵀ where
//! parts of the rod are compressed, as long as its step descends) and converge
//! quadratically. Because the pins alone remove the rigid motions,
//! `K` is singular on its own; the augmented Lagrangian term \\(\rho G^T G\\) (see
//! [`crate::newton::NewtonProblem::augmentation`]) makes the matrix definite without
//! changing the constrained step.
//!
//! **Continuation.** From a start far from equilibrium (a straight rod squeezed between
//! its pins, a fold) Newton can fail even so. The solver then restarts from the given
//! state and follows a pseudo-transient path: implicit Euler steps from rest,
//!
//! \[ q_{k+1} = \arg\min_q \tfrac{1}{2h_k^2} (q - q_k)^T M (q - q_k) + E(q)
//!     \quad\text{subject to the pins}, \]
//!
//! each a proximal step that lowers `E`, with `h` growing ×4 after a converged step and
//! shrinking ×4 after a failed one; after each step a short static Newton solve is
//! tried from the new point, and the first that converges ends the path. As \(h \to
//! \infty\) the step becomes the static problem itself, so the path ends at an
//! equilibrium reached by descent. The number of steps is
//! [`StaticSolver::continuation_steps`].
//!
//! **Stability.** The definite Hessian hides unstable directions, so Newton can stop on
//! an unstable equilibrium (parts of the rod held in compression). Every converged
//! point is therefore checked with the exact Hessian (block \\(U^TDU\\), whose `D` has
//! the Hessian's inertia); while it has negative curvature the rod is pushed along that
//! direction and solved again, so that the solver returns a (local) minimum.

mod problem;

use crate::incremental::{Increment, Stepper};
use crate::linear::LinearSolverKind;
use crate::newton::{self, NewtonParams, NewtonWorkspace, Tangent};
use crate::{Integrator, IntegratorError, Role, StepStats, System};
use nalgebra::Vector3;
use problem::{add_counts, newton_params, shortest_period, StaticProblem};
use splinerod_core::{HessianKind, Real};

/// Settings of the static solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StaticParams {
    /// Most Newton iterations. Default 200.
    pub max_iterations: usize,
    /// Converged when a full, unregularised Newton step moves no point by more than
    /// `tolerance · rest_length`. Default 1e-12.
    pub tolerance: Real,
    /// The factorisation of the Newton matrix. Default banded.
    pub linear_solver: LinearSolverKind,
    /// Most pseudo-transient continuation steps after a failed Newton solve (0: none,
    /// the failure is returned). Default 200: the 16-point cable with EA = 1e7 N from
    /// the straight start squeezed 20 % needs 114.
    pub max_continuation_steps: usize,
}

impl Default for StaticParams {
    fn default() -> Self {
        Self {
            max_iterations: 200,
            tolerance: 1e-12,
            linear_solver: LinearSolverKind::Banded,
            max_continuation_steps: 200,
        }
    }
}

/// Largest move of a material point in one static Newton iteration, in rest lengths:
/// far from equilibrium the iterates then follow a descent path instead of jumping into
/// another basin (from the straight 0.8 m start, EA = 1e4 N, an unlimited Newton lands
/// on a 0.5 m high arch that membrane locking makes stable; limited, on the catenary).
const STEP_LIMIT: Real = 0.1;

/// Stiffness continuation (module docs): the first stage softens the rod's stiffness by
/// this factor, then by its square, … .
const SOFTENING: Real = 1e-2;

/// Stiffness continuation: the most softenings tried for the first stage (down to
/// `SOFTENING⁵ = 1e-10` of the stiffness).
const MAX_SOFTENINGS: usize = 5;

/// Stiffness continuation: the factor from one stage's stiffness to the next.
const STIFFENING: Real = 10.0;

/// Stiffness continuation: after failed stages the factor is square-rooted down to this,
/// below which the continuation gives up.
const MIN_STIFFENING: Real = 1.2;

/// Newton iterations a stage of the stiffness continuation may take.
const STAGE_ITERATIONS: usize = 50;

/// Pseudo-transient steps a stage of the stiffness continuation may take.
const STAGE_CONTINUATION_STEPS: usize = 10;

/// Most pushes off unstable equilibria in one solve.
const MAX_SADDLE_ESCAPES: usize = 10;

/// Newton iterations of the static solve tried after each continuation step.
const STATIC_TRY_ITERATIONS: usize = 15;

/// Largest constraint violation (mean strain of a tension function) an equilibrium
/// with multipliers may keep ([`StaticSolver::solve_constrained`]).
pub const CONSTRAINT_TOLERANCE: Real = 1e-12;

/// Multiplier updates [`StaticSolver::solve_constrained`] may take.
pub const MAX_MULTIPLIER_UPDATES: usize = 40;

/// Finds equilibria of a [`System`] (velocities are set to zero). As an
/// [`Integrator`] ([`Integrator::role`] [`Role::Equilibrium`]) each step is
/// [`StaticSolver::solve_constrained`] under the loads at the step's end: a
/// quasi-static sequence.
#[derive(Debug, Default)]
pub struct StaticSolver {
    /// Settings.
    pub params: StaticParams,
    workspace: NewtonWorkspace,
    x: Vec<Vector3<Real>>,
    stepper: Stepper,
    continuation_steps: usize,
}

impl StaticSolver {
    /// A static solver with the given settings.
    pub fn new(params: StaticParams) -> Result<Self, IntegratorError> {
        newton_params(&params, params.max_iterations).validate()?;
        Ok(Self {
            params,
            ..Self::default()
        })
    }

    /// Moves the rod to equilibrium. On error the rod is left as it was (and
    /// [`StaticSolver::pin_forces`] is empty). Every Newton iteration polls
    /// [`System::interrupted`]: a solve abandoned there (also in a continuation stage)
    /// returns [`IntegratorError::Interrupted`].
    pub fn solve(&mut self, system: &mut dyn System) -> Result<StepStats, IntegratorError> {
        system.rod().check_finite()?;
        let saved = (
            system.rod().positions.clone(),
            system.rod().velocities.clone(),
        );
        let bodies = system.bodies().to_vec();
        self.continuation_steps = 0;
        let mut total = StepStats::default();
        let result = self
            .solve_from_here(system, &mut total)
            .and_then(|_| self.leave_saddles(system, &mut total))
            .map(|_| total);
        if result.is_err() {
            let rod = system.rod_mut();
            (rod.positions, rod.velocities) = saved;
            system.bodies_mut().clone_from_slice(&bodies);
            // The multipliers of an abandoned iterate are no pin forces of that state.
            self.workspace.set_multipliers(std::iter::empty());
        }
        result
    }

    /// Newton from the rod's positions, then continuation from them if Newton fails.
    fn solve_from_here(
        &mut self,
        system: &mut dyn System,
        total: &mut StepStats,
    ) -> Result<(), IntegratorError> {
        let start = system.rod().positions.clone();
        let bodies = system.bodies().to_vec();
        let first = self.newton(system, self.params.max_iterations, total);
        let recoverable = first.as_ref().map_or_else(|e| e.is_recoverable(), |ok| !ok);
        match first {
            Ok(true) => Ok(()),
            _ if recoverable && self.params.max_continuation_steps > 0 => {
                system.rod_mut().positions.clone_from(&start);
                system.bodies_mut().clone_from_slice(&bodies);
                if self.soften_and_stiffen(system, total)? {
                    return Ok(());
                }
                system.rod_mut().positions.clone_from(&start);
                system.bodies_mut().clone_from_slice(&bodies);
                self.continuation(system, total)
            }
            Ok(false) => Err(IntegratorError::NotConverged {
                iterations: total.newton_iterations,
                residual: total.residual,
            }),
            Err(e) => Err(e),
        }
    }

    /// The stiffness continuation of the module docs from the rod's positions: the
    /// equilibrium of a rod softened by [`SOFTENING`], [`SOFTENING`]², … (the first that
    /// Newton, or a short pseudo-transient path, reaches from the start), then of stiffer
    /// rods, ×[`STIFFENING`] at a time (×√[`STIFFENING`] after a failed stage), each from
    /// the last, up to the rod itself. `Ok(false)` (the rod's stiffness restored, its
    /// positions left anywhere) if the system has no stiffness to scale or no stage
    /// succeeded.
    fn soften_and_stiffen(
        &mut self,
        system: &mut dyn System,
        total: &mut StepStats,
    ) -> Result<bool, IntegratorError> {
        if !system.set_stiffness_scale(1.0) {
            return Ok(false);
        }
        let found = self.stages(system, total);
        // Restored whatever happened (an interrupted stage returns early).
        system.set_stiffness_scale(1.0);
        found
    }

    /// The stages of [`Self::soften_and_stiffen`], leaving the stiffness scaled.
    fn stages(
        &mut self,
        system: &mut dyn System,
        total: &mut StepStats,
    ) -> Result<bool, IntegratorError> {
        let start = system.rod().positions.clone();
        let mut scale = 1.0;
        let mut found = false;
        for _ in 0..MAX_SOFTENINGS {
            scale *= SOFTENING;
            system.set_stiffness_scale(scale);
            system.rod_mut().positions.clone_from(&start);
            if self.stage(system, total)? {
                found = true;
                break;
            }
        }
        let mut factor = STIFFENING;
        while found && scale < 1.0 {
            let next = (scale * factor).min(1.0);
            let before = system.rod().positions.clone();
            system.set_stiffness_scale(next);
            if self.stage(system, total)? {
                scale = next;
                factor = STIFFENING;
            } else if factor > MIN_STIFFENING {
                system.rod_mut().positions.clone_from(&before);
                factor = factor.sqrt();
            } else {
                found = false;
            }
        }
        Ok(found)
    }

    /// One stage of [`Self::soften_and_stiffen`]: Newton, then a short pseudo-transient
    /// path if it fails; whether an equilibrium was reached.
    fn stage(
        &mut self,
        system: &mut dyn System,
        total: &mut StepStats,
    ) -> Result<bool, IntegratorError> {
        let here = system.rod().positions.clone();
        match self.newton(
            system,
            STAGE_ITERATIONS.min(self.params.max_iterations),
            total,
        ) {
            Ok(true) => return Ok(true),
            Err(e) if !e.is_recoverable() => return Err(e),
            _ => {}
        }
        system.rod_mut().positions.clone_from(&here);
        let steps = self
            .params
            .max_continuation_steps
            .min(STAGE_CONTINUATION_STEPS);
        match self.continuation_for(system, total, steps) {
            Ok(()) => Ok(true),
            Err(e) if e.is_recoverable() => Ok(false),
            Err(e) => Err(e),
        }
    }

    /// The definite Hessian cannot see an unstable equilibrium (a cable squeezed
    /// straight, an arch): at a converged point the exact Hessian is factorised, and
    /// while it has a direction of negative curvature the rod is pushed along it (by
    /// 1e-3 L, on the side of lower energy) and solved again. Each push counts as a
    /// continuation step.
    fn leave_saddles(
        &mut self,
        system: &mut dyn System,
        total: &mut StepStats,
    ) -> Result<(), IntegratorError> {
        let mut direction = Vec::new();
        for _ in 0..MAX_SADDLE_ESCAPES {
            let mut check = StaticProblem {
                regularization: 0.0,
                kind: HessianKind::Exact,
                rho: 0.0,
                rate: 0.0,
            };
            let ws = &mut self.workspace;
            if newton::negative_curvature(&mut check, system, ws, &mut direction)?.is_none() {
                return Ok(());
            }
            let largest = direction.iter().map(|v| v.amax()).fold(0.0, Real::max);
            if largest.is_nan() || largest <= 0.0 {
                return Ok(());
            }
            let kick = 1e-3 * system.rod().material().rest_length / largest;
            let base = system.rod().positions.clone();
            let push = |system: &mut dyn System, amount: Real| {
                let rod = system.rod_mut();
                for ((q, b), d) in rod.positions.iter_mut().zip(&base).zip(&direction) {
                    *q = b + d * amount;
                }
                system.potential_energy()
            };
            let still = push(system, 0.0);
            let (up, down) = (push(system, kick), push(system, -kick));
            if up.min(down) >= still {
                push(system, 0.0);
                return Ok(());
            }
            push(system, if up < down { kick } else { -kick });
            self.continuation_steps += 1;
            self.solve_from_here(system, total)?;
        }
        Ok(())
    }

    /// Continuation steps the last solve took (0 when Newton converged directly).
    pub fn continuation_steps(&self) -> usize {
        self.continuation_steps
    }

    /// Forces the pins exert on the rod at equilibrium, N.
    pub fn pin_forces(&self) -> &[Vector3<Real>] {
        self.workspace.multipliers()
    }

    /// Sensitivities of the equilibrium the system is at (after a converged
    /// [`StaticSolver::solve`]): solves each [`Tangent`] problem,
    /// \\(K\dot x - G^T\dot\mu = -\partial r/\partial p\\), \\(G\dot x = \dot c\\), with one
    /// factorisation of the exact Hessian `K` by this solver's linear solver (never the
    /// definite stand-in: an error instead), so that \\(\dot\mu\\) is the derivative of
    /// [`StaticSolver::pin_forces`]. The pins' forces the last solve found are kept.
    pub fn sensitivities(
        &mut self,
        system: &dyn System,
        cases: &mut [Tangent],
    ) -> Result<StepStats, IntegratorError> {
        let mut problem = StaticProblem {
            regularization: 0.0,
            kind: HessianKind::Exact,
            rho: 0.0,
            rate: 0.0,
        };
        let forces = self.workspace.multipliers().to_vec();
        self.workspace
            .solver_kind(self.params.linear_solver, system);
        let exact = |p: &dyn newton::NewtonProblem| p.indefinite_allowed();
        let cases = (cases, crate::remainder::TANGENT_TOLERANCE);
        let stats = newton::tangents(&mut problem, system, &mut self.workspace, &exact, cases);
        self.workspace.set_multipliers(forces.into_iter());
        stats
    }

    /// [`StaticSolver::solve`], repeated with updated multipliers
    /// ([`System::update_multipliers`]) while a constraint (the inextensible rod) is
    /// violated by more than [`CONSTRAINT_TOLERANCE`], at most
    /// [`MAX_MULTIPLIER_UPDATES`] times; the counters summed over the solves.
    pub fn solve_constrained(
        &mut self,
        system: &mut dyn System,
    ) -> Result<StepStats, IntegratorError> {
        let mut stats = self.solve(system)?;
        let mut continuation = self.continuation_steps;
        for updates in 0..=MAX_MULTIPLIER_UPDATES {
            let violation = system.update_multipliers(true);
            if violation <= CONSTRAINT_TOLERANCE {
                stats.multiplier_updates = updates;
                stats.continuation_steps = continuation;
                return Ok(stats);
            }
            if updates == MAX_MULTIPLIER_UPDATES {
                return Err(IntegratorError::ConstraintNotMet {
                    violation,
                    updates,
                    tolerance: CONSTRAINT_TOLERANCE,
                });
            }
            let more = self.solve(system)?;
            continuation += self.continuation_steps;
            stats.add_counts(&more);
            stats.converged = more.converged;
        }
        Ok(stats)
    }

    /// A static Newton solve of at most `iterations` from the rod's positions; adds its
    /// counters to `total` and returns whether it converged.
    fn newton(
        &mut self,
        system: &mut dyn System,
        iterations: usize,
        total: &mut StepStats,
    ) -> Result<bool, IntegratorError> {
        self.x.clone_from(&system.rod().positions);
        let mut problem = StaticProblem {
            regularization: 1e-3,
            kind: HessianKind::Definite,
            rho: 0.0,
            rate: 0.0,
        };
        let params = NewtonParams {
            max_step: Some(STEP_LIMIT * system.rod().material().rest_length),
            ..newton_params(&self.params, iterations)
        };
        let ws = &mut self.workspace;
        let stats = newton::solve(&mut problem, system, &mut self.x, &params, ws);
        if let Ok(s) = &stats {
            add_counts(total, s);
            ws.write_bodies(system);
        }
        Ok(stats?.converged)
    }

    /// The pseudo-transient path of the module docs, from the rod's positions.
    fn continuation(
        &mut self,
        system: &mut dyn System,
        total: &mut StepStats,
    ) -> Result<(), IntegratorError> {
        self.continuation_for(system, total, self.params.max_continuation_steps)
    }

    /// [`Self::continuation`] of at most `steps` steps.
    fn continuation_for(
        &mut self,
        system: &mut dyn System,
        total: &mut StepStats,
        steps: usize,
    ) -> Result<(), IntegratorError> {
        let mut h = shortest_period(system, &mut self.workspace);
        let pseudo = NewtonParams {
            max_iterations: 20,
            tolerance: 1e-8,
            accept_unconverged: true,
            ..newton_params(&self.params, 20)
        };
        let mut point = system.rod().positions.clone();
        self.stepper.definite_only = true;
        self.stepper.bodies = true;
        for _ in 0..steps {
            system.rod_mut().velocities.fill(Vector3::zeros());
            self.stepper.begin(system, h)?;
            let step = Increment { beta: h, reach: h };
            let result = self.stepper.solve(system, &pseudo, step);
            match self.stepper.finish(system, result) {
                Ok(stats) => {
                    add_counts(total, &stats);
                    self.continuation_steps += 1;
                    point.clone_from(&system.rod().positions);
                    match self.newton(system, STATIC_TRY_ITERATIONS, total) {
                        Ok(true) => return Ok(()),
                        Err(e) if !e.is_recoverable() => return Err(e),
                        _ => {}
                    }
                    system.rod_mut().positions.clone_from(&point);
                    h *= if stats.converged { 4.0 } else { 0.5 };
                }
                Err(e) if !e.is_recoverable() || h < 1e-300 => return Err(e),
                Err(_) => h *= 0.25,
            }
        }
        Err(IntegratorError::NotConverged {
            iterations: total.newton_iterations,
            residual: total.residual,
        })
    }
}

impl Integrator for StaticSolver {
    fn name(&self) -> &str {
        "static"
    }

    fn step(&mut self, system: &mut dyn System, _dt: Real) -> Result<StepStats, IntegratorError> {
        self.solve_constrained(system)
    }

    fn role(&self) -> Role {
        Role::Equilibrium
    }

    fn pin_forces(&self) -> Vec<Vector3<Real>> {
        StaticSolver::pin_forces(self).to_vec()
    }
}
