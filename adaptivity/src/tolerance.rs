//! The tolerance criterion: resolution from an error estimate in metres
//! ([`crate::estimate`]) instead of angle thresholds.
//!
//! With tolerance `τ` and the latest estimate:
//!
//! * **refine** a span at its midpoint when the midpoint's estimate exceeds `τ`;
//! * **raise the multiplicity** at an interaction point (a grab, a contact) when one
//!   more knot there would remove more than `τ`: a point force on a string makes a
//!   kink, which knots of multiplicity `d` represent exactly and no amount of span
//!   halving does;
//! * **coarsen**, only while the whole rod's estimate is within `τ`: propose removing an
//!   interior knot when the estimate on its two spans, grown by `2^{d+1}` (the error of
//!   a span twice as long for a method of order `d + 1`), plus the removal's bounded
//!   shape change stays below `coarsen · τ` (default a quarter), and never two
//!   neighbouring knots in one step. Refining above `τ` and coarsening far below it is the
//!   hysteresis that keeps a knot from coming and going; the adapter adds its own
//!   (a fresh knot stays for `hysteresis_steps`).
//!
//! A step whose estimate exceeds `reject · τ` (default 2τ) is **rejected**: the
//! simulation restores its start, inserts this criterion's marks there (exactly) and
//! computes it again, so an under-resolved transient does not leave its error in the
//! motion.
//!
//! Knots at interactions and cuts are never proposed for removal.

use crate::estimate::ErrorEstimate;
use crate::{AdaptError, Refinement, RefinementCriterion};
use splinerod_core::{Real, Rod};

/// Refines where the estimated error exceeds a tolerance, coarsens far below it.
#[derive(Debug, Clone, PartialEq)]
pub struct ToleranceCriterion {
    /// Largest error wanted, m.
    pub tolerance: Real,
    /// Fraction of the tolerance below which a removal (its shape change plus the
    /// grown estimate) is proposed. Default 0.25.
    pub coarsen: Real,
    /// A step whose estimate exceeds `reject · tolerance` is recomputed on a finer basis.
    /// Default 2.
    pub reject: Real,
    /// The latest estimate (set by [`RefinementCriterion::observe`]).
    estimate: ErrorEstimate,
}

impl ToleranceCriterion {
    /// A criterion for `tolerance > 0` metres.
    pub fn new(tolerance: Real) -> Result<Self, AdaptError> {
        crate::error::positive("tolerance", tolerance)?;
        Ok(Self {
            tolerance,
            coarsen: 0.25,
            reject: 2.0,
            estimate: ErrorEstimate::default(),
        })
    }

    /// The same criterion with another coarsening fraction in `(0, 1)`.
    pub fn with_coarsen(mut self, coarsen: Real) -> Result<Self, AdaptError> {
        if !(coarsen > 0.0 && coarsen < 1.0) {
            let reason = "must be strictly between 0 and 1";
            return Err(AdaptError::InvalidParameter {
                name: "coarsen",
                value: coarsen,
                reason,
            });
        }
        self.coarsen = coarsen;
        Ok(self)
    }

    /// Proposes removal of knot `k` if the coarser rod would stay far below tolerance.
    fn removable(&self, rod: &Rod, interactions: &[Real], k: usize) -> bool {
        let basis = rod.basis();
        let knots = basis.knots();
        let (start, end) = basis.domain();
        let t = knots[k];
        if t <= start || t >= end || rod.is_cut_knot(k) || interactions.contains(&t) {
            return false;
        }
        let left = knots[..k].iter().rev().find(|&&x| x < t).copied();
        let right = knots[k..].iter().find(|&&x| x > t).copied();
        let (Some(a), Some(b)) = (left, right) else {
            return false;
        };
        let growth = (2.0 as Real).powi(basis.degree() as i32 + 1);
        let Ok(removal) = basis.removal(k) else {
            return false;
        };
        let change = removal.shape_error(&rod.positions);
        growth * self.estimate.on(a, b) + change <= self.coarsen * self.tolerance
    }
}

impl RefinementCriterion for ToleranceCriterion {
    fn name(&self) -> &str {
        "tolerance"
    }

    fn wants_estimate(&self) -> bool {
        true
    }

    fn observe(&mut self, estimate: Option<&ErrorEstimate>) {
        match estimate {
            Some(e) => self.estimate.clone_from(e),
            // Without a fresh estimate nothing is marked.
            None => {
                self.estimate.spans.clear();
                self.estimate.corners.clear();
                self.estimate.global = Real::INFINITY;
            }
        }
    }

    fn content(&self, estimate: &ErrorEstimate) -> bool {
        estimate.max() <= self.coarsen * self.tolerance
    }

    fn rejects(&self, estimate: &ErrorEstimate) -> bool {
        estimate.max() > self.reject * self.tolerance
    }

    fn mark(&self, rod: &Rod, interactions: &[Real], out: &mut Vec<Refinement>) {
        let tol = self.tolerance;
        for c in &self.estimate.corners {
            // Only while the multiplicity is the one estimated (later rounds see a change).
            if c.error > tol && rod.knot_multiplicity(c.at) == c.multiplicity {
                out.push(Refinement::Insert { at: c.at });
            }
        }
        let knots = rod.basis().knots();
        for span in &self.estimate.spans {
            // Only spans still as estimated (not split by an earlier round).
            let i = knots.partition_point(|&t| t <= span.start);
            let unchanged = knots.get(i) == Some(&span.end);
            if span.midpoint > tol && unchanged {
                let at = 0.5 * (span.start + span.end);
                out.push(Refinement::Insert { at });
            }
        }
        // Coarsen only a rod within tolerance, and never two neighbouring knots in one
        // step (their spans would merge into one three times as long as estimated).
        if self.estimate.max() > tol {
            return;
        }
        let mut last_proposed: Option<Real> = None;
        for k in 0..knots.len() {
            let previous = knots[..k].iter().rev().find(|&&x| x < knots[k]);
            if previous.is_some() && previous == last_proposed.as_ref() {
                continue;
            }
            if self.removable(rod, interactions, k) {
                out.push(Refinement::Remove { knot: k });
                last_proposed = Some(knots[k]);
            }
        }
    }

    fn vetoes_removal(&self, _rod: &Rod, _interactions: &[Real], knot: Real) -> bool {
        // Other criteria may not remove a knot where the estimate is above tolerance.
        self.estimate.on(knot, knot) > self.tolerance
    }
}
