//! [`BlockBanded`]: the 3×3-block Newton matrices \\(A = c_M M \otimes I_3 + c_K K\\) of a
//! rod, a block band plus a short list of *far* blocks.
//!
//! Energies that integrate along the curve couple control points at most `d` apart, so
//! their Hessians live in the band; the upper blocks `(i, i + k)`, `0 ≤ k ≤ bandwidth`,
//! are stored at `i · (bandwidth + 1) + k`. Interactions between distant parts of the
//! rod (self-contact) couple control points far apart: those blocks are appended to a
//! list by [`BlockBanded::add_coupling`], each as an upper block `(row < col)`; entries
//! with the same position are summed. A matrix with far blocks is no longer banded, and
//! the solvers switch to a general sparse factorisation for it.
//! Assembly is O(n + far blocks) and allocation-free once sized.

use crate::banded::SymBanded;
use crate::Real;
use nalgebra::{Matrix3, Vector3};

/// An upper block `(row, col)`, `col > row + bandwidth`, outside the band of a
/// [`BlockBanded`] matrix; the matrix also holds its transpose at `(col, row)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FarBlock {
    /// Block row (control point), smaller than `col`.
    pub row: usize,
    /// Block column (control point).
    pub col: usize,
    /// The 3×3 block \\(A_{row,col}\\).
    pub block: Matrix3<Real>,
}

/// A symmetric positive semi-definite rank-one term \\(c\, u u^T\\) of a [`BlockBanded`]
/// matrix: a coupling of every control point with every other (the twist of a rod between
/// two clamps depends on the whole centreline), kept as a vector instead of `n²` blocks.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LowRank {
    /// The coefficient `c ≥ 0`.
    pub coefficient: Real,
    /// The vector `u`, one entry per control point.
    pub vector: Vec<Vector3<Real>>,
}

/// A symmetric matrix of 3×3 blocks with `bandwidth` block off-diagonals on each side,
/// plus any number of [`FarBlock`]s outside the band and of [`LowRank`] terms
/// \\(c\, u u^T\\) (which [`block`](BlockBanded::block) does not include; solvers apply
/// them by the Sherman–Morrison formula).
///
/// [`add_block`](BlockBanded::add_block)`(i, j, B)` means \\(A_{ij} \mathrel{+}= B\\) and,
/// for `i ≠ j`, \\(A_{ji} \mathrel{+}= B^T\\): assemble each unordered pair once.
#[derive(Debug, Default)]
pub struct BlockBanded {
    n: usize,
    bandwidth: usize,
    blocks: Vec<Matrix3<Real>>,
    far: Vec<FarBlock>,
    /// Low-rank terms; only the first `low_rank_used` are live (the rest keep their
    /// allocations for the next assembly).
    low_rank: Vec<LowRank>,
    low_rank_used: usize,
}

/// Equal size, band, far blocks (in order) and live low-rank terms.
impl PartialEq for BlockBanded {
    fn eq(&self, other: &Self) -> bool {
        (self.n, self.bandwidth) == (other.n, other.bandwidth)
            && self.blocks == other.blocks
            && self.far == other.far
            && self.low_rank() == other.low_rank()
    }
}

impl Clone for BlockBanded {
    fn clone(&self) -> Self {
        let mut copy = Self::default();
        copy.clone_from(self);
        copy
    }

    /// Copies `source` into this matrix's storage: no allocation once it has grown to
    /// the size (a solver factorising a copy each Newton iteration relies on it).
    fn clone_from(&mut self, source: &Self) {
        (self.n, self.bandwidth) = (source.n, source.bandwidth);
        self.blocks.clone_from(&source.blocks);
        self.far.clone_from(&source.far);
        let live = &source.low_rank[..source.low_rank_used];
        if self.low_rank.len() < live.len() {
            self.low_rank.resize_with(live.len(), LowRank::default);
        }
        for (term, from) in self.low_rank.iter_mut().zip(live) {
            term.coefficient = from.coefficient;
            term.vector.clone_from(&from.vector);
        }
        self.low_rank_used = live.len();
    }
}

impl BlockBanded {
    /// The zero matrix of `n × n` blocks.
    pub fn zeros(n: usize, bandwidth: usize) -> Self {
        Self {
            n,
            bandwidth,
            blocks: vec![Matrix3::zeros(); n * (bandwidth + 1)],
            far: Vec::new(),
            low_rank: Vec::new(),
            low_rank_used: 0,
        }
    }

