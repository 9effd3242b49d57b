//! Tangent (sensitivity) solves at a converged point with the Newton machinery's own
//! factorisation: for a parameter `p` of an equilibrium \\(r(x(p), p) = G^T\mu\\),
//! \\(G x = c(p)\\), the implicit-function theorem gives the linear KKT system
//!
//! \\[ K\,\dot x - G^T \dot\mu = -\partial r/\partial p, \qquad G \dot x = \dot c, \\]
//!
//! with `K` the exact Hessian. It is the Newton step's system with the residual
//! replaced by \\(\partial r/\partial p\\), the pins' gaps by \\(\dot c\\) and the iterate by
//! zero, so one factorisation (by the solver the Newton iterations use: banded, sparse
//! or periodic; the pins' Schur complement; the remainder's correction by conjugate
//! gradients, for a static scene to relative 1e-13, [`TANGENT_TOLERANCE`], tighter than
//! a Newton step's 1e-9) serves every parameter.

use super::{factor_matrix, solve_factored, NewtonProblem, NewtonWorkspace};
#[cfg(doc)]
use crate::remainder::{RELATIVE_TOLERANCE, TANGENT_TOLERANCE};
use crate::{IntegratorError, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::Real;

/// One parameter's tangent problem and, after [`tangents`], its solution.
#[derive(Debug, Clone, Default)]
pub struct Tangent {
    /// \\(\partial r/\partial p\\): the derivative of the residual (the potential's
    /// gradient) with respect to the parameter, one entry per control point.
    pub residual_rate: Vec<Vector3<Real>>,
    /// \\(\dot c\\): the derivative of each pin's target (zero unless the parameter moves it).
    pub target_rates: Vec<Vector3<Real>>,
    /// \\(\dot x\\), the control points' derivative (the solution).
    pub positions: Vec<Vector3<Real>>,
    /// \\(\dot\mu\\), the derivative of the pins' multipliers (their forces, for statics).
    pub multipliers: Vec<Vector3<Real>>,
}

/// Factorises `problem`'s matrix at the applied state once (it must be the exact
/// Hessian: `exact` tells whether the problem still assembles it after the
/// factorisation, which may have switched it to a definite fallback — then an error,
/// not an approximate answer) and solves every
/// tangent problem with it, the Hessian remainder's correction to the relative accuracy
/// `relative` (static sensitivities: [`TANGENT_TOLERANCE`]; a run's steps: the Newton
/// steps' [`RELATIVE_TOLERANCE`], whose cost they repeat every step). Returns the
/// counters of the factorisation and solves.
pub fn tangents(
    problem: &mut dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
    exact: &dyn Fn(&dyn NewtonProblem) -> bool,
    (cases, relative): (&mut [Tangent], Real),
) -> Result<StepStats, IntegratorError> {
    let n = system.rod().len();
    ws.resize(n, system.pins().len());
    ws.coupling.clear();
    ws.constraints.set_held(std::iter::empty());
    ws.constraints.setup(system.rod(), system.pins())?;
    let mut stats = StepStats::default();
    factor_matrix(problem, system, ws, false)?;
    ws.constraints.factor(&mut ws.solver)?;
    let carried = carry_if_indefinite(problem, system, ws)?;
    if !carried && !exact(problem) {
        return Err(IntegratorError::NotPositiveDefinite {
            context: "the exact Hessian at the equilibrium, for sensitivities",
        });
    }
    let zeros = std::mem::take(&mut ws.origin);
    ws.remainder.set_relative_tolerance(Some(relative));
    let solved = solve_cases(problem, system, ws, &zeros, cases, &mut stats);
    ws.remainder.set_relative_tolerance(None);
    ws.origin = zeros;
    ws.carried.active = false;
    solved.map(|()| stats)
}

/// When the exact banded matrix was factorised indefinite and a remainder needs the
/// correction (which an indefinite factor cannot precondition), switches to the
/// problem's definite matrix and carries the difference ([`super::carried`]); whether
/// it did.
pub(super) fn carry_if_indefinite(
    problem: &mut dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
) -> Result<bool, IntegratorError> {
    let corrected = problem.hessian_scale() > 0.0 && system.has_hessian_remainder();
    if !(ws.solver.is_indefinite() && corrected) {
        return Ok(false);
    }
    let carried = &mut ws.carried;
    problem.matrix(system, &mut carried.exact);
    if !problem.on_not_positive_definite() {
        return Ok(false);
    }
    problem.matrix(system, &mut carried.definite);
    factor_matrix(problem, system, ws, false)?;
    ws.constraints.factor(&mut ws.solver)?;
    ws.carried.active = !ws.solver.is_indefinite();
    Ok(ws.carried.active)
}

/// Solves each case with the factorised matrix, from the iterate `zeros`.
fn solve_cases(
    problem: &mut dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
    zeros: &[Vector3<Real>],
    cases: &mut [Tangent],
    stats: &mut StepStats,
) -> Result<(), IntegratorError> {
    let n = zeros.len();
    let remainder = remainder_kind(problem, system, ws);
    if remainder == Remainder::AllPins {
        problem.matrix(system, &mut ws.spare);
    }
    for case in cases.iter_mut() {
        let pins = system.pins().len();
        if case.residual_rate.len() != n || case.target_rates.len() != pins {
            return Err(IntegratorError::InvalidParameter {
                name: "tangent problem size",
                value: case.residual_rate.len() as Real,
                reason: "one residual rate per control point and one target rate per pin",
            });
        }
        ws.r.copy_from_slice(&case.residual_rate);
        ws.constraints.targets.clone_from(&case.target_rates);
        ws.floor = 0.0;
        ws.motion = None;
        solve_factored(problem, system, zeros, ws, stats)?;
        match remainder {
            Remainder::None => {}
            Remainder::PointPins => remainder_multipliers(problem, system, ws, zeros),
            Remainder::AllPins => all_multipliers(problem, system, ws)?,
        }
        case.positions.clone_from(&ws.dx);
        case.multipliers.clone_from(&ws.multipliers);
    }
    Ok(())
}

/// After a solve with the remainder's correction: the eliminated pins' multipliers
/// from the final step, their rows completed by the remainder's product
/// \\(sR\, \dot x\\) (a Newton step's multipliers need not: its step vanishes at
/// convergence, a tangent's does not). For pins only at control points (the common
/// case: no extra assembly); a closed rod's Schur pins keep the banded step's.
fn remainder_multipliers(
    problem: &dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
    zeros: &[Vector3<Real>],
) {
    // The row's rest: r − a (a = ρGᵀc, the augmentation's right-hand side at x = 0)
    // plus sR ẋ.
    let rho = problem.augmentation();
    ws.base.iter_mut().for_each(|b| *b = Vector3::zeros());
    ws.constraints.add_gram_rhs(rho, zeros, &mut ws.base);
    for (b, r) in ws.base.iter_mut().zip(&ws.r) {
        *b = r - *b;
    }
    let scale = problem.hessian_scale();
    system.add_hessian_remainder(&ws.dx, scale, &mut ws.base);
    ws.carried.add_product(&ws.dx, 1.0, &mut ws.base);
    ws.constraints
        .remainder_multipliers(&ws.flat, &ws.base, &mut ws.multipliers);
}

/// How the multipliers of a tangent solve are completed for the Hessian remainder.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Remainder {
    /// No remainder's correction ran: the solve's multipliers are exact.
    None,
    /// Every pin is eliminated: their rows, completed ([`remainder_multipliers`]).
    PointPins,
    /// Some pins go through the Schur complement: all from the whole matrix
    /// ([`all_multipliers`]).
    AllPins,
}

