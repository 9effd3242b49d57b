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

mod kernels;
#[cfg(target_arch = "x86_64")]
mod rows;
#[cfg(test)]
mod tests;

use crate::IntegratorError;
use kernels::*;
pub(crate) use kernels::{entries, inverse_cholesky, inverse_factor, PivotArith};
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
/// only rows already final are read besides. On processors with AVX2 and FMA the
/// products are fused (one rounding each; the same algorithm).
pub(crate) fn factor_blocks(
    u: &mut [Matrix3<Real>],
    n: usize,
    bw: usize,
) -> Result<(), IntegratorError> {
    #[cfg(target_arch = "x86_64")]
    if splinerod_core::lanes::wide() {
        // SAFETY: the processor has AVX2 and FMA (checked on the line above).
        return unsafe { rows::factor_rows(u, n, bw) };
    }
    factor_blocks_with::<false>(u, n, bw)
}

/// The compiled instances of [`factor_blocks`] and [`solve_blocks`], for tests that run
/// each whatever the process's kernel set is ([`splinerod_core::kernels`]; the table of
/// every Cholesky variant, `crate::cholesky_variants`).
#[cfg(test)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Instance {
    /// The plain kernels (the portable set).
    Plain,
    /// The fused kernels on column-major blocks (the reference of the row form).
    FusedColumns,
    /// The fused kernels on row-major off-diagonal blocks (the avx2-fma set).
    FusedRows,
}

#[cfg(test)]
impl Instance {
    /// Whether this processor runs it (the fused ones need AVX2 and FMA).
    pub(crate) fn available(self) -> bool {
        self == Instance::Plain || splinerod_core::kernels::KernelSet::Avx2Fma.available()
    }

    /// Factorises the band `u` (the layout of [`factor_blocks`]) in place and solves
    /// `x` with the factor. Panics where the processor cannot run it.
    pub(crate) fn factor_and_solve(
        self,
        u: &mut [Matrix3<Real>],
        n: usize,
        bw: usize,
        x: &mut [Real],
    ) -> Result<(), IntegratorError> {
        assert!(self.available(), "{self:?} needs AVX2 and FMA");
        match self {
            Instance::Plain => {
                factor_blocks_with::<false>(u, n, bw)?;
                solve_blocks_with::<false, false>(u, n, bw, x);
            }
            // SAFETY (both): the processor has AVX2 and FMA (asserted above).
            #[cfg(target_arch = "x86_64")]
            Instance::FusedColumns => unsafe {
                factor_blocks_wide(u, n, bw)?;
                solve_blocks_with::<true, false>(u, n, bw, x);
            },
            #[cfg(target_arch = "x86_64")]
            Instance::FusedRows => unsafe {
                rows::factor_rows(u, n, bw)?;
                solve_blocks_wide(u, n, bw, x);
            },
            #[cfg(not(target_arch = "x86_64"))]
            _ => unreachable!("checked by available"),
        }
        Ok(())
    }
}

/// [`factor_blocks_with`] fused, compiled for AVX2 and FMA: the column-form fused
/// factor, which [`rows::factor_rows`] equals bit for bit (transposed; tested).
#[cfg(all(test, target_arch = "x86_64"))]
#[target_feature(enable = "avx2,fma")]
unsafe fn factor_blocks_wide(
    u: &mut [Matrix3<Real>],
    n: usize,
    bw: usize,
) -> Result<(), IntegratorError> {
    factor_blocks_with::<true>(u, n, bw)
}

