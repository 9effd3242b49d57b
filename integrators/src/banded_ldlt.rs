//! Block \\(U^T D U\\) factorisation of a symmetric, possibly *indefinite*, 3×3-block
//! banded matrix ([`BlockBanded`]): `U` unit upper block-banded with the matrix's
//! bandwidth, `D` block diagonal with symmetric 3×3 blocks,
//!
//! \\[ D_i = A_{ii} - \sum_{k<i} U_{ki}^T V_{ki}, \qquad
//! V_{ij} = A_{ij} - \sum_{k<i} U_{ki}^T V_{kj}, \qquad U_{ij} = D_i^{-1} V_{ij}
//! \quad (i < j \le i + b), \\]
//!
//! with \\(V_{ij} = D_i U_{ij}\\) kept to halve the work; solved by \\(U^T y = r\\),
//! \\(z_i = D_i^{-1} y_i\\), \\(U x = z\\). No pivoting: the 3×3 pivot blocks are inverted
//! whole, which is stable as long as none is nearly singular — the factorisation refuses
//! a pivot block whose reciprocal condition number is below [`MIN_PIVOT_RCOND`]. Newton
//! uses it for the exact Hessian of a rod under compression, where Cholesky fails but
//! the exact step (quadratic convergence, also to a saddle of the merit such as a planar
//! state that could buckle out of plane) is still wanted; see [`crate::newton`].

use crate::banded_cholesky::{band_shape, for_each_rhs, get3, reset_blocks, set3};
use crate::IntegratorError;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, Real};

/// Smallest accepted \\(1 / (\lVert D_i\rVert_\infty \lVert D_i^{-1}\rVert_\infty)\\) of a
/// pivot block.
pub const MIN_PIVOT_RCOND: Real = 1e-12;

/// The factors `U`, `V = D U` and \\(D^{-1}\\) of a block-banded symmetric matrix.
#[derive(Debug, Clone, Default)]
pub struct BandedLdlt {
    n: usize,
    bw: usize,
    /// `U_{i,i+k}` at `i·(bw+1) + k` (`k ≥ 1`; the unit diagonal is not stored).
    u: Vec<Matrix3<Real>>,
    /// `V_{i,i+k} = D_i U_{i,i+k}`, same layout.
    v: Vec<Matrix3<Real>>,
    /// \\(D_i^{-1}\\).
    d_inv: Vec<Matrix3<Real>>,
    factored: bool,
}

fn singular() -> IntegratorError {
    IntegratorError::NotPositiveDefinite {
        context: "banded LDLT: nearly singular pivot",
    }
}

/// ∞-norm of a 3×3 matrix.
fn norm_inf(m: &Matrix3<Real>) -> Real {
    (0..3)
        .map(|r| m.row(r).iter().map(|x| x.abs()).sum::<Real>())
        .fold(0.0, Real::max)
}

impl BandedLdlt {
    /// An empty factor.
    pub fn new() -> Self {
        Self::default()
    }

    /// Factorises `a` (reusing the storage). Errors if `a` has far blocks or a pivot
    /// block is nearly singular.
    pub fn factor(&mut self, a: &BlockBanded) -> Result<(), IntegratorError> {
        self.factored = false;
        let (n, bw) = band_shape(a)?;
        let w = bw + 1;
        (self.n, self.bw) = (n, bw);
        reset_blocks(&mut self.u, n * w);
        reset_blocks(&mut self.v, n * w);
        reset_blocks(&mut self.d_inv, n);
        for i in 0..n {
            let mut d = *a.upper(i, 0);
            for k in i.saturating_sub(bw)..i {
                d -= self.u[k * w + (i - k)].tr_mul(&self.v[k * w + (i - k)]);
            }
            let d = 0.5 * (d + d.transpose());
            let d_inv = d.try_inverse().ok_or_else(singular)?;
            let rcond = 1.0 / (norm_inf(&d) * norm_inf(&d_inv));
            if rcond.is_nan() || rcond < MIN_PIVOT_RCOND {
                return Err(singular());
            }
            self.d_inv[i] = d_inv;
            for j in i + 1..(i + w).min(n) {
                let mut m = *a.upper(i, j - i);
                for k in j.saturating_sub(bw)..i {
                    m -= self.u[k * w + (i - k)].tr_mul(&self.v[k * w + (j - k)]);
                }
                self.v[i * w + (j - i)] = m;
                self.u[i * w + (j - i)] = d_inv * m;
            }
        }
        self.factored = true;
        Ok(())
    }

    /// Solves `A x = b` in place for `k = rhs.len() / (3n)` right-hand sides stored
    /// column after column.
    pub fn solve_in_place(&self, rhs: &mut [Real]) -> Result<(), IntegratorError> {
        for_each_rhs(self.factored, self.n, rhs, |column| self.solve_one(column))
    }

    /// A direction `d` of negative curvature, \\(d^T A d < 0\\), if `A` is indefinite:
    /// with `w` the eigenvector of the most negative eigenvalue `e` among the pivot
    /// blocks \\(D_i\\), \\(U d = e_i \otimes w\\) gives \\(d^T A d = e\\) (Sylvester: `A` and
    /// `D` have the same inertia). `None` when `A` is positive definite.
    pub fn negative_curvature(&self, d: &mut [Vector3<Real>]) -> Option<Real> {
        if !self.factored || d.len() != self.n {
            return None;
        }
        let mut best: Option<(usize, Real, Vector3<Real>)> = None;
        for (i, inv) in self.d_inv.iter().enumerate() {
            let eig = (0.5 * (inv + inv.transpose())).symmetric_eigen();
            for k in 0..3 {
                // An eigenvalue ν of D⁻¹ is 1/e for the eigenvalue e of D.
                let e = 1.0 / eig.eigenvalues[k];
                if e < 0.0 && best.is_none_or(|(_, b, _)| e < b) {
                    best = Some((i, e, eig.eigenvectors.column(k).into_owned()));
                }
            }
        }
        let (i, e, w) = best?;
        d.iter_mut().for_each(|v| *v = Vector3::zeros());
        d[i] = w;
        let w = self.bw + 1;
        for r in (0..i).rev() {
            let mut v = d[r];
            for j in r + 1..(r + w).min(self.n) {
                v -= self.u[r * w + (j - r)] * d[j];
            }
            d[r] = v;
        }
        Some(e)
    }

    fn solve_one(&self, x: &mut [Real]) {
        let (n, bw, w) = (self.n, self.bw, self.bw + 1);
        for i in 0..n {
            let mut r = get3(x, i);
            for k in i.saturating_sub(bw)..i {
                r -= self.u[k * w + (i - k)].tr_mul(&get3(x, k));
            }
            set3(x, i, r);
        }
        for i in 0..n {
            set3(x, i, self.d_inv[i] * get3(x, i));
        }
        for i in (0..n).rev() {
            let mut r = get3(x, i);
            for j in i + 1..(i + w).min(n) {
                r -= self.u[i * w + (j - i)] * get3(x, j);
            }
            set3(x, i, r);
        }
    }
}