/// Which [`Remainder`] case the solves of `problem` are.
fn remainder_kind(
    problem: &dyn NewtonProblem,
    system: &dyn System,
    ws: &NewtonWorkspace,
) -> Remainder {
    let corrected = problem.hessian_scale() > 0.0 && !ws.solver.is_indefinite();
    if !(corrected && system.has_hessian_remainder()) {
        Remainder::None
    } else if ws.constraints.has_schur_pins() && !system.rod().is_closed() {
        Remainder::AllPins
    } else {
        Remainder::PointPins
    }
}

/// Every pin's multiplier from \\(w = r + (A + sR)\,\dot x = G^T\mu\\), with `A` the
/// problem's matrix (assembled unfactorised in `ws.spare`) and the remainder's product.
fn all_multipliers(
    problem: &dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
) -> Result<(), IntegratorError> {
    ws.spare.mul_vec(&ws.dx, &mut ws.base);
    for (b, r) in ws.base.iter_mut().zip(&ws.r) {
        *b += r;
    }
    system.add_hessian_remainder(&ws.dx, problem.hessian_scale(), &mut ws.base);
    ws.carried.add_product(&ws.dx, 1.0, &mut ws.base);
    ws.constraints.multipliers_of(&ws.base, &mut ws.multipliers)
}
