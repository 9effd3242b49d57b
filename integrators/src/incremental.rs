//! The Newton problem shared by the implicit schemes, and the step bookkeeping around it
//! (validation, saved start state, finite check, rollback).
//!
//! Implicit Euler, the implicit midpoint rule and BDF2 all reduce to one minimisation in
//! an unknown velocity `x`, with a base position \\(\hat q\\), a reference velocity
//! \\(\hat v\\) and an effective step β:
//!
//! \\[ \Phi(x) = \tfrac12 (x - \hat v)^T M (x - \hat v) + E(\hat q + \beta x)
//!     + \tfrac{\beta\alpha}{2}\, x^T M x, \\]
//!
//! residual \\(r = \nabla\Phi = M(x - \hat v) + \beta \nabla E(\hat q + \beta x) +
//! \beta\alpha M x\\), Newton matrix \\(A = (1 + \beta\alpha) M + \beta^2 K\\) (exact
//! Hessian, factorised by Cholesky or, under compression, by the indefinite block
//! \\(U^TDU\\); the definite Hessian of [`HessianKind::Definite`] for an iteration
//! whose exact step would not descend). The rod holds
//! positions \\(\hat q + \beta x\\) and velocities `x` while Newton runs. Pins are reached
//! at the *end* of the step, which is \\(\hat q + \rho x\\) with a reach `ρ` (= β except
//! for the midpoint rule): \\(G x = (p - G\hat q)/\rho\\).
//!
//! For joined rods of different damping ([`Rod::join`](splinerod_core::Rod::join)),
//! `αM` is \\(\operatorname{diag}(\alpha_i) M\\), one rate per control point.

use crate::error::positive;
use crate::newton::{self, BodyForm, NewtonParams, NewtonProblem, NewtonWorkspace};
use crate::{IntegratorError, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::{
    rod::check_finite, BasisValues, BlockBanded, HessianKind, Pin, Real, RigidBody, Rod,
};

/// Scalars of one incremental problem.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Increment {
    /// Effective step β: positions during the solve are \\(\hat q + \beta x\\).
    pub beta: Real,
    /// Reach ρ: end-of-step positions are \\(\hat q + \rho x\\) (pins hold there).
    pub reach: Real,
}

/// Mass-proportional damping rates: one `α` for the rod, or one per control point
/// (joined rods of different damping, [`Rod::damping_at`]).
#[derive(Debug, Default)]
struct DampingRates {
    uniform: Real,
    /// Empty when uniform.
    per_point: Vec<Real>,
}

impl DampingRates {
    /// `α_i`.
    fn at(&self, i: usize) -> Real {
        self.per_point.get(i).copied().unwrap_or(self.uniform)
    }

    /// Reads and checks the rod's rates (finite, non-negative).
    fn read(&mut self, rod: &Rod) -> Result<(), IntegratorError> {
        self.per_point.clear();
        let check = |alpha: Real| {
            if alpha.is_finite() && alpha >= 0.0 {
                Ok(alpha)
            } else {
                let reason = "must be finite and non-negative";
                Err(IntegratorError::InvalidParameter {
                    name: "damping",
                    value: alpha,
                    reason,
                })
            }
        };
        match rod.uniform_damping() {
            Some(alpha) => self.uniform = check(alpha)?,
            None => {
                for segment in rod.segments() {
                    check(segment.damping)?;
                }
                self.per_point
                    .extend((0..rod.len()).map(|i| rod.damping_at(i)));
            }
        }
        Ok(())
    }
}

struct IncrementalProblem<'a> {
    base_q: &'a [Vector3<Real>],
    base_v: &'a [Vector3<Real>],
    step: Increment,
    alpha: &'a DampingRates,
    scratch: &'a mut [Vector3<Real>],
    hessian: HessianKind,
    definite_only: bool,
    /// Whether rigid bodies move with the step (the scheme's base is its start state).
    bodies: bool,
    /// The bodies' base when it is not their start state ([`Stepper::body_base`]).
    body_base: Option<&'a [RigidBody]>,
}

