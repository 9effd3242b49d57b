//! The global sparse solve, and the [`LinearSolver`] that picks a factorisation: the
//! [`crate::BandedCholesky`] for a band, the block sparse
//! [`BlockSparseCholesky`](crate::block_sparse::BlockSparseCholesky) for a matrix with far
//! blocks (self-contact). [`SparseCholesky`], faer's scalar simplicial Cholesky of the
//! same matrices, is kept as the reference the block one is tested against; on
//! `knot_tying_adaptive.toml` (up to 40 control points) the block one factorises about
//! 3.9 times faster with the same ordering rule (callgrind, symbolic analyses included:
//! 372 000 instructions per factorisation over 1 919 factorisations, against 95 000 over
//! 1 443).
//!
//! **[`SparseCholesky`].** The pattern is the full block band plus the far blocks
//! (self-contact couplings), laid out by `block_pattern`. The natural ordering is optimal for a band (faer's AMD finds
//! the same fill at 10–35 % more cost per factorisation), and stays the choice while
//! the far blocks enlarge the pattern's envelope — which the natural-order factor fills
//! — by at most [`NATURAL_FILL_LIMIT`]: couplings between nearby control points. Far
//! blocks joining distant parts of the rod close a long loop, whose natural-order fill
//! spans everything between them; faer's AMD ordering is used then (it about doubles the
//! band's fill along the loop, the least a loop allows). The symbolic analysis is redone
//! only when the rod's topology epoch, the size, the bandwidth or the set of far block
//! positions changes (duplicates and their order do not count); each Newton iteration
//! writes the values straight into the CSC array and runs the numeric factorisation.
//! Factorisation and solves allocate nothing once sized.
//! (faer 0.24 reads the pattern as the upper triangle, `Side::Upper`, whatever the
//! ordering: with AMD it permutes that triangle itself.)

use crate::block_pattern::{BlockShape, CscLayout, Index};
use crate::IntegratorError;
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymmetricOrdering,
};
use faer::sparse::linalg::SupernodalThreshold;
use faer::sparse::{SparseColMatRef, SymbolicSparseColMat};
use faer::{Conj, MatMut, Par, Side};
use splinerod_core::{BlockBanded, Real};

/// The natural ordering is kept while its fill (the pattern's envelope) is at most this
/// multiple of the band's nonzeros; beyond, AMD. AMD costs 10–35 % more than the natural
/// ordering at equal fill on these chains, so a 25 % larger envelope is about break-even.
pub const NATURAL_FILL_LIMIT: Real = 1.25;

/// Factorisation of a sparse SPD [`BlockBanded`] matrix (band and far blocks), with
/// symbolic reuse.
#[derive(Default)]
pub struct SparseCholesky {
    /// Topology epoch of the current analysis (`None`: no valid analysis).
    epoch: Option<u64>,
    /// The analysed block shape and its CSC layout.
    layout: CscLayout,
    /// Scratch: the shape of the matrix being factorised.
    incoming: BlockShape,
    pattern: Option<SymbolicSparseColMat<Index>>,
    symbolic: Option<SymbolicCholesky<Index>>,
    values: Vec<Real>,
    factor: Vec<Real>,
    memory: Option<MemBuffer>,
    rhs_capacity: usize,
    factored: bool,
    analyses: usize,
}

impl std::fmt::Debug for SparseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseCholesky")
            .field("epoch", &self.epoch)
            .field("far_blocks", &self.layout.shape().has_far())
            .field("factored", &self.factored)
            .finish()
    }
}

impl SparseCholesky {
    /// An empty solver; the first [`factor`](Self::factor) runs the symbolic analysis.
    pub fn new() -> Self {
        Self::default()
    }

