//! Low-rank terms of a Newton matrix by the Sherman–Morrison formula.
//!
//! A [`BlockBanded`] matrix may carry terms \\(c_i u_i u_i^T\\) that couple every control
//! point with every other ([`splinerod_core::LowRank`]: the twist of a rod between two
//! clamps). Only the band `A₀` is factorised; with \\(A_{i+1} = A_i + c_i u_i u_i^T\\),
//!
//! \\[ A_{i+1}^{-1} b = A_i^{-1} b - z_i\, \gamma_i\, u_i^T A_i^{-1} b, \qquad
//!     z_i = A_i^{-1} u_i, \quad \gamma_i = \frac{c_i}{1 + c_i\, u_i^T z_i}, \\]
//!
//! so each term costs one extra solve per factorisation and two dot products per solve:
//! O(n), no dense matrix.

use crate::IntegratorError;
use splinerod_core::{BlockBanded, Real};

/// One prepared term: `u` (flat), \\(z = A_i^{-1} u\\) and γ.
#[derive(Debug, Default, Clone)]
struct Term {
    u: Vec<Real>,
    z: Vec<Real>,
    gamma: Real,
}

/// The prepared Sherman–Morrison corrections of the last factorisation.
#[derive(Debug, Default, Clone)]
pub(crate) struct LowRankCorrections {
    terms: Vec<Term>,
    used: usize,
}

impl LowRankCorrections {
    /// Forgets the terms (keeps the storage).
    pub fn clear(&mut self) {
        self.used = 0;
    }

    /// Prepares the terms of `a`, given `solve` with the band's factorisation `A₀`.
    pub fn prepare(
        &mut self,
        a: &BlockBanded,
        mut solve: impl FnMut(&mut [Real]) -> Result<(), IntegratorError>,
    ) -> Result<(), IntegratorError> {
        self.used = 0;
        for source in a.low_rank() {
            if self.used == self.terms.len() {
                self.terms.push(Term::default());
            }
            let term = &mut self.terms[self.used];
            term.u.clear();
            term.u
                .extend(source.vector.iter().flat_map(|v| v.iter().copied()));
            term.z.clear();
            term.z.extend_from_slice(&term.u);
            solve(&mut term.z)?;
            let (done, rest) = self.terms.split_at_mut(self.used);
            let term = &mut rest[0];
            apply_terms(done, &mut term.z);
            let denominator = 1.0 + source.coefficient * dot(&term.u, &term.z);
            if !(denominator.is_finite() && denominator > 0.0) {
                return Err(IntegratorError::NotPositiveDefinite {
                    context: "low-rank term (Sherman–Morrison)",
                });
            }
            term.gamma = source.coefficient / denominator;
            self.used += 1;
        }
        Ok(())
    }

    /// Turns \\(A_0^{-1} b\\) into \\(A^{-1} b\\) for every column of `x` (columns of the
    /// terms' length, stored one after another).
    pub fn apply(&self, x: &mut [Real]) {
        let terms = &self.terms[..self.used];
        let Some(first) = terms.first() else {
            return;
        };
        for column in x.chunks_mut(first.u.len()) {
            apply_terms(terms, column);
        }
    }
}

fn apply_terms(terms: &[Term], x: &mut [Real]) {
    for t in terms {
        let s = t.gamma * dot(&t.u, x);
        x.iter_mut().zip(&t.z).for_each(|(x, z)| *x -= z * s);
    }
}

fn dot(a: &[Real], b: &[Real]) -> Real {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

#[cfg(test)]
mod tests {
    use crate::linear::{LinearSolver, LinearSolverKind};
    use nalgebra::{DVector, Matrix3, Vector3};
    use splinerod_core::{BlockBanded, Real};

    /// A banded SPD chain plus two rank-one terms (and a far block if `far`).
    fn matrix(n: usize, far: bool) -> BlockBanded {
        let mut a = BlockBanded::zeros(n, 3);
        for i in 0..n {
            a.add_block(i, i, &(Matrix3::identity() * 4.0));
            if i + 1 < n {
                a.add_block(i, i + 1, &(Matrix3::identity() * -1.0));
            }
        }
        if far {
            a.add_coupling(1, n - 2, &(Matrix3::identity() * 0.5));
            a.add_coupling(1, 1, &(Matrix3::identity() * 0.5));
            a.add_coupling(n - 2, n - 2, &(Matrix3::identity() * 0.5));
        }
        let u: Vec<Vector3<Real>> = (0..n)
            .map(|i| Vector3::new((i as Real).sin(), 1.0, (i as Real * 0.3).cos()))
            .collect();
        let v: Vec<Vector3<Real>> = (0..n).map(|i| Vector3::new(0.0, i as Real, -1.0)).collect();
        a.add_low_rank(2.5, &u);
        a.add_low_rank(0.7, &v);
        a
    }

    #[test]
    fn solves_with_low_rank_terms_match_the_dense_solve() {
        for (kind, far) in [
            (LinearSolverKind::Banded, false),
            (LinearSolverKind::Sparse, false),
            (LinearSolverKind::Banded, true),
        ] {
            let n = 12;
            let a = matrix(n, far);
            let mut solver = LinearSolver::new(kind);
            solver.factor(&a, 1).unwrap();
            let b: Vec<Real> = (0..6 * n).map(|i| (i % 7) as Real - 3.0).collect();
            let mut x = b.clone();
            solver.solve_in_place(&mut x).unwrap();
            let dense = a.to_dense();
            for (column, solved) in b.chunks(3 * n).zip(x.chunks(3 * n)) {
                let exact = dense
                    .clone()
                    .cholesky()
                    .unwrap()
                    .solve(&DVector::from_column_slice(column));
                let error = (DVector::from_column_slice(solved) - &exact).norm() / exact.norm();
                assert!(error < 1e-12, "{kind:?}, far {far}: {error:e}");
            }
            // The indefinite factorisation takes the same path.
            if !far {
                solver.factor_indefinite(&a).unwrap();
                let mut y = b[..3 * n].to_vec();
                solver.solve_in_place(&mut y).unwrap();
                let exact = dense
                    .cholesky()
                    .unwrap()
                    .solve(&DVector::from_column_slice(&b[..3 * n]));
                assert!((DVector::from(y) - &exact).norm() < 1e-12 * exact.norm());
            }
        }
    }
}
