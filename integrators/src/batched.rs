//! Banded Cholesky factorisation of [`LANES`] block-banded matrices of the same shape at
//! once, structure of arrays: every scalar of a 3×3 block holds one value per matrix
//! (lane), so each arithmetic operation of [`crate::BandedCholesky`]'s recursion
//!
//! \\[ U_{ii}^T U_{ii} = A_{ii} - \sum_{k<i} U_{ki}^T U_{ki}, \qquad
//! U_{ij} = U_{ii}^{-T}\Big(A_{ij} - \sum_{k<i} U_{ki}^T U_{kj}\Big) \\]
//!
//! runs over the lanes in one loop the compiler vectorises. It is the linear algebra of
//! batched ensemble steps (#17: members that share a basis have Newton matrices of the
//! same band); each lane's result equals the scalar factorisation's up to round-off.

use crate::banded_cholesky::{inverse_factor, PivotArith};
use crate::IntegratorError;
use splinerod_core::lanes::{LaneBlock, ZERO};
use splinerod_core::{BlockBanded, LaneBand};
pub use splinerod_core::{Lanes, LANES};

/// A 3×3 block per lane, column-major: entry `(r, c)` at `3c + r`.
type Block = LaneBlock;

/// The factors `U` of [`LANES`] block-banded SPD matrices of the same size and bandwidth.
#[derive(Debug, Clone, Default)]
pub struct BatchedBandedCholesky {
    n: usize,
    bw: usize,
    /// `U_{i,i+k}` at `i·(bw+1) + k`; the diagonal slots hold \\(U_{ii}^{-T}\\) (lower
    /// triangular), as in [`crate::banded_cholesky`].
    u: LaneBand,
    factored: bool,
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
        let mut band = std::mem::take(&mut self.u);
        band.reset(n, bw);
        for i in 0..n {
            for (k, slot) in band.row_mut(i).iter_mut().enumerate() {
                for (lane, m) in a.iter().enumerate() {
                    for (e, &v) in slot.iter_mut().zip(m.upper(i, k).as_slice()) {
                        e[lane] = v;
                    }
                }
            }
        }
        self.u = band;
        self.factor_in_place()
            .iter()
            .all(|&ok| ok)
            .then_some(())
            .ok_or_else(not_definite)
    }

    /// Factorises the lane matrices of `a`; returns per lane whether it was positive
    /// definite. A lane that was not holds a factor of no use (finite, with unit pivots
    /// from its failure on), and [`Self::solve_in_place`] gives it a meaningless step.
    ///
    /// The factor takes `a`'s storage, and `a` is left with the previous factor's (of no
    /// use but to be reset and assembled again): no copy, no allocation.
    pub fn factor_band(&mut self, a: &mut LaneBand) -> [bool; LANES] {
        std::mem::swap(&mut self.u, a);
        self.factor_in_place()
    }

    /// Gives the factor's storage back to `a` (after the solves that needed it), taking
    /// `a`'s in exchange: a Newton loop that factors, solves and releases each iteration
    /// assembles into one band only, a working set half the size. The factor is gone.
    pub fn release_band(&mut self, a: &mut LaneBand) {
        std::mem::swap(&mut self.u, a);
        self.factored = false;
    }

    fn factor_in_place(&mut self) -> [bool; LANES] {
        (self.n, self.bw) = (self.u.dim(), self.u.bandwidth());
        self.factored = true;
        #[cfg(target_arch = "x86_64")]
        if splinerod_core::lanes::wide() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            return unsafe { factor_lanes_wide(&mut self.u, self.n, self.bw) };
        }
        factor_lanes::<false>(&mut self.u, self.n, self.bw)
    }

    /// Solves `A x = b` in place for every lane: `x[3i + c]` holds coordinate `c` of
    /// control point `i`, one value per lane.
    pub fn solve_in_place(&self, x: &mut [Lanes]) -> Result<(), IntegratorError> {
        if x.len() != 3 * self.n || !self.factored {
            return Err(IntegratorError::SolverState(
                "solve before a successful factor, or a right-hand side of another size",
            ));
        }
        #[cfg(target_arch = "x86_64")]
        if splinerod_core::lanes::wide() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            unsafe { self.solve_wide(x) };
            return Ok(());
        }
        self.substitute::<false>(x);
        Ok(())
    }

    /// [`Self::substitute`] compiled for AVX2 with fused multiply-add.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn solve_wide(&self, x: &mut [Lanes]) {
        self.substitute::<true>(x);
    }

    /// The two triangular solves with the factor.
    #[inline(always)]
    fn substitute<const FUSED: bool>(&self, x: &mut [Lanes]) {
        let w = self.bw + 1;
        let u = self.u.blocks();
        // Uᵀ y = b.
        for i in 0..self.n {
            let mut r = [x[3 * i], x[3 * i + 1], x[3 * i + 2]];
            for k in i.saturating_sub(self.bw)..i {
                let y = [x[3 * k], x[3 * k + 1], x[3 * k + 2]];
                sub_product::<FUSED>(&mut r, &u[k * w + (i - k)], &y, true);
            }
            x[3 * i..3 * i + 3].copy_from_slice(&product::<FUSED>(&u[i * w], &r, false));
        }
        // U x = y.
        for i in (0..self.n).rev() {
            let mut r = [x[3 * i], x[3 * i + 1], x[3 * i + 2]];
            for j in i + 1..(i + w).min(self.n) {
                let y = [x[3 * j], x[3 * j + 1], x[3 * j + 2]];
                sub_product::<FUSED>(&mut r, &u[i * w + (j - i)], &y, false);
            }
            x[3 * i..3 * i + 3].copy_from_slice(&product::<FUSED>(&u[i * w], &r, true));
        }
    }
}