    /// Factorises `a`. Returns whether a symbolic analysis was needed (the epoch, size,
    /// bandwidth or far block positions changed). Errors if `a` is not positive definite
    /// or a far block was moved into the band by hand.
    pub fn factor(&mut self, a: &BlockBanded, epoch: u64) -> Result<bool, IntegratorError> {
        self.factored = false;
        self.incoming.read(a)?;
        let analysed = self.epoch != Some(epoch)
            || self.symbolic.is_none()
            || self.incoming != *self.layout.shape();
        if analysed {
            self.epoch = None;
            self.layout.replace(&mut self.incoming);
            self.analyse()?;
            self.epoch = Some(epoch);
        }
        let (Some(pattern), Some(symbolic), Some(memory)) =
            (&self.pattern, &self.symbolic, &mut self.memory)
        else {
            return Err(IntegratorError::NotPositiveDefinite {
                context: "no symbolic analysis",
            });
        };
        self.layout.fill(a, pattern.col_ptr(), &mut self.values);
        let matrix = SparseColMatRef::new(pattern.as_ref(), &self.values);
        symbolic
            .factorize_numeric_llt::<Real>(
                &mut self.factor,
                matrix,
                Side::Upper,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(memory),
                Default::default(),
            )
            .map_err(|_| IntegratorError::NotPositiveDefinite {
                context: "sparse Cholesky",
            })?;
        self.factored = true;
        Ok(analysed)
    }

    /// Symbolic analyses run so far (one per basis or contact pattern change, ideally).
    pub fn analyses(&self) -> usize {
        self.analyses
    }

    /// Builds the pattern of the current layout and its symbolic factorisation (natural
    /// ordering unless far blocks enlarge the envelope beyond [`NATURAL_FILL_LIMIT`],
    /// then AMD). On error no analysis is left in place.
    fn analyse(&mut self) -> Result<(), IntegratorError> {
        self.analyses += 1;
        self.pattern = None;
        self.symbolic = None;
        let pattern = self.layout.symbolic()?;
        let ordering = self.ordering();
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SIMPLICIAL,
            ..Default::default()
        };
        let symbolic = factorize_symbolic_cholesky(pattern.as_ref(), Side::Upper, ordering, params)
            .map_err(|_| IntegratorError::NotPositiveDefinite {
                context: "symbolic analysis",
            })?;
        self.values.clear();
        self.values.resize(pattern.compute_nnz(), 0.0);
        self.factor.clear();
        self.factor.resize(symbolic.len_val(), 0.0);
        self.pattern = Some(pattern);
        self.symbolic = Some(symbolic);
        self.rhs_capacity = 0;
        self.reserve_rhs(1);
        Ok(())
    }

    /// The fill-reducing ordering for the current layout: natural while the envelope is
    /// within [`NATURAL_FILL_LIMIT`] of the band, AMD beyond.
    fn ordering(&self) -> SymmetricOrdering<'static, Index> {
        let natural_fill = self.layout.envelope() as Real / self.layout.band_nnz().max(1) as Real;
        if natural_fill <= NATURAL_FILL_LIMIT {
            SymmetricOrdering::Identity
        } else {
            SymmetricOrdering::Amd
        }
    }

    /// Makes sure `count` right-hand sides can be solved at once without allocating.
    fn reserve_rhs(&mut self, count: usize) {
        if count <= self.rhs_capacity {
            return;
        }
        if let Some(symbolic) = &self.symbolic {
            let need = StackReq::any_of(&[
                symbolic.factorize_numeric_llt_scratch::<Real>(Par::Seq, Default::default()),
                symbolic.solve_in_place_scratch::<Real>(count, Par::Seq),
            ]);
            self.memory = Some(MemBuffer::new(need));
            self.rhs_capacity = count;
        }
    }

    /// Solves `A x = b` in place for `k = rhs.len() / (3n)` right-hand sides stored
    /// column after column. Errors if no factorisation succeeded since the last
    /// [`factor`](Self::factor) call or if the length is not a multiple of `3n`.
    pub fn solve_in_place(&mut self, rhs: &mut [Real]) -> Result<(), IntegratorError> {
        let n = match (&self.symbolic, self.factored) {
            (Some(symbolic), true) => symbolic.nrows(),
            _ => {
                return Err(IntegratorError::SolverState(
                    "solve before a successful factor",
                ))
            }
        };
        if n == 0 || rhs.len() % n != 0 {
            return Err(IntegratorError::SolverState(
                "right-hand side length is not a multiple of 3n",
            ));
        }
        let k = rhs.len() / n;
        self.reserve_rhs(k);
        if let (Some(symbolic), Some(memory)) = (&self.symbolic, &mut self.memory) {
            let x = MatMut::from_column_major_slice_mut(rhs, n, k);
            LltRef::<Index, Real>::new(symbolic, &self.factor).solve_in_place_with_conj(
                Conj::No,
                x,
                Par::Seq,
                MemStack::new(memory),
            );
        }
        Ok(())
    }
}

