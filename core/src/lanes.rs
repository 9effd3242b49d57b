//! Structure-of-arrays storage for stepping [`LANES`] rods of one shape at once (batched
//! ensembles, #17): every scalar holds one value per rod ("lane"), so each arithmetic
//! operation of an assembly or a factorisation runs over the lanes in one loop the
//! compiler vectorises.
//!
//! A field of 3-vectors over `n` control points is a `[Lanes]` of length `3n`, coordinate
//! `c` of point `i` at `3i + c`. A [`LaneBand`] is the lane form of
//! [`crate::BlockBanded`]'s band: block `(i, i + k)`, `0 ≤ k ≤ bw`, at `i · (bw + 1) + k`,
//! each block column-major (entry `(r, c)` at `3c + r`).

use crate::Real;

/// Rods stepped together.
pub const LANES: usize = 4;

/// One scalar per lane.
pub type Lanes = [Real; LANES];

/// A 3×3 block per lane, column-major: entry `(r, c)` at `3c + r`.
pub type LaneBlock = [Lanes; 9];

/// Zero in every lane.
pub const ZERO: Lanes = [0.0; LANES];

/// The upper band of [`LANES`] symmetric block-banded matrices of one size and bandwidth.
///
/// A band cleared with [`Self::clear_lazily`] holds stale blocks until they are written:
/// [`Self::row_to_add`] says which of a row's blocks still hold values, and every other
/// mutable accessor zeroes the stale blocks it hands out. The read-only accessors expect
/// none left (after [`Self::blocks_mut`] or a [`Self::row_mut`] of every row).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LaneBand {
    n: usize,
    bw: usize,
    blocks: Vec<LaneBlock>,
    /// Per row, how many of its leading blocks hold values (the rest are stale); all of
    /// them unless `stale`.
    written: Vec<usize>,
    /// Whether some block may be stale.
    stale: bool,
}

impl LaneBand {
    /// Resizes to `n × n` blocks of bandwidth `bw` and zeroes every block (no allocation
    /// once grown to the size).
    pub fn reset(&mut self, n: usize, bw: usize) {
        (self.n, self.bw) = (n, bw);
        self.blocks.resize(n * (bw + 1), [ZERO; 9]);
        self.blocks.fill([ZERO; 9]);
        self.stale = false;
    }

    /// [`Self::reset`] without writing the zeros: every block is zero to the accessors,
    /// which write a block's zeros only if it is handed out before being written (an
    /// assembly that writes most blocks saves a pass over the band). The slots past the
    /// end of the matrix are zeroed.
    pub fn clear_lazily(&mut self, n: usize, bw: usize) {
        let w = bw + 1;
        (self.n, self.bw) = (n, bw);
        self.blocks.resize(n * w, [ZERO; 9]);
        for i in n.saturating_sub(bw)..n {
            self.blocks[i * w + (n - i)..(i + 1) * w].fill([ZERO; 9]);
        }
        self.written.clear();
        self.written.resize(n, 0);
        self.stale = true;
    }

    /// The first `len` blocks `(i, i ..= i + len − 1)` of row `i` for adding to, and how
    /// many of them hold values: the blocks from there on are stale (after
    /// [`Self::clear_lazily`]) and must be written, not added to; they count as written
    /// once handed out. Panics past the band or the matrix.
    #[inline]
    pub fn row_to_add(&mut self, i: usize, len: usize) -> (&mut [LaneBlock], usize) {
        let w = self.bw + 1;
        assert!(len <= w.min(self.n - i));
        let held = if self.stale {
            let held = self.written[i].min(len);
            self.written[i] = self.written[i].max(len);
            held
        } else {
            len
        };
        (&mut self.blocks[i * w..i * w + len], held)
    }

    /// Zeroes the stale blocks of row `i` (after [`Self::clear_lazily`]).
    #[inline]
    fn fill_row(&mut self, i: usize) {
        if self.stale {
            let w = self.bw + 1;
            let len = w.min(self.n - i);
            let held = self.written[i].min(len);
            if held < len {
                self.blocks[i * w + held..i * w + len].fill([ZERO; 9]);
                self.written[i] = len;
            }
        }
    }

    /// Dimension in blocks.
    pub fn dim(&self) -> usize {
        self.n
    }

    /// Block bandwidth.
    pub fn bandwidth(&self) -> usize {
        self.bw
    }

    /// Blocks `(i, i ..= i + bw)` (fewer at the end of the matrix); stale ones zeroed.
    #[inline]
    pub fn row_mut(&mut self, i: usize) -> &mut [LaneBlock] {
        self.fill_row(i);
        let w = self.bw + 1;
        let len = w.min(self.n - i);
        &mut self.blocks[i * w..i * w + len]
    }

    /// Blocks `(i, i ..= i + bw)` (fewer at the end of the matrix).
    #[inline]
    pub fn row(&self, i: usize) -> &[LaneBlock] {
        debug_assert!(!self.stale, "stale blocks");
        let w = self.bw + 1;
        let len = w.min(self.n - i);
        &self.blocks[i * w..i * w + len]
    }

    /// Every stored block, rows of `bw + 1` slots (slots past the end of the matrix are
    /// zero).
    pub fn blocks(&self) -> &[LaneBlock] {
        debug_assert!(!self.stale, "stale blocks");
        &self.blocks
    }

    /// Every stored block, mutably (layout of [`Self::blocks`]; stale ones zeroed).
    pub fn blocks_mut(&mut self) -> &mut [LaneBlock] {
        self.fill_stale();
        &mut self.blocks
    }

    /// Zeroes every stale block (after [`Self::clear_lazily`]; cheap when the rows were
    /// written).
    pub fn fill_stale(&mut self) {
        if self.stale {
            (0..self.n).for_each(|i| self.fill_row(i));
            self.stale = false;
        }
    }