/// `acc − a · b`, lane by lane (one rounding when `FUSED`).
#[inline(always)]
fn sub_mul<const FUSED: bool>(mut acc: Lanes, a: Lanes, b: Lanes) -> Lanes {
    for l in 0..LANES {
        acc[l] = if FUSED {
            (-a[l]).mul_add(b[l], acc[l])
        } else {
            acc[l] - a[l] * b[l]
        };
    }
    acc
}

/// `m v` (or `mᵀ v` with `transposed`), lane by lane.
#[inline(always)]
fn product<const FUSED: bool>(m: &Block, v: &[Lanes; 3], transposed: bool) -> [Lanes; 3] {
    // The sums of `sub_product` from zero, negated: the same roundings (rounding to
    // nearest is symmetric), without a pass to negate them. Plain loops, no closures: a
    // closure is compiled without the caller's target features and, when not inlined
    // (measured: it was not after unrelated changes elsewhere in the crate), its
    // products run as scalar SSE and library calls.
    let mut out = [[0.0; LANES]; 3];
    for (row, acc) in out.iter_mut().enumerate() {
        *acc = splinerod_core::lanes::mul(entry(m, row, 0, transposed), v[0]);
        for (col, vc) in v.iter().enumerate().skip(1) {
            splinerod_core::lanes::fma::<FUSED>(acc, entry(m, row, col, transposed), *vc);
        }
    }
    out
}

/// Entry `(row, col)` of the column-major block `m` (of `mᵀ` with `transposed`).
#[inline(always)]
fn entry(m: &Block, row: usize, col: usize, transposed: bool) -> Lanes {
    if transposed {
        m[3 * row + col]
    } else {
        m[3 * col + row]
    }
}

/// `r −= m v` (or `mᵀ v` with `transposed`), lane by lane.
#[inline(always)]
fn sub_product<const FUSED: bool>(r: &mut [Lanes; 3], m: &Block, v: &[Lanes; 3], transposed: bool) {
    for (row, out) in r.iter_mut().enumerate() {
        let mut acc = *out;
        for (col, vc) in v.iter().enumerate() {
            let e = if transposed {
                m[3 * row + col]
            } else {
                m[3 * col + row]
            };
            acc = sub_mul::<FUSED>(acc, e, *vc);
        }
        *out = acc;
    }
}

