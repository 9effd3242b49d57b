//! The stability check of a stationary point (the static solver's exit from saddles).

use super::{assemble, NewtonProblem, NewtonWorkspace};
use crate::{IntegratorError, System};
use nalgebra::Vector3;
use splinerod_core::Real;

/// Whether the applied state is a stable stationary point: assembles the problem's
/// matrix (with the pins as in a solve) and factorises it. `None` if it is positive
/// definite (or too singular to tell); otherwise the curvature and, in `d`, a direction
/// of negative curvature (zero at the control points the pins hold).
pub(crate) fn negative_curvature(
    problem: &mut dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
    d: &mut Vec<Vector3<Real>>,
) -> Result<Option<Real>, IntegratorError> {
    let n = system.rod().len();
    ws.resize(n, system.pins().len());
    ws.solver.periodic = system.rod().basis().periodic_count();
    ws.coupling.clear();
    ws.constraints.set_held(std::iter::empty());
    ws.constraints.setup(system.rod(), system.pins())?;
    assemble(problem, system, ws, false);
    let epoch = system.rod().topology_epoch();
    if ws.solver.factor_assembled(epoch).is_ok() {
        return Ok(None);
    }
    if !ws.solver.matrix_intact() {
        assemble(problem, system, ws, false);
    }
    let far = ws.solver.matrix().is_none_or(|m| m.has_far_blocks());
    if far || ws.solver.factor_indefinite_assembled().is_err() {
        return Ok(None);
    }
    d.resize(n, Vector3::zeros());
    let curvature = ws.solver.negative_curvature(d);
    for k in ws.constraints.points.control_points() {
        d[k] = Vector3::zeros();
    }
    Ok(curvature)
}