/// Which factorisation the Newton solves use for purely banded matrices; a matrix with
/// far blocks always goes through the block sparse Cholesky.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum LinearSolverKind {
    /// [`crate::BandedCholesky`]: dense 3×3-block band, no symbolic phase. Default: 2.1 to
    /// 2.5× faster than the sparse path from 16 to 100 000 control points.
    #[default]
    Banded,
    /// The block sparse Cholesky
    /// ([`BlockSparseCholesky`](crate::block_sparse::BlockSparseCholesky)), with the
    /// symbolic analysis reused while the basis and the far block pattern are unchanged.
    Sparse,
}

/// The linear solver of a Newton workspace: either factorisation behind one interface.
///
/// It owns the Newton matrix ([`matrix_mut`](Self::matrix_mut) to assemble it), and the
/// banded path factorises it in place: the factor takes the matrix's own storage, so a
/// step holds one band of blocks, not two. After a banded factorisation the matrix is
/// no longer intact ([`matrix_intact`](Self::matrix_intact)): reassemble it to look at it
/// again.
#[derive(Debug, Default)]
pub struct LinearSolver {
    /// Which one factorises a banded matrix (far blocks force the sparse path).
    pub kind: LinearSolverKind,
    /// The Newton matrix; after a banded factorisation, its band holds the factor.
    matrix: BlockBanded,
    /// Whether the band of `matrix` holds the factor instead of the matrix.
    consumed: bool,
    sparse: crate::block_sparse::BlockSparseCholesky,
    ldlt: crate::banded_ldlt::BandedLdlt,
    /// The path of the last [`factor`](Self::factor) call, which the solves use.
    active: Option<LinearSolverKind>,
    /// Whether the last factorisation was [`factor_indefinite`](Self::factor_indefinite).
    indefinite: bool,
    /// The matrix's low-rank terms, applied after each solve.
    low_rank: crate::low_rank::LowRankCorrections,
    /// For a closed rod, its number `m` of distinct control points: the matrix is then
    /// folded onto them (`integrators/src/periodic.rs`) and solves keep the copies equal. Set it
    /// before each factorisation (Newton does, from the rod's basis).
    pub periodic: Option<usize>,
    /// The folded system's solver, for a closed rod.
    folded: Option<Box<crate::periodic::Folded>>,
}

impl LinearSolver {
    /// A solver preferring `kind` for banded matrices.
    pub fn new(kind: LinearSolverKind) -> Self {
        Self {
            kind,
            ..Self::default()
        }
    }

    /// The matrix, to assemble in place before [`factor_assembled`](Self::factor_assembled)
    /// (its contents are whatever the last use left: reset it first).
    pub fn matrix_mut(&mut self) -> &mut BlockBanded {
        self.consumed = false;
        self.active = None;
        &mut self.matrix
    }

    /// The matrix as assembled, if no banded factorisation has overwritten it since.
    pub fn matrix(&self) -> Option<&BlockBanded> {
        (!self.consumed).then_some(&self.matrix)
    }

    /// Whether [`matrix`](Self::matrix) still holds the assembled matrix.
    pub fn matrix_intact(&self) -> bool {
        !self.consumed
    }

    /// Factorises a copy of `a`; `epoch` identifies the basis (the sparse path
    /// re-analyses when it or the far block pattern changes). A matrix with far blocks is
    /// factorised by the sparse path whatever [`kind`](Self::kind) says.
    pub fn factor(&mut self, a: &BlockBanded, epoch: u64) -> Result<(), IntegratorError> {
        self.matrix_mut().clone_from(a);
        self.factor_assembled(epoch)
    }

