//! The linearised equilibrium at a converged state, for sensitivities (issue #48): with
//! the exact Hessian `K` of the potential at the applied positions and the pins held,
//!
//! \\[ \begin{pmatrix} K & G^T \\ G & 0 \end{pmatrix}
//! \begin{pmatrix} \dot x \\ \dot\mu \end{pmatrix} =
//! \begin{pmatrix} -b \\ 0 \end{pmatrix}, \\]
//!
//! one factorisation for every right-hand side `b` (a parameter's \\(\partial \nabla E /
//! \partial p\\)): the implicit-function theorem on \\(\nabla E(x) + G^T \mu = 0\\),
//! \\(G x = c\\). `K` is factorised exactly — by Cholesky, or by the indefinite `UᵀDU`
//! where parts of the rod are compressed — never replaced by the definite Hessian the
//! solver may iterate with (that would be another derivative). A Hessian remainder (the
//! consistent mixed stretching's) is added by the conjugate-gradient correction of the
//! Newton steps, to its relative accuracy 1e-9.

use super::{factor_matrix, NewtonProblem, NewtonWorkspace};
use crate::linear::LinearSolverKind;
use crate::{IntegratorError, System};
use nalgebra::Vector3;
use splinerod_core::Real;

/// Solves the system of the module docs in place: each `rhs[k]` holds `b_k` (one entry
/// per control point) on entry and \\(\dot x_k\\) on return (zero where point pins hold).
/// `problem` must assemble the exact Hessian and refuse to fall back on another
/// (`on_not_positive_definite` false for it): an error otherwise.
pub(crate) fn solve_linearized(
    problem: &mut dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
    linear_solver: LinearSolverKind,
    rhs: &mut [Vec<Vector3<Real>>],
) -> Result<(), IntegratorError> {
    let n = system.rod().len();
    ws.solver.kind = linear_solver;
    ws.resize(n, system.pins().len());
    ws.solver.periodic = system.rod().basis().periodic_count();
    ws.constraints.setup(system.rod(), system.pins())?;
    factor_matrix(problem, system, ws, false)?;
    ws.constraints.factor(&mut ws.solver)?;
    let x = &system.rod().positions;
    for b in rhs.iter_mut() {
        if b.len() != n {
            return Err(IntegratorError::SolverState(
                "a sensitivity right-hand side needs one entry per control point",
            ));
        }
        for (i, v) in b.iter().enumerate() {
            ws.flat[3 * i..3 * i + 3].copy_from_slice((-v).as_slice());
        }
        let (solver, constraints, mu) = (&mut ws.solver, &mut ws.constraints, &mut ws.scratch_mu);
        constraints.solve_homogeneous(solver, x, &mut ws.flat, mu)?;
        if system.has_hessian_remainder() && !solver.is_indefinite() {
            ws.remainder.correct(
                &mut ws.flat,
                0.0,
                &mut |v, sign, out| system.add_hessian_remainder(v, sign, out),
                &mut |z| constraints.solve_homogeneous(solver, x, z, mu),
            )?;
        }
        for (i, v) in b.iter_mut().enumerate() {
            *v = Vector3::new(ws.flat[3 * i], ws.flat[3 * i + 1], ws.flat[3 * i + 2]);
        }
        if b.iter().any(|v| !v.iter().all(|c| c.is_finite())) {
            return Err(IntegratorError::NonFinite {
                what: "sensitivity",
            });
        }
    }
    Ok(())
}
