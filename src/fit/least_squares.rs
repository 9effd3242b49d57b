//! Weighted nonlinear least squares over a few scalar parameters, for identification
//! (issue #48): minimise
//!
//! \\[ \tfrac12 \sum_i r_i(p)^2, \qquad r_i = (\text{observed}_i - \text{model}_i(p)) / \sigma_i, \\]
//!
//! by Levenberg–Marquardt (the `levenberg-marquardt` crate: MINPACK's `lmder`) with the
//! exact Jacobian \\(J = \partial r / \partial p\\) a [`Model`] supplies (from the
//! sensitivities). Positive parameters are fitted in log space (`x = ln p`), so a step
//! never makes them negative and stiffnesses spanning decades are scaled alike; bounds
//! `[lo, hi]` use the transform `x ↦ lo + (hi − lo)(1 + sin x)/2` (MINUIT's) on the
//! fitted variable. The variables are not rescaled (MINPACK's `diag`): in log space
//! they are already comparable, and the Jacobian's column norms (residuals in units of
//! σ: huge for precise data) made the first trust region so small that the first six
//! steps of a clamped cable's fit only doubled it; unscaled, Gauss–Newton's full step
//! is taken from the start (4–5 simulations to the optimum instead of 7–13).
//!
//! **Uncertainty.** At the optimum, with `m` residuals and `n` parameters, the
//! Gauss–Newton covariance scaled by the residual,
//!
//! \\[ C = s^2 (J^T J)^{-1}, \qquad s^2 = \frac{\sum_i r_i^2}{m - n}, \\]
//!
//! gives each parameter's standard deviation \\(\sqrt{C_{jj}}\\) and the correlations
//! \\(C_{jk} / \sqrt{C_{jj} C_{kk}}\\).
//!
//! **What the observations cannot separate.** The Jacobian in relative units
//! (\\(J_{ij} p_j\\), each column scaled to unit length) is decomposed into singular
//! values; a singular value below [`UNIDENTIFIABLE`] times the largest is a direction
//! of parameters the residuals do not see (a static catenary's shape sees `EA/μ` and
//! `EI/μ`, not `μ`: the direction `(1, 1, 1)` in `ln EA, ln EI, ln μ`). Its parameters
//! are reported as a group, with the direction, and their standard deviations are
//! infinite — not a number the fit made up.

use crate::Error;
use levenberg_marquardt::{LeastSquaresProblem, LevenbergMarquardt};
use lm_nalgebra::{DMatrix, DVector, Dyn, Owned};
use nalgebra::{DMatrix as Matrix, SVD};
use splinerod_core::Real;
use std::cell::RefCell;

/// Relative singular value below which a direction of parameters counts as not
/// determined by the observations.
pub const UNIDENTIFIABLE: Real = 1e-6;

/// The fit stops when a step changes the sum of squares, or the fitted variables, by a
/// relative amount below this (predicted and actual): far below any parameter's
/// statistical uncertainty, and above the round-off the minimiser would otherwise
/// keep probing (each probe a simulation).
pub const RELATIVE_TOLERANCE: Real = 1e-10;

/// What a fit adjusts: weighted residuals and their Jacobian at given parameters.
pub trait Model {
    /// Number of residuals.
    fn residual_count(&self) -> usize;
    /// Writes the residuals at parameters `p` into `residuals` and, if asked, their
    /// derivatives into `jacobian` (row-major: residual `i`, parameter `j` at
    /// `i · p.len() + j`). One call is one simulation.
    fn evaluate(
        &mut self,
        p: &[Real],
        residuals: &mut [Real],
        jacobian: Option<&mut [Real]>,
    ) -> Result<(), Error>;
}

/// How one parameter is fitted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParameterSpace {
    /// Fit `ln p` (the parameter must stay positive).
    pub log: bool,
    /// Bounds on the parameter (`lo < hi`, positive with `log`), if any.
    pub bounds: Option<(Real, Real)>,
}

