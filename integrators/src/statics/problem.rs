//! The static solver's Newton problem: the potential's gradient and (regularised,
//! augmented) Hessian at fixed pins, with the Levenberg–Marquardt schedule of the
//! module docs (`statics/mod.rs`): \\(A = K + \varepsilon M\\), ε ×4 after a cut step,
//! ÷10 after a full one, the exact Hessian once ε ≤ 1e-6.

use crate::newton::{BodyForm, NewtonParams, NewtonProblem, NewtonWorkspace};
use crate::statics::StaticParams;
use crate::{StepStats, System};
use nalgebra::Vector3;
use splinerod_core::{BasisValues, BlockBanded, HessianKind, Pin, Real, Rod};

/// Adds the counters of one solve to `total` (the last one's convergence wins).
pub(super) fn add_counts(total: &mut StepStats, s: &StepStats) {
    total.add_counts(s);
    total.converged = s.converged;
}

/// The largest diagonal entries of the stiffness (of the assembled `k_matrix`) and of
/// the rod's mass matrix.
pub(super) fn diagonal_scales(rod: &Rod, k_matrix: &BlockBanded) -> (Real, Real) {
    let k = (0..rod.len())
        .map(|i| k_matrix.upper(i, 0).diagonal().amax())
        .fold(0.0, Real::max);
    let m = (0..rod.len())
        .map(|i| rod.mass_matrix().get(i, i))
        .fold(0.0, Real::max);
    (k, m)
}

/// \(\sqrt{\max_i M_{ii} / \max_i K_{ii}}\), s: the time scale of the stiffest local
/// motion, where continuation starts (a step this short is dominated by inertia).
pub(super) fn shortest_period(system: &dyn System, ws: &mut NewtonWorkspace) -> Real {
    let rod = system.rod();
    let a = ws.matrix_mut();
    a.reset(rod.len(), system.hessian_bandwidth());
    system.add_potential_hessian(HessianKind::Definite, a);
    let (k, m) = diagonal_scales(rod, a);
    if k > 0.0 && m > 0.0 {
        (m / k).sqrt()
    } else {
        1e-3
    }
}

pub(super) fn newton_params(p: &StaticParams, max_iterations: usize) -> NewtonParams {
    NewtonParams {
        max_iterations,
        tolerance: p.tolerance,
        line_search: true,
        linear_solver: p.linear_solver,
        max_step: None,
        accept_unconverged: true,
    }
}

pub(super) struct StaticProblem {
    /// ε relative to max diag K / max diag M.
    pub(super) regularization: Real,
    /// The Hessian of the next iteration: the definite one while regularised, the exact
    /// one (by Cholesky or the indefinite LDLT, if it descends) once the regularisation
    /// is negligible, so that the last iterations converge quadratically also where
    /// parts of the rod are compressed.
    pub(super) kind: HessianKind,
    /// Augmented Lagrangian weight: the largest diagonal entry of `K` (a stiffness scale).
    pub(super) rho: Real,
    /// max K / max M of the last matrix (1/s²): the regularisation's scale.
    pub(super) rate: Real,
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
        a.reset(rod.len(), system.hessian_bandwidth());
        system.add_potential_hessian(self.kind, a);
        let (k, m) = diagonal_scales(rod, a);
        let k = if k > 0.0 { k } else { m };
        self.rho = k;
        self.rate = k / m;
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

    fn hessian_scale(&self) -> Real {
        1.0
    }

    fn augmentation(&self) -> Real {
        self.rho
    }

    /// Bodies take the rod's regularisation on their mass and inertia, at least 1e-10
    /// of the scale: a direction only gravity and the pins act in (a welded body's roll
    /// about a rod without twist) is neutral, and the floor keeps its matrix definite.
    fn body_form(&self) -> Option<BodyForm> {
        Some(BodyForm::Static {
            regularization: self.regularization.max(1e-10) * self.rate,
        })
    }

    fn on_not_positive_definite(&mut self) -> bool {
        if self.kind == HessianKind::Exact {
            self.kind = HessianKind::Definite;
            return true;
        }
        self.regularization = (self.regularization * 10.0).max(1e-8);
        self.regularization < 1e8
    }

    fn indefinite_allowed(&self) -> bool {
        self.kind == HessianKind::Exact
    }

    /// A static solve's steps stay exact where the banded matrix is indefinite and a
    /// remainder needs the correction (a rope on a sphere): they converge quadratically
    /// and the solve ends at its tolerance, not short of it.
    fn carries_indefinite(&self) -> bool {
        true
    }

    /// A step below the tolerance ends the solve once the regularisation is negligible
    /// (≤ 1e-6 relative: it changes the step, not the fixed point, so it only slows the
    /// convergence; line-search cuts at round-off level keep it from reaching zero).
    fn converged(&self, step: Real, tolerance: Real) -> bool {
        self.regularization <= 1e-6 && step <= tolerance
    }

    fn on_step(&mut self, step_length: Real) {
        self.regularization = if step_length < 1.0 {
            (self.regularization * 4.0).max(1e-6)
        } else if self.regularization < 1e-12 {
            0.0
        } else {
            self.regularization / 10.0
        };
        self.kind = if self.regularization <= 1e-6 {
            HessianKind::Exact
        } else {
            HessianKind::Definite
        };
    }
}
