//! The block arithmetic of the mixed form's Hessian and gradient, shared by the
//! tabulated passes ([`super::tabulated`]) and the point-by-point sweep
//! ([`super::mixed`]): per tension function `k` with derivatives \\(\\partial b_k\\),
//! stiffness \\(c_k\\) and tension \\(\\lambda_k\\), the blocks
//! \\(c_k\\, \\partial_a b_k\\, \\partial_b b_k^T + \\lambda_k (G_k)_{ab}\\, I\\) and the gradient
//! \\(\\lambda_k\\, \\partial_a b_k\\).

use super::table::Moment;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, HessianKind, Real};

/// The tension the geometric stiffness uses: all of it for the exact Hessian, only
/// its positive part for the definite one.
#[inline]
pub(super) fn geometric_tension(kind: HessianKind, tension: Real) -> Real {
    match kind {
        HessianKind::Exact => tension,
        _ => tension.max(0.0),
    }
}

/// `gradient[first + a] += tension · db[a]`.
#[inline]
pub(super) fn add_scaled(
    gradient: &mut [Vector3<Real>],
    first: usize,
    db: &[Vector3<Real>],
    tension: Real,
) {
    for (g, v) in gradient[first..].iter_mut().zip(db) {
        *g += v * tension;
    }
}

/// Adds one tension function's material and geometric stiffness,
/// \\(c\\, \\partial b_a \\partial b_b^T + \\lambda (G_k)_{ab} I\\) at blocks `(first + a, first + b)`,
/// `a ≤ b`, in one pass over its blocks of the band (the same sums, in the same order,
/// as [`add_outer_products`] then [`add_scaled_identities`], which take a band too
/// narrow for it).
/// With `FUSED` (processors with AVX2 and FMA) the blocks are updated in four-wide
/// registers (`add_function_blocks_wide`).
#[inline(always)]
pub(super) fn add_function_blocks<const FUSED: bool>(
    hessian: &mut BlockBanded,
    k: &Moment<'_>,
    c: Real,
    lambda: Real,
) {
    let v = k.db;
    if v.len() > hessian.bandwidth() + 1 {
        add_outer_products(hessian, k.first, c, v);
        add_scaled_identities(hessian, k, lambda);
        return;
    }
    #[cfg(target_arch = "x86_64")]
    if FUSED {
        // SAFETY: the fused pass runs only where the processor has AVX2 and FMA
        // (`Stretching::fused_derivatives_wide`).
        unsafe { add_function_blocks_wide(hessian, k, c, lambda) };
        return;
    }
    for (a, va) in v.iter().enumerate() {
        let u = va * c;
        let g = &k.g[k.rows[a]..];
        let row = hessian.band_row_mut(k.first + a);
        for ((block, vb), &gab) in row.iter_mut().zip(&v[a..]).zip(g) {
            // The block summed in registers and stored once (adding `d` to the stored
            // diagonal would reload entries just stored, and wait on the store).
            let mut sum = *block;
            add_rank_one(&mut sum, &u, vb);
            let d = lambda * gab;
            let e = sum.as_mut_slice();
            e[0] += d;
            e[4] += d;
            e[8] += d;
            *block = sum;
        }
    }
}