    /// Resizes (reusing the allocation when possible), sets every block to zero and
    /// drops the far blocks.
    pub fn reset(&mut self, n: usize, bandwidth: usize) {
        self.n = n;
        self.bandwidth = bandwidth;
        self.blocks.clear();
        self.blocks.resize(n * (bandwidth + 1), Matrix3::zeros());
        self.far.clear();
        self.low_rank_used = 0;
    }

    /// Adds the term \\(c\, u u^T\\) (`c ≥ 0`, `u` one entry per control point).
    /// Reuses the storage of earlier assemblies: no allocation once sized.
    #[track_caller]
    pub fn add_low_rank(&mut self, coefficient: Real, u: &[Vector3<Real>]) {
        assert!(u.len() == self.n, "dimension mismatch");
        self.add_low_rank_with(coefficient, |v| v.copy_from_slice(u));
    }

    /// Adds the term \\(c\, u u^T\\) with `u` written by `fill` into a zeroed vector of
    /// one entry per control point (no allocation once sized).
    pub fn add_low_rank_with(
        &mut self,
        coefficient: Real,
        fill: impl FnOnce(&mut [Vector3<Real>]),
    ) {
        if self.low_rank_used == self.low_rank.len() {
            self.low_rank.push(LowRank::default());
        }
        let term = &mut self.low_rank[self.low_rank_used];
        term.coefficient = coefficient;
        term.vector.clear();
        term.vector.resize(self.n, Vector3::zeros());
        fill(&mut term.vector);
        self.low_rank_used += 1;
    }

    /// The low-rank terms \\(c\, u u^T\\), in the order they were added.
    pub fn low_rank(&self) -> &[LowRank] {
        &self.low_rank[..self.low_rank_used]
    }

    /// The low-rank terms, mutably (e.g. to zero the entries of an eliminated unknown).
    pub fn low_rank_mut(&mut self) -> &mut [LowRank] {
        &mut self.low_rank[..self.low_rank_used]
    }

    /// Number of block rows.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of stored block off-diagonals.
    pub fn bandwidth(&self) -> usize {
        self.bandwidth
    }

    /// Block `(i, j)` of the full symmetric matrix (band and far blocks).
    pub fn block(&self, i: usize, j: usize) -> Matrix3<Real> {
        let (lo, hi) = (i.min(j), i.max(j));
        let upper = if hi >= self.n {
            Matrix3::zeros()
        } else if hi - lo <= self.bandwidth {
            self.blocks[lo * (self.bandwidth + 1) + hi - lo]
        } else {
            self.far
                .iter()
                .filter(|f| f.row == lo && f.col == hi)
                .map(|f| f.block)
                .sum()
        };
        if i <= j {
            upper
        } else {
            upper.transpose()
        }
    }

    /// The band's storage: upper block `(i, i + k)` at `i · (bandwidth + 1) + k` (slots
    /// past the last row are zero).
    pub fn band_blocks(&self) -> &[Matrix3<Real>] {
        &self.blocks
    }

    /// The band's storage, mutably (for factorisations in place, which leave the
    /// matrix holding their factor).
    pub fn band_blocks_mut(&mut self) -> &mut [Matrix3<Real>] {
        &mut self.blocks
    }

    /// The stored upper band block `(i, i + k)`.
    #[inline]
    pub fn upper(&self, i: usize, k: usize) -> &Matrix3<Real> {
        &self.blocks[i * (self.bandwidth + 1) + k]
    }

    /// The far blocks, in the order they were added (positions may repeat: they sum).
    pub fn far_blocks(&self) -> &[FarBlock] {
        &self.far
    }

    /// The far blocks, mutably (e.g. to zero the couplings of an eliminated unknown).
    pub fn far_blocks_mut(&mut self) -> &mut [FarBlock] {
        &mut self.far
    }

    /// Whether the matrix has blocks outside the band.
    pub fn has_far_blocks(&self) -> bool {
        !self.far.is_empty()
    }

    /// Sets band block `(i, j)` to `b` (and `(j, i)` to `bᵀ`); `b` must be symmetric if
    /// `i == j`.
    #[track_caller]
    pub fn set_block(&mut self, i: usize, j: usize, b: &Matrix3<Real>) {
        let w = self.bandwidth + 1;
        let (lo, hi, stored) = if i <= j {
            (i, j, *b)
        } else {
            (j, i, b.transpose())
        };
        assert!(
            hi - lo < w && hi < self.n,
            "block ({i}, {j}) is outside the band"
        );
        self.blocks[lo * w + hi - lo] = stored;
    }