impl IncrementalProblem<'_> {
    /// Writes the inertia and damping part of the residual, \\(M((1 + \\beta\\alpha) x -
    /// \\hat v)\\), into `r`, and zeroes the scratch for the potential's gradient.
    fn inertia_residual(&mut self, rod: &Rod, r: &mut [Vector3<Real>]) {
        let beta = self.step.beta;
        let tmp = &mut *self.scratch;
        let alpha = self.alpha;
        if alpha.per_point.is_empty() {
            for ((t, v), v0) in tmp.iter_mut().zip(&rod.velocities).zip(self.base_v) {
                *t = v * (1.0 + beta * alpha.uniform) - v0;
            }
        } else {
            // diag(α) commutes with M (constant on its diagonal blocks).
            let rows = tmp.iter_mut().zip(&rod.velocities).zip(self.base_v);
            for (((t, v), v0), a) in rows.zip(&alpha.per_point) {
                *t = v * (1.0 + beta * a) - v0;
            }
        }
        rod.mass_matrix().mul_vec3(tmp, r);
        tmp.iter_mut().for_each(|t| *t = Vector3::zeros());
    }

    /// `r += β g` with the potential's gradient `g` in the scratch.
    fn add_scaled_gradient(&self, r: &mut [Vector3<Real>]) {
        let beta = self.step.beta;
        r.iter_mut()
            .zip(self.scratch.iter())
            .for_each(|(r, g)| *r += g * beta);
    }

    /// Turns the potential's Hessian `K` in `a` into \\(\\beta^2 K + (1 + \\beta\\alpha) M\\).
    fn finish_matrix(&self, rod: &Rod, a: &mut BlockBanded) {
        let beta = self.step.beta;
        let (m, s) = (rod.mass_matrix(), beta * beta);
        if self.alpha.per_point.is_empty() {
            let c = 1.0 + beta * self.alpha.uniform;
            a.scale_and_add_row_scaled_scalar(s, |_| c, m);
        } else {
            let alpha = self.alpha;
            a.scale_and_add_row_scaled_scalar(s, |i| 1.0 + beta * alpha.at(i), m);
        }
    }
}

impl NewtonProblem for IncrementalProblem<'_> {
    fn apply(&self, rod: &mut Rod, x: &[Vector3<Real>]) {
        rod.velocities.copy_from_slice(x);
        for ((q, q0), v) in rod.positions.iter_mut().zip(self.base_q).zip(x) {
            *q = q0 + v * self.step.beta;
        }
    }

    fn residual(&mut self, system: &dyn System, r: &mut [Vector3<Real>]) {
        self.inertia_residual(system.rod(), r);
        system.add_potential_gradient(self.scratch);
        self.add_scaled_gradient(r);
    }

    fn matrix(&mut self, system: &dyn System, a: &mut BlockBanded) {
        a.reset(system.rod().len(), system.hessian_bandwidth());
        system.add_potential_hessian(self.hessian, a);
        self.finish_matrix(system.rod(), a);
    }

    fn residual_and_matrix(
        &mut self,
        system: &dyn System,
        r: &mut [Vector3<Real>],
        a: &mut BlockBanded,
    ) {
        self.inertia_residual(system.rod(), r);
        a.reset(system.rod().len(), system.hessian_bandwidth());
        system.add_potential_gradient_and_hessian(self.hessian, self.scratch, a);
        self.add_scaled_gradient(r);
        self.finish_matrix(system.rod(), a);
    }

    fn merit(&mut self, system: &dyn System) -> Real {
        let rod = system.rod();
        let tmp = &mut *self.scratch;
        tmp.iter_mut()
            .zip(&rod.velocities)
            .zip(self.base_v)
            .for_each(|((t, v), v0)| *t = v - v0);
        let m = rod.mass_matrix();
        let inertia = 0.5 * m.bilinear_vec3(tmp, tmp);
        let half_beta = 0.5 * self.step.beta;
        let damping = if self.alpha.per_point.is_empty() {
            half_beta * self.alpha.uniform * m.bilinear_vec3(&rod.velocities, &rod.velocities)
        } else {
            for (i, (t, v)) in tmp.iter_mut().zip(&rod.velocities).enumerate() {
                *t = v * self.alpha.at(i);
            }
            half_beta * m.bilinear_vec3(tmp, &rod.velocities)
        };
        inertia + system.potential_energy() + damping
    }

    fn target(&self, row: &BasisValues, pin: &Pin) -> Vector3<Real> {
        (pin.position - row.combine(&row.value, self.base_q)) / self.step.reach
    }

    fn length_per_unknown(&self) -> Real {
        self.step.reach
    }

    fn hessian_scale(&self) -> Real {
        self.step.beta * self.step.beta
    }

    fn on_not_positive_definite(&mut self) -> bool {
        let retry = self.hessian == HessianKind::Exact;
        self.hessian = HessianKind::Definite;
        retry
    }

    fn indefinite_allowed(&self) -> bool {
        !self.definite_only && self.hessian == HessianKind::Exact
    }

    fn body_form(&self) -> Option<BodyForm> {
        self.bodies.then_some(BodyForm::Dynamic {
            beta: self.step.beta,
            reach: self.step.reach,
        })
    }

    fn body_base(&self) -> Option<&[RigidBody]> {
        self.body_base
    }

    /// Every iteration starts from the exact Hessian again: the definite one converges
    /// only linearly, and is needed only while the exact step climbs the merit.
    fn on_step(&mut self, _step_length: Real) {
        self.hessian = HessianKind::Exact;
    }
}

