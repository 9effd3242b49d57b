//! The fused factorisation with its off-diagonal blocks stored **by rows** (processors
//! with AVX2 and FMA).
//!
//! Every update of the factorisation is a product \\(U_{ki}^T U_{kj}\\), whose row `r`
//! is \\(\sum_m (U_{ki})_{mr}\\, \text{row}_m(U_{kj})\\): with the rows of `U` in
//! four-wide registers (the fourth lane is a neighbour's entry, never stored) a block
//! product is nine fused multiply-adds of a broadcast entry with a row, instead of
//! 27 scalar ones. Each lane runs the scalar kernels' chain of the same products in the
//! same order (`m = 0, 1, 2`, blocks `k` ascending), so the factor is the column-form
//! fused factor's bit for bit, transposed (tested).
//!
//! Layout on exit, in place of the band: the off-diagonal slot of \\(U_{ij}\\) holds its
//! entries row-major; the diagonal slot holds \\(U_{ii}^{-T}\\) column-major, as in the
//! plain path. The solves read it with [`super::solve_blocks_with`]`::<true, true>`.

use super::kernels::{inverse_cholesky, Entries};
use super::not_definite;
use crate::IntegratorError;
use core::arch::x86_64::*;
use nalgebra::Matrix3;
use splinerod_core::simd::{load_block, store_block, Triple};
use splinerod_core::Real;

/// Three rows (or columns) of a 3×3 block, one per register.
type Rows = Triple;

/// The rows of the column-major block at `p`.
///
/// # Safety
/// As [`load_block`].
#[inline(always)]
unsafe fn load_transposed(p: *const Real) -> Rows {
    let [c0, c1, c2] = load_block(p);
    let (t0, t1) = (_mm256_unpacklo_pd(c0, c1), _mm256_unpackhi_pd(c0, c1));
    let (t2, t3) = (_mm256_unpacklo_pd(c2, c2), _mm256_unpackhi_pd(c2, c2));
    [
        _mm256_permute2f128_pd::<0x20>(t0, t2),
        _mm256_permute2f128_pd::<0x20>(t1, t3),
        _mm256_permute2f128_pd::<0x31>(t0, t2),
    ]
}

/// `s −= aᵀ b` in rows, `a` row-major at `a`: row `r` of `s` takes
/// \\(-a_{mr}\\, \text{row}_m(b)\\) for `m = 0, 1, 2`, each fused.
///
/// # Safety
/// `a` must point at 9 readable values; the processor must have AVX2 and FMA.
#[inline(always)]
unsafe fn sub_transposed_times(s: &mut Rows, a: *const Real, b: &Rows) {
    for (r, row) in s.iter_mut().enumerate() {
        for (m, b) in b.iter().enumerate() {
            *row = _mm256_fnmadd_pd(_mm256_broadcast_sd(&*a.add(3 * m + r)), *b, *row);
        }
    }
}

/// `l m` in rows for the column-major lower triangular `l`: row `r` sums
/// \\(l_{rt}\\, \text{row}_t(m)\\) for `t ≤ r`, the first a product, the others fused.
///
/// # Safety
/// The processor must have AVX2 and FMA.
#[inline(always)]
unsafe fn lower_times(l: &Entries, m: &Rows) -> Rows {
    // Plain loops, no closures: a closure is compiled without this function's target
    // features, and would call the intrinsics out of line.
    let mut out = [_mm256_setzero_pd(); 3];
    for (r, sum) in out.iter_mut().enumerate() {
        *sum = _mm256_mul_pd(_mm256_set1_pd(l[r]), m[0]);
        for (t, row) in m.iter().enumerate().take(r + 1).skip(1) {
            *sum = _mm256_fmadd_pd(_mm256_set1_pd(l[3 * t + r]), *row, *sum);
        }
    }
    out
}

/// The lower entries `(r ≥ c)` of the diagonal block, column-major, from `s`: the
/// columns of \\(A_{ii}\\) as loaded, each updated as a row by the symmetric Gram sum
/// (whose entries `(r, c)` and `(c, r)` are the same products in the same order). So
/// entry `(r, c)` is lane `r` of vector `c`: \\(A_{rc}\\) minus the sum, the lower
/// entry the plain path computes, also where assembly left \\(A_{ii}\\) asymmetric by
/// round-off. The upper entries are not read by [`inverse_cholesky`] and left zero.
///
/// # Safety
/// The processor must have AVX.
#[inline(always)]
unsafe fn lower_entries(s: &Rows) -> Entries {
    let mut lanes = [0.0; 12];
    for (c, column) in s.iter().enumerate() {
        _mm256_storeu_pd(lanes.as_mut_ptr().add(4 * c), *column);
    }
    [
        lanes[0], lanes[1], lanes[2], 0.0, lanes[5], lanes[6], 0.0, 0.0, lanes[10],
    ]
}

/// [`super::factor_blocks`] in row form (see the module docs): on entry `u[i·(bw+1) + k]`
/// holds \\(A_{i,i+k}\\) column-major, on exit \\(U_{i,i+k}\\) row-major and
/// \\(U_{ii}^{-T}\\) column-major in the diagonal slots.
///
/// # Safety
/// The processor must have AVX2 and FMA.
#[target_feature(enable = "avx2,fma")]
pub(super) unsafe fn factor_rows(
    u: &mut [Matrix3<Real>],
    n: usize,
    bw: usize,
) -> Result<(), IntegratorError> {
    let w = bw + 1;
    // The last slot read is row n − 1's diagonal.
    if n == 0 {
        return Ok(());
    }
    if u.len() < (n - 1) * w + 1 {
        return Err(IntegratorError::SolverState(
            "a band shorter than its shape",
        ));
    }
    let base = u.as_mut_ptr().cast::<Real>();
    // SAFETY (every `at`): slots k·w + (j − k) with k ≤ j < min(k + w, n) are below
    // (n − 1)·w + 1, checked above; each is 9 values.
    let at = |slot: usize| base.add(9 * slot);
    for i in 0..n {
        let mut s = load_block(at(i * w));
        for k in i.saturating_sub(bw)..i {
            let a = at(k * w + (i - k));
            sub_transposed_times(&mut s, a, &load_block(a));
        }
        let linv = inverse_cholesky(&lower_entries(&s)).ok_or_else(not_definite)?;
        std::ptr::copy_nonoverlapping(linv.as_ptr(), at(i * w), 9);
        for j in i + 1..(i + w).min(n) {
            let slot = at(i * w + (j - i));
            let mut m = load_transposed(slot);
            for k in j.saturating_sub(bw)..i {
                let b = load_block(at(k * w + (j - k)));
                sub_transposed_times(&mut m, at(k * w + (i - k)), &b);
            }
            store_block(slot, lower_times(&linv, &m));
        }
    }
    Ok(())
}