/// `m −= aᵀ b` (3×3 blocks), lane by lane, each entry summed in a register.
#[inline(always)]
fn sub_transposed_times<const FUSED: bool>(m: &mut Block, a: &Block, b: &Block) {
    for c in 0..3 {
        for r in 0..3 {
            let mut acc = m[3 * c + r];
            for k in 0..3 {
                acc = sub_mul::<FUSED>(acc, a[3 * r + k], b[3 * c + k]);
            }
            m[3 * c + r] = acc;
        }
    }
}

/// `l⁻¹ m` for a lower-triangular `l` (stored as a full block), lane by lane.
#[inline(always)]
fn times<const FUSED: bool>(l: &Block, m: &Block) -> Block {
    let mut out = [ZERO; 9];
    for c in 0..3 {
        for r in 0..3 {
            let mut acc = ZERO;
            for k in 0..3 {
                acc = sub_mul::<FUSED>(acc, l[3 * k + r], m[3 * c + k]);
            }
            out[3 * c + r] = acc.map(|x| -x);
        }
    }
    out
}

/// Lane by lane, as plain loops over the lanes (which vectorise; array `map` and
/// closures did not, and left the pivots as scalar code).
impl PivotArith for Lanes {
    #[inline(always)]
    fn mul(mut self, b: Self) -> Self {
        for l in 0..LANES {
            self[l] *= b[l];
        }
        self
    }
    #[inline(always)]
    fn add(mut self, b: Self) -> Self {
        for l in 0..LANES {
            self[l] += b[l];
        }
        self
    }
    #[inline(always)]
    fn sub(mut self, b: Self) -> Self {
        for l in 0..LANES {
            self[l] -= b[l];
        }
        self
    }
    #[inline(always)]
    fn div(mut self, b: Self) -> Self {
        for l in 0..LANES {
            self[l] /= b[l];
        }
        self
    }
    #[inline(always)]
    fn sqrt(mut self) -> Self {
        for l in 0..LANES {
            self[l] = self[l].sqrt();
        }
        self
    }
    #[inline(always)]
    fn neg(mut self) -> Self {
        for l in 0..LANES {
            self[l] = -self[l];
        }
        self
    }
    #[inline(always)]
    fn one() -> Self {
        [1.0; LANES]
    }
}

/// The inverse of the lower Cholesky factor of the symmetric 3×3 block `s`, lane by
/// lane; a lane whose leading minors are not positive gets the identity and `false` in
/// `ok`. Each operation runs over the lanes at once (square roots and divisions
/// included), each lane with the arithmetic of the scalar factor
/// ([`crate::banded_cholesky::inverse_factor`]).
#[inline(always)]
fn inverse_cholesky(s: &Block, ok: &mut [bool; LANES]) -> Block {
    let ([a, m10, m20, b, m21, c], minors) = inverse_factor([s[0], s[1], s[2], s[4], s[5], s[8]]);
    let mut out = [a, m10, m20, ZERO, b, m21, ZERO, ZERO, c];
    // Per lane: definite and finite (plain loops over the lanes, which vectorise).
    let mut good = *ok;
    for m in &minors {
        for l in 0..LANES {
            good[l] &= m[l] > 0.0;
        }
    }
    for x in &out {
        for l in 0..LANES {
            good[l] &= x[l].is_finite();
        }
    }
    if good != [true; LANES] {
        for l in (0..LANES).filter(|&l| !good[l]) {
            ok[l] = false;
            for (e, v) in out
                .iter_mut()
                .zip([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0])
            {
                e[l] = v;
            }
        }
    }
    out
}

