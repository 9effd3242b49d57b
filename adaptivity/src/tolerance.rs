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
//! * **coarsen** locally, wherever the rest of the rod stands: propose removing an
//!   interior knot when the estimate on its two spans, grown by `2^{d+1}` (the error of
//!   a span twice as long for a method of order `d + 1`), plus the removal's bounded
//!   shape change — the removal's *cost* — stays below `coarsen · τ` (default a
//!   quarter), and never two neighbouring knots in one step. Refining above `τ` and
//!   coarsening far below it is the hysteresis that keeps a knot from coming and going;
//!   the adapter adds its own (a fresh knot stays for `hysteresis_steps`).
//! * **trade at rest**: while every span is within `τ` but the largest span estimate
//!   `e_max` is above `coarsen · τ`, one knot per step whose cost is below
//!   `0.7 · e_max` moves to the middle of the worst span (each such trade lowers the
//!   largest estimate by 0.7 at least, so it ends): the placement a transient left is
//!   evened out once the rod settles.
//! * **trade at the budget**: when the rod has `budget` control points (the adapter's
//!   `max_control_points`) and spans above `τ` want more than the budget allows, the
//!   knots whose cost is below half the largest span estimate `e_max` are removed,
//!   cheapest first and as many as the insertions need, so that resolution moves from
//!   where the estimate is smallest to where it is largest. Each trade lowers the
//!   largest estimate by at least half (the merged span costs at most `e_max/2`, the
//!   refined one drops by about `2^{d+1}`), so trading ends, with the estimate as
//!   uniform as the budget allows: no removable knot costs less than `e_max/2`, so no
//!   span is below `e_max / 2^{d+2}` unless a knot there cannot go (an interaction, a
//!   cut, a fresh knot).
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

