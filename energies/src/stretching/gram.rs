//! The consistent Gram matrix of the tension functions, which turns the strain moments
//! into the tension coefficients of the mixed form ([`super::mixed`]):
//!
//! \\[ G_{jk} = \int \varphi_j\, \varphi_k\, dl_0, \qquad
//! \lambda = EA\, G^{-1} b, \qquad E = \tfrac{EA}{2}\, b^T G^{-1} b
//! = \tfrac{EA}{2} \int (\Pi \varepsilon)^2\, dl_0, \\]
//!
//! with \\(\Pi\\) the \\(L^2(dl_0)\\) projection onto the tension space. `G` is symmetric
//! positive definite and banded: functions of degree `d − 1` overlap with `d − 1`
//! neighbours on each side. It depends only on the basis, the quadrature and the rest
//! metric, so it is built and factorised (banded Cholesky, `G = UᵀU`) once per basis,
//! alongside [`super::table`]; a rod it does not match gets one built on the fly.
//!
//! Its row sums are the lumped weights \\(m_j = \int \varphi_j\, dl_0\\) (the functions
//! sum to one), and since its entries are non-negative, \\(\mathrm{diag}(m) - G\\) is
//! diagonally dominant: \\(G \preceq \mathrm{diag}(m)\\), so
//! \\(G^{-1} \succeq \mathrm{diag}(m)^{-1}\\). The lumped material stiffness is therefore a
//! lower bound of the consistent one, which is what makes it a preconditioner for the
//! Hessian's remainder (see [`crate::Energy::add_hessian_remainder`]).

use super::Stretching;
use splinerod_core::{Real, Rod};

/// The banded Gram matrix of the tension functions `1 ..= n − 1` and its Cholesky factor.
#[derive(Debug, Clone, Default)]
pub(super) struct TensionGram {
    /// Topology epoch and quadrature point count of the rod it was built for.
    built_for: Option<(u64, usize)>,
    /// Entries per row: the diagonal and `d − 1` neighbours to the right.
    width: usize,
    /// Row `i` (function `i + 1`): `U_{i,i+o}` at `i·width + o` once factorised.
    u: Vec<Real>,
}

impl TensionGram {
    /// Whether it was built for `rod`'s current basis and quadrature.
    #[inline]
    pub fn matches(&self, rod: &Rod) -> bool {
        self.built_for == Some((rod.topology_epoch(), rod.quadrature().len()))
    }

    /// Builds and factorises `G` for `rod` with the rest metric of `energy`. Functions
    /// with an empty support (inside a cut) get a unit diagonal: their moment is zero,
    /// and so is their tension.
    pub fn build(&mut self, energy: &Stretching, rod: &Rod) {
        let d = rod.basis().degree();
        let functions = rod.len().saturating_sub(1);
        self.width = d.max(1);
        self.u.clear();
        self.u.resize(functions * self.width, 0.0);
        let table = rod.quadrature();
        for p in 0..table.len() {
            let qp = table.point(p);
            let root = energy.root_g0(p);
            // lower[k] is function first + 1 + k, stored at row first + k.
            for (k, &phi) in qp.lower.iter().enumerate() {
                let row = qp.first + k;
                if row >= functions {
                    break;
                }
                let w = qp.weight * root * phi;
                let entries = &mut self.u[row * self.width..(row + 1) * self.width];
                for (o, &other) in qp.lower[k..].iter().enumerate() {
                    if row + o < functions {
                        entries[o] += w * other;
                    }
                }
            }
        }
        self.factor();
        self.built_for = Some((rod.topology_epoch(), table.len()));
    }

    /// In-place banded Cholesky `G = UᵀU` (upper rows). `G` is a Gram matrix of
    /// linearly independent functions, so its pivots are positive; a non-positive one
    /// (a degenerate quadrature) is replaced by the unit pivot of a decoupled function.
    fn factor(&mut self) {
        let (w, n) = (self.width, self.u.len() / self.width.max(1));
        for i in 0..n {
            let mut pivot = self.u[i * w];
            if pivot.is_nan() || pivot <= 0.0 {
                self.u[i * w + 1..(i + 1) * w]
                    .iter_mut()
                    .for_each(|x| *x = 0.0);
                pivot = 1.0;
            }
            let pivot = pivot.sqrt();
            self.u[i * w] = pivot;
            for o in 1..w.min(n - i) {
                self.u[i * w + o] /= pivot;
            }
            // Update the trailing rows i + a (a ≥ 1) with row i's entries.
            for a in 1..w.min(n - i) {
                let ua = self.u[i * w + a];
                for b in a..w.min(n - i) {
                    self.u[(i + a) * w + (b - a)] -= ua * self.u[i * w + b];
                }
            }
        }
    }

    /// Solves \\(G x = r\\) in place, with `r[j]` the entry of function `j` (`j = 0 ..= n`;
    /// entries `0` and `n` are not tension functions and are left alone).
    pub fn solve(&self, r: &mut [Real]) {
        let w = self.width.max(1);
        let n = self.u.len() / w;
        let x = &mut r[1..=n];
        // Uᵀ y = r, row by row of U.
        for (i, row) in self.u.chunks_exact(w).enumerate() {
            let yi = x[i] / row[0];
            x[i] = yi;
            for (x, &u) in x[i + 1..].iter_mut().zip(&row[1..]) {
                *x -= u * yi;
            }
        }
        // U x = y.
        for (i, row) in self.u.chunks_exact(w).enumerate().rev() {
            let (head, tail) = x[i..].split_at_mut(1);
            let s: Real = tail.iter().zip(&row[1..]).map(|(x, &u)| u * x).sum();
            head[0] = (head[0] - s) / row[0];
        }
    }
}
