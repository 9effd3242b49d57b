//! The upper-triangle CSC pattern of a [`BlockBanded`] matrix — its block band plus its
//! far blocks — and the copy of the matrix's values into it.
//!
//! Column `j = 3 jb + b` (block column `jb`, coordinate `b`) holds, in increasing row
//! order, the three rows of every distinct far block `(ib, jb)` (all `ib < jb − bw`),
//! then the band rows `3 (jb − bw)⁺ ..= j`. Far blocks at the same position share their
//! nine slots, where their values are summed. Reading a matrix's [`BlockShape`] and
//! filling the values allocate nothing once the buffers have grown to the pattern.

use crate::IntegratorError;
use faer::sparse::SymbolicSparseColMat;
use splinerod_core::{BlockBanded, FarBlock, Real};

/// Sparse index type: 32 bits halve the pattern's memory; rods up to ~10⁸ nonzeros.
pub(crate) type Index = u32;

/// The block structure a symbolic analysis depends on: size, bandwidth and the sorted,
/// deduplicated far block positions. Two matrices with equal shapes share an analysis.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct BlockShape {
    n: usize,
    bw: usize,
    /// Distinct far positions as `(col, row)`, sorted: column-major, as the CSC needs.
    far: Vec<(usize, usize)>,
}

impl BlockShape {
    /// Reads the shape of `a`, reusing this shape's storage. Errors on a far block that
    /// is not strictly above the band or lies outside the matrix (possible only by
    /// editing [`BlockBanded::far_blocks_mut`] positions by hand).
    pub fn read(&mut self, a: &BlockBanded) -> Result<(), IntegratorError> {
        self.n = a.dim();
        self.bw = a.bandwidth();
        self.far.clear();
        for f in a.far_blocks() {
            if !self.is_far(f) {
                return Err(IntegratorError::SolverState(
                    "a far block lies inside the band, below the diagonal or outside the matrix",
                ));
            }
            self.far.push((f.col, f.row));
        }
        self.far.sort_unstable();
        self.far.dedup();
        Ok(())
    }

    /// Whether `f` is a valid far block of this shape.
    fn is_far(&self, f: &FarBlock) -> bool {
        f.row < f.col && f.col < self.n && f.col - f.row > self.bw
    }

    /// Whether the shape has blocks outside the band.
    pub fn has_far(&self) -> bool {
        !self.far.is_empty()
    }

    /// Number of block rows.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Block bandwidth.
    pub fn bw(&self) -> usize {
        self.bw
    }

    /// Distinct far block positions `(col, row)`, sorted column-major.
    pub fn far(&self) -> &[(usize, usize)] {
        &self.far
    }
}

/// A [`BlockShape`] with the per-column index of its far blocks: the map from blocks
/// to CSC slots.
#[derive(Debug, Clone, Default)]
pub(crate) struct CscLayout {
    shape: BlockShape,
    /// `shape.far[far_start[jb]..far_start[jb + 1]]` are the far blocks of block column `jb`.
    far_start: Vec<usize>,
}

/// First band row of column `j` for block bandwidth `bw`.
fn first_row(j: usize, bw: usize) -> usize {
    (j / 3).saturating_sub(bw) * 3
}

impl CscLayout {
    /// The analysed shape.
    pub fn shape(&self) -> &BlockShape {
        &self.shape
    }

    /// Replaces the shape by `shape` (the old one is left in `shape`, as scratch) and
    /// indexes its far blocks by column.
    pub fn replace(&mut self, shape: &mut BlockShape) {
        std::mem::swap(&mut self.shape, shape);
        let (n, far) = (self.shape.n, &self.shape.far);
        self.far_start.clear();
        let mut p = 0;
        for jb in 0..=n {
            while p < far.len() && far[p].0 < jb {
                p += 1;
            }
            self.far_start.push(p);
        }
    }

    /// Far blocks in block column `jb`.
    fn far_in(&self, jb: usize) -> &[(usize, usize)] {
        &self.shape.far[self.far_start[jb]..self.far_start[jb + 1]]
    }

    /// Nonzeros of the upper triangle of the block band alone.
    pub fn band_nnz(&self) -> usize {
        let (dofs, bw) = (3 * self.shape.n, self.shape.bw);
        (0..dofs).map(|j| j + 1 - first_row(j, bw)).sum()
    }

    /// Size of the pattern's envelope: \\(\sum_j (j - f_j + 1)\\) with \\(f_j\\) the first
    /// row of column `j`. A Cholesky factor in the natural ordering lies within it, and
    /// for a band plus far blocks (a chain with a few long edges) fills it almost
    /// entirely: the fill of the natural ordering, known without a symbolic analysis.
    pub fn envelope(&self) -> usize {
        let bw = self.shape.bw;
        let mut size = 0;
        for jb in 0..self.shape.n {
            let first_far = self.far_in(jb).first().map(|&(_, ib)| 3 * ib);
            for j in 3 * jb..3 * jb + 3 {
                let first = first_far.unwrap_or(usize::MAX).min(first_row(j, bw));
                size += j + 1 - first;
            }
        }
        size
    }

