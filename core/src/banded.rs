//! Symmetric banded storage: [`SymBanded`] for scalar matrices such as the mass matrix
//! \\(M_{ij} = \int \mu\, b_i b_j\, ds\\) (bandwidth `d`); the 3×3-block Newton matrices
//! are [`crate::BlockBanded`].
//!
//! Only the upper triangle is stored: entry `(i, i + k)`, `0 ≤ k ≤ bandwidth`, lives at
//! `i · (bandwidth + 1) + k`. Assembly is O(n) and allocation-free once sized.

use crate::Real;
use nalgebra::Vector3;

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

    /// The stored upper band: entry `(i, i + k)` at `i · (bandwidth + 1) + k` (slots past
    /// the end of the matrix are zero).
    pub fn band(&self) -> &[Real] {
        &self.data
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
