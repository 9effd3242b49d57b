//! Cholesky factorisation \\(A = U^T U\\) of a symmetric positive definite 3×3-block
//! banded matrix ([`BlockBanded`]) in its own storage layout: `U` is upper block-banded
//! with the same bandwidth (no fill-in), computed block by block with fixed-size 3×3
//! arithmetic,
//!
//! \\[ U_{ii}^T U_{ii} = A_{ii} - \sum_{k<i} U_{ki}^T U_{ki}, \qquad
//! U_{ij} = U_{ii}^{-T}\Big(A_{ij} - \sum_{k<i} U_{ki}^T U_{kj}\Big)\ (i < j \le i + b), \\]
//!
//! then solved by \\(U^T y = r\\), \\(U x = y\\). No symbolic phase and no indirection:
//! O(n b²) flops, all on contiguous blocks. An alternative to the general sparse
//! Cholesky for the banded Newton matrices of a single rod; a matrix with far blocks
//! (self-contact) is refused with an error, since they would fill in the band's gaps:
//! [`crate::linear::LinearSolver`] sends those to the sparse path.

use crate::IntegratorError;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, Real};

/// The factor `U` of a block-banded SPD matrix.
#[derive(Debug, Clone, Default)]
pub struct BandedCholesky {
    n: usize,
    bw: usize,
    /// `U_{i,i+k}` at `i·(bw+1) + k`, `k ≥ 1`; the diagonal slots hold \\(U_{ii}^{-T}\\)
    /// (lower triangular), so that both the factorisation's off-diagonal blocks and the
    /// solves multiply instead of dividing.
    u: Vec<Matrix3<Real>>,
    factored: bool,
}

fn not_definite() -> IntegratorError {
    IntegratorError::NotPositiveDefinite {
        context: "banded Cholesky",
    }
}

/// `(n, bandwidth)` of `a`; an error if it has far blocks, which a band cannot hold
/// (the sparse path takes those).
pub(crate) fn band_shape(a: &BlockBanded) -> Result<(usize, usize), IntegratorError> {
    if a.has_far_blocks() {
        return Err(IntegratorError::SolverState(
            "a banded factorisation cannot hold far blocks (use the sparse path)",
        ));
    }
    Ok((a.dim(), a.bandwidth()))
}

/// Empties `blocks` and refills it with `len` zero blocks (no allocation once sized).
pub(crate) fn reset_blocks(blocks: &mut Vec<Matrix3<Real>>, len: usize) {
    blocks.clear();
    blocks.resize(len, Matrix3::zeros());
}

/// Runs `solve` on each right-hand side of `rhs` (columns of `3n` values), after
/// checking that a factorisation of an `n`-block matrix is in place.
pub(crate) fn for_each_rhs(
    factored: bool,
    n: usize,
    rhs: &mut [Real],
    solve: impl Fn(&mut [Real]),
) -> Result<(), IntegratorError> {
    let dofs = 3 * n;
    if !factored || dofs == 0 || rhs.len() % dofs != 0 {
        return Err(IntegratorError::SolverState(
            "solve before a successful factor",
        ));
    }
    rhs.chunks_exact_mut(dofs).for_each(solve);
    Ok(())
}

/// A 3×3 block's entries, column-major: `(r, c)` at `3c + r` (the storage of
/// [`Matrix3`]).
type Entries = [Real; 9];

/// The entries of `m`.
#[inline(always)]
pub(crate) fn entries(m: &Matrix3<Real>) -> Entries {
    let s = m.as_slice();
    std::array::from_fn(|e| s[e])
}

/// Inverse of a lower triangular 3×3 matrix with a non-zero diagonal (forward
/// substitution written out).
#[cfg(test)]
fn lower_inverse(l: &Matrix3<Real>) -> Matrix3<Real> {
    let at = |r: usize, c: usize| l[(r, c)];
    let lower = [at(0, 0), at(1, 0), at(2, 0), at(1, 1), at(2, 1), at(2, 2)];
    Matrix3::from_column_slice(&lower_inverse_entries(lower))
}

/// The entries of \(L^{-1}\) for the lower triangular `L` given as
/// `[l00, l10, l20, l11, l21, l22]`.
#[inline(always)]
fn lower_inverse_entries([l00, l10, l20, l11, l21, l22]: [Real; 6]) -> Entries {
    let (a, b, c) = (1.0 / l00, 1.0 / l11, 1.0 / l22);
    let m10 = -l10 * a * b;
    let m21 = -l21 * b * c;
    let m20 = -(l20 * a + l21 * m10) * c;
    [a, m10, m20, 0.0, b, m21, 0.0, 0.0, c]
}

