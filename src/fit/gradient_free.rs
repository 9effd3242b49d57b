//! The gradient-free baseline a fit is compared against (issue #48's report): the
//! Nelder–Mead simplex (the `argmin` crate's) on the same objective as
//! [`crate::fit::fit`],
//!
//! \\[ f(x) = \tfrac12 \sum_i r_i(p(x))^2, \\]
//!
//! in the same fitted variables `x` (log space for positive parameters, MINUIT's bounds
//! transform), from the same start, stopped once it reaches a given residual. The
//! starting simplex steps each variable by [`SIMPLEX_STEP`] (10 % of a log-space
//! parameter). A simulation that fails counts, and scores `+∞` (the simplex moves
//! away from it). What is compared is the number of simulations each method needs to
//! reach one residual: Nelder–Mead sees only the residual's size, the least-squares fit
//! also its exact derivatives, from the same solve.

use crate::fit::least_squares::{Model, ParameterSpace};
use crate::Error;
use argmin::core::{CostFunction, Executor, State};
use argmin::solver::neldermead::NelderMead;
use splinerod_core::Real;
use std::cell::{Cell, RefCell};

/// Step of the starting simplex in each fitted variable.
pub const SIMPLEX_STEP: Real = 0.1;

/// What the gradient-free fit reached.
#[derive(Debug, Clone, PartialEq)]
pub struct GradientFreeFit {
    /// The best parameters found.
    pub parameters: Vec<Real>,
    /// Root mean square of the weighted residuals there.
    pub residual_rms: Real,
    /// Model evaluations (simulations) made.
    pub simulations: usize,
    /// Whether it reached the target residual within its budget.
    pub reached: bool,
}

/// Minimises the model's squared residuals by Nelder–Mead from `start` (each parameter
/// fitted as `spaces` says) until their root mean square is at most `target_rms`, with
/// at most `max_simulations` model evaluations (and as many simplex iterations).
pub fn nelder_mead(
    model: &mut dyn Model,
    start: &[Real],
    spaces: &[ParameterSpace],
    target_rms: Real,
    max_simulations: usize,
) -> Result<GradientFreeFit, Error> {
    let n = start.len();
    let m = model.residual_count();
    if spaces.len() != n || n == 0 || m < n {
        let reason = format!("{m} residuals for {n} parameters: a fit needs at least as many");
        return Err(Error::field("observations", m, reason));
    }
    if !(target_rms.is_finite() && target_rms >= 0.0) {
        return Err(Error::field(
            "target_rms",
            target_rms,
            "must be finite and ≥ 0",
        ));
    }
    let x0: Vec<Real> = spaces
        .iter()
        .zip(start)
        .map(|(s, &p)| s.variable(p))
        .collect();
    let simplex = (0..=n)
        .map(|k| {
            let mut x = x0.clone();
            if k > 0 {
                x[k - 1] += SIMPLEX_STEP;
            }
            x
        })
        .collect();
    let objective = Objective {
        model: RefCell::new(model),
        spaces,
        residuals: RefCell::new(vec![0.0; m]),
        simulations: Cell::new(0),
        budget: max_simulations,
    };
    let target = 0.5 * m as Real * target_rms * target_rms;
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(0.0)
        .map_err(|e| Error::field("nelder_mead", 0.0, e.to_string()))?;
    let budget = max_simulations as u64;
    let result = Executor::new(&objective, solver)
        .configure(|state| state.target_cost(target).max_iters(budget))
        .run()
        .map_err(|e| Error::field("nelder_mead", 0.0, e.to_string()))?;
    let state = result.state();
    let best = state.get_best_param().cloned().unwrap_or(x0);
    let cost = state.get_best_cost();
    Ok(GradientFreeFit {
        parameters: ParameterSpace::parameters(spaces, &best),
        residual_rms: (2.0 * cost / m as Real).sqrt(),
        simulations: objective.simulations.get(),
        reached: cost <= target,
    })
}

/// The model's squared residuals in the fitted variables, counting simulations.
struct Objective<'a> {
    model: RefCell<&'a mut dyn Model>,
    spaces: &'a [ParameterSpace],
    residuals: RefCell<Vec<Real>>,
    simulations: Cell<usize>,
    /// Most simulations: past them every point scores `+∞` without one.
    budget: usize,
}

impl CostFunction for &Objective<'_> {
    type Param = Vec<Real>;
    type Output = Real;

    fn cost(&self, x: &Self::Param) -> Result<Real, argmin::core::Error> {
        if self.simulations.get() >= self.budget {
            return Ok(Real::INFINITY);
        }
        self.simulations.set(self.simulations.get() + 1);
        let p = ParameterSpace::parameters(self.spaces, x);
        let mut r = self.residuals.borrow_mut();
        let cost = match self.model.borrow_mut().evaluate(&p, &mut r, None) {
            Ok(()) => 0.5 * r.iter().map(|r| r * r).sum::<Real>(),
            Err(_) => Real::INFINITY,
        };
        Ok(if cost.is_nan() { Real::INFINITY } else { cost })
    }
}