    /// Factorises the matrix assembled through [`matrix_mut`](Self::matrix_mut) (see
    /// [`factor`](Self::factor)); the banded path overwrites it with the factor.
    pub fn factor_assembled(&mut self, epoch: u64) -> Result<(), IntegratorError> {
        if self.consumed {
            return Err(IntegratorError::SolverState(
                "the matrix was factorised already: assemble it again",
            ));
        }
        let kind = if self.matrix.has_far_blocks() {
            LinearSolverKind::Sparse
        } else {
            self.kind
        };
        self.active = None;
        self.indefinite = false;
        self.low_rank.clear();
        if let Some(m) = self.periodic_count() {
            let folded = self.folded.get_or_insert_with(Default::default);
            folded.solver.kind = self.kind;
            folded.factor(&self.matrix, m, epoch)?;
            self.active = folded.solver.factored_with();
            return Ok(());
        }
        match kind {
            LinearSolverKind::Banded => {
                let (n, bw) = crate::banded_cholesky::band_shape(&self.matrix)?;
                self.consumed = true;
                crate::banded_cholesky::factor_blocks(self.matrix.band_blocks_mut(), n, bw)?;
            }
            LinearSolverKind::Sparse => self.sparse.factor(&self.matrix, epoch).map(|_| ())?,
        }
        self.active = Some(kind);
        self.prepare_low_rank()
    }

    /// Prepares the Sherman–Morrison corrections of the matrix's low-rank terms with
    /// the band's factorisation just computed.
    fn prepare_low_rank(&mut self) -> Result<(), IntegratorError> {
        if self.matrix.low_rank().is_empty() {
            return Ok(());
        }
        let mut corrections = std::mem::take(&mut self.low_rank);
        let matrix = std::mem::take(&mut self.matrix);
        let result = corrections.prepare(&matrix, |x| self.solve_band(&matrix, x));
        (self.matrix, self.low_rank) = (matrix, corrections);
        if result.is_err() {
            self.active = None;
        }
        result
    }

    /// Factorises a symmetric, possibly indefinite, banded `a` by the block
    /// [`BandedLdlt`](crate::banded_ldlt::BandedLdlt); errors for far blocks or a nearly
    /// singular pivot.
    pub fn factor_indefinite(&mut self, a: &BlockBanded) -> Result<(), IntegratorError> {
        self.matrix_mut().clone_from(a);
        self.factor_indefinite_assembled()
    }

    /// [`factor_indefinite`](Self::factor_indefinite) of the assembled matrix (which
    /// must be intact); the matrix stays intact.
    pub fn factor_indefinite_assembled(&mut self) -> Result<(), IntegratorError> {
        self.active = None;
        self.low_rank.clear();
        if self.periodic_count().is_some() {
            return Err(IntegratorError::SolverState(
                "the indefinite factorisation does not fold a closed rod's matrix",
            ));
        }
        if self.consumed {
            return Err(IntegratorError::SolverState(
                "the matrix was factorised already: assemble it again",
            ));
        }
        self.ldlt.factor(&self.matrix)?;
        self.active = Some(LinearSolverKind::Banded);
        self.indefinite = true;
        self.prepare_low_rank()
    }

    /// A direction of negative curvature of the matrix last given to
    /// [`factor_indefinite`](Self::factor_indefinite), and its curvature (see
    /// [`BandedLdlt::negative_curvature`](crate::banded_ldlt::BandedLdlt::negative_curvature)).
    pub fn negative_curvature(&self, d: &mut [nalgebra::Vector3<Real>]) -> Option<Real> {
        self.ldlt.negative_curvature(d)
    }

    /// Whether the current factorisation is the indefinite one.
    pub fn is_indefinite(&self) -> bool {
        self.active.is_some() && self.indefinite
    }

    /// Solves in place for right-hand sides stored column after column, with the
    /// factorisation of the last [`factor`](Self::factor) call (an error if it failed).
    /// Low-rank terms of the matrix (see [`BlockBanded::add_low_rank`]) are applied by
    /// the Sherman–Morrison formula.
    pub fn solve_in_place(&mut self, rhs: &mut [Real]) -> Result<(), IntegratorError> {
        if let (Some(m), Some(folded)) = (self.periodic_count(), self.folded.as_mut()) {
            if self.active.is_none() {
                return Err(IntegratorError::SolverState(
                    "solve before a successful factor",
                ));
            }
            return folded.solve_in_place(rhs, self.matrix.dim(), m);
        }
        let matrix = std::mem::take(&mut self.matrix);
        let result = self.solve_band(&matrix, rhs);
        self.matrix = matrix;
        result?;
        self.low_rank.apply(rhs);
        Ok(())
    }

