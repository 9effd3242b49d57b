//! Assembly of the contact Hessian one candidate segment pair at a time: the sample
//! pairs of two touching segments share a few control points, so their blocks are
//! summed in a small dense matrix first. Neighbouring segment pairs share control points
//! too, so the far blocks of all groups are then sorted and merged by position before
//! they reach the global matrix: one far block per coupled pair of control points
//! (measured on a dense coil: 13 duplicates per position before merging).

use nalgebra::Matrix3;
use splinerod_core::basis::MAX_ORDER;
use splinerod_core::{BlockBanded, Real};
use std::ops::Range;

/// A symmetric 3×3 block by its six entries `xx, yy, zz, xy, xz, yz`: every block of
/// the contact Hessian is one (a sum of weights times symmetric matrices), so a third of
/// the arithmetic of full blocks suffices.
type SymBlock = [Real; 6];

/// The entries of a symmetric `m`.
fn entries(m: &Matrix3<Real>) -> SymBlock {
    [
        m[(0, 0)],
        m[(1, 1)],
        m[(2, 2)],
        m[(0, 1)],
        m[(0, 2)],
        m[(1, 2)],
    ]
}

/// The full block of `e`.
fn block(e: &SymBlock) -> Matrix3<Real> {
    Matrix3::new(e[0], e[3], e[4], e[3], e[1], e[5], e[4], e[5], e[2])
}

/// Dense symmetric block matrix over the control points of one group (reused).
#[derive(Debug, Clone, Default)]
pub(crate) struct GroupHessian {
    index: Vec<usize>,
    /// The group's control points as (up to two) runs `(first, end, local offset)`.
    runs: [(usize, usize, usize); 2],
    blocks: Vec<SymBlock>,
    /// Far blocks of every group so far, `(row < col)`, merged by [`Self::flush`].
    far: Vec<(usize, usize, Matrix3<Real>)>,
}

impl GroupHessian {
    /// Starts a group over the control points of two runs `a` and `b` (the two strands'
    /// samples touch consecutive control points), which may overlap.
    pub fn start(&mut self, a: Range<usize>, b: Range<usize>) {
        let (first, second) = if a.start <= b.start { (a, b) } else { (b, a) };
        self.index.clear();
        if second.start <= first.end {
            let end = first.end.max(second.end);
            self.runs = [(first.start, end, 0), (end, end, end - first.start)];
            self.index.extend(first.start..end);
        } else {
            let len = first.len();
            self.runs = [(first.start, first.end, 0), (second.start, second.end, len)];
            self.index.extend(first.clone().chain(second));
        }
        let n = self.index.len();
        self.blocks.clear();
        self.blocks.resize(n * n, [0.0; 6]);
    }

    /// Adds `w_i w_j · m` (`m` symmetric) at every pair `(i, j)`, `i ≤ j` in local order,
    /// of `weights` (control point, weight); every control point must belong to the group.
    /// Each product is formed as `(m w_i) w_j` with `i` the lower of the two in local
    /// order.
    pub fn add(&mut self, weights: &[(usize, Real)], m: &Matrix3<Real>) {
        let m = entries(m);
        let n = self.index.len();
        let mut local = [(0, 0.0, [0.0; 6]); 2 * MAX_ORDER];
        let count = weights.len().min(local.len());
        for (slot, &(i, w)) in local.iter_mut().zip(weights) {
            *slot = (self.local(i), w, m.map(|x| x * w));
        }
        let local = &local[..count];
        for (k, &(a, wa, ma)) in local.iter().enumerate() {
            for &(b, wb, mb) in &local[k..] {
                // (m w_lower) w_higher, stored at (lower, higher).
                let (at, row, w) = if a <= b {
                    (a * n + b, ma, wb)
                } else {
                    (b * n + a, mb, wa)
                };
                for (t, r) in self.blocks[at].iter_mut().zip(&row) {
                    *t += r * w;
                }
            }
        }
    }

    /// Adds the group's band blocks to `hessian` and keeps its far blocks for
    /// [`Self::flush`].
    pub fn finish(&mut self, hessian: &mut BlockBanded) {
        let n = self.index.len();
        for a in 0..n {
            for b in a..n {
                let (i, j) = (self.index[a], self.index[b]);
                let block = block(&self.blocks[a * n + b]);
                if j - i <= hessian.bandwidth() {
                    hessian.add_block(i, j, &block);
                } else {
                    self.far.push((i, j, block));
                }
            }
        }
    }

    /// Adds the kept far blocks to `hessian`, one per position.
    pub fn flush(&mut self, hessian: &mut BlockBanded) {
        self.far.sort_unstable_by_key(|&(i, j, _)| (i, j));
        let mut k = 0;
        while k < self.far.len() {
            let (i, j, mut sum) = self.far[k];
            k += 1;
            while k < self.far.len() && (self.far[k].0, self.far[k].1) == (i, j) {
                sum += self.far[k].2;
                k += 1;
            }
            hessian.add_coupling(i, j, &sum);
        }
        self.far.clear();
    }

    /// Position of control point `i` in the group (which holds it).
    #[inline]
    fn local(&self, i: usize) -> usize {
        let [(lo, hi, offset), (lo2, _, offset2)] = self.runs;
        if (lo..hi).contains(&i) {
            i - lo + offset
        } else {
            i - lo2 + offset2
        }
    }
}
