//! Four-wide registers for 3-vectors and 3×3 blocks (x86-64 with AVX2): a 3-vector in
//! lanes 0–2 of an `__m256d`, a block as its three stored 3-vectors (the columns of a
//! column-major [`nalgebra::Matrix3`], or the rows of a row-major one).
//!
//! A product of blocks or a rank-one update is then three fused multiply-adds of a
//! 3-vector with a broadcast entry, instead of nine scalar ones: the fused kernels of
//! the banded Cholesky factorisation and of the stretching's Hessian use these. Lane 3
//! holds whatever the load brought in (a neighbouring entry) and is never stored, so
//! the helpers work on the packed 9-value storage, without padding.
//!
//! Every function is `unsafe`: the processor must have AVX2
//! ([`crate::lanes::wide`]), and the pointers must cover the values named. They are
//! `#[inline(always)]`, to be compiled into a caller with
//! `#[target_feature(enable = "avx2,fma")]`; called from a closure (which does not take
//! its caller's target features) the intrinsics would not be inlined.

use crate::Real;
use core::arch::x86_64::*;

/// The three 3-vectors of a 3×3 block, one per register.
pub type Triple = [__m256d; 3];

/// The 3-vector at `p`, lane 3 zero.
///
/// # Safety
/// `p` must point at 3 readable values; the processor must have AVX.
#[inline(always)]
pub unsafe fn load3(p: *const Real) -> __m256d {
    let low = _mm256_castpd128_pd256(_mm_loadu_pd(p));
    _mm256_insertf128_pd::<1>(low, _mm_load_sd(p.add(2)))
}

/// Writes lanes 0–2 of `v` at `p`.
///
/// # Safety
/// `p` must point at 3 writable values; the processor must have AVX.
#[inline(always)]
pub unsafe fn store3(p: *mut Real, v: __m256d) {
    _mm_storeu_pd(p, _mm256_castpd256_pd128(v));
    _mm_store_sd(p.add(2), _mm256_extractf128_pd::<1>(v));
}

/// The three 3-vectors stored one after the other at `p` (lane 3 of each holds the
/// entry after it).
///
/// # Safety
/// `p` must point at 9 readable values; the processor must have AVX2.
#[inline(always)]
pub unsafe fn load_block(p: *const Real) -> Triple {
    // The third vector ends the block: loaded from one entry earlier and shifted down.
    let last = _mm256_permute4x64_pd::<0b11_11_10_01>(_mm256_loadu_pd(p.add(5)));
    [_mm256_loadu_pd(p), _mm256_loadu_pd(p.add(3)), last]
}

/// Writes three 3-vectors one after the other at `p` (9 values; each lane 3 is
/// overwritten by the next vector or not stored).
///
/// # Safety
/// `p` must point at 9 writable values; the processor must have AVX.
#[inline(always)]
pub unsafe fn store_block(p: *mut Real, block: Triple) {
    _mm256_storeu_pd(p, block[0]);
    _mm256_storeu_pd(p.add(3), block[1]);
    store3(p.add(6), block[2]);
}

/// Adds `d` (lane 0) to the diagonal of the block whose columns (or rows) are `block`:
/// entry `c` of vector `c`. The other lanes take −0, which leaves every value as it is
/// (also a −0), so this is the scalar `b[(c, c)] += d` bit for bit.
///
/// # Safety
/// The processor must have AVX.
#[inline(always)]
pub unsafe fn add_diagonal(block: &mut Triple, d: Real) {
    let (d, negative_zero) = (_mm256_set1_pd(d), _mm256_set1_pd(-0.0));
    block[0] = _mm256_add_pd(block[0], _mm256_blend_pd::<0b0001>(negative_zero, d));
    block[1] = _mm256_add_pd(block[1], _mm256_blend_pd::<0b0010>(negative_zero, d));
    block[2] = _mm256_add_pd(block[2], _mm256_blend_pd::<0b0100>(negative_zero, d));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_and_vectors_round_trip_without_touching_their_neighbours() {
        if !crate::lanes::wide() {
            return;
        }
        let mut buffer: Vec<Real> = (0..13).map(|k| k as Real + 0.5).collect();
        // SAFETY: AVX2 checked above; offsets 1..10 and 10..13 lie in the buffer.
        unsafe {
            let block = load_block(buffer.as_ptr().add(1));
            let v = load3(buffer.as_ptr().add(10));
            let mut lanes = [0.0; 4];
            _mm256_storeu_pd(lanes.as_mut_ptr(), block[2]);
            assert_eq!(&lanes[..3], &[7.5, 8.5, 9.5]);
            _mm256_storeu_pd(lanes.as_mut_ptr(), v);
            assert_eq!(lanes, [10.5, 11.5, 12.5, 0.0]);
            let twice = block.map(|b| _mm256_add_pd(b, b));
            store_block(buffer.as_mut_ptr().add(1), twice);
            store3(buffer.as_mut_ptr().add(10), _mm256_add_pd(v, v));
            // A diagonal added: only the entries (c, c) change, −0 stays −0.
            let mut block = [0.0, -0.0, 1.0, -0.0, 2.0, 3.0, 4.0, 5.0, -0.0];
            let mut columns = load_block(block.as_ptr());
            add_diagonal(&mut columns, 0.5);
            store_block(block.as_mut_ptr(), columns);
            let bits = |b: &[Real]| b.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            let expected = [0.5, -0.0, 1.0, -0.0, 2.5, 3.0, 4.0, 5.0, 0.5];
            assert_eq!(bits(&block), bits(&expected));
        }
        let expected: Vec<Real> = (0..13)
            .map(|k| if k == 0 { 0.5 } else { 2.0 * (k as Real + 0.5) })
            .collect();
        assert_eq!(buffer, expected);
    }
}