/// [`factor_lanes`] compiled for AVX2 with fused multiply-add (four lanes per
/// instruction instead of two, one instruction per multiply-add).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn factor_lanes_wide(band: &mut LaneBand, n: usize, bw: usize) -> [bool; LANES] {
    factor_lanes::<true>(band, n, bw)
}

/// The factorisation of [`crate::banded_cholesky`], every lane at once; per lane whether
/// its matrix was positive definite.
#[inline(always)]
fn factor_lanes<const FUSED: bool>(band: &mut LaneBand, n: usize, bw: usize) -> [bool; LANES] {
    let w = bw + 1;
    let mut ok = [true; LANES];
    for i in 0..n {
        let u = band.blocks_mut();
        let (done, rest) = u.split_at_mut(i * w);
        let len = w.min(rest.len());
        let row = &mut rest[..len];
        let mut s = row[0];
        for k in i.saturating_sub(bw)..i {
            let uki = &done[k * w + (i - k)];
            sub_transposed_times::<FUSED>(&mut s, uki, uki);
        }
        let linv = inverse_cholesky(&s, &mut ok);
        row[0] = linv;
        for j in i + 1..(i + w).min(n) {
            let mut m = row[j - i];
            for k in j.saturating_sub(bw)..i {
                let (a, b) = (&done[k * w + (i - k)], &done[k * w + (j - k)]);
                sub_transposed_times::<FUSED>(&mut m, a, b);
            }
            let mut product = times::<FUSED>(&linv, &m);
            if !ok.iter().all(|&ok| ok) {
                for l in (0..LANES).filter(|&l| !ok[l]) {
                    product.iter_mut().for_each(|e| e[l] = 0.0);
                }
            }
            row[j - i] = product;
        }
    }
    ok
}

#[cfg(test)]
impl BatchedBandedCholesky {
    /// [`Self::factor_band`] and [`Self::solve_in_place`] with the plain kernels, or
    /// with `fused` the fused ones, whatever the process's kernel set is (for the table
    /// of every Cholesky variant, `crate::cholesky_variants`); per lane whether it was
    /// positive definite, `None` where the processor lacks AVX2 and FMA.
    pub(crate) fn factor_and_solve_with(
        &mut self,
        fused: bool,
        a: &mut LaneBand,
        x: &mut [Lanes],
    ) -> Option<[bool; LANES]> {
        std::mem::swap(&mut self.u, a);
        (self.n, self.bw, self.factored) = (self.u.dim(), self.u.bandwidth(), true);
        assert_eq!(x.len(), 3 * self.n);
        if !fused {
            let ok = factor_lanes::<false>(&mut self.u, self.n, self.bw);
            self.substitute::<false>(x);
            return Some(ok);
        }
        #[cfg(target_arch = "x86_64")]
        if splinerod_core::kernels::KernelSet::Avx2Fma.available() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            unsafe {
                let ok = factor_lanes_wide(&mut self.u, self.n, self.bw);
                self.solve_wide(x);
                return Some(ok);
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cholesky_variants::{Fill, Shape};
    use nalgebra::Matrix3;

    /// The table's diagonally dominant `n × bw` band (lane 0's).
    fn band(n: usize, bw: usize) -> BlockBanded {
        Shape {
            n,
            bw,
            fill: Fill::Dominant,
        }
        .matrix(0)
    }

    #[test]
    fn mismatched_shapes_and_indefinite_lanes_are_errors() {
        let (a, b) = (band(8, 3), band(9, 3));
        let mut batched = BatchedBandedCholesky::default();
        assert!(batched.factor([&a, &a, &b, &a]).is_err());
        let mut c = band(8, 3);
        c.add_block(4, 4, &(Matrix3::identity() * -1e3));
        assert!(batched.factor([&a, &a, &c, &a]).is_err());
        assert!(batched.solve_in_place(&mut [[0.0; LANES]; 5]).is_err());
    }
}
