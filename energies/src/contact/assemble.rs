//! Assembly of the contact Hessian's cross terms \(-(B_a B_b^T + B_b B_a^T) \otimes M\)
//! (see [`super::sample_sums`] for the one-sample terms) one candidate segment pair at a
//! time: the sample pairs of two touching segments share a few control points, so their
//! blocks are summed in a small dense matrix first. Neighbouring segment pairs share control points
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
pub(crate) type SymBlock = [Real; 6];

/// The full block of `e`.
pub(crate) fn block(e: &SymBlock) -> Matrix3<Real> {
    Matrix3::new(e[0], e[3], e[4], e[3], e[1], e[5], e[4], e[5], e[2])
}

/// Dense symmetric block matrix over the control points of one group (reused).
#[derive(Debug, Clone, Default)]
pub(crate) struct GroupHessian {
    index: Vec<usize>,
    /// The group's control points as (up to two) runs `(first, end, local offset)`.
    runs: [(usize, usize, usize); 2],
    blocks: Vec<SymBlock>,
    /// Far blocks of every group so far, `(row < col)`, merged by [`Self::flush`]:
    /// their positions (`row · 2³² + col`, index into `far_blocks`) and entries.
    far: Vec<(u64, u32)>,
    far_blocks: Vec<SymBlock>,
    /// The sample whose cross terms are being summed, see [`Self::add_cross`].
    pending: Pending,
    /// Per local column: the pending sample's \(\sum_b B_b \otimes m\).
    columns: Vec<SymBlock>,
}

/// The sample of [`GroupHessian::add_cross`]'s current sums.
#[derive(Debug, Clone, Copy, Default)]
struct Pending {
    sample: Option<u32>,
    /// Local position of its first control point.
    local: usize,
    row: [Real; MAX_ORDER],
    len: usize,
    /// The local columns summed so far, `lo..hi`.
    lo: usize,
    hi: usize,
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
        self.columns.clear();
        self.columns.resize(n, [0.0; 6]);
        self.pending = Pending {
            lo: usize::MAX,
            ..Pending::default()
        };
    }

    /// Adds the cross terms \(-(B_a B_b^T + B_b B_a^T) \otimes m\) of a sample pair:
    /// sample `a` (index, first control point, basis row) and `b` (first control point,
    /// basis row of the same length); each row's control points must lie in one run of
    /// the group. Consecutive pairs of one sample `a` are summed first,
    /// \(\sum_b B_b \otimes m\) per local column, and spread over `a`'s row once it
    /// changes ([`Self::spread_pending`]): `order` products per pair instead of
    /// `order²`.
    pub fn add_cross(&mut self, a: (u32, usize, &[Real]), b: (usize, &[Real]), m: &SymBlock) {
        if self.pending.sample != Some(a.0) {
            self.spread_pending();
            let local = self.local(a.1);
            let p = &mut self.pending;
            p.sample = Some(a.0);
            p.local = local;
            p.len = a.2.len().min(MAX_ORDER);
            p.row[..p.len].copy_from_slice(&a.2[..p.len]);
        }
        // A row lies in one run: its local positions are consecutive.
        let lb = self.local(b.0);
        let columns = &mut self.columns[lb..lb + b.1.len()];
        for (column, &w) in columns.iter_mut().zip(b.1) {
            for (t, x) in column.iter_mut().zip(m) {
                *t += x * w;
            }
        }
        let p = &mut self.pending;
        (p.lo, p.hi) = (p.lo.min(lb), p.hi.max(lb + b.1.len()));
    }

    /// Spreads the pending sample's column sums over its row: entry `(i, c)` goes to the
    /// stored block `(min, max)` in local order with weight `−w_i`, twice where `i = c`
    /// (both products of the cross term land there).
    fn spread_pending(&mut self) {
        let n = self.index.len();
        let p = &mut self.pending;
        if p.sample.take().is_none() {
            return;
        }
        for (i, &wa) in p.row[..p.len].iter().enumerate() {
            let li = p.local + i;
            for (c, column) in self.columns[p.lo..p.hi].iter().enumerate() {
                let lc = p.lo + c;
                let (at, w) = if li == lc {
                    (li * n + li, -2.0 * wa)
                } else {
                    (li.min(lc) * n + li.max(lc), -wa)
                };
                for (t, r) in self.blocks[at].iter_mut().zip(column) {
                    *t += r * w;
                }
            }
        }
        self.columns[p.lo..p.hi].fill([0.0; 6]);
        (p.lo, p.hi) = (usize::MAX, 0);
    }

    /// Adds the group's band blocks to `hessian` and keeps its far blocks for
    /// [`Self::flush`].
    pub fn finish(&mut self, hessian: &mut BlockBanded) {
        self.spread_pending();
        let n = self.index.len();
        // Cross terms couple the two runs only: with separate runs, the blocks within
        // each run stay zero (and are not added, nor kept as far blocks).
        let [(lo, hi, _), (_, _, second)] = self.runs;
        let separate = hi - lo == second && second < n;
        let rows = if separate { second } else { n };
        for a in 0..rows {
            let from = if separate { second } else { a };
            for b in from..n {
                let (i, j) = (self.index[a], self.index[b]);
                let entries = &self.blocks[a * n + b];
                if j - i <= hessian.bandwidth() {
                    hessian.add_block(i, j, &block(entries));
                } else {
                    let key = ((i as u64) << 32) | j as u64;
                    self.far.push((key, self.far_blocks.len() as u32));
                    self.far_blocks.push(*entries);
                }
            }
        }
    }

    /// Adds the kept far blocks to `hessian`, one per position.
    pub fn flush(&mut self, hessian: &mut BlockBanded) {
        // Small keys sort fast; unique ones (with the index) sort deterministically,
        // and the blocks of one position are summed in the order they were kept.
        self.far.sort_unstable();
        let mut k = 0;
        while k < self.far.len() {
            let (key, first) = self.far[k];
            let mut sum = self.far_blocks[first as usize];
            k += 1;
            while k < self.far.len() && self.far[k].0 == key {
                let next = &self.far_blocks[self.far[k].1 as usize];
                sum.iter_mut().zip(next).for_each(|(s, x)| *s += x);
                k += 1;
            }
            let (i, j) = ((key >> 32) as usize, (key & u64::from(u32::MAX)) as usize);
            hessian.add_coupling(i, j, &block(&sum));
        }
        self.far.clear();
        self.far_blocks.clear();
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