    /// Whether every stored entry is finite.
    pub fn is_finite(&self) -> bool {
        let finite = |b: &Matrix3<Real>| b.iter().all(|x| x.is_finite());
        self.blocks.iter().all(finite)
            && self.far.iter().all(|f| finite(&f.block))
            && self.low_rank().iter().all(|t| {
                t.coefficient.is_finite()
                    && t.vector.iter().all(|v| v.iter().all(|x| x.is_finite()))
            })
    }

    /// Adds `b` at band position `(i, j)` and `bᵀ` at `(j, i)`; for `i == j`, `b` should
    /// be symmetric. Panics outside the band (use [`add_coupling`](Self::add_coupling)
    /// for distant control points).
    #[track_caller]
    #[inline(always)]
    pub fn add_block(&mut self, i: usize, j: usize, b: &Matrix3<Real>) {
        let w = self.bandwidth + 1;
        if i <= j {
            assert!(
                j - i < w && j < self.n,
                "block ({i}, {j}) is outside the band"
            );
            self.blocks[i * w + j - i] += b;
        } else {
            assert!(
                i - j < w && i < self.n,
                "block ({i}, {j}) is outside the band"
            );
            self.blocks[j * w + i - j] += b.transpose();
        }
    }

    /// The stored upper blocks of row `i`, `(i, i) ..= (i, min(i + bandwidth, n − 1))`,
    /// mutably: for assembly loops that add a row of blocks without a bounds check per
    /// block. Adding `B` at index `k ≥ 1` means \\(A_{i,i+k} \mathrel{+}= B\\) and
    /// \\(A_{i+k,i} \mathrel{+}= B^T\\); the block at `k = 0` must stay symmetric.
    #[inline]
    pub fn band_row_mut(&mut self, i: usize) -> &mut [Matrix3<Real>] {
        let w = self.bandwidth + 1;
        let len = w.min(self.n.saturating_sub(i));
        &mut self.blocks[i * w..i * w + len]
    }

    /// Adds \\(g I_3\\) at band position `(i, j)` (and `(j, i)`), `i ≤ j`: a scalar
    /// coupling such as a geometric stiffness. Panics outside the band.
    #[track_caller]
    #[inline(always)]
    pub fn add_scalar(&mut self, i: usize, j: usize, g: Real) {
        let w = self.bandwidth + 1;
        assert!(
            i <= j && j - i < w && j < self.n,
            "block ({i}, {j}) is outside the band"
        );
        let b = &mut self.blocks[i * w + j - i];
        b[(0, 0)] += g;
        b[(1, 1)] += g;
        b[(2, 2)] += g;
    }

    /// Adds `b` at `(i, j)` and `bᵀ` at `(j, i)` for any pair of control points: into the
    /// band when `|i − j| ≤ bandwidth`, otherwise as a [`FarBlock`]. Panics if an index
    /// is out of range.
    #[track_caller]
    pub fn add_coupling(&mut self, i: usize, j: usize, b: &Matrix3<Real>) {
        assert!(i < self.n && j < self.n, "block ({i}, {j}) is out of range");
        if i.abs_diff(j) <= self.bandwidth {
            self.add_block(i, j, b);
        } else if i < j {
            self.far.push(FarBlock {
                row: i,
                col: j,
                block: *b,
            });
        } else {
            self.far.push(FarBlock {
                row: j,
                col: i,
                block: b.transpose(),
            });
        }
    }

    /// Adds `other` (a smaller matrix of the same or a narrower band) with its block
    /// `(0, 0)` at `(first, first)`: band, far blocks and low-rank terms (their vectors
    /// padded with zeros). For the Hessian of one part of a joined rod. Panics if it
    /// does not fit.
    #[track_caller]
    pub fn add_shifted(&mut self, other: &BlockBanded, first: usize) {
        assert!(first + other.n <= self.n, "block does not fit");
        let w = other.bandwidth + 1;
        for i in 0..other.n {
            for k in 0..w.min(other.n - i) {
                let b = &other.blocks[i * w + k];
                if *b != Matrix3::zeros() {
                    self.add_coupling(first + i, first + i + k, b);
                }
            }
        }
        for f in &other.far {
            self.add_coupling(first + f.row, first + f.col, &f.block);
        }
        for t in other.low_rank() {
            self.add_low_rank_with(t.coefficient, |u| {
                u[first..first + other.n].copy_from_slice(&t.vector);
            });
        }
    }

