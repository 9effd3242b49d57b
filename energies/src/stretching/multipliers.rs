//! The inextensible rod: the mixed form's constraints \\(b_k = 0\\) held by an augmented
//! Lagrangian with multipliers \\(\hat\lambda_k\\) on the same tension space,
//!
//! \\[ E = \sum_k \hat\lambda_k b_k + \frac{\rho}{2} \frac{b_k^2}{m_k}, \qquad
//! \lambda_k = \hat\lambda_k + \rho\, \frac{b_k}{m_k}, \\]
//!
//! so the energy's tension is \\(\lambda_k\\) and its derivatives are the mixed form's
//! with that tension. [`Multipliers::update`] is the method-of-multipliers step
//! \\(\hat\lambda_k \leftarrow \lambda_k\\): a static solve repeated with updated
//! multipliers converges to \\(b_k = 0\\) (every tension function's mean strain to
//! round-off), and in time stepping with a dissipative scheme one update per step keeps
//! the mean strain at the step's tension change over ρ. (The facade skips the updates
//! under the energy-conserving midpoint rule: each update moves the energy's minimum,
//! and a scheme that does not dissipate would keep the axial ringing it starts; the
//! penalty alone then holds the mean strain at T/ρ.) The penalty ρ only sets how fast: it starts at
//! \\(10^6 \mu g_0 L\\) (\\(g_0\\) = 9.81 m/s², a stiffness far above the rod's weight,
//! far below round-off trouble) and, between repeated static solves, grows tenfold (up
//! to \\(10^6\\) times) whenever an update fails to cut the violation by four; time steps
//! keep it fixed.
//!
//! After a change of knots the multiplier field \\(\hat T(s) = \sum_k \hat\lambda_k
//! \varphi_k(s)\\) is projected onto the new tension functions (lumped, as the tension
//! itself): \\(\hat\lambda'_k = \int \varphi'_k \hat T\, dl_0 / m'_k\\). The next
//! updates restore \\(b_k = 0\\) on the new space.

use splinerod_core::bspline::bspline_values;
use splinerod_core::{CoreError, Real, Rod, SavedState, StateReader};

/// Standard gravity, m/s²: the penalty's scale.
const G0: Real = 9.81;

/// Growth of the penalty when an update does not cut the violation by four, and the
/// largest growth allowed.
const GROWTH: Real = 10.0;
const MAX_GROWTH: Real = 1e6;

/// Multipliers of the inextensibility constraints and the penalty.
#[derive(Debug, Clone, PartialEq)]
pub struct Multipliers {
    /// \\(\hat\lambda_j\\), N, indexed by tension function `j` (`0 ..= n`).
    pub values: Vec<Real>,
    /// The knot vector they are defined on.
    knots: Vec<Real>,
    /// Penalty ρ, N.
    pub penalty: Real,
    /// The first penalty, N.
    initial: Real,
    /// Violation at the last update (largest |b_k/m_k|).
    last: Real,
}

impl Multipliers {
    /// Zero multipliers for `rod`, penalty \\(10^6 \mu g_0 L\\).
    pub fn new(rod: &Rod) -> Self {
        let m = rod.material();
        let penalty = 1e6 * m.linear_density * G0 * m.rest_length;
        Self {
            values: vec![0.0; rod.len() + 1],
            knots: rod.basis().knots().to_vec(),
            penalty,
            initial: penalty,
            last: Real::INFINITY,
        }
    }

    /// Method-of-multipliers step (with `stiffen`, also the penalty growth) from the
    /// current tension coefficients
    /// \\(\\lambda_j = \\hat\\lambda_j + \\rho\\, b_j/m_j\\); returns the violation before it,
    /// the largest mean strain |b_j/m_j|.
    pub fn update(&mut self, tensions: &[(Real, Real)], stiffen: bool) -> Real {
        let mut violation: Real = 0.0;
        for (value, (lambda, _)) in self.values.iter_mut().zip(tensions) {
            violation = violation.max(((lambda - *value) / self.penalty).abs());
            *value = *lambda;
        }
        if stiffen && violation > 0.25 * self.last && self.penalty < MAX_GROWTH * self.initial {
            self.penalty *= GROWTH;
        }
        self.last = violation;
        violation
    }

    /// Appends the multipliers, penalty and last violation (checkpoints).
    pub fn save(&self, out: &mut SavedState) {
        out.reals(&self.values);
        out.reals(&self.knots);
        out.real(self.penalty);
        out.real(self.last);
    }

    /// Reads back what [`save`](Self::save) wrote.
    pub fn load(&mut self, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        input.reals_into(&mut self.values)?;
        input.reals_into(&mut self.knots)?;
        self.penalty = input.real()?;
        self.last = input.real()?;
        Ok(())
    }

    /// Re-projects the multiplier field onto `rod`'s new tension space.
    pub fn remap(&mut self, rod: &Rod, g0: impl Fn(usize) -> Real) {
        let d = rod.basis().degree();
        let old = std::mem::take(&mut self.knots);
        let mut acc = vec![(0.0, 0.0); rod.len() + 1];
        let table = rod.quadrature();
        for p in 0..table.len() {
            let qp = table.point(p);
            let field = field_at(&old, &self.values, d, qp.s);
            let w = qp.weight * g0(p).sqrt();
            for (a, &phi) in acc[qp.first + 1..].iter_mut().zip(qp.lower) {
                a.0 += phi * w * field;
                a.1 += phi * w;
            }
        }
        self.values = acc
            .iter()
            .map(|&(num, den)| if den > 0.0 { num / den } else { 0.0 })
            .collect();
        self.knots = rod.basis().knots().to_vec();
        self.last = Real::INFINITY;
    }
}

/// \\(\hat T(s) = \sum_j \hat\lambda_j \varphi_j(s)\\) on the knot vector `knots` (degree `d`
/// positions, so degree `d − 1` tension functions).
fn field_at(knots: &[Real], values: &[Real], d: usize, s: Real) -> Real {
    let n = knots.len() - d - 1;
    // The non-empty span containing s, clamped to the domain [t_d, t_n).
    let span = (d + knots[d + 1..n].partition_point(|&t| t <= s)).min(n - 1);
    let phi = bspline_values(knots, d - 1, span, s);
    (0..d)
        .map(|k| values.get(span + 1 + k - d).copied().unwrap_or(0.0) * phi[k])
        .sum()
}