/// Buffers of an implicit scheme: the start-of-step state (for rollback), the base of
/// the incremental problem, the unknown and the Newton workspace. No allocation once
/// sized for the rod.
#[derive(Debug, Default)]
pub(crate) struct Stepper {
    /// Newton buffers and factorisation.
    pub workspace: NewtonWorkspace,
    /// Positions at the start of the step.
    pub q0: Vec<Vector3<Real>>,
    /// Velocities at the start of the step.
    pub v0: Vec<Vector3<Real>>,
    /// Base position \\(\hat q\\).
    pub base_q: Vec<Vector3<Real>>,
    /// Reference velocity \\(\hat v\\).
    pub base_v: Vec<Vector3<Real>>,
    /// The unknown velocity `x`.
    pub x: Vec<Vector3<Real>>,
    scratch: Vec<Vector3<Real>>,
    alpha: DampingRates,
    /// β of the last solve (pin forces are multipliers / β).
    beta: Real,
    /// The last solve's β and ρ (what a forward sensitivity step differentiates).
    pub step: Option<Increment>,
    /// The multipliers of the step, kept across a tangent solve.
    saved_mu: Vec<Vector3<Real>>,
    /// Never factorise an indefinite matrix: every step descends to a minimum of the
    /// merit, never to a saddle (the static solver's continuation path needs this).
    pub definite_only: bool,
    /// Whether the scheme moves rigid bodies ([`System::bodies`]): its base is the start
    /// state (implicit Euler, the static solver's pseudo-time steps) or `body_base`
    /// (BDF2). Default false: a system with bodies is refused.
    pub bodies: bool,
    /// The bodies at the start of the step (for rollback).
    bodies0: Vec<RigidBody>,
    /// The bodies' base of the step when it is not their start state (BDF2's blend of
    /// the last two states), used while `blend_bodies`.
    pub body_base: Vec<RigidBody>,
    /// Whether the step starts the bodies from `body_base`; cleared by [`Self::begin`].
    pub blend_bodies: bool,
}

impl Stepper {
    /// Checks `dt`, the damping and the state, and saves the start state; the base is
    /// set to it (`base_q = q0`, `base_v = v0`) and the initial guess to `x = v0`.
    pub fn begin(&mut self, system: &dyn System, dt: Real) -> Result<(), IntegratorError> {
        positive("dt", dt)?;
        let rod = system.rod();
        self.alpha.read(rod)?;
        rod.check_finite()?;
        let n = rod.len();
        for v in [
            &mut self.q0,
            &mut self.v0,
            &mut self.base_q,
            &mut self.base_v,
            &mut self.x,
            &mut self.scratch,
        ] {
            v.resize(n, Vector3::zeros());
        }
        self.q0.copy_from_slice(&rod.positions);
        self.v0.copy_from_slice(&rod.velocities);
        self.base_q.copy_from_slice(&rod.positions);
        self.base_v.copy_from_slice(&rod.velocities);
        self.x.copy_from_slice(&rod.velocities);
        self.bodies0.clear();
        self.bodies0.extend_from_slice(system.bodies());
        self.blend_bodies = false;
        Ok(())
    }

    /// The bodies at the start of the step.
    pub fn start_bodies(&self) -> &[RigidBody] {
        &self.bodies0
    }

    /// Runs Newton on the incremental problem; the solution is left applied to the rod.
    /// A solve that stops at the iteration limit is [`IntegratorError::NotConverged`]
    /// unless `params.accept_unconverged` (or a single iteration was asked for).
    pub fn solve(
        &mut self,
        system: &mut dyn System,
        params: &NewtonParams,
        step: Increment,
    ) -> Result<StepStats, IntegratorError> {
        self.beta = step.beta;
        self.step = Some(step);
        if params.max_step.is_some() && step.beta > 0.0 {
            // Start from the current positions (not the predictor x = v₀), so that the
            // step limit governs the whole path from the start state.
            for ((x, q0), b) in self.x.iter_mut().zip(&self.q0).zip(&self.base_q) {
                *x = (q0 - b) / step.beta;
            }
        }
        let mut problem = IncrementalProblem {
            base_q: &self.base_q,
            base_v: &self.base_v,
            step,
            alpha: &self.alpha,
            scratch: &mut self.scratch,
            hessian: HessianKind::Exact,
            definite_only: self.definite_only,
            bodies: self.bodies,
            body_base: self.blend_bodies.then_some(&self.body_base[..]),
        };
        let stats = newton::solve(
            &mut problem,
            system,
            &mut self.x,
            params,
            &mut self.workspace,
        )?;
        if params.accepts(stats.converged) {
            Ok(stats)
        } else {
            Err(IntegratorError::NotConverged {
                iterations: stats.newton_iterations,
                residual: stats.residual,
            })
        }
    }

