//! The mixed form's derivatives from its tabulated integrals ([`super::table`]): per
//! tension function `k` with derivatives \\(\\partial b_k\\), stiffness \\(c_k = EA/m_k\\)
//! and tension \\(\\lambda_k\\), the blocks
//!
//! \\[ H_{ab} \\mathrel{+}= c_k\\, \\partial_a b_k\\, \\partial_b b_k^T + \\lambda_k (G_k)_{ab}\\, I,
//! \\qquad g_a \\mathrel{+}= \\lambda_k\\, \\partial_a b_k, \\]
//!
//! and the block arithmetic the point-by-point sweep ([`super::mixed`]) shares. On an
//! open rod with the lumped form (each tension from its own moment) one plain pass
//! does it all ([`Stretching::lumped_derivatives`]); on processors with AVX2 and FMA
//! that pass runs with fused multiply-adds (detected at run time), its results equal to
//! round-off (tested in `tests/stretch_table.rs` against the sweep, and below against
//! the plain pass).

use super::seam;
use super::table::{add_times, Moment, MAX_WIDTH};
use super::Stretching;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, HessianKind, Real, Rod};

impl Stretching {
    /// [`Self::mixed_hessian`] from the tabulated integrals ([`super::table`]): per tension
    /// function, the material term \\(\\tfrac{EA}{m_k} \\partial b_k \\partial b_k^T\\), the
    /// geometric term \\(\\lambda_k G_k \\otimes I\\) and the gradient \\(\\lambda_k \\partial b_k\\).
    pub(super) fn tabulated_derivatives(
        &self,
        rod: &Rod,
        kind: HessianKind,
        gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        if self.lumped_open(rod) {
            #[cfg(target_arch = "x86_64")]
            if splinerod_core::lanes::wide() {
                // SAFETY: the processor has AVX2 and FMA (checked on the line above).
                return unsafe { self.lumped_derivatives_wide(rod, kind, gradient, hessian) };
            }
            // The same operations as below, in the same order (no merged pairs, no
            // tension solve on a lumped open rod).
            return self.lumped_derivatives::<false>(rod, kind, gradient, hessian);
        }
        self.general_derivatives(rod, kind, gradient, hessian);
    }

    /// [`Self::tabulated_derivatives`] in every case: the consistent form's tensions,
    /// a closed rod's merged pairs and seam.
    fn general_derivatives(
        &self,
        rod: &Rod,
        kind: HessianKind,
        mut gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        let merged = self.merged_weights(rod);
        let mut heads = rod.is_closed().then(seam::Heads::default);
        self.with_consistent_tensions(rod, |t| {
            self.for_each_moment(rod, |k| {
                let c = self.lumped_stiffness(merged.get(k.index).map_or(k.m, |p| p.1));
                let tension = self.tension_of(t, k.index, k.b, k.m);
                if let Some(g) = gradient.as_deref_mut() {
                    add_scaled(g, k.first, k.db, tension);
                }
                add_function_blocks::<false>(hessian, k, c, geometric_tension(kind, tension));
                if let Some(heads) = heads.as_mut() {
                    match seam::partner(rod, k.index) {
                        Some(tail) if tail > k.index => heads.keep(k.index, k.first, k.db),
                        Some(head) => {
                            seam::add_cross_term(hessian, c, heads.get(head), (k.first, k.db))
                        }
                        None => {}
                    }
                }
            });
        });
    }

    /// Whether `rod` takes the lumped form's tabulated derivatives on an open rod: the
    /// energy's own table matches it, and no tension solve or seam is involved.
    #[inline]
    fn lumped_open(&self, rod: &Rod) -> bool {
        !self.consistent() && !rod.is_closed() && self.table.matches(rod)
    }