/// [`factor_blocks`], its products fused with `FUSED`.
#[inline(always)]
fn factor_blocks_with<const FUSED: bool>(
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
            sub_gram_lower::<FUSED>(&mut s, &entries(&done[k * w + (i - k)]));
        }
        let linv = inverse_cholesky(&s).ok_or_else(not_definite)?;
        row[0] = Matrix3::from_column_slice(&linv);
        // Off-diagonal blocks of row i.
        for j in i + 1..(i + w).min(n) {
            let mut m = entries(&row[j - i]);
            for k in j.saturating_sub(bw)..i {
                let a = entries(&done[k * w + (i - k)]);
                sub_transposed_times::<FUSED>(&mut m, &a, &entries(&done[k * w + (j - k)]));
            }
            // U_ij = L⁻¹ m with L = U_iiᵀ lower triangular.
            row[j - i] = Matrix3::from_column_slice(&lower_times::<FUSED>(&linv, &m));
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
/// [`factor_blocks`]. The 3×3 products are written out on the stored entries
/// (measured: half the instructions of nalgebra's generic products here), and fused on
/// processors with AVX2 and FMA, where the factor's off-diagonal blocks are row-major
/// ([`rows`]).
pub(crate) fn solve_blocks(u: &[Matrix3<Real>], n: usize, bw: usize, x: &mut [Real]) {
    #[cfg(target_arch = "x86_64")]
    if splinerod_core::lanes::wide() {
        // SAFETY: the processor has AVX2 and FMA (checked on the line above).
        return unsafe { solve_blocks_wide(u, n, bw, x) };
    }
    solve_blocks_with::<false, false>(u, n, bw, x)
}

/// [`solve_blocks_with`] fused on the row-form factor, compiled for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn solve_blocks_wide(u: &[Matrix3<Real>], n: usize, bw: usize, x: &mut [Real]) {
    solve_blocks_with::<true, true>(u, n, bw, x)
}

/// Where entry `(r, c)` of an off-diagonal factor block is: `3r + c` if `ROWS` (the
/// fused factor's row-major blocks), else `3c + r` (column-major).
#[inline(always)]
fn at<const ROWS: bool>(r: usize, c: usize) -> usize {
    if ROWS {
        3 * r + c
    } else {
        3 * c + r
    }
}

/// [`solve_blocks`], its products fused with `FUSED`, the off-diagonal blocks row-major
/// with `ROWS` (the diagonal slots always column-major). The coordinates are read and
/// written as 3-vectors and each row's blocks by index, so that a row costs little
/// besides its blocks' products.
#[inline(always)]
fn solve_blocks_with<const FUSED: bool, const ROWS: bool>(
    u: &[Matrix3<Real>],
    n: usize,
    bw: usize,
    x: &mut [Real],
) {
    let w = bw + 1;
    let x = &mut points(x)[..n];
    // Uᵀ y = b: y_i = U_iiᵀ⁻¹ (b_i − Σ_{k<i} U_kiᵀ y_k).
    for i in 0..n {
        let mut r = x[i];
        for k in i.saturating_sub(bw)..i {
            let m = entries(&u[k * w + (i - k)]);
            let y = x[k];
            for (c, r) in r.iter_mut().enumerate() {
                let column = std::array::from_fn(|t| m[at::<ROWS>(t, c)]);
                *r = sub_dot::<FUSED>(*r, column, y);
            }
        }
        x[i] = lower_product::<FUSED>(&entries(&u[i * w]), r);
    }
    // U x = y: x_i = U_ii⁻¹ (y_i − Σ_{j>i} U_ij x_j).
    for i in (0..n).rev() {
        let mut r = x[i];
        for j in i + 1..(i + w).min(n) {
            let m = entries(&u[i * w + (j - i)]);
            let xj = x[j];
            for (c, r) in r.iter_mut().enumerate() {
                let row = std::array::from_fn(|t| m[at::<ROWS>(c, t)]);
                *r = sub_dot::<FUSED>(*r, row, xj);
            }
        }
        x[i] = lower_transposed_product::<FUSED>(&entries(&u[i * w]), r);
    }
}

/// Flat coordinates as the 3-vectors of their points (a trailing partial point left
/// out): `slice::as_chunks_mut`, which the minimum supported Rust version lacks.
#[inline(always)]
fn points(x: &mut [Real]) -> &mut [[Real; 3]] {
    let len = x.len() / 3;
    // SAFETY: `[Real; 3]` has `Real`'s alignment and no padding, and the first `3 len`
    // values of `x` are borrowed mutably for the lifetime of the result.
    unsafe { std::slice::from_raw_parts_mut(x.as_mut_ptr().cast::<[Real; 3]>(), len) }
}