/// Within tolerance, a knot whose cost is below this fraction of the largest span
/// estimate is moved to that span (each such trade lowers the largest estimate by this
/// factor at least, so trading ends).
const AT_REST_TRADE: Real = 0.7;

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
    /// Control points the rod may have (the adapter's `max_control_points`): at it,
    /// resolution is traded (module docs). `None`: no trading.
    pub budget: Option<usize>,
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
            budget: None,
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

    /// The same criterion trading resolution at `max_control_points` (module docs).
    pub fn with_budget(mut self, max_control_points: usize) -> Self {
        self.budget = Some(max_control_points);
        self
    }

    /// The cost of removing knot `k` (module docs): its two spans' estimate grown by
    /// `2^{d+1}` plus the removal's shape change, m; `None` for a knot that may not go
    /// (an end, a cut, an interaction point, a repeated knot's inner copies).
    fn removal_cost(&self, rod: &Rod, interactions: &[Real], k: usize) -> Option<Real> {
        let basis = rod.basis();
        let knots = basis.knots();
        let (start, end) = basis.domain();
        let t = knots[k];
        if t <= start || t >= end || rod.is_cut_knot(k) || interactions.contains(&t) {
            return None;
        }
        let left = knots[..k].iter().rev().find(|&&x| x < t).copied()?;
        let right = knots[k..].iter().find(|&&x| x > t).copied()?;
        let growth = (2.0 as Real).powi(basis.degree() as i32 + 1);
        let removal = basis.removal(k).ok()?;
        let change = removal.shape_error(&rod.positions);
        let cost = growth * self.estimate.on(left, right) + change;
        cost.is_finite().then_some(cost)
    }

    /// Appends removals, never of two neighbouring knots: every knot whose cost is at
    /// most `coarsen · τ` (in knot order, allocating nothing), then (a trade) the
    /// `extra` cheapest of the others costing at most `limit`. Returns the trades.
    fn mark_removals(
        &self,
        rod: &Rod,
        interactions: &[Real],
        limit: Real,
        extra: usize,
        out: &mut Vec<Refinement>,
    ) -> usize {
        let knots = rod.basis().knots();
        let cheap = self.coarsen * self.tolerance;
        let from = out.len();
        let mut last: Option<Real> = None;
        for k in 0..knots.len() {
            let t = knots[k];
            let previous = knots[..k].iter().rev().find(|&&x| x < t);
            if last == Some(t) || (previous.is_some() && previous == last.as_ref()) {
                continue;
            }
            let cost = self.removal_cost(rod, interactions, k);
            if cost.is_some_and(|c| c <= cheap) {
                out.push(Refinement::Remove { knot: k });
                last = Some(t);
            }
        }
        if extra == 0 {
            return 0;
        }
        self.mark_trades(rod, interactions, (cheap, limit), extra, from, out)
    }

    /// At the budget: appends removals of the `extra` cheapest knots costing within
    /// `costs` (above the cheap ones already in `out[from..]`), never next to another
    /// removal. Returns how many.
    fn mark_trades(
        &self,
        rod: &Rod,
        interactions: &[Real],
        costs: (Real, Real),
        extra: usize,
        from: usize,
        out: &mut Vec<Refinement>,
    ) -> usize {
        let knots = rod.basis().knots();
        let mut values = knots.to_vec();
        values.dedup();
        let rank = |t: Real| values.partition_point(|&v| v < t);
        // A removal blocks its own knot value and both neighbours.
        let mut blocked = vec![false; values.len() + 1];
        let block = |r: usize, blocked: &mut [bool]| {
            blocked[r.saturating_sub(1)..=(r + 1).min(values.len())].fill(true);
        };
        for m in &out[from..] {
            if let Refinement::Remove { knot } = *m {
                block(rank(knots[knot]), &mut blocked);
            }
        }
        let mut candidates: Vec<(Real, usize)> = (0..knots.len())
            .filter(|&k| k == 0 || knots[k - 1] != knots[k])
            .filter_map(|k| Some((self.removal_cost(rod, interactions, k)?, k)))
            .filter(|&(cost, _)| cost > costs.0 && cost <= costs.1)
            .collect();
        candidates.sort_unstable_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        let mut traded = 0;
        for (_, k) in candidates {
            let r = rank(knots[k]);
            if traded >= extra {
                break;
            }
            if blocked[r] {
                continue;
            }
            block(r, &mut blocked);
            out.push(Refinement::Remove { knot: k });
            traded += 1;
        }
        traded
    }

    /// Insertions the spans above tolerance want beyond the budget (0 without one).
    fn over_budget(&self, rod: &Rod, wanted: usize) -> usize {
        self.budget
            .map_or(0, |b| (rod.len() + wanted).saturating_sub(b))
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
        let from = out.len();
        let knots = rod.basis().knots();
        let mut largest: Real = 0.0;
        for span in &self.estimate.spans {
            // Only spans still as estimated (not split by an earlier round).
            let i = knots.partition_point(|&t| t <= span.start);
            let unchanged = knots.get(i) == Some(&span.end);
            if span.midpoint > tol && unchanged {
                let at = 0.5 * (span.start + span.end);
                out.push(Refinement::Insert { at });
                largest = largest.max(span.midpoint);
            }
        }
        // Largest estimate first, so that a budget goes where the error is.
        let error = |m: &Refinement| match *m {
            Refinement::Insert { at } => self.estimate.on(at, at),
            Refinement::Remove { .. } => 0.0,
        };
        out[from..].sort_unstable_by(|a, b| error(b).total_cmp(&error(a)));
        // Without a fresh estimate nothing is removed.
        if self.estimate.spans.is_empty() || !self.estimate.max().is_finite() {
            return;
        }
        // Knots far below tolerance go; at the budget, also the cheapest of the others
        // as many as the insertions need (a trade).
        let wanted = out.len() - from;
        let over = self.over_budget(rod, wanted);
        // Refining (some span above tolerance, split in this step or not): the cheap
        // knots go and, at the budget, trades; no trade at rest.
        if self.estimate.spans.iter().any(|s| s.midpoint > tol) {
            self.mark_removals(rod, interactions, 0.5 * largest, over, out);
            return;
        }
        // Within tolerance but not content: one trade towards the largest estimate.
        let Some(worst) = self
            .estimate
            .spans
            .iter()
            .max_by(|a, b| a.midpoint.total_cmp(&b.midpoint))
        else {
            return;
        };
        let uneven = worst.midpoint > self.coarsen * tol;
        let extra = usize::from(uneven);
        if self.mark_removals(
            rod,
            interactions,
            AT_REST_TRADE * worst.midpoint,
            extra,
            out,
        ) > 0
        {
            let i = knots.partition_point(|&t| t <= worst.start);
            if knots.get(i) == Some(&worst.end) {
                out.push(Refinement::Insert {
                    at: 0.5 * (worst.start + worst.end),
                });
            }
        }
    }

    fn vetoes_removal(&self, _rod: &Rod, _interactions: &[Real], knot: Real) -> bool {
        // Other criteria may not remove a knot where the estimate is above tolerance.
        self.estimate.on(knot, knot) > self.tolerance
    }
}