    /// Takes a step solved elsewhere (the batched form, [`crate::lane_euler`], which
    /// checked the start state, the damping and the end state finite) as this scheme's
    /// own: the end state `end` (positions, velocities) becomes the rod's by exchanging
    /// the buffers (`end` is left with the start state), and the pin forces are kept.
    pub fn accept(
        &mut self,
        system: &mut dyn System,
        end: &mut (Vec<Vector3<Real>>, Vec<Vector3<Real>>),
        (stats, pin_forces): (StepStats, &[Vector3<Real>]),
        dt: Real,
    ) -> Result<StepStats, IntegratorError> {
        positive("dt", dt)?;
        let rod = system.rod_mut();
        let fits = rod.positions.len() == end.0.len() && rod.velocities.len() == end.1.len();
        if !fits {
            return Err(IntegratorError::SolverState(
                "a step solved elsewhere for another number of control points",
            ));
        }
        std::mem::swap(&mut rod.positions, &mut end.0);
        std::mem::swap(&mut rod.velocities, &mut end.1);
        self.beta = dt;
        self.step = None;
        let forces = pin_forces.iter().map(|f| f * dt);
        self.workspace.set_multipliers(forces);
        Ok(stats)
    }

    /// `α_i`, the damping rate at control point `i` of the last step.
    pub fn damping_at(&self, i: usize) -> Real {
        self.alpha.at(i)
    }

    /// Solves the tangent problems `cases` ([`newton::tangents`]) with the Newton matrix
    /// of the last solve at the applied iterate (the rod must hold it: positions
    /// \(\hat q + \beta x\), velocities `x`); the step's multipliers (its pin forces)
    /// are kept. An error if the last step was not solved here, or the matrix is not the
    /// exact Hessian's.
    pub fn tangents(
        &mut self,
        system: &dyn System,
        params: &NewtonParams,
        cases: &mut [newton::Tangent],
    ) -> Result<StepStats, IntegratorError> {
        let step = self.step.ok_or(IntegratorError::SolverState(
            "forward sensitivities need the step solved by this integrator",
        ))?;
        let mut problem = IncrementalProblem {
            base_q: &self.base_q,
            base_v: &self.base_v,
            step,
            alpha: &self.alpha,
            scratch: &mut self.scratch,
            hessian: HessianKind::Exact,
            definite_only: false,
            bodies: false,
            body_base: None,
        };
        self.saved_mu.clear();
        self.saved_mu
            .extend_from_slice(self.workspace.multipliers());
        self.workspace.solver_kind(params.linear_solver, system);
        let exact = |p: &dyn NewtonProblem| p.indefinite_allowed();
        let cases = (cases, crate::remainder::RELATIVE_TOLERANCE);
        let stats = newton::tangents(&mut problem, system, &mut self.workspace, &exact, cases);
        let mu = self.saved_mu.iter().copied();
        self.workspace.set_multipliers(mu);
        stats
    }

    /// Forces the pins exerted on the rod during the last step, N: the KKT multipliers
    /// divided by β, since the momentum balance reads \(M(x - \hat v) = \beta(f + G^T\lambda)\).
    pub fn pin_forces(&self) -> Vec<Vector3<Real>> {
        let beta = self.beta;
        let forces = self.workspace.multipliers().iter();
        forces
            .map(|m| if beta > 0.0 { m / beta } else { *m })
            .collect()
    }

    /// Checks the end state; on any error (from `result` or non-finite values) restores
    /// the start state exactly and returns the error.
    pub fn finish(
        &self,
        system: &mut dyn System,
        result: Result<StepStats, IntegratorError>,
    ) -> Result<StepStats, IntegratorError> {
        let result = result.and_then(|stats| {
            let rod = system.rod();
            check_finite("position", &rod.positions)
                .and_then(|_| check_finite("velocity", &rod.velocities))
                .map_err(|_| IntegratorError::NonFinite {
                    what: "positions or velocities",
                })?;
            Ok(stats)
        });
        if result.is_err() {
            let rod = system.rod_mut();
            rod.positions.copy_from_slice(&self.q0);
            rod.velocities.copy_from_slice(&self.v0);
            system.bodies_mut().clone_from_slice(&self.bodies0);
        } else if self.step.is_some() {
            self.workspace.write_bodies(system);
        }
        result
    }
}
