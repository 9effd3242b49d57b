//! Static equilibrium: minimise the potential energy \\(E(q)\\) subject to the pins
//! \\(G q = p\\), by Newton's method with a line search and Levenberg–Marquardt
//! regularisation \\(A = K + \varepsilon M\\).
//!
//! `K` is the positive semi-definite Hessian, singular where the rod is slack (a
//! compressed straight rod has no transverse stiffness), so \\(\varepsilon\\) starts at
//! `1e-3 · max diag K / max diag M`, grows ×4 whenever the line search had to cut the step
//! and shrinks ÷10 after every full step, reaching zero: the last iterations are pure
//! Newton and converge quadratically. Because the pins alone remove the rigid motions,
//! `K` is singular on its own; the augmented Lagrangian term \\(\rho G^T G\\) (see
//! [`crate::newton::NewtonProblem::augmentation`]) makes the matrix definite without
//! changing the constrained step.

use crate::linear::LinearSolverKind;
use crate::newton::{self, NewtonParams, NewtonProblem, NewtonWorkspace};
use crate::{IntegratorError, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::{BasisValues, BlockBanded, HessianKind, Pin, Real, Rod};

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
}

impl Default for StaticParams {
    fn default() -> Self {
        Self {
            max_iterations: 200,
            tolerance: 1e-12,
            linear_solver: LinearSolverKind::Banded,
        }
    }
}

/// Finds equilibria of a [`System`] (velocities are set to zero).
#[derive(Debug, Default)]
pub struct StaticSolver {
    /// Settings.
    pub params: StaticParams,
    workspace: NewtonWorkspace,
    x: Vec<Vector3<Real>>,
}

impl StaticSolver {
    /// A static solver with the given settings.
    pub fn new(params: StaticParams) -> Result<Self, IntegratorError> {
        newton_params(&params).validate()?;
        Ok(Self {
            params,
            ..Self::default()
        })
    }

    /// Moves the rod to equilibrium. On error the rod is left as it was.
    pub fn solve(&mut self, system: &mut dyn System) -> Result<StepStats, IntegratorError> {
        system.rod().check_finite()?;
        let saved = (
            system.rod().positions.clone(),
            system.rod().velocities.clone(),
        );
        self.x.clone_from(&system.rod().positions);
        let mut problem = StaticProblem {
            regularization: 1e-3,
            rho: 0.0,
        };
        let params = newton_params(&self.params);
        let result = newton::solve(
            &mut problem,
            system,
            &mut self.x,
            &params,
            &mut self.workspace,
        );
        let result = match result {
            Ok(stats) if stats.converged => Ok(stats),
            Ok(stats) => Err(IntegratorError::NotConverged {
                iterations: stats.newton_iterations,
                residual: stats.residual,
            }),
            Err(e) => Err(e),
        };
        if result.is_err() {
            let rod = system.rod_mut();
            (rod.positions, rod.velocities) = saved;
        }
        result
    }

    /// Forces the pins exert on the rod at equilibrium, N.
    pub fn pin_forces(&self) -> &[Vector3<Real>] {
        self.workspace.multipliers()
    }
}

fn newton_params(p: &StaticParams) -> NewtonParams {
    NewtonParams {
        max_iterations: p.max_iterations,
        tolerance: p.tolerance,
        line_search: true,
        linear_solver: p.linear_solver,
        max_step: None,
    }
}

struct StaticProblem {
    /// ε relative to max diag K / max diag M.
    regularization: Real,
    /// Augmented Lagrangian weight: the largest diagonal entry of `K` (a stiffness scale).
    rho: Real,
}

impl NewtonProblem for StaticProblem {
    fn apply(&self, rod: &mut Rod, x: &[Vector3<Real>]) {
        rod.positions.copy_from_slice(x);
        rod.velocities
            .iter_mut()
            .for_each(|v| *v = Vector3::zeros());
    }

    fn residual(&mut self, system: &dyn System, r: &mut [Vector3<Real>]) {
        r.iter_mut().for_each(|v| *v = Vector3::zeros());
        system.add_potential_gradient(r);
    }

    fn matrix(&mut self, system: &dyn System, a: &mut BlockBanded) {
        let rod = system.rod();
        a.reset(rod.len(), rod.basis().degree());
        system.add_potential_hessian(HessianKind::Definite, a);
        let k = (0..rod.len())
            .map(|i| a.upper(i, 0).diagonal().amax())
            .fold(0.0, Real::max);
        let m = (0..rod.len())
            .map(|i| rod.mass_matrix().get(i, i))
            .fold(0.0, Real::max);
        let k = if k > 0.0 { k } else { m };
        self.rho = k;
        if self.regularization > 0.0 {
            a.add_scaled_scalar(self.regularization * k / m, rod.mass_matrix());
        }
    }

    fn merit(&mut self, system: &dyn System) -> Real {
        system.potential_energy()
    }

    fn target(&self, _row: &BasisValues, pin: &Pin) -> Vector3<Real> {
        pin.position
    }

    fn length_per_unknown(&self) -> Real {
        1.0
    }

    fn augmentation(&self) -> Real {
        self.rho
    }

    fn on_not_positive_definite(&mut self) -> bool {
        self.regularization = (self.regularization * 10.0).max(1e-8);
        self.regularization < 1e8
    }

    fn converged(&self, step: Real, tolerance: Real) -> bool {
        self.regularization == 0.0 && step <= tolerance
    }

    fn on_step(&mut self, step_length: Real) {
        self.regularization = if step_length < 1.0 {
            (self.regularization * 4.0).max(1e-6)
        } else if self.regularization < 1e-12 {
            0.0
        } else {
            self.regularization / 10.0
        };
    }
}