    /// [`Self::lumped_derivatives`] with fused products, compiled for AVX2 and FMA (the
    /// same sums as [`Self::tabulated_derivatives`], each product rounded once).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn lumped_derivatives_wide(
        &self,
        rod: &Rod,
        kind: HessianKind,
        gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        self.lumped_derivatives::<true>(rod, kind, gradient, hessian);
    }

    /// [`Self::tabulated_derivatives`] where [`Self::lumped_open`] holds: per function
    /// its tension \\(\\hat\\lambda_k + EA\\, b_k/m_k\\) from its own moment, one pass.
    /// Plain loops and `#[inline(always)]` callees only, so that all of it is compiled
    /// for the caller's instruction set (fused multiply-add where `FUSED`).
    #[inline(always)]
    fn lumped_derivatives<const FUSED: bool>(
        &self,
        rod: &Rod,
        kind: HessianKind,
        mut gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        let mut scratch = [[Vector3::zeros(); MAX_WIDTH]; 2];
        for j in 0..self.table.functions() {
            let g = gradient.as_deref_mut();
            match self.table.width(j) {
                // A cubic's interior functions touch 6 points: with the width a
                // constant, every loop of their sums unrolls.
                6 => self.lumped_function::<FUSED, 6>(rod, kind, j, &mut scratch, (g, hessian)),
                _ => self.lumped_function::<FUSED, 0>(rod, kind, j, &mut scratch, (g, hessian)),
            }
        }
    }

    /// [`Self::lumped_derivatives`]' terms of function `j + 1`, whose width is `W` (if
    /// not 0; else the table's), added to the gradient (if any) and the Hessian.
    #[inline(always)]
    fn lumped_function<const FUSED: bool, const W: usize>(
        &self,
        rod: &Rod,
        kind: HessianKind,
        j: usize,
        scratch: &mut [[Vector3<Real>; MAX_WIDTH]; 2],
        (gradient, hessian): (Option<&mut [Vector3<Real>]>, &mut BlockBanded),
    ) {
        let width = if W > 0 { W } else { self.table.width(j) };
        let k = self.table.moment_at::<FUSED>(rod, (j, width), scratch);
        let c = self.lumped_stiffness(k.m);
        let tension = self.tension_of(None, k.index, k.b, k.m);
        if let Some(g) = gradient {
            for (g, v) in g[k.first..].iter_mut().zip(k.db) {
                add_times::<FUSED>(g, v, tension);
            }
        }
        add_function_blocks::<FUSED>(hessian, &k, c, geometric_tension(kind, tension));
    }
}

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
fn add_function_blocks<const FUSED: bool>(
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
        // (`Stretching::lumped_derivatives_wide`).
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Energy;
    use splinerod_core::{BSplineSpace, Material};

    /// Gradient and Hessian (dense) of `e` on `rod` by `pass`.
    fn derivatives(
        e: &Stretching,
        rod: &Rod,
        pass: impl Fn(&Stretching, &Rod, Option<&mut [Vector3<Real>]>, &mut BlockBanded),
    ) -> (Vec<Vector3<Real>>, nalgebra::DMatrix<Real>) {
        let mut g = vec![Vector3::zeros(); rod.len()];
        let mut h = BlockBanded::zeros(rod.len(), e.bandwidth(rod));
        pass(e, rod, Some(&mut g), &mut h);
        (g, h.to_dense())
    }

    #[test]
    fn the_lumped_pass_is_the_general_one_bit_for_bit_and_fused_to_round_off() {
        let material = Material {
            rest_length: 1.0,
            linear_density: 0.1,
        };
        for (degree, points) in [(2, 7), (3, 5), (3, 16), (4, 11)] {
            let basis = BSplineSpace::clamped_uniform(degree, points, 1.0).expect("basis");
            let end = Vector3::new(1.1, 0.2, -0.1);
            let mut rod =
                Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
            for (i, q) in rod.positions.iter_mut().enumerate() {
                *q += Vector3::new(0.0, 0.03 * (i as Real).sin(), 0.02 * (i as Real).cos());
            }
            let mut e = Stretching::new(250.0).expect("stretching");
            e.begin_step(&rod, 1e-3).expect("table");
            assert!(e.lumped_open(&rod));
            for kind in [HessianKind::Exact, HessianKind::Definite] {
                let general =
                    derivatives(&e, &rod, |e, r, g, h| e.general_derivatives(r, kind, g, h));
                let plain = derivatives(&e, &rod, |e, r, g, h| {
                    e.lumped_derivatives::<false>(r, kind, g, h)
                });
                assert_eq!(general, plain, "degree {degree}, {points} points");
                #[cfg(target_arch = "x86_64")]
                if splinerod_core::lanes::wide() {
                    // SAFETY: the processor has AVX2 and FMA (checked on the line above).
                    let fused = derivatives(&e, &rod, |e, r, g, h| unsafe {
                        e.lumped_derivatives_wide(r, kind, g, h)
                    });
                    let scale_h = general.1.amax();
                    assert!((&fused.1 - &general.1).amax() <= 1e-12 * scale_h);
                    let scale_g = general.0.iter().map(|v| v.amax()).fold(0.0, Real::max);
                    let gap = fused.0.iter().zip(&general.0).map(|(a, b)| (a - b).amax());
                    assert!(gap.fold(0.0, Real::max) <= 1e-12 * scale_g);
                    assert_ne!(fused.1, general.1, "the fused pass rounds differently");
                }
            }
        }
    }
}