/// A fit's outcome (the JSON of `splinerod fit`).
#[derive(Debug, Clone, serde::Serialize)]
pub struct FitReport {
    /// The fitted parameters.
    pub parameters: Vec<Real>,
    /// Their standard deviations (infinite for a parameter the observations cannot
    /// separate from others).
    pub std: Vec<Real>,
    /// Their correlation matrix, row by row.
    pub correlation: Vec<Vec<Real>>,
    /// Root mean square of the weighted residuals at the fit.
    pub residual_rms: Real,
    /// Jacobian evaluations (Levenberg–Marquardt iterations).
    pub iterations: usize,
    /// Model evaluations (simulations).
    pub simulations: usize,
    /// Whether the minimiser reported convergence.
    pub converged: bool,
    /// The residuals' root mean square after each simulation, in order (non-finite for
    /// a failed one).
    #[serde(skip)]
    pub history: Vec<Real>,
    /// Groups of parameters (indices) the observations cannot separate, each with the
    /// direction in the fitted variables (log for log-space parameters) they do not see.
    pub unidentifiable: Vec<(Vec<usize>, Vec<Real>)>,
}

/// The fitted variable `x` of parameter value `p`, and back.
impl ParameterSpace {
    /// The fitted variable of the parameter value `p`.
    pub(crate) fn variable(self, p: Real) -> Real {
        let v = if self.log { p.ln() } else { p };
        match self.bounds.map(|(lo, hi)| self.scaled(lo, hi)) {
            Some((lo, hi)) => (2.0 * (v - lo) / (hi - lo) - 1.0).clamp(-1.0, 1.0).asin(),
            None => v,
        }
    }

    /// The parameter values of the fitted variables `x`, each fitted as `spaces` says.
    pub(crate) fn parameters(spaces: &[Self], x: &[Real]) -> Vec<Real> {
        spaces.iter().zip(x).map(|(s, &x)| s.parameter(x)).collect()
    }

    /// The parameter value of the fitted variable `x`.
    pub(crate) fn parameter(self, x: Real) -> Real {
        let v = match self.bounds.map(|(lo, hi)| self.scaled(lo, hi)) {
            Some((lo, hi)) => lo + (hi - lo) * (1.0 + x.sin()) / 2.0,
            None => x,
        };
        if self.log {
            v.exp()
        } else {
            v
        }
    }

    /// `dp/dx` at the variable `x`.
    fn derivative(self, x: Real) -> Real {
        let p = self.parameter(x);
        let dv = match self.bounds.map(|(lo, hi)| self.scaled(lo, hi)) {
            Some((lo, hi)) => (hi - lo) * x.cos() / 2.0,
            None => 1.0,
        };
        if self.log {
            p * dv
        } else {
            dv
        }
    }

    fn scaled(self, lo: Real, hi: Real) -> (Real, Real) {
        if self.log {
            (lo.ln(), hi.ln())
        } else {
            (lo, hi)
        }
    }
}

/// Fits `model` from the parameters `start` (each fitted as `spaces` says), with at most
/// `max_simulations` model evaluations.
pub fn fit(
    model: &mut dyn Model,
    start: &[Real],
    spaces: &[ParameterSpace],
    max_simulations: usize,
) -> Result<FitReport, Error> {
    let n = start.len();
    let m = model.residual_count();
    if spaces.len() != n || m < n || n == 0 {
        let reason = format!("{m} residuals for {n} parameters: a fit needs at least as many");
        return Err(Error::field("observations", m, reason));
    }
    let x: Vec<Real> = spaces
        .iter()
        .zip(start)
        .map(|(s, &p)| s.variable(p))
        .collect();
    let mut problem = Problem {
        model: RefCell::new(model),
        spaces,
        basis: Matrix::identity(n, n),
        origin: x.clone(),
        z: DVector::zeros(n),
        cache: RefCell::new(Cache::default()),
    };
    problem.restrict_to_what_is_seen();
    let patience = max_simulations.div_ceil(n + 1).max(1);
    let (problem, report) = LevenbergMarquardt::new()
        .with_patience(patience)
        .with_scale_diag(false)
        .with_ftol(RELATIVE_TOLERANCE)
        .with_xtol(RELATIVE_TOLERANCE)
        .minimize(problem);
    let x = problem.variables();
    problem.evaluate(&x);
    let cache = problem.cache.into_inner();
    if let Some(e) = cache.error {
        return Err(e);
    }
    let parameters: Vec<Real> = spaces
        .iter()
        .zip(&x)
        .map(|(s, &x)| s.parameter(x))
        .collect();
    let uncertainty = Uncertainty::of(&cache.jacobian_p, &cache.residuals, &parameters);
    Ok(FitReport {
        residual_rms: (cache.residuals.iter().map(|r| r * r).sum::<Real>() / m as Real).sqrt(),
        parameters,
        std: uncertainty.std,
        correlation: uncertainty.correlation,
        iterations: cache.jacobians,
        simulations: cache.simulations,
        converged: report.termination.was_successful(),
        unidentifiable: uncertainty.unidentifiable,
        history: cache.history,
    })
}

