//! What Newton's method does after the Cholesky factorisation of its matrix failed.

use super::{assemble, NewtonProblem, NewtonWorkspace};
use crate::{IntegratorError, System};

/// What to do after the Cholesky factorisation failed.
pub(super) enum Fallback {
    /// The indefinite factorisation took the matrix.
    Factored,
    /// The problem switched to its definite matrix: assemble and factorise again.
    Retry,
    /// Neither: report the failure.
    Fail,
}

/// After a failed Cholesky factorisation: the matrix (reassembled if the banded factor
/// overwrote it) is checked for non-finite entries, factorised by the indefinite `UᵀDU`
/// if the problem allows and it has no far blocks, or the problem is asked for its
/// definite matrix.
pub(super) fn indefinite_fallback(
    problem: &mut dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
) -> Result<Fallback, IntegratorError> {
    if !ws.solver.matrix_intact() {
        assemble(problem, system, ws, false);
    }
    let (finite, far) = ws
        .solver
        .matrix()
        .map_or((false, false), |m| (m.is_finite(), m.has_far_blocks()));
    if !finite {
        return Err(IntegratorError::NonFinite {
            what: "Newton matrix",
        });
    }
    if problem.indefinite_allowed() && !far && ws.solver.factor_indefinite_assembled().is_ok() {
        return Ok(Fallback::Factored);
    }
    Ok(if problem.on_not_positive_definite() {
        Fallback::Retry
    } else {
        Fallback::Fail
    })
}
