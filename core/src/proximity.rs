//! Proximity queries between pieces of a rod: the groundwork for self-contact (issue 6).
//!
//! # Broad phase: [`SpanBoxes`]
//!
//! On a non-empty knot span only the `d + 1` functions \\(b_f, \dots, b_{f+d}\\) are
//! non-zero; they are non-negative and sum to one, so the span's curve lies in the convex
//! hull of \\(q_f, \dots, q_{f+d}\\) (the B-spline convex-hull property) and hence in their
//! axis-aligned bounding box. Each box is inflated by a `margin` (typically the rod
//! radius `r`): if two spans come closer than `2 · margin`, their boxes overlap. The boxes
//! are never tighter than the curve, so the broad phase has no false negatives.
//!
//! Overlapping pairs are found by *sort and sweep* along the axis where the box centres
//! spread most: boxes are sorted by their lower bound on that axis, and each box is
//! compared with the boxes that follow it until one starts above its upper bound; pairs
//! that overlap on that axis are then tested on the other two. Costs, for `n` spans and
//! `k` pairs overlapping on the sweep axis:
//!
//! * sorting: O(n log n) with `sort_unstable`, or close to O(n) when the previous order is
//!   reused (an insertion sort warm start, which gives up and falls back to
//!   `sort_unstable` after `4n` moves, so it is never worse than O(n log n));
//! * sweeping: O(n + k). For a rod whose spans are short compared with its extent
//!   (non-degenerate configurations) `k` is proportional to `n`; it degrades to O(n²)
//!   only when many spans share one slab of the sweep axis, e.g. a flat coil lying across
//!   it.
//!
//! **Exclusion.** Neighbouring spans always overlap, so pairs are kept only when their
//! *material separation* — the rest-arclength gap \\(s^j_{start} - s^i_{end}\\) between
//! span `i` and a later span `j`, zero for adjacent spans — is at least `exclusion`.
//! Spans on different pieces (a [cut](crate::Rod::cut) between them: they share no
//! control point) have infinite separation: pieces can collide however close they were
//! in the uncut rod. Excluding a pair by its gap drops some point pairs that are up to
//! `exclusion + h_i + h_j` apart in material, so choose `exclusion` a span length or so
//! below the material distance a contact law needs to ignore.
//!
//! # Narrow phase: [`closest_points`]
//!
//! Closest points between two spans by projected Newton on the squared distance; see
//! [`narrow`] for the maths.

pub mod narrow;
mod segment;
mod sweep;

pub use narrow::{closest_points, closest_points_between, Closest};
pub use segment::closest_on_segments;
pub use sweep::BoxSweep;

use crate::basis::{spans, Span};
use crate::rod::{check_finite, non_negative};
use crate::{CoreError, Real, Rod};
use nalgebra::Vector3;

/// Axis-aligned bounding boxes of every non-empty span of a rod, inflated by a margin, and
/// the sort order used to sweep them (module docs). All buffers are kept between calls of
/// [`update`](Self::update), so a rod whose span count does not grow allocates nothing.
#[derive(Debug, Clone, Default)]
pub struct SpanBoxes {
    spans: Vec<Span>,
    piece: Vec<usize>,
    lower: Vec<Vector3<Real>>,
    upper: Vec<Vector3<Real>>,
    sweep: BoxSweep,
    margin: Real,
}

impl SpanBoxes {
    /// Boxes of the spans of `rod`, inflated by `margin` (see [`update`](Self::update)).
    pub fn new(rod: &Rod, margin: Real) -> Result<Self, CoreError> {
        let mut boxes = Self::default();
        boxes.update(rod, margin)?;
        Ok(boxes)
    }