    /// Solves with the factorised band and far blocks only; `matrix` is the solver's
    /// own (holding the banded factor), lent out.
    fn solve_band(
        &mut self,
        matrix: &BlockBanded,
        rhs: &mut [Real],
    ) -> Result<(), IntegratorError> {
        if self.is_indefinite() {
            return self.ldlt.solve_in_place(rhs);
        }
        match self.active {
            Some(LinearSolverKind::Banded) => {
                let (n, bw) = (matrix.dim(), matrix.bandwidth());
                let column = |c: &mut [Real]| {
                    crate::banded_cholesky::solve_blocks(matrix.band_blocks(), n, bw, c)
                };
                crate::banded_cholesky::for_each_rhs(self.consumed, n, rhs, column)
            }
            Some(LinearSolverKind::Sparse) => self.sparse.solve_in_place(rhs),
            None => Err(IntegratorError::SolverState(
                "solve before a successful factor",
            )),
        }
    }

    /// The distinct control points of a closed rod's matrix, if it is one (and folding
    /// changes it: `m` smaller than the matrix).
    fn periodic_count(&self) -> Option<usize> {
        self.periodic.filter(|&m| m < self.matrix.dim())
    }

    /// The path the last [`factor`](Self::factor) call took, if any.
    pub fn factored_with(&self) -> Option<LinearSolverKind> {
        self.active
    }

    /// Symbolic analyses run so far (only the sparse path runs them).
    pub fn analyses(&self) -> usize {
        let folded = self.folded.as_ref().map_or(0, |f| f.solver.analyses());
        self.sparse.analyses() + folded
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DVector, Matrix3};

    /// A chain of springs with masses (SPD), plus springs between `pairs`.
    fn chain(n: usize, pairs: &[(usize, usize)]) -> BlockBanded {
        let mut a = BlockBanded::zeros(n, 3);
        let spring = |a: &mut BlockBanded, i: usize, j: usize| {
            let k = Matrix3::identity();
            a.add_coupling(i, i, &k);
            a.add_coupling(j, j, &k);
            a.add_coupling(i, j, &-k);
        };
        for i in 0..n {
            a.add_block(i, i, &Matrix3::identity());
            for j in i + 1..(i + 4).min(n) {
                spring(&mut a, i, j);
            }
        }
        for &(i, j) in pairs {
            spring(&mut a, i, j);
        }
        a
    }

    /// Factorises and solves `a`; returns whether the natural ordering was kept.
    fn natural_and_checked(a: &BlockBanded) -> bool {
        let mut solver = SparseCholesky::new();
        solver.factor(a, 0).unwrap();
        let b: Vec<Real> = (0..3 * a.dim()).map(|i| (i % 5) as Real - 2.0).collect();
        let mut x = b.clone();
        solver.solve_in_place(&mut x).unwrap();
        let exact = a.to_dense().cholesky().unwrap().solve(&DVector::from(b));
        let error = (DVector::from(x) - &exact).norm() / exact.norm();
        assert!(error < 1e-12, "relative error {error:e}");
        solver.symbolic.as_ref().unwrap().perm().is_none()
    }

    #[test]
    fn the_ordering_follows_the_natural_fill() {
        assert!(natural_and_checked(&chain(100, &[])));
        // Springs 6 apart: a few percent more envelope, natural ordering.
        assert!(natural_and_checked(&chain(
            100,
            &[(10, 16), (50, 56), (52, 58)]
        )));
        // A spring closing the rod into a loop: AMD.
        assert!(!natural_and_checked(&chain(100, &[(2, 97)])));
        assert!(!natural_and_checked(&chain(
            100,
            &[(2, 97), (97, 2), (5, 40)]
        )));
    }
}