/// [`add_function_blocks`] fused, a block's columns in four-wide registers
/// ([`splinerod_core::simd`]): column `c` takes \\(c\\,\\partial_a b\\, (\\partial_b b)_c\\) in
/// one fused multiply-add, then its diagonal entry \\(\\lambda (G_k)_{ab}\\) (and −0
/// elsewhere, which leaves every value as it is): the same operations, lane by lane, as
/// the scalar fused pass.
///
/// # Safety
/// The processor must have AVX2 and FMA; the band must be wide enough for the function.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn add_function_blocks_wide(
    hessian: &mut BlockBanded,
    k: &Moment<'_>,
    c: Real,
    lambda: Real,
) {
    use core::arch::x86_64::*;
    use splinerod_core::simd::{add_diagonal, load3, load_block, store_block};
    let v = k.db;
    // Plain loops, no closures (see `splinerod_core::simd`).
    for (a, va) in v.iter().enumerate() {
        let u = _mm256_mul_pd(load3(va.as_ptr()), _mm256_set1_pd(c));
        let g = &k.g[k.rows[a]..];
        let row = hessian.band_row_mut(k.first + a);
        for ((block, vb), &gab) in row.iter_mut().zip(&v[a..]).zip(g) {
            let p = block.as_mut_ptr();
            let mut columns = load_block(p);
            for (column, &vbc) in columns.iter_mut().zip(vb.iter()) {
                *column = _mm256_fmadd_pd(u, _mm256_set1_pd(vbc), *column);
            }
            add_diagonal(&mut columns, lambda * gab);
            store_block(p, columns);
        }
    }
}

/// Adds \\(\\lambda (G_k)_{ab} I\\) at blocks `(first + a, first + b)`, `a ≤ b`, into the
/// band (or block by block where it is narrower, see [`add_any`]).
#[inline]
fn add_scaled_identities(hessian: &mut BlockBanded, k: &Moment<'_>, lambda: Real) {
    let width = k.db.len();
    let wide = width <= hessian.bandwidth() + 1;
    for a in 0..width {
        if wide {
            let row = hessian.band_row_mut(k.first + a);
            for (b, block) in (a..width).zip(row.iter_mut()) {
                let g = lambda * k.entry(a, b);
                block[(0, 0)] += g;
                block[(1, 1)] += g;
                block[(2, 2)] += g;
            }
        } else {
            for b in a..width {
                let block = Matrix3::identity() * (lambda * k.entry(a, b));
                add_any(hessian, k.first + a, k.first + b, &block);
            }
        }
    }
}

/// Adds \\(c\\, v_a v_b^T\\) at blocks `(first + a, first + b)` for every pair `a ≤ b` of
/// `v`: one tension function's material stiffness. Row by row into the band when it is
/// wide enough (no per-block bounds check), else block by block (far blocks for a matrix
/// sized narrower, see [`add_any`]).
#[inline]
pub(super) fn add_outer_products(
    hessian: &mut BlockBanded,
    first: usize,
    c: Real,
    v: &[Vector3<Real>],
) {
    if v.len() <= hessian.bandwidth() + 1 {
        for (a, va) in v.iter().enumerate() {
            let u = va * c;
            let row = hessian.band_row_mut(first + a);
            for (block, vb) in row.iter_mut().zip(&v[a..]) {
                add_rank_one(block, &u, vb);
            }
        }
    } else {
        for (a, va) in v.iter().enumerate() {
            let u = va * c;
            for (b, vb) in v.iter().enumerate().skip(a) {
                add_any(hessian, first + a, first + b, &(u * vb.transpose()));
            }
        }
    }
}

/// `block += u vᵀ`, written out (the compiler keeps it in registers; a temporary 3×3
/// product through nalgebra's operators was measured 2–3 times slower here). The
/// fused pass does this in four-wide registers instead (`add_function_blocks_wide`).
#[inline(always)]
fn add_rank_one(block: &mut Matrix3<Real>, u: &Vector3<Real>, v: &Vector3<Real>) {
    // Column-major: entry (r, c) at 3c + r.
    let e = block.as_mut_slice();
    for (column, &vc) in e.chunks_exact_mut(3).zip(v.iter()) {
        for (x, &ur) in column.iter_mut().zip(u.iter()) {
            *x += ur * vc;
        }
    }
}

/// Adds a block inside the band, or as a far block for a matrix sized with a narrower
/// band than [`crate::Energy::bandwidth`] (a caller that sized it by the degree).
#[inline]
fn add_any(hessian: &mut BlockBanded, i: usize, j: usize, block: &Matrix3<Real>) {
    if j - i <= hessian.bandwidth() {
        hessian.add_block(i, j, block);
    } else {
        hessian.add_coupling(i, j, block);
    }
}
