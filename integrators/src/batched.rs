//! Banded Cholesky factorisation of [`LANES`] block-banded matrices of the same shape at
//! once, structure of arrays: every scalar of a 3×3 block holds one value per matrix
//! (lane), so each arithmetic operation of [`crate::banded_cholesky`]'s recursion
//!
//! \\[ U_{ii}^T U_{ii} = A_{ii} - \sum_{k<i} U_{ki}^T U_{ki}, \qquad
//! U_{ij} = U_{ii}^{-T}\Big(A_{ij} - \sum_{k<i} U_{ki}^T U_{kj}\Big) \\]
//!
//! runs over the lanes in one loop the compiler vectorises. It is the linear algebra of
//! batched ensemble steps (#17: members that share a basis have Newton matrices of the
//! same band); each lane's result equals the scalar factorisation's up to round-off.

use crate::IntegratorError;
use splinerod_core::{BlockBanded, Real};

/// Matrices factorised together.
pub const LANES: usize = 4;

/// One scalar per lane.
pub type Lanes = [Real; LANES];

/// A 3×3 block per lane, column-major: entry `(r, c)` at `3c + r`.
type Block = [Lanes; 9];

/// The factors `U` of [`LANES`] block-banded SPD matrices of the same size and bandwidth.
#[derive(Debug, Clone, Default)]
pub struct BatchedBandedCholesky {
    n: usize,
    bw: usize,
    /// `U_{i,i+k}` at `i·(bw+1) + k`; the diagonal slots hold \\(U_{ii}^{-T}\\) (lower
    /// triangular), as in [`crate::banded_cholesky`].
    u: Vec<Block>,
}

fn not_definite() -> IntegratorError {
    IntegratorError::NotPositiveDefinite {
        context: "batched banded Cholesky",
    }
}

impl BatchedBandedCholesky {
    /// Factorises the matrices `a` (one per lane; same size and bandwidth, no far
    /// blocks). Errors if the shapes differ or a lane is not positive definite.
    pub fn factor(&mut self, a: [&BlockBanded; LANES]) -> Result<(), IntegratorError> {
        let (n, bw) = (a[0].dim(), a[0].bandwidth());
        if a.iter()
            .any(|m| m.dim() != n || m.bandwidth() != bw || m.has_far_blocks())
        {
            return Err(IntegratorError::SolverState(
                "batched matrices must share one band shape without far blocks",
            ));
        }
        (self.n, self.bw) = (n, bw);
        let w = bw + 1;
        self.u.clear();
        self.u.resize(n * w, [[0.0; LANES]; 9]);
        for (lane, m) in a.iter().enumerate() {
            for (slot, block) in self.u.iter_mut().zip(m.band_blocks()) {
                for (e, &v) in slot.iter_mut().zip(block.as_slice()) {
                    e[lane] = v;
                }
            }
        }
        factor_lanes(&mut self.u, n, bw)
    }

    /// Solves `A x = b` in place for every lane: `x[3i + c]` holds coordinate `c` of
    /// control point `i`, one value per lane.
    pub fn solve_in_place(&self, x: &mut [Lanes]) -> Result<(), IntegratorError> {
        if x.len() != 3 * self.n || self.u.is_empty() {
            return Err(IntegratorError::SolverState(
                "solve before a successful factor, or a right-hand side of another size",
            ));
        }
        let w = self.bw + 1;
        // Uᵀ y = b.
        for i in 0..self.n {
            let mut r = [x[3 * i], x[3 * i + 1], x[3 * i + 2]];
            for k in i.saturating_sub(self.bw)..i {
                let y = [x[3 * k], x[3 * k + 1], x[3 * k + 2]];
                sub_product(&mut r, &self.u[k * w + (i - k)], &y, true);
            }
            x[3 * i..3 * i + 3].copy_from_slice(&product(&self.u[i * w], &r, false));
        }
        // U x = y.
        for i in (0..self.n).rev() {
            let mut r = [x[3 * i], x[3 * i + 1], x[3 * i + 2]];
            for j in i + 1..(i + w).min(self.n) {
                let y = [x[3 * j], x[3 * j + 1], x[3 * j + 2]];
                sub_product(&mut r, &self.u[i * w + (j - i)], &y, false);
            }
            x[3 * i..3 * i + 3].copy_from_slice(&product(&self.u[i * w], &r, true));
        }
        Ok(())
    }
}

/// `m v` (or `mᵀ v` with `transposed`), lane by lane.
#[inline(always)]
fn product(m: &Block, v: &[Lanes; 3], transposed: bool) -> [Lanes; 3] {
    let mut out = [[0.0; LANES]; 3];
    sub_product(&mut out, m, v, transposed);
    out.map(|row| row.map(|x| -x))
}

/// `r −= m v` (or `mᵀ v` with `transposed`), lane by lane.
#[inline(always)]
fn sub_product(r: &mut [Lanes; 3], m: &Block, v: &[Lanes; 3], transposed: bool) {
    for (row, out) in r.iter_mut().enumerate() {
        for (col, vc) in v.iter().enumerate() {
            let e = if transposed {
                &m[3 * row + col]
            } else {
                &m[3 * col + row]
            };
            for l in 0..LANES {
                out[l] -= e[l] * vc[l];
            }
        }
    }
}

/// `m −= aᵀ b` (3×3 blocks), lane by lane.
#[inline(always)]
fn sub_transposed_times(m: &mut Block, a: &Block, b: &Block) {
    for c in 0..3 {
        for r in 0..3 {
            let out = &mut m[3 * c + r];
            for k in 0..3 {
                let (x, y) = (&a[3 * r + k], &b[3 * c + k]);
                for l in 0..LANES {
                    out[l] -= x[l] * y[l];
                }
            }
        }
    }
}

