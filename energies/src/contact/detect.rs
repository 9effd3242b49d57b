//! Contact detection between parts of one rod: the broad phase of
//! [`SpanBoxes`](splinerod_core::proximity::SpanBoxes) (boxes inflated by half the
//! reach, so every pair of spans closer than the reach is a candidate; only adjacent
//! spans are skipped), then [`closest_points`] on each candidate pair.
//!
//! A candidate becomes a contact when its closest points are closer than the reach and
//! at least `exclusion` apart in rest arclength: closer points are neighbours on the
//! rod, not a contact — also across a cut, whose two new ends start at one point and
//! separate freely instead of being blown apart by the penalty. A closest point at a span boundary is counted
//! once: a point at the end of a span belongs to the next span of the same piece (which
//! finds it at its start or inside); a point at the start of a span is dropped when the
//! distance still decreases into the previous span (the previous span finds it inside).
//! So a contact sliding across a knot hands over from one pair to the next without
//! being counted twice or lost.
//!
//! The detection is cached on the positions and the basis epoch: the energy, gradient
//! and Hessian of one Newton iterate detect once.

use nalgebra::Vector3;
use splinerod_core::basis::Span;
use splinerod_core::proximity::{closest_points, SpanBoxes};
use splinerod_core::{BasisValues, CoreError, Real, Rod};

/// One contact: closest points `C(s)` and `C(t)` of two parts of the rod.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    /// Material coordinate on the first part, m of rest arclength.
    pub s: Real,
    /// Material coordinate on the second part, m of rest arclength.
    pub t: Real,
    /// Distance \\(|C(s) - C(t)|\\) between the centre lines, m.
    pub distance: Real,
    /// Unit vector from `C(t)` to `C(s)`.
    pub normal: Vector3<Real>,
    /// Basis row at `s`.
    pub(crate) row_s: BasisValues,
    /// Basis row at `t`.
    pub(crate) row_t: BasisValues,
}

/// Buffers and cache of the detection (reused: no allocation once sized).
#[derive(Debug, Clone, Default)]
pub(crate) struct Detector {
    boxes: SpanBoxes,
    pairs: Vec<(usize, usize)>,
    /// Contacts found by the last detection.
    pub contacts: Vec<ContactPoint>,
    /// Candidate pairs of the last detection (broad phase output).
    pub candidates: usize,
    cached: Option<(u64, Real, Real)>,
    positions: Vec<Vector3<Real>>,
}

/// Largest float below `x`.
fn below(x: Real) -> Real {
    f64::from_bits(x.to_bits().saturating_sub(1))
}

impl Detector {
    /// Detects contacts closer than `reach` (m) between points at least `exclusion` (m)
    /// apart in rest arclength, unless the rod is unchanged since the last call with the
    /// same settings.
    pub fn detect(&mut self, rod: &Rod, reach: Real, exclusion: Real) -> Result<(), CoreError> {
        let key = (rod.topology_epoch(), reach, exclusion);
        if self.cached == Some(key) && self.positions == rod.positions {
            return Ok(());
        }
        self.cached = None;
        self.contacts.clear();
        self.boxes.update(rod, 0.5 * reach)?;
        // Adjacent spans have zero separation: any positive threshold skips just them.
        let adjacent = 1e-12 * rod.material().rest_length;
        self.boxes.candidate_pairs(adjacent, &mut self.pairs)?;
        self.candidates = self.pairs.len();
        for p in 0..self.pairs.len() {
            let (i, j) = self.pairs[p];
            if let Some(contact) = self.narrow(rod, i, j, reach, exclusion)? {
                self.contacts.push(contact);
            }
        }
        self.positions.clone_from(&rod.positions);
        self.cached = Some(key);
        Ok(())
    }

    /// The contact of spans `i < j`, if their closest points are one.
    fn narrow(
        &self,
        rod: &Rod,
        i: usize,
        j: usize,
        reach: Real,
        exclusion: Real,
    ) -> Result<Option<ContactPoint>, CoreError> {
        let spans = self.boxes.spans();
        let c = closest_points(rod, &spans[i], &spans[j])?;
        if c.distance >= reach || (c.t - c.s).abs() < exclusion {
            return Ok(None);
        }
        let r = c.normal * c.distance; // C(s) − C(t)
        if !self.owns(rod, i, c.s, &r, 1.0)? || !self.owns(rod, j, c.t, &r, -1.0)? {
            return Ok(None);
        }
        let mut row_s = BasisValues::default();
        let mut row_t = BasisValues::default();
        rod.basis().evaluate(c.s, &mut row_s)?;
        rod.basis().evaluate(c.t, &mut row_t)?;
        Ok(Some(ContactPoint {
            s: c.s,
            t: c.t,
            distance: c.distance,
            normal: c.normal,
            row_s,
            row_t,
        }))
    }

    /// Whether span `k` owns the closest point at `u` (module docs); `sign` is +1 for the
    /// first parameter (∂f/∂s = r·C′(s)) and −1 for the second (∂f/∂t = −r·C′(t)).
    fn owns(
        &self,
        rod: &Rod,
        k: usize,
        u: Real,
        r: &Vector3<Real>,
        sign: Real,
    ) -> Result<bool, CoreError> {
        let spans = self.boxes.spans();
        let span: &Span = &spans[k];
        let continues = |other: usize| self.boxes.piece(other) == self.boxes.piece(k);
        if u >= below(span.end) && k + 1 < spans.len() && continues(k + 1) {
            return Ok(false);
        }
        if u <= span.start && k > 0 && continues(k - 1) {
            let mut left = BasisValues::default();
            rod.basis().evaluate(below(span.start), &mut left)?;
            let tangent = left.combine(&left.d1, &rod.positions);
            return Ok(sign * r.dot(&tangent) <= 0.0);
        }
        Ok(true)
    }
}