    /// Block `(i, j)` of the full symmetric matrix (the transpose of the stored `(j, i)`
    /// below the diagonal; zero outside the band).
    pub fn block(&self, i: usize, j: usize) -> LaneBlock {
        debug_assert!(!self.stale, "stale blocks");
        let (lo, hi) = (i.min(j), i.max(j));
        if hi - lo > self.bw || hi >= self.n {
            return [ZERO; 9];
        }
        let b = self.blocks[lo * (self.bw + 1) + hi - lo];
        if i <= j {
            b
        } else {
            std::array::from_fn(|e| b[3 * (e % 3) + e / 3])
        }
    }

    /// Whether every entry of every lane is finite.
    pub fn is_finite(&self) -> bool {
        debug_assert!(!self.stale, "stale blocks");
        self.blocks
            .iter()
            .flatten()
            .flatten()
            .all(|x| x.is_finite())
    }
}

/// Where a lane evaluation adds its derivatives: the gradient field and the Hessian's
/// upper band, the Hessian multiplied by `hessian_scale` (an implicit step's `h²`, so
/// that the band needs no separate pass).
#[derive(Debug)]
pub struct Derivatives<'a> {
    /// Gradient, coordinate `c` of point `i` at `3i + c`.
    pub gradient: &'a mut [Lanes],
    /// Hessian (upper band), times `hessian_scale`.
    pub hessian: &'a mut LaneBand,
    /// Factor of the Hessian.
    pub hessian_scale: Real,
}

impl Derivatives<'_> {
    /// A shorter-lived borrow of the same buffers.
    pub fn reborrow(&mut self) -> Derivatives<'_> {
        Derivatives {
            gradient: self.gradient,
            hessian: self.hessian,
            hessian_scale: self.hessian_scale,
        }
    }
}

/// `a + b`, lane by lane.
#[inline(always)]
pub fn add(a: Lanes, b: Lanes) -> Lanes {
    std::array::from_fn(|l| a[l] + b[l])
}

/// `a − b`, lane by lane.
#[inline(always)]
pub fn sub(a: Lanes, b: Lanes) -> Lanes {
    std::array::from_fn(|l| a[l] - b[l])
}

/// `a · b`, lane by lane.
#[inline(always)]
pub fn mul(a: Lanes, b: Lanes) -> Lanes {
    std::array::from_fn(|l| a[l] * b[l])
}

/// `acc += a · b`, lane by lane.
#[inline(always)]
pub fn mul_add(acc: &mut Lanes, a: Lanes, b: Lanes) {
    for l in 0..LANES {
        acc[l] += a[l] * b[l];
    }
}

/// `acc += a · b`, lane by lane, fused (one rounding) when `FUSED`: for kernels compiled
/// twice, for processors with fused multiply-add (where `f64::mul_add` is one
/// instruction) and without (where it would be a library call).
#[inline(always)]
pub fn fma<const FUSED: bool>(acc: &mut Lanes, a: Lanes, b: Lanes) {
    for l in 0..LANES {
        acc[l] = if FUSED {
            a[l].mul_add(b[l], acc[l])
        } else {
            acc[l] + a[l] * b[l]
        };
    }
}

/// Whether this process runs the wide kernels: AVX2 (four lanes per instruction) with
/// fused multiply-add. The one switch every kernel with two instances branches on:
/// true exactly when the process's kernel set ([`crate::kernels::active`], chosen once
/// from `SPLINEROD_KERNELS`) is [`crate::kernels::KernelSet::Avx2Fma`], which implies
/// the processor has both.
#[cfg(target_arch = "x86_64")]
#[inline]
pub fn wide() -> bool {
    crate::kernels::active() == crate::kernels::KernelSet::Avx2Fma
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_below_the_diagonal_are_transposes_and_outside_the_band_zero() {
        let mut band = LaneBand::default();
        band.reset(4, 1);
        band.row_mut(1)[1] = std::array::from_fn(|e| [e as Real; LANES]);
        let upper = band.block(1, 2);
        let lower = band.block(2, 1);
        for r in 0..3 {
            for c in 0..3 {
                assert_eq!(upper[3 * c + r], lower[3 * r + c]);
            }
        }
        assert_eq!(band.block(0, 3), [ZERO; 9]);
        assert_eq!(band.row(3).len(), 1);
        assert!(band.is_finite());
        band.row_mut(0)[0][4][2] = Real::NAN;
        assert!(!band.is_finite());
    }

    #[test]
    fn a_band_cleared_lazily_reads_as_zero_and_says_which_blocks_hold_values() {
        let mut band = LaneBand::default();
        band.reset(5, 2);
        band.blocks_mut().fill([[7.0; LANES]; 9]);
        band.clear_lazily(5, 2);
        let (row, held) = band.row_to_add(1, 2);
        assert_eq!((row.len(), held), (2, 0));
        row[0] = [[1.0; LANES]; 9];
        row[1] = [[2.0; LANES]; 9];
        assert_eq!(band.row_to_add(1, 3).1, 2);
        band.row_to_add(3, 1).0[0] = [[3.0; LANES]; 9];
        assert_eq!(band.row_mut(3)[1], [ZERO; 9]);
        let mut zeroed = LaneBand::default();
        zeroed.reset(5, 2);
        zeroed.row_mut(1)[0] = [[1.0; LANES]; 9];
        zeroed.row_mut(1)[1] = [[2.0; LANES]; 9];
        zeroed.row_mut(3)[0] = [[3.0; LANES]; 9];
        // Row 1's third block was handed out by `row_to_add` and is left as it was.
        zeroed.row_mut(1)[2] = band.blocks_mut()[5];
        assert_eq!(band.blocks(), zeroed.blocks());
    }
}