    /// Recomputes the boxes for the current control points (and basis) of `rod`, each
    /// inflated by `margin` (m, non-negative), and re-sorts them along the axis of largest
    /// spread, reusing the previous order as a warm start. Errors on a negative or
    /// non-finite margin or non-finite control points.
    pub fn update(&mut self, rod: &Rod, margin: Real) -> Result<(), CoreError> {
        non_negative("margin", margin)?;
        check_finite("control point", &rod.positions)?;
        self.margin = margin;
        self.spans.clear();
        self.piece.clear();
        self.lower.clear();
        self.upper.clear();
        let d = rod.basis().degree();
        let mut piece = 0;
        for span in spans(rod.basis()) {
            if self.spans.last().is_some_and(|p| span.first - p.first > d) {
                piece += 1; // no shared control point: a cut lies between
            }
            let hull =
                rod.positions
                    .get(span.first..=span.first + d)
                    .ok_or(CoreError::CountMismatch {
                        what: "control points",
                        expected: span.first + d + 1,
                        found: rod.positions.len(),
                    })?;
            let (lo, hi) = bounding_box(hull, margin);
            self.spans.push(span);
            self.piece.push(piece);
            self.lower.push(lo);
            self.upper.push(hi);
        }
        self.sweep.sort(&self.lower, &self.upper);
        Ok(())
    }

    /// Writes into `out` (cleared first) the pairs `(i, j)`, `i < j`, of span indices
    /// whose boxes overlap and whose [material separation](Self::material_separation) is
    /// at least `exclusion` (m, non-negative), in sweep order. Allocates only if `out`
    /// must grow.
    pub fn candidate_pairs(
        &self,
        exclusion: Real,
        out: &mut Vec<(usize, usize)>,
    ) -> Result<(), CoreError> {
        non_negative("exclusion", exclusion)?;
        out.clear();
        self.sweep.pairs(&self.lower, &self.upper, 0.0, |i, j| {
            let pair = (i.min(j), i.max(j));
            if self.material_separation(pair.0, pair.1) >= exclusion {
                out.push(pair);
            }
        });
        Ok(())
    }

    /// Rest-arclength gap between spans `i < j`: `start_j − end_i` (zero when adjacent),
    /// or infinity when a cut separates them (they lie on different pieces).
    pub fn material_separation(&self, i: usize, j: usize) -> Real {
        if self.piece[i] != self.piece[j] {
            Real::INFINITY
        } else {
            (self.spans[j].start - self.spans[i].end).max(0.0)
        }
    }

    /// The non-empty spans, in material order; pair indices refer to this slice.
    pub fn spans(&self) -> &[Span] {
        &self.spans
    }

    /// Index of the piece (between cuts) that span `i` belongs to, counting from 0.
    pub fn piece(&self, i: usize) -> usize {
        self.piece[i]
    }

    /// Inflated box of span `i`: its lower and upper corners.
    pub fn bounds(&self, i: usize) -> (Vector3<Real>, Vector3<Real>) {
        (self.lower[i], self.upper[i])
    }

    /// The sweep axis (0, 1 or 2) chosen by the last update.
    pub fn axis(&self) -> usize {
        self.sweep.axis()
    }

    /// The margin of the last update.
    pub fn margin(&self) -> Real {
        self.margin
    }

    /// Number of spans (boxes).
    pub fn len(&self) -> usize {
        self.spans.len()
    }

    /// Whether there are no boxes (before the first update).
    pub fn is_empty(&self) -> bool {
        self.spans.is_empty()
    }

    /// Capacities of the internal buffers, for allocation tests.
    #[cfg(test)]
    pub(crate) fn capacities(&self) -> [usize; 5] {
        [
            self.spans.capacity(),
            self.piece.capacity(),
            self.lower.capacity(),
            self.upper.capacity(),
            self.sweep.capacity(),
        ]
    }
}

/// Bounding box of `points`, inflated by `margin` on every side.
fn bounding_box(points: &[Vector3<Real>], margin: Real) -> (Vector3<Real>, Vector3<Real>) {
    let mut lo = Vector3::repeat(Real::INFINITY);
    let mut hi = Vector3::repeat(Real::NEG_INFINITY);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    let m = Vector3::repeat(margin);
    (lo - m, hi + m)
}