    /// Multiplies every entry by `c`.
    pub fn scale(&mut self, c: Real) {
        self.blocks.iter_mut().for_each(|b| *b *= c);
        self.far.iter_mut().for_each(|f| f.block *= c);
        self.low_rank_mut()
            .iter_mut()
            .for_each(|t| t.coefficient *= c);
    }

    /// Adds \\(c\, M \otimes I_3\\) for a scalar banded matrix `m` of the same size.
    #[track_caller]
    pub fn add_scaled_scalar(&mut self, c: Real, m: &SymBanded) {
        assert!(
            m.dim() == self.n && m.bandwidth() <= self.bandwidth,
            "shape mismatch"
        );
        for i in 0..self.n {
            for k in 0..=m.bandwidth().min(self.n - 1 - i) {
                let v = c * m.get(i, i + k);
                let b = &mut self.blocks[i * (self.bandwidth + 1) + k];
                b[(0, 0)] += v;
                b[(1, 1)] += v;
                b[(2, 2)] += v;
            }
        }
    }

    /// [`Self::scale`] by `s`, then [`Self::add_row_scaled_scalar`] of `c` and `m`, in
    /// one pass over the band (each block scaled, then its diagonal added to: the same
    /// operations as the two passes, in the same order).
    #[track_caller]
    pub fn scale_and_add_row_scaled_scalar(
        &mut self,
        s: Real,
        c: impl Fn(usize) -> Real,
        m: &SymBanded,
    ) {
        assert!(
            m.dim() == self.n && m.bandwidth() <= self.bandwidth,
            "shape mismatch"
        );
        #[cfg(target_arch = "x86_64")]
        if crate::lanes::wide() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            unsafe { self.scale_and_add_band_wide(s, &c, m) };
        } else {
            self.scale_and_add_band(s, &c, m);
        }
        #[cfg(not(target_arch = "x86_64"))]
        self.scale_and_add_band(s, &c, m);
        self.far.iter_mut().for_each(|f| f.block *= s);
        self.low_rank_mut()
            .iter_mut()
            .for_each(|t| t.coefficient *= s);
    }

    /// The band's part of [`Self::scale_and_add_row_scaled_scalar`].
    fn scale_and_add_band(&mut self, s: Real, c: &impl Fn(usize) -> Real, m: &SymBanded) {
        let (w, n, mw) = (self.bandwidth + 1, self.n, m.bandwidth() + 1);
        let rows = self
            .blocks
            .chunks_exact_mut(w)
            .zip(m.band().chunks_exact(mw));
        for (i, (row, mass)) in rows.enumerate() {
            let ci = c(i);
            // The mass couples row `i` to the next `mw - 1` points (those that exist).
            let (near, rest) = row.split_at_mut(mw.min(n - i));
            for (b, &mik) in near.iter_mut().zip(mass) {
                // Scaled and added to in registers, stored once (adding to the stored
                // diagonal would reload entries just stored, and wait on the store).
                let mut x = *b * s;
                let v = ci * mik;
                x[(0, 0)] += v;
                x[(1, 1)] += v;
                x[(2, 2)] += v;
                *b = x;
            }
            rest.iter_mut().for_each(|b| *b *= s);
        }
    }

    /// [`Self::scale_and_add_band`] with each block's columns in four-wide registers
    /// ([`crate::simd`]): every entry times `s`, then the diagonal's `c(i) M_ij` added
    /// (and −0 elsewhere, which leaves every value as it is), the same operations as
    /// the scalar pass.
    ///
    /// # Safety
    /// The processor must have AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn scale_and_add_band_wide(
        &mut self,
        s: Real,
        c: &impl Fn(usize) -> Real,
        m: &SymBanded,
    ) {
        use crate::simd::{add_diagonal, load_block, store_block};
        use core::arch::x86_64::*;
        let (w, n, mw) = (self.bandwidth + 1, self.n, m.bandwidth() + 1);
        let scale = _mm256_set1_pd(s);
        let rows = self
            .blocks
            .chunks_exact_mut(w)
            .zip(m.band().chunks_exact(mw));
        // Plain loops, no closures (see `crate::simd`).
        for (i, (row, mass)) in rows.enumerate() {
            let ci = c(i);
            let near = mw.min(n - i);
            for (k, block) in row.iter_mut().enumerate() {
                let p = block.as_mut_ptr();
                let mut columns = load_block(p);
                for column in columns.iter_mut() {
                    *column = _mm256_mul_pd(*column, scale);
                }
                if k < near {
                    add_diagonal(&mut columns, ci * mass[k]);
                }
                store_block(p, columns);
            }
        }
    }

    /// Adds \\(\operatorname{diag}(c)\, M \otimes I_3\\): block `(i, j)` gains
    /// `c(i) M_ij I`. Symmetric only when `c(i) = c(j)` wherever `M_ij ≠ 0` (a factor
    /// constant on each block of a block-diagonal `M`, e.g. per joined rod); the upper
    /// triangle stored here takes row `i`'s factor.
    #[track_caller]
    pub fn add_row_scaled_scalar(&mut self, c: impl Fn(usize) -> Real, m: &SymBanded) {
        assert!(
            m.dim() == self.n && m.bandwidth() <= self.bandwidth,
            "shape mismatch"
        );
        for i in 0..self.n {
            let ci = c(i);
            for k in 0..=m.bandwidth().min(self.n - 1 - i) {
                let v = ci * m.get(i, i + k);
                let b = &mut self.blocks[i * (self.bandwidth + 1) + k];
                b[(0, 0)] += v;
                b[(1, 1)] += v;
                b[(2, 2)] += v;
            }
        }
    }

    /// `y = self · x`.
    #[track_caller]
    pub fn mul_vec(&self, x: &[Vector3<Real>], y: &mut [Vector3<Real>]) {
        assert!(x.len() == self.n && y.len() == self.n, "dimension mismatch");
        y.iter_mut().for_each(|v| *v = Vector3::zeros());
        let w = self.bandwidth + 1;
        for i in 0..self.n {
            y[i] += self.blocks[i * w] * x[i];
            for k in 1..w.min(self.n - i) {
                let b = &self.blocks[i * w + k];
                y[i] += b * x[i + k];
                y[i + k] += b.tr_mul(&x[i]);
            }
        }
        for f in &self.far {
            y[f.row] += f.block * x[f.col];
            y[f.col] += f.block.tr_mul(&x[f.row]);
        }
        for t in self.low_rank() {
            let s: Real = t.vector.iter().zip(x).map(|(u, x)| u.dot(x)).sum();
            y.iter_mut()
                .zip(&t.vector)
                .for_each(|(y, u)| *y += u * (t.coefficient * s));
        }
    }

    /// The full matrix as a dense `3n × 3n` array (tests and small analyses only).
    pub fn to_dense(&self) -> nalgebra::DMatrix<Real> {
        let mut a = nalgebra::DMatrix::zeros(3 * self.n, 3 * self.n);
        for i in 0..self.n {
            for j in i.saturating_sub(self.bandwidth)..(i + self.bandwidth + 1).min(self.n) {
                a.fixed_view_mut::<3, 3>(3 * i, 3 * j)
                    .copy_from(&self.block(i, j));
            }
        }
        for f in &self.far {
            let mut upper = a.fixed_view_mut::<3, 3>(3 * f.row, 3 * f.col);
            upper += f.block;
            let mut lower = a.fixed_view_mut::<3, 3>(3 * f.col, 3 * f.row);
            lower += f.block.transpose();
        }
        for t in self.low_rank() {
            let u = nalgebra::DVector::from_iterator(
                3 * self.n,
                t.vector.iter().flat_map(|v| v.iter().copied()),
            );
            a += &u * u.transpose() * t.coefficient;
        }
        a
    }
}

/// Adds the linear operator `apply` (`apply(v, out)` adds `A v` to `out`, for vectors of
/// `n` 3-vectors) to the dense `a` (3n × 3n), one column per unit vector: for tests and
/// small dense analyses of an operator that is not stored (a Hessian's remainder).
pub fn add_operator_columns(
    n: usize,
    a: &mut nalgebra::DMatrix<Real>,
    mut apply: impl FnMut(&[Vector3<Real>], &mut [Vector3<Real>]),
) {
    let (mut v, mut out) = (vec![Vector3::zeros(); n], vec![Vector3::zeros(); n]);
    for c in 0..3 * n {
        v[c / 3][c % 3] = 1.0;
        out.iter_mut().for_each(|o| *o = Vector3::zeros());
        apply(&v, &mut out);
        v[c / 3][c % 3] = 0.0;
        for (r, o) in out.iter().enumerate() {
            for b in 0..3 {
                a[(3 * r + b, c)] += o[b];
            }
        }
    }
}
