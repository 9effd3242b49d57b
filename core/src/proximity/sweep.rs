//! [`BoxSweep`]: sort and sweep over axis-aligned boxes, shared by the span boxes of
//! [`SpanBoxes`](super::SpanBoxes) and the contact segments of the contact energy.
//!
//! Boxes are sorted by their lower bound along the axis where their centres spread
//! most; each box is compared with the boxes after it until one starts more than
//! `margin` above its upper bound. Sorting reuses the previous order as a warm start
//! (insertion sort, giving up after `4n` moves for `sort_unstable`), so it is close to
//! O(n) while the boxes move little between calls and never worse than O(n log n); the
//! sweep is O(n + k) for `k` pairs overlapping along the sweep axis. Boxes with equal
//! lower bounds are ordered by index, so the order (and the order pairs are visited in)
//! depends on the boxes alone, not on the warm start: a run resumed from a checkpoint,
//! whose sweep starts cold, visits them as the run never stopped does.

use crate::Real;
use nalgebra::Vector3;

/// The sort order and axis of a sort and sweep, kept between calls (no allocation once
/// the number of boxes stops growing).
#[derive(Debug, Clone, Default)]
pub struct BoxSweep {
    order: Vec<usize>,
    axis: usize,
}

impl BoxSweep {
    /// Sorts the boxes `lower[i]..upper[i]` along the axis of widest spread.
    pub fn sort(&mut self, lower: &[Vector3<Real>], upper: &[Vector3<Real>]) {
        let n = lower.len();
        let axis = widest_axis(lower, upper);
        let warm = axis == self.axis && self.order.len() == n;
        self.axis = axis;
        if !warm {
            self.order.clear();
            self.order.extend(0..n);
        }
        let key = |i: usize| lower[i][axis];
        if !warm || !insertion_sort(&mut self.order, key, 4 * n) {
            self.order.sort_unstable_by(|&a, &b| ordering(key, a, b));
        }
    }

    /// Calls `visit(i, j)` (in sweep order, `i ≠ j`) for every pair of boxes less than
    /// `margin` apart on every axis, after a [`sort`](Self::sort) of the same boxes.
    pub fn pairs(
        &self,
        lower: &[Vector3<Real>],
        upper: &[Vector3<Real>],
        margin: Real,
        mut visit: impl FnMut(usize, usize),
    ) {
        let axis = self.axis;
        for (a, &i) in self.order.iter().enumerate() {
            let top = upper[i][axis] + margin;
            for &j in &self.order[a + 1..] {
                if lower[j][axis] > top {
                    break;
                }
                let near = (0..3).all(|k| {
                    lower[j][k] <= upper[i][k] + margin && lower[i][k] <= upper[j][k] + margin
                });
                if near {
                    visit(i, j);
                }
            }
        }
    }

    /// The sweep axis (0, 1 or 2) chosen by the last sort.
    pub fn axis(&self) -> usize {
        self.axis
    }

    /// Capacity of the order buffer, for allocation tests.
    pub fn capacity(&self) -> usize {
        self.order.capacity()
    }
}

/// Axis along which the box centres spread most.
fn widest_axis(lower: &[Vector3<Real>], upper: &[Vector3<Real>]) -> usize {
    let mut min = Vector3::repeat(Real::INFINITY);
    let mut max = Vector3::repeat(Real::NEG_INFINITY);
    for (lo, hi) in lower.iter().zip(upper) {
        let centre = (lo + hi) * 0.5;
        min = min.inf(&centre);
        max = max.sup(&centre);
    }
    (max - min).imax()
}

/// The sweep's total order: by lower bound (`total_cmp`), then by index.
#[inline]
fn ordering(key: impl Fn(usize) -> Real, a: usize, b: usize) -> std::cmp::Ordering {
    key(a).total_cmp(&key(b)).then(a.cmp(&b))
}

/// Sorts `order` by `key` with at most `budget` element moves; returns false (leaving a
/// permutation of the input) when the budget runs out.
fn insertion_sort(order: &mut [usize], key: impl Fn(usize) -> Real, budget: usize) -> bool {
    let mut moves = 0;
    for a in 1..order.len() {
        let item = order[a];
        let mut b = a;
        while b > 0 && ordering(&key, order[b - 1], item).is_gt() {
            order[b] = order[b - 1];
            b -= 1;
            moves += 1;
        }
        order[b] = item;
        if moves > budget {
            return false;
        }
    }
    true
}
