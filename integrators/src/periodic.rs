//! Closed rods: the Newton system folded onto the distinct control points.
//!
//! A closed rod ([`splinerod_core::PeriodicBSplineSpace`]) has `N = m + d` control
//! points of which the last `d` copy the first: \\(q = T z\\) with `z` the `m` distinct
//! ones and \\(T_{i,\,i \bmod m} = 1\\). A Newton step that keeps the copies equal solves
//! the folded system
//!
//! \\[ (T^T A T)\, \Delta z = T^T b, \qquad \Delta q = T\, \Delta z, \\]
//!
//! so the solver applies \\(P = T (T^T A T)^{-1} T^T\\) wherever it applied \\(A^{-1}\\):
//! pins (the Schur complement on their rows), the remainder's conjugate gradients and
//! every other user see the same interface, and their results stay on the tied subspace.
//! Folding maps block `(i, j)` to `(i mod m, j mod m)`: the band stays a band, and the
//! couplings across the seam become far blocks, which the sparse factorisation orders
//! (still O(m) fill: a cycle). Allocation-free once sized.

use crate::linear::LinearSolver;
use crate::IntegratorError;
use nalgebra::Matrix3;
use splinerod_core::{BlockBanded, Real};

/// The folded matrix's solver and the scratch for folded right-hand sides.
#[derive(Debug, Default)]
pub(crate) struct Folded {
    /// Solver of \\(T^T A T\\) (its own matrix holds the folded one).
    pub solver: LinearSolver,
    rhs: Vec<Real>,
}

impl Folded {
    /// Folds `a` (size `N`) onto `m` control points into the inner solver's matrix and
    /// factorises it.
    pub fn factor(&mut self, a: &BlockBanded, m: usize, epoch: u64) -> Result<(), IntegratorError> {
        fold_matrix(a, m, self.solver.matrix_mut());
        self.solver.factor_assembled(epoch)
    }

    /// Replaces each column of `rhs` (length `3N`) by \\(P\\,\\) column.
    pub fn solve_in_place(
        &mut self,
        rhs: &mut [Real],
        n: usize,
        m: usize,
    ) -> Result<(), IntegratorError> {
        let (full, folded) = (3 * n, 3 * m);
        if full == 0 || rhs.len() % full != 0 {
            return Err(IntegratorError::SolverState(
                "solve before a successful factor",
            ));
        }
        let columns = rhs.len() / full;
        self.rhs.clear();
        self.rhs.resize(columns * folded, 0.0);
        for (column, out) in rhs
            .chunks_exact(full)
            .zip(self.rhs.chunks_exact_mut(folded))
        {
            out.copy_from_slice(&column[..folded]);
            for (o, c) in out.iter_mut().zip(&column[folded..]) {
                *o += c;
            }
        }
        self.solver.solve_in_place(&mut self.rhs)?;
        for (column, solved) in rhs
            .chunks_exact_mut(full)
            .zip(self.rhs.chunks_exact(folded))
        {
            column[..folded].copy_from_slice(solved);
            let copies = full - folded;
            column[folded..].copy_from_slice(&solved[..copies]);
        }
        Ok(())
    }
}

/// Writes \\(T^T A T\\) into `out` (band, far blocks and low-rank terms of `a`).
pub(crate) fn fold_matrix(a: &BlockBanded, m: usize, out: &mut BlockBanded) {
    let (n, bw) = (a.dim(), a.bandwidth());
    out.reset(m, bw.min(m - 1));
    let mut add = |i: usize, j: usize, b: &Matrix3<Real>| {
        let (p, q) = (i % m, j % m);
        if p == q && i != j {
            out.add_block(p, p, &(b + b.transpose()));
        } else {
            out.add_coupling(p, q, b);
        }
    };
    for i in 0..n {
        for k in 0..=bw.min(n - 1 - i) {
            add(i, i + k, a.upper(i, k));
        }
    }
    for far in a.far_blocks() {
        add(far.row, far.col, &far.block);
    }
    for term in a.low_rank() {
        out.add_low_rank_with(term.coefficient, |u| {
            for (i, v) in term.vector.iter().enumerate() {
                u[i % m] += v;
            }
        });
    }
}
