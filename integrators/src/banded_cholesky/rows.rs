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
use splinerod_core::Real;

/// Three rows (or columns) of a 3×3 block, one per register.
type Rows = [__m256d; 3];

/// The three 3-vectors stored one after the other at `p` (the rows of a row-major
/// block, the columns of a column-major one). Lane 3 of each holds the next entry.
///
/// # Safety
/// `p` must point at 9 readable values; the processor must have AVX2.
#[inline(always)]
unsafe fn load_rows(p: *const Real) -> Rows {
    // The third vector ends the block: loaded from one entry earlier and shifted down.
    let last = _mm256_permute4x64_pd::<0b11_11_10_01>(_mm256_loadu_pd(p.add(5)));
    [_mm256_loadu_pd(p), _mm256_loadu_pd(p.add(3)), last]
}

/// Writes three 3-vectors one after the other at `p` (9 values; the lanes 3 are
/// overwritten by the next vector or not stored).
///
/// # Safety
/// `p` must point at 9 writable values; the processor must have AVX2.
#[inline(always)]
unsafe fn store_rows(p: *mut Real, rows: Rows) {
    _mm256_storeu_pd(p, rows[0]);
    _mm256_storeu_pd(p.add(3), rows[1]);
    _mm_storeu_pd(p.add(6), _mm256_castpd256_pd128(rows[2]));
    _mm_store_sd(p.add(8), _mm256_extractf128_pd::<1>(rows[2]));
}

/// The rows of the column-major block at `p`.
///
/// # Safety
/// As [`load_rows`].
#[inline(always)]
unsafe fn load_transposed(p: *const Real) -> Rows {
    let [c0, c1, c2] = load_rows(p);
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

/// The lower entries of the symmetric block whose rows are `s`, column-major (the
/// upper entries are not read by [`inverse_cholesky`] and left zero).
///
/// # Safety
/// The processor must have AVX.
#[inline(always)]
unsafe fn lower_entries(s: &Rows) -> Entries {
    let mut rows = [0.0; 12];
    for (r, row) in s.iter().enumerate() {
        _mm256_storeu_pd(rows.as_mut_ptr().add(4 * r), *row);
    }
    [
        rows[0], rows[4], rows[8], 0.0, rows[5], rows[9], 0.0, 0.0, rows[10],
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
        let mut s = load_rows(at(i * w));
        for k in i.saturating_sub(bw)..i {
            let a = at(k * w + (i - k));
            sub_transposed_times(&mut s, a, &load_rows(a));
        }
        let linv = inverse_cholesky(&lower_entries(&s)).ok_or_else(not_definite)?;
        std::ptr::copy_nonoverlapping(linv.as_ptr(), at(i * w), 9);
        for j in i + 1..(i + w).min(n) {
            let slot = at(i * w + (j - i));
            let mut m = load_transposed(slot);
            for k in j.saturating_sub(bw)..i {
                let b = load_rows(at(k * w + (j - k)));
                sub_transposed_times(&mut m, at(k * w + (i - k)), &b);
            }
            store_rows(slot, lower_times(&linv, &m));
        }
    }
    Ok(())
}