/// `l⁻¹ m` for a lower-triangular `l` (stored as a full block), lane by lane.
#[inline(always)]
fn times(l: &Block, m: &Block) -> Block {
    let mut out = [[0.0; LANES]; 9];
    for c in 0..3 {
        for r in 0..3 {
            for k in 0..3 {
                let (x, y) = (&l[3 * k + r], &m[3 * c + k]);
                for lane in 0..LANES {
                    out[3 * c + r][lane] += x[lane] * y[lane];
                }
            }
        }
    }
    out
}

/// The inverse of the lower Cholesky factor of the symmetric 3×3 block `s`, lane by
/// lane; `None` if a pivot is not positive.
fn inverse_cholesky(s: &Block) -> Option<Block> {
    let mut out = [[0.0; LANES]; 9];
    for l in 0..LANES {
        let at = |r: usize, c: usize| s[3 * c + r][l];
        let l00 = at(0, 0).sqrt();
        let l10 = at(1, 0) / l00;
        let l20 = at(2, 0) / l00;
        let l11 = (at(1, 1) - l10 * l10).sqrt();
        let l21 = (at(2, 1) - l20 * l10) / l11;
        let l22 = (at(2, 2) - l20 * l20 - l21 * l21).sqrt();
        let (a, b, c) = (1.0 / l00, 1.0 / l11, 1.0 / l22);
        let m10 = -l10 * a * b;
        let m21 = -l21 * b * c;
        let m20 = -(l20 * a + l21 * m10) * c;
        let inverse = [a, m10, m20, 0.0, b, m21, 0.0, 0.0, c];
        if !inverse.iter().all(|x| x.is_finite()) {
            return None;
        }
        for (e, v) in out.iter_mut().zip(inverse) {
            e[l] = v;
        }
    }
    Some(out)
}

/// The factorisation of [`crate::banded_cholesky`], every lane at once.
fn factor_lanes(u: &mut [Block], n: usize, bw: usize) -> Result<(), IntegratorError> {
    let w = bw + 1;
    for i in 0..n {
        let (done, rest) = u.split_at_mut(i * w);
        let len = w.min(rest.len());
        let row = &mut rest[..len];
        let mut s = row[0];
        for k in i.saturating_sub(bw)..i {
            let uki = &done[k * w + (i - k)];
            sub_transposed_times(&mut s, uki, uki);
        }
        let linv = inverse_cholesky(&s).ok_or_else(not_definite)?;
        row[0] = linv;
        for j in i + 1..(i + w).min(n) {
            let mut m = row[j - i];
            for k in j.saturating_sub(bw)..i {
                sub_transposed_times(&mut m, &done[k * w + (i - k)], &done[k * w + (j - k)]);
            }
            row[j - i] = times(&linv, &m);
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::banded_cholesky::BandedCholesky;
    use nalgebra::Matrix3;

    /// A block-banded SPD matrix: a band of pseudo-random blocks made diagonally
    /// dominant, different per `seed`.
    fn band(n: usize, bw: usize, seed: Real) -> BlockBanded {
        let mut a = BlockBanded::zeros(n, bw);
        for i in 0..n {
            for j in i..(i + bw + 1).min(n) {
                let block = Matrix3::from_fn(|r, c| {
                    ((i * 31 + j * 17 + r * 7 + c * 3) as Real * seed).sin()
                });
                let block = if i == j {
                    block + block.transpose() + Matrix3::identity() * (12.0 * bw as Real)
                } else {
                    block
                };
                a.add_block(i, j, &block);
            }
        }
        a
    }

    #[test]
    fn every_lane_solves_like_the_scalar_factorisation() {
        let (n, bw) = (16, 5);
        let mats: Vec<BlockBanded> = (0..LANES).map(|l| band(n, bw, 0.3 + l as Real)).collect();
        let mut batched = BatchedBandedCholesky::default();
        batched
            .factor([&mats[0], &mats[1], &mats[2], &mats[3]])
            .expect("factor");
        let rhs = |l: usize, k: usize| ((k * 13 + l * 5) as Real * 0.7).cos();
        let mut x: Vec<Lanes> = (0..3 * n)
            .map(|k| std::array::from_fn(|l| rhs(l, k)))
            .collect();
        batched.solve_in_place(&mut x).expect("solve");
        for (l, m) in mats.iter().enumerate() {
            let mut solver = BandedCholesky::new();
            solver.factor(m).expect("scalar factor");
            let mut y: Vec<Real> = (0..3 * n).map(|k| rhs(l, k)).collect();
            solver.solve_in_place(&mut y).expect("scalar solve");
            let worst = y
                .iter()
                .zip(&x)
                .map(|(a, b)| (a - b[l]).abs() / a.abs().max(1.0))
                .fold(0.0, Real::max);
            assert!(worst < 1e-13, "lane {l}: {worst:e}");
        }
    }

    #[test]
    fn mismatched_shapes_and_indefinite_lanes_are_errors() {
        let (a, b) = (band(8, 3, 0.5), band(9, 3, 0.5));
        let mut batched = BatchedBandedCholesky::default();
        assert!(batched.factor([&a, &a, &b, &a]).is_err());
        let mut c = band(8, 3, 0.5);
        c.add_block(4, 4, &(Matrix3::identity() * -1e3));
        assert!(batched.factor([&a, &a, &c, &a]).is_err());
        assert!(batched.solve_in_place(&mut [[0.0; LANES]; 5]).is_err());
    }
}
