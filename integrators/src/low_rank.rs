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