/// \(L^{-1}\) of the Cholesky factor \(L L^T = s\) of a symmetric 3×3 block, with
/// the arithmetic of nalgebra's `Matrix3::cholesky` (column by column, each pivot
/// square-rooted when positive), or `None` if a pivot is not positive or the inverse
/// not finite.
#[inline(always)]
pub(crate) fn inverse_cholesky(s: &Entries) -> Option<Entries> {
    let pivot = |d: Real| (d > 0.0).then(|| d.sqrt());
    let l00 = pivot(s[0])?;
    let (l10, l20) = (s[1] / l00, s[2] / l00);
    let l11 = pivot(-l10 * l10 + s[4])?;
    let l21 = (-l10 * l20 + s[5]) / l11;
    let l22 = pivot(-l21 * l21 + (-l20 * l20 + s[8]))?;
    let inverse = lower_inverse_entries([l00, l10, l20, l11, l21, l22]);
    inverse.iter().all(|x| x.is_finite()).then_some(inverse)
}

/// `s −= aᵀ b` for 3×3 blocks: each entry of the product a dot product of two columns,
/// \((a_0 b_0 + a_1 b_1) + a_2 b_2\), then subtracted (nalgebra's order).
#[inline(always)]
fn sub_transposed_times(s: &mut Entries, a: &Entries, b: &Entries) {
    for c in 0..3 {
        for r in 0..3 {
            let p = a[3 * r] * b[3 * c] + a[3 * r + 1] * b[3 * c + 1] + a[3 * r + 2] * b[3 * c + 2];
            s[3 * c + r] -= p;
        }
    }
}

/// `a b` for 3×3 blocks, each entry \((a_{r0} b_{0c} + a_{r1} b_{1c}) + a_{r2} b_{2c}\)
/// (nalgebra's order).
#[inline(always)]
fn times(a: &Entries, b: &Entries) -> Entries {
    std::array::from_fn(|e| {
        let (r, c) = (e % 3, e / 3);
        a[r] * b[3 * c] + a[3 + r] * b[3 * c + 1] + a[6 + r] * b[3 * c + 2]
    })
}

impl BandedCholesky {
    /// An empty factor.
    pub fn new() -> Self {
        Self::default()
    }

    /// Factorises `a` (reusing the storage when the size allows). Errors with
    /// [`IntegratorError::SolverState`] if `a` has far blocks, which a band cannot hold.
    pub fn factor(&mut self, a: &BlockBanded) -> Result<(), IntegratorError> {
        self.factored = false;
        let (n, bw) = band_shape(a)?;
        (self.n, self.bw) = (n, bw);
        self.u.clear();
        self.u.extend_from_slice(a.band_blocks());
        factor_blocks(&mut self.u, n, bw)?;
        self.factored = true;
        Ok(())
    }

    /// Solves `A x = b` in place for `k = rhs.len() / (3n)` right-hand sides stored
    /// column after column (3 coordinates per control point).
    pub fn solve_in_place(&self, rhs: &mut [Real]) -> Result<(), IntegratorError> {
        for_each_rhs(self.factored, self.n, rhs, |column| self.solve_one(column))
    }

    fn solve_one(&self, x: &mut [Real]) {
        solve_blocks(&self.u, self.n, self.bw, x);
    }
}

/// Factorises a band in place: on entry `u[i·(bw+1) + k]` holds \\(A_{i,i+k}\\) (the
/// layout of [`BlockBanded`]'s band), on exit \\(U_{i,i+k}\\), with the diagonal slots
/// holding \\(U_{ii}^{-T}\\). Each block of `A` is read before its slot is written, and
/// only rows already final are read besides.
pub(crate) fn factor_blocks(
    u: &mut [Matrix3<Real>],
    n: usize,
    bw: usize,
) -> Result<(), IntegratorError> {
    let w = bw + 1;
    for i in 0..n {
        // Rows above are final (read only); row i is being written.
        let (done, rest) = u.split_at_mut(i * w);
        let len = w.min(rest.len());
        let row = &mut rest[..len];
        // Diagonal block.
        let mut s = entries(&row[0]);
        for k in i.saturating_sub(bw)..i {
            let uki = entries(&done[k * w + (i - k)]);
            sub_transposed_times(&mut s, &uki, &uki);
        }
        let linv = inverse_cholesky(&s).ok_or_else(not_definite)?;
        row[0] = Matrix3::from_column_slice(&linv);
        // Off-diagonal blocks of row i.
        for j in i + 1..(i + w).min(n) {
            let mut m = entries(&row[j - i]);
            for k in j.saturating_sub(bw)..i {
                let a = entries(&done[k * w + (i - k)]);
                sub_transposed_times(&mut m, &a, &entries(&done[k * w + (j - k)]));
            }
            // U_ij = L⁻¹ m with L = U_iiᵀ lower triangular.
            row[j - i] = Matrix3::from_column_slice(&times(&linv, &m));
        }
    }
    Ok(())
}

/// The 3-vector of control point `i` in a flat array of coordinates.
#[inline]
pub(crate) fn get3(x: &[Real], i: usize) -> Vector3<Real> {
    Vector3::new(x[3 * i], x[3 * i + 1], x[3 * i + 2])
}