    /// The upper-triangle CSC pattern, rows sorted in each column.
    pub fn symbolic(&self) -> Result<SymbolicSparseColMat<Index>, IntegratorError> {
        let (n, bw) = (self.shape.n, self.shape.bw);
        let dofs = 3 * n;
        let nnz = self.band_nnz() + 9 * self.shape.far.len();
        if nnz > Index::MAX as usize {
            return Err(IntegratorError::TooLarge {
                what: "the 32-bit sparse pattern",
                dofs,
                limit: Index::MAX as usize / (3 * (bw + 1)),
            });
        }
        let mut col_ptr: Vec<Index> = Vec::with_capacity(dofs + 1);
        let mut rows: Vec<Index> = Vec::with_capacity(nnz);
        col_ptr.push(0);
        for jb in 0..n {
            for b in 0..3 {
                for &(_, ib) in self.far_in(jb) {
                    rows.extend((3 * ib..3 * ib + 3).map(|i| i as Index));
                }
                let j = 3 * jb + b;
                rows.extend((first_row(j, bw)..=j).map(|i| i as Index));
                col_ptr.push(rows.len() as Index);
            }
        }
        Ok(SymbolicSparseColMat::new_checked(
            dofs, dofs, col_ptr, None, rows,
        ))
    }

    /// Writes the upper triangle of `a` (whose shape must be this layout's) into the CSC
    /// `values` of the pattern with column pointers `col_ptr`: the band column by column,
    /// then the far blocks summed into their slots.
    pub fn fill(&self, a: &BlockBanded, col_ptr: &[Index], values: &mut [Real]) {
        self.fill_band(a, values);
        for f in a.far_blocks() {
            let Ok(p) = self.shape.far.binary_search(&(f.col, f.row)) else {
                debug_assert!(false, "far block ({}, {}) not in the layout", f.row, f.col);
                continue;
            };
            let rank = p - self.far_start[f.col];
            for b in 0..3 {
                let at = col_ptr[3 * f.col + b] as usize + 3 * rank;
                for r in 0..3 {
                    values[at + r] += f.block[(r, b)];
                }
            }
        }
    }

    /// Copies the upper block band into its slots and zeroes the far slots.
    fn fill_band(&self, a: &BlockBanded, values: &mut [Real]) {
        let bw = self.shape.bw;
        let mut at = 0;
        for jb in 0..self.shape.n {
            let far = 3 * self.far_in(jb).len();
            for b in 0..3 {
                values[at..at + far].fill(0.0);
                at += far;
                let j = 3 * jb + b;
                for ib in jb.saturating_sub(bw)..=jb {
                    let block = a.upper(ib, jb - ib);
                    for r in 0..3 {
                        if 3 * ib + r > j {
                            break;
                        }
                        values[at] = block[(r, b)];
                        at += 1;
                    }
                }
            }
        }
        debug_assert_eq!(at, values.len());
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    fn matrix() -> BlockBanded {
        let mut a = BlockBanded::zeros(8, 2);
        a.add_coupling(6, 1, &Matrix3::from_fn(|r, c| (3 * r + c) as Real));
        a.add_coupling(0, 7, &Matrix3::identity());
        a.add_coupling(1, 6, &Matrix3::identity());
        a
    }

    #[test]
    fn shape_is_sorted_and_deduplicated() {
        let mut shape = BlockShape::default();
        shape.read(&matrix()).unwrap();
        assert_eq!(shape.far, vec![(6, 1), (7, 0)]);
    }

    #[test]
    fn csc_holds_the_full_upper_triangle_with_summed_duplicates() {
        let a = matrix();
        let mut shape = BlockShape::default();
        shape.read(&a).unwrap();
        let mut layout = CscLayout::default();
        layout.replace(&mut shape);
        let pattern = layout.symbolic().unwrap();
        let mut values = vec![Real::NAN; pattern.compute_nnz()];
        layout.fill(&a, pattern.col_ptr(), &mut values);
        let dense = a.to_dense();
        let mut seen = nalgebra::DMatrix::<Real>::zeros(24, 24);
        for j in 0..24 {
            let range = pattern.col_ptr()[j] as usize..pattern.col_ptr()[j + 1] as usize;
            let rows = &pattern.row_idx()[range.clone()];
            assert!(rows.windows(2).all(|w| w[0] < w[1]), "column {j} unsorted");
            for (&i, &v) in rows.iter().zip(&values[range]) {
                seen[(i as usize, j)] = v;
            }
        }
        assert_eq!(seen, dense.upper_triangle());
        // Envelope: band rows, plus columns 18..=20 reaching up to row 3 (block 1) instead
        // of 12 (block 4) and columns 21..=23 up to row 0 instead of 15.
        assert_eq!(layout.band_nnz(), pattern.compute_nnz() - 18);
        assert_eq!(layout.envelope(), layout.band_nnz() + 3 * 9 + 3 * 15);
    }

    #[test]
    fn a_far_block_inside_the_band_is_an_error() {
        let mut a = matrix();
        a.far_blocks_mut()[0].row = 5;
        assert!(BlockShape::default().read(&a).is_err());
    }
}