impl FitReport {
    /// Simulations the fit made until its residuals' root mean square was first at most
    /// `rms`, if it ever was.
    pub fn simulations_to(&self, rms: Real) -> Option<usize> {
        self.history.iter().position(|&r| r <= rms).map(|k| k + 1)
    }
}

/// The last evaluation of the model.
#[derive(Default)]
struct Cache {
    x: Vec<Real>,
    residuals: Vec<Real>,
    /// The Jacobian in the parameters (row-major).
    jacobian_p: Vec<Real>,
    error: Option<Error>,
    simulations: usize,
    jacobians: usize,
    /// The residuals' root mean square after each simulation.
    history: Vec<Real>,
}

/// The model as `levenberg-marquardt` sees it: residuals and Jacobian in the fitted
/// variables `x = origin + basis · z`, one simulation per new point. The basis spans
/// the directions the observations see at the start (all of them, but for a model with
/// parameters they cannot separate): along the others the minimiser would wander
/// (a density-free cable fit drifted to EA = 1e79 along EA/μ = const), so they stay
/// where they started.
struct Problem<'a> {
    model: RefCell<&'a mut dyn Model>,
    spaces: &'a [ParameterSpace],
    basis: Matrix<Real>,
    origin: Vec<Real>,
    z: DVector<Real>,
    cache: RefCell<Cache>,
}

impl Problem<'_> {
    /// The fitted variables at the current `z`.
    fn variables(&self) -> Vec<Real> {
        let shift = &self.basis * nalgebra::DVector::from_column_slice(self.z.as_slice());
        self.origin
            .iter()
            .zip(shift.iter())
            .map(|(o, s)| o + s)
            .collect()
    }

    /// `dp/dx` of each parameter at the variables `x`.
    fn chain(&self, x: &[Real]) -> Vec<Real> {
        self.spaces
            .iter()
            .zip(x)
            .map(|(s, &x)| s.derivative(x))
            .collect()
    }

    /// Sets the basis to the directions the observations see at the origin (singular
    /// values of the column-scaled Jacobian above [`UNIDENTIFIABLE`] of the largest).
    fn restrict_to_what_is_seen(&mut self) {
        let x = self.origin.clone();
        self.evaluate(&x);
        let cache = self.cache.borrow();
        let (n, m) = (x.len(), cache.residuals.len());
        if cache.error.is_some() {
            return;
        }
        let chain = self.chain(&x);
        let j = Matrix::from_fn(m, n, |i, k| cache.jacobian_p[i * n + k] * chain[k]);
        let norms: Vec<Real> = j
            .column_iter()
            .map(|c| c.norm().max(Real::MIN_POSITIVE))
            .collect();
        let scaled = Matrix::from_fn(m, n, |i, k| j[(i, k)] / norms[k]);
        let svd = SVD::new(scaled, false, true);
        let (Some(v_t), largest) = (svd.v_t, svd.singular_values.max()) else {
            return;
        };
        let seen: Vec<usize> = (0..n)
            .filter(|&k| svd.singular_values[k] > UNIDENTIFIABLE * largest)
            .collect();
        if seen.len() == n {
            return;
        }
        let basis = Matrix::from_fn(n, seen.len(), |i, c| v_t[(seen[c], i)] / norms[i]);
        drop(cache);
        self.z = DVector::zeros(seen.len());
        self.basis = basis;
    }

    /// Evaluates the model at variables `x` unless it was the last point evaluated; a
    /// failed simulation leaves non-finite residuals (a step the minimiser rejects).
    fn evaluate(&self, x: &[Real]) {
        let mut cache = self.cache.borrow_mut();
        if cache.simulations > 0 && cache.x == x {
            return;
        }
        let p = ParameterSpace::parameters(self.spaces, x);
        let mut model = self.model.borrow_mut();
        let m = model.residual_count();
        let mut residuals = vec![0.0; m];
        let mut jacobian = vec![0.0; m * x.len()];
        cache.simulations += 1;
        cache.x = x.to_vec();
        cache.error = model
            .evaluate(&p, &mut residuals, Some(&mut jacobian))
            .err();
        if cache.error.is_some() {
            residuals.fill(Real::NAN);
        }
        let rms = (residuals.iter().map(|r| r * r).sum::<Real>() / m as Real).sqrt();
        cache.history.push(rms);
        (cache.residuals, cache.jacobian_p) = (residuals, jacobian);
    }
}