/// Writes the 3-vector of control point `i` into a flat array of coordinates.
#[inline]
pub(crate) fn set3(x: &mut [Real], i: usize, v: Vector3<Real>) {
    x[3 * i..3 * i + 3].copy_from_slice(v.as_slice());
}

/// Solves `A x = b` in place for one right-hand side with the factor of
/// [`factor_blocks`]. The 3×3 products are written out on the column-major storage
/// (measured: half the instructions of nalgebra's generic products here).
pub(crate) fn solve_blocks(u: &[Matrix3<Real>], n: usize, bw: usize, x: &mut [Real]) {
    let w = bw + 1;
    // Uᵀ y = b: y_i = U_iiᵀ⁻¹ (b_i − Σ_{k<i} U_kiᵀ y_k).
    for i in 0..n {
        let (done, rest) = x.split_at_mut(3 * i);
        let mut r = [rest[0], rest[1], rest[2]];
        let lo = i.saturating_sub(bw);
        for (k, y) in (lo..i).zip(done[3 * lo..].chunks_exact(3)) {
            sub_transposed_product(&mut r, &u[k * w + (i - k)], y);
        }
        rest[..3].copy_from_slice(&product(&u[i * w], &r));
    }
    // U x = y: x_i = U_ii⁻¹ (y_i − Σ_{j>i} U_ij x_j).
    for i in (0..n).rev() {
        let (head, later) = x.split_at_mut(3 * i + 3);
        let own = &mut head[3 * i..];
        let mut r = [own[0], own[1], own[2]];
        let row = &u[i * w + 1..(i * w + w).min(u.len())];
        for (block, xj) in row.iter().zip(later[..3 * (n - i - 1)].chunks_exact(3)) {
            sub_product(&mut r, block, xj);
        }
        own.copy_from_slice(&transposed_product(&u[i * w], &r));
    }
}

/// `m v` on the column-major entries.
#[inline(always)]
fn product(m: &Matrix3<Real>, v: &[Real]) -> [Real; 3] {
    let s = m.as_slice();
    [
        s[0] * v[0] + s[3] * v[1] + s[6] * v[2],
        s[1] * v[0] + s[4] * v[1] + s[7] * v[2],
        s[2] * v[0] + s[5] * v[1] + s[8] * v[2],
    ]
}

/// `mᵀ v` on the column-major entries.
#[inline(always)]
fn transposed_product(m: &Matrix3<Real>, v: &[Real]) -> [Real; 3] {
    let s = m.as_slice();
    [
        s[0] * v[0] + s[1] * v[1] + s[2] * v[2],
        s[3] * v[0] + s[4] * v[1] + s[5] * v[2],
        s[6] * v[0] + s[7] * v[1] + s[8] * v[2],
    ]
}

/// `r −= m v`.
#[inline(always)]
fn sub_product(r: &mut [Real; 3], m: &Matrix3<Real>, v: &[Real]) {
    let p = product(m, v);
    r.iter_mut().zip(p).for_each(|(r, p)| *r -= p);
}

/// `r −= mᵀ v`.
#[inline(always)]
fn sub_transposed_product(r: &mut [Real; 3], m: &Matrix3<Real>, v: &[Real]) {
    let p = transposed_product(m, v);
    r.iter_mut().zip(p).for_each(|(r, p)| *r -= p);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Pseudo-random 3×3 blocks: `k`-th of a fixed sequence.
    fn block(k: usize) -> Matrix3<Real> {
        Matrix3::from_fn(|r, c| ((k * 9 + 3 * c + r) as Real * 0.731 + 0.2).sin() * 3.7)
    }

    #[test]
    fn the_written_out_block_arithmetic_is_nalgebras_bit_for_bit() {
        let bits = |e: &[Real]| e.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        for k in 0..200 {
            let (a, b, s) = (block(3 * k), block(3 * k + 1), block(3 * k + 2));
            let mut ours = entries(&s);
            sub_transposed_times(&mut ours, &entries(&a), &entries(&b));
            assert_eq!(bits(&ours), bits((s - a.tr_mul(&b)).as_slice()));
            assert_eq!(
                bits(&times(&entries(&a), &entries(&b))),
                bits((a * b).as_slice())
            );
            let spd = a.tr_mul(&a) + Matrix3::identity() * 0.1 * k as Real;
            let expected = spd.cholesky().map(|c| lower_inverse(&c.l()));
            let ours = inverse_cholesky(&entries(&spd));
            match (expected, ours) {
                (Some(e), Some(o)) => assert_eq!(bits(e.as_slice()), bits(&o)),
                (e, o) => assert_eq!(e.is_some(), o.is_some(), "block {k}"),
            }
        }
    }

    #[test]
    fn indefinite_and_zero_pivots_are_refused() {
        let mut s = entries(&Matrix3::identity());
        s[4] = -1.0;
        assert!(inverse_cholesky(&s).is_none());
        s[4] = 0.0;
        assert!(inverse_cholesky(&s).is_none());
        s[4] = Real::NAN;
        assert!(inverse_cholesky(&s).is_none());
    }
}
