//! Symmetric banded storage: [`SymBanded`] for scalar matrices such as the mass matrix
//! \\(M_{ij} = \int \mu\, b_i b_j\, ds\\) (bandwidth `d`), and [`BlockBanded`] for the
//! 3×3-block Newton matrices \\(A = c_M M \otimes I_3 + c_K K\\) of a rod.
//!
//! Only the upper triangle is stored: entry `(i, i + k)`, `0 ≤ k ≤ bandwidth`, lives at
//! `i · (bandwidth + 1) + k`. Assembly is O(n) and allocation-free once sized.

use crate::Real;
use nalgebra::{Matrix3, Vector3};

/// A symmetric scalar matrix with `bandwidth` off-diagonals on each side.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SymBanded {
    n: usize,
    bandwidth: usize,
    data: Vec<Real>,
}

impl SymBanded {
    /// The `n × n` zero matrix with the given bandwidth.
    pub fn zeros(n: usize, bandwidth: usize) -> Self {
        Self {
            n,
            bandwidth,
            data: vec![0.0; n * (bandwidth + 1)],
        }
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of stored off-diagonals.
    pub fn bandwidth(&self) -> usize {
        self.bandwidth
    }

    /// Entry `(i, j)` (zero outside the band).
    pub fn get(&self, i: usize, j: usize) -> Real {
        let (i, j) = (i.min(j), i.max(j));
        if j - i > self.bandwidth || j >= self.n {
            return 0.0;
        }
        self.data[i * (self.bandwidth + 1) + j - i]
    }

    /// Adds `v` to entries `(i, j)` and `(j, i)` (once if `i == j`).
    #[track_caller]
    #[inline]
    pub fn add(&mut self, i: usize, j: usize, v: Real) {
        let (i, j) = (i.min(j), i.max(j));
        assert!(
            j - i <= self.bandwidth && j < self.n,
            "entry ({i}, {j}) is outside the band"
        );
        self.data[i * (self.bandwidth + 1) + j - i] += v;
    }

    /// Replaces the rows and columns `old` by `new_len` zero rows and columns, moving the
    /// rows after them (whose entries keep their offsets). Entries coupling a replaced
    /// index with another index are zeroed; the rest are untouched.
    pub fn reindex(&mut self, old: &std::ops::Range<usize>, new_len: usize) {
        let w = self.bandwidth + 1;
        for i in old.start.saturating_sub(self.bandwidth)..old.start {
            for k in (old.start - i)..w {
                self.data[i * w + k] = 0.0;
            }
        }
        let zeros = std::iter::repeat_n(0.0, new_len * w);
        self.data.splice(old.start * w..old.end * w, zeros);
        self.n = self.n + new_len - old.len();
    }

    /// `y = self · x` for a field of 3-vectors (the matrix acts on each coordinate).
    #[track_caller]
    pub fn mul_vec3(&self, x: &[Vector3<Real>], y: &mut [Vector3<Real>]) {
        assert!(x.len() == self.n && y.len() == self.n, "dimension mismatch");
        let w = self.bandwidth + 1;
        y.iter_mut().for_each(|v| *v = Vector3::zeros());
        for i in 0..self.n {
            let row = &self.data[i * w..(i + 1) * w];
            y[i] += x[i] * row[0];
            for k in 1..w.min(self.n - i) {
                y[i] += x[i + k] * row[k];
                y[i + k] += x[i] * row[k];
            }
        }
    }

    /// The quadratic form \\(\sum_{ij} M_{ij}\, x_i \cdot y_j\\) for two 3-vector fields.
    #[track_caller]
    pub fn bilinear_vec3(&self, x: &[Vector3<Real>], y: &[Vector3<Real>]) -> Real {
        assert!(x.len() == self.n && y.len() == self.n, "dimension mismatch");
        let w = self.bandwidth + 1;
        let mut sum = 0.0;
        for i in 0..self.n {
            let row = &self.data[i * w..(i + 1) * w];
            sum += row[0] * x[i].dot(&y[i]);
            for k in 1..w.min(self.n - i) {
                sum += row[k] * (x[i].dot(&y[i + k]) + x[i + k].dot(&y[i]));
            }
        }
        sum
    }
}

/// A symmetric matrix of 3×3 blocks with `bandwidth` block off-diagonals on each side.
///
/// [`add_block`](BlockBanded::add_block)`(i, j, B)` means \\(A_{ij} \mathrel{+}= B\\) and,
/// for `i ≠ j`, \\(A_{ji} \mathrel{+}= B^T\\): assemble each unordered pair once.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BlockBanded {
    n: usize,
    bandwidth: usize,
    blocks: Vec<Matrix3<Real>>,
}

impl BlockBanded {
    /// The zero matrix of `n × n` blocks.
    pub fn zeros(n: usize, bandwidth: usize) -> Self {
        Self {
            n,
            bandwidth,
            blocks: vec![Matrix3::zeros(); n * (bandwidth + 1)],
        }
    }

    /// Resizes (reusing the allocation when possible) and sets every block to zero.
    pub fn reset(&mut self, n: usize, bandwidth: usize) {
        self.n = n;
        self.bandwidth = bandwidth;
        self.blocks.clear();
        self.blocks.resize(n * (bandwidth + 1), Matrix3::zeros());
    }

    /// Number of block rows.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Number of stored block off-diagonals.
    pub fn bandwidth(&self) -> usize {
        self.bandwidth
    }

    /// Block `(i, j)` of the full symmetric matrix (zero outside the band).
    pub fn block(&self, i: usize, j: usize) -> Matrix3<Real> {
        let (lo, hi) = (i.min(j), i.max(j));
        if hi - lo > self.bandwidth || hi >= self.n {
            return Matrix3::zeros();
        }
        let b = self.blocks[lo * (self.bandwidth + 1) + hi - lo];
        if i <= j {
            b
        } else {
            b.transpose()
        }
    }

    /// The stored upper block `(i, i + k)`.
    #[inline]
    pub fn upper(&self, i: usize, k: usize) -> &Matrix3<Real> {
        &self.blocks[i * (self.bandwidth + 1) + k]
    }

    /// Sets block `(i, j)` to `b` (and `(j, i)` to `bᵀ`); `b` must be symmetric if `i == j`.
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
        self.blocks.iter().all(|b| b.iter().all(|x| x.is_finite()))
    }

    /// Adds `b` at `(i, j)` and `bᵀ` at `(j, i)`; for `i == j`, `b` should be symmetric.
    #[track_caller]
    #[inline]
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

    /// Multiplies every entry by `c`.
    pub fn scale(&mut self, c: Real) {
        self.blocks.iter_mut().for_each(|b| *b *= c);
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
        a
    }
}