impl LeastSquaresProblem<Real, Dyn, Dyn> for Problem<'_> {
    type ResidualStorage = Owned<Real, Dyn>;
    type JacobianStorage = Owned<Real, Dyn, Dyn>;
    type ParameterStorage = Owned<Real, Dyn>;

    fn set_params(&mut self, z: &DVector<Real>) {
        self.z.copy_from(z);
    }

    fn params(&self) -> DVector<Real> {
        self.z.clone()
    }

    fn residuals(&self) -> Option<DVector<Real>> {
        self.evaluate(&self.variables());
        Some(DVector::from_vec(self.cache.borrow().residuals.clone()))
    }

    fn jacobian(&self) -> Option<DMatrix<Real>> {
        let x = self.variables();
        self.evaluate(&x);
        let mut cache = self.cache.borrow_mut();
        cache.jacobians += 1;
        let (n, r) = (x.len(), self.z.len());
        let m = cache.residuals.len();
        let chain = self.chain(&x);
        let j = &cache.jacobian_p;
        let basis = &self.basis;
        Some(DMatrix::from_fn(m, r, |i, c| {
            (0..n)
                .map(|k| j[i * n + k] * chain[k] * basis[(k, c)])
                .sum()
        }))
    }
}

/// Standard deviations, correlations and unidentifiable groups at the optimum.
struct Uncertainty {
    std: Vec<Real>,
    correlation: Vec<Vec<Real>>,
    unidentifiable: Vec<(Vec<usize>, Vec<Real>)>,
}

impl Uncertainty {
    /// From the Jacobian `j` in the parameters (row-major), the residuals `r` and the
    /// parameters `p` (see the module docs).
    fn of(j: &[Real], r: &[Real], p: &[Real]) -> Self {
        let (m, n) = (r.len(), p.len());
        let s2 = r.iter().map(|x| x * x).sum::<Real>() / (m - n).max(1) as Real;
        // Columns in relative units, scaled to unit length: z_k = p_k / (scale_k).
        let relative = |k: usize| if p[k] != 0.0 { p[k].abs() } else { 1.0 };
        let mut a = Matrix::from_fn(m, n, |i, k| j[i * n + k] * relative(k));
        let norms: Vec<Real> = a.column_iter().map(|c| c.norm()).collect();
        for (k, &c) in norms.iter().enumerate() {
            a.column_mut(k)
                .scale_mut(if c > 0.0 { 1.0 / c } else { 0.0 });
        }
        let svd = SVD::new(a, false, true);
        let v_t = svd.v_t.expect("V asked for");
        let largest = svd.singular_values.max();
        let mut hidden = vec![false; n];
        let mut unidentifiable = Vec::new();
        // Covariance of the scaled variables: s² V Σ⁻² Vᵀ over the determined directions.
        let mut cov = Matrix::zeros(n, n);
        for (k, &sigma) in svd.singular_values.iter().enumerate() {
            let v = v_t.row(k).transpose();
            if sigma.is_nan() || sigma <= UNIDENTIFIABLE * largest {
                let direction: Vec<Real> = (0..n)
                    .map(|i| v[i] / norms[i].max(Real::MIN_POSITIVE))
                    .collect();
                let size = direction.iter().map(|d| d * d).sum::<Real>().sqrt();
                let direction: Vec<Real> = direction.iter().map(|d| d / size).collect();
                let group: Vec<usize> = (0..n).filter(|&i| direction[i].abs() > 0.1).collect();
                group.iter().for_each(|&i| hidden[i] = true);
                unidentifiable.push((group, direction));
                continue;
            }
            cov += (&v * v.transpose()) * (s2 / (sigma * sigma));
        }
        let scale: Vec<Real> = (0..n).map(|k| relative(k) / norms[k]).collect();
        let std: Vec<Real> = (0..n)
            .map(|k| {
                if hidden[k] {
                    Real::INFINITY
                } else {
                    cov[(k, k)].sqrt() * scale[k]
                }
            })
            .collect();
        let correlation = (0..n)
            .map(|a| {
                (0..n)
                    .map(|b| match hidden[a] || hidden[b] {
                        true => Real::NAN,
                        false => cov[(a, b)] / (cov[(a, a)] * cov[(b, b)]).sqrt(),
                    })
                    .collect()
            })
            .collect();
        Self {
            std,
            correlation,
            unidentifiable,
        }
    }
}
