//! The backtracking line search of Newton's method (module docs of [`crate::newton`]):
//! halve `t` until \\(\Phi(x + t\Delta x) \le \Phi(x) + 10^{-4}\, t\, r \cdot \Delta x\\),
//! within the merit's round-off, or take a trusted converging step whole.

use super::{NewtonProblem, NewtonWorkspace};
use crate::{IntegratorError, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::Real;

/// What the line search is asked to do with a step.
#[derive(Debug, Clone, Copy)]
pub(super) struct Trial {
    /// Search at all (else the full step is taken).
    pub(super) search: bool,
    /// Take the full step without the merit test
    /// ([`crate::convergence::ConvergenceTracker::converging`]), if admissible.
    pub(super) trust: bool,
    /// The step's slope \(r \cdot \Delta x\).
    pub(super) slope: Real,
}

/// Takes the step `x += t Δx`, halving `t` until the merit decreases enough. The line
/// search runs only from a feasible iterate (pins satisfied), where `Δx` is a descent
/// direction; from an infeasible one the full step restores feasibility first. `known`
/// is the merit at the current iterate if measured already (the previous search's
/// last trial); returns `t` and the merit at the new iterate if it was measured.
pub(super) fn line_search(
    problem: &mut dyn NewtonProblem,
    system: &mut dyn System,
    x: &mut [Vector3<Real>],
    ws: &mut NewtonWorkspace,
    trial: Trial,
    known: Option<Real>,
    stats: &mut StepStats,
) -> Result<(Real, Option<Real>), IntegratorError> {
    let Trial {
        search: enabled,
        trust,
        slope,
    } = trial;
    let feasible = (0..ws.constraints.len()).all(|p| {
        let c = ws.constraints.targets[p];
        ws.constraints.gap(p, x).amax() <= 1e-10 * (1.0 + c.amax())
    });
    let search = enabled && feasible && slope < 0.0;
    let phi0 = match (search, known) {
        (false, _) => 0.0,
        (true, Some(phi)) => phi,
        (true, None) => problem.merit(system) + ws.coupling.merit(system),
    };
    // An admissible iterate stays admissible (System::admissible).
    let guard = search && system.admissible();
    ws.base.copy_from_slice(x);
    ws.coupling.save();
    let mut t: Real = 1.0;
    loop {
        for ((xi, b), d) in x.iter_mut().zip(&ws.base).zip(&ws.dx) {
            *xi = b + d * t;
        }
        ws.coupling.stage(t);
        problem.apply(system.rod_mut(), x);
        if !search {
            return Ok((t, None));
        }
        let phi = problem.merit(system) + ws.coupling.merit(system);
        let admissible = !guard || system.admissible();
        let armijo = admissible && phi <= phi0 + 1e-4 * t * slope;
        let noise = admissible && (phi - phi0).abs() <= 1e-14 * phi0.abs();
        let trusted = admissible && trust && t == 1.0;
        if armijo || noise || trusted || t < 1e-8 {
            if !admissible {
                // No admissible point along the step: stay where we are.
                t = 0.0;
                for (xi, b) in x.iter_mut().zip(&ws.base) {
                    *xi = *b;
                }
                ws.coupling.stage(0.0);
                problem.apply(system.rod_mut(), x);
                return Ok((t, Some(phi0)));
            }
            if !phi.is_finite() {
                return Err(IntegratorError::NonFinite { what: "merit" });
            }
            return Ok((t, Some(phi)));
        }
        t *= 0.5;
        stats.line_search_cuts += 1;
    }
}
