//! The adapt step run after each integration step (paper §4.1, ADAPTATION()): insert
//! while some criterion marks an insertion, then remove what is marked for removal, then
//! (when removals made room under `max_control_points`) insert once more: a criterion
//! at the budget trades resolution this way.
//!
//! Guards, all in [`AdaptParams`]: at most `max_control_points`; no span shorter than
//! `min_span` (m); removals only while together they move the curve by at most
//! `shape_tolerance` (m, summing the bounds of [`splinerod_core::KnotMap::shape_error`]);
//! never below `min_control_points`; never a cut knot; and
//! hysteresis: a knot inserted is not removed during the next `hysteresis_steps` adapt
//! steps, so nothing oscillates. Every applied map is reported through a callback, so
//! energies with per-coefficient caches can follow (`Lifecycle::on_knot_change`) without
//! this crate knowing about them.

use crate::{AdaptError, Continuity, ErrorEstimate, Refinement, RefinementCriterion};
use splinerod_core::{KnotMap, Real, Rod};

/// Limits of the adapt step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AdaptParams {
    /// Never more control points than this.
    pub max_control_points: usize,
    /// Never fewer control points than this (removals stop there).
    pub min_control_points: usize,
    /// Never a knot span shorter than this (m of rest arclength).
    pub min_span: Real,
    /// Largest curve displacement a removal may cause (m).
    pub shape_tolerance: Real,
    /// Adapt steps during which a freshly inserted knot may not be removed.
    pub hysteresis_steps: usize,
    /// Most insertion rounds per adapt step (each round re-evaluates the criteria).
    pub max_rounds: usize,
}

impl Default for AdaptParams {
    fn default() -> Self {
        Self {
            max_control_points: 200,
            min_control_points: 4,
            min_span: 1e-3,
            shape_tolerance: 1e-6,
            hysteresis_steps: 10,
            max_rounds: 4,
        }
    }
}

impl AdaptParams {
    /// Checks the ranges.
    pub fn validate(&self) -> Result<(), AdaptError> {
        crate::error::positive("min_span", self.min_span)?;
        crate::error::positive("shape_tolerance", self.shape_tolerance)?;
        if self.min_control_points > self.max_control_points {
            let reason = "must not exceed max_control_points";
            return Err(AdaptError::InvalidParameter {
                name: "min_control_points",
                value: self.min_control_points as Real,
                reason,
            });
        }
        if self.max_rounds == 0 {
            let reason = "must be at least 1";
            return Err(AdaptError::InvalidParameter {
                name: "max_rounds",
                value: 0.0,
                reason,
            });
        }
        Ok(())
    }
}

/// What one adapt step did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AdaptReport {
    /// Knots inserted.
    pub inserted: usize,
    /// Knots removed.
    pub removed: usize,
    /// Times the step was recomputed on a finer basis (its estimate was rejected).
    pub redone_steps: usize,
}

impl std::ops::AddAssign for AdaptReport {
    fn add_assign(&mut self, other: AdaptReport) {
        self.inserted += other.inserted;
        self.removed += other.removed;
        self.redone_steps += other.redone_steps;
    }
}

/// Criteria, limits and the memory (hysteresis) of the adapt step.
pub struct Adapter {
    /// Limits.
    pub params: AdaptParams,
    /// The criteria consulted, in order.
    pub criteria: Vec<Box<dyn RefinementCriterion>>,
    /// Where insertions may repeat a knot up to the degree (a corner); elsewhere at most
    /// `d − 1` ([`Continuity`]; default: corners nowhere).
    pub continuity: Continuity,
    /// Recently inserted knot values and the adapt steps they stay protected.
    protected: Vec<(Real, usize)>,
    marks: Vec<Refinement>,
    /// Knot indices proposed for removal (reused buffer).
    removals: Vec<usize>,
}

impl std::fmt::Debug for Adapter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = self.criteria.iter().map(|c| c.name()).collect();
        f.debug_struct("Adapter")
            .field("params", &self.params)
            .field("criteria", &names)
            .field("continuity", &self.continuity)
            .field("protected", &self.protected)
            .finish()
    }
}

impl Adapter {
    /// The knots protected from removal for a while (coordinate, adapt steps left): the
    /// adapter's memory between steps (checkpoints save it).
    pub fn protected(&self) -> &[(Real, usize)] {
        &self.protected
    }

    /// Puts back a saved [`protected`](Self::protected) list.
    pub fn set_protected(&mut self, protected: &[(Real, usize)]) {
        self.protected.clear();
        self.protected.extend_from_slice(protected);
    }

    /// An adapter with the given limits and no criteria.
    pub fn new(params: AdaptParams) -> Result<Self, AdaptError> {
        params.validate()?;
        Ok(Self {
            params,
            criteria: Vec::new(),
            continuity: Continuity::default(),
            protected: Vec::new(),
            marks: Vec::new(),
            removals: Vec::new(),
        })
    }

    /// The same adapter keeping `continuity` (builder style).
    pub fn with_continuity(mut self, continuity: Continuity) -> Self {
        self.continuity = continuity;
        self
    }

    /// Adds a criterion.
    pub fn with(mut self, criterion: impl RefinementCriterion + 'static) -> Self {
        self.criteria.push(Box::new(criterion));
        self
    }

    /// Whether a criterion reads an error estimate (pass one to [`Adapter::adapt`]).
    pub fn wants_estimate(&self) -> bool {
        self.criteria.iter().any(|c| c.wants_estimate())
    }

    /// Runs the adapt step on `rod`; `interactions` are the material coordinates where
    /// something acts on it; `estimate` (the one made for this step, if any) goes to the
    /// criteria first; `on_change`
    /// sees the rod after every applied map.
    pub fn adapt(
        &mut self,
        rod: &mut Rod,
        interactions: &[Real],
        estimate: Option<&ErrorEstimate>,
        on_change: &mut dyn FnMut(&Rod, &KnotMap),
    ) -> Result<AdaptReport, AdaptError> {
        self.criteria.iter_mut().for_each(|c| c.observe(estimate));
        self.protected.retain_mut(|(_, steps)| {
            *steps = steps.saturating_sub(1);
            *steps > 0
        });
        let mut report = AdaptReport::default();
        for _ in 0..self.params.max_rounds {
            let inserted = self.insert_round(rod, interactions, on_change)?;
            report.inserted += inserted;
            if inserted == 0 {
                break;
            }
        }
        report.removed = self.remove_round(rod, interactions, on_change)?;
        if report.removed > 0 && rod.len() < self.params.max_control_points {
            // Removals at the budget made room for insertions it had blocked.
            report.inserted += self.insert_round(rod, interactions, on_change)?;
        }
        Ok(report)
    }

    /// Whether a criterion rejects the step that produced `estimate` (and the rod may
    /// still grow): recompute it after [`Adapter::refine`].
    pub fn rejects(&self, rod: &Rod, estimate: &ErrorEstimate) -> bool {
        rod.len() < self.params.max_control_points
            && self.criteria.iter().any(|c| c.rejects(estimate))
    }

    /// Whether every criterion is content with `estimate` (see
    /// [`RefinementCriterion::content`]): estimates may then come less often.
    pub fn content(&self, estimate: &ErrorEstimate) -> bool {
        self.criteria.iter().all(|c| c.content(estimate))
    }

    /// One round of insertions only, from `estimate` (for the restored start of a
    /// rejected step); returns the knots inserted.
    pub fn refine(
        &mut self,
        rod: &mut Rod,
        interactions: &[Real],
        estimate: &ErrorEstimate,
        on_change: &mut dyn FnMut(&Rod, &KnotMap),
    ) -> Result<usize, AdaptError> {
        self.criteria
            .iter_mut()
            .for_each(|c| c.observe(Some(estimate)));
        self.insert_round(rod, interactions, on_change)
    }

    fn collect(&mut self, rod: &Rod, interactions: &[Real]) {
        self.marks.clear();
        for c in &self.criteria {
            c.mark(rod, interactions, &mut self.marks);
        }
    }

    fn insert_round(
        &mut self,
        rod: &mut Rod,
        interactions: &[Real],
        on_change: &mut dyn FnMut(&Rod, &KnotMap),
    ) -> Result<usize, AdaptError> {
        self.collect(rod, interactions);
        let mut count = 0;
        let marks = std::mem::take(&mut self.marks);
        for (k, m) in marks.iter().enumerate() {
            let Refinement::Insert { at } = *m else {
                continue;
            };
            // One insertion per value and round (criteria may agree on a place).
            let repeated = marks[..k].contains(m);
            if repeated || rod.len() >= self.params.max_control_points || !self.room_for(rod, at) {
                continue;
            }
            let map = rod.insert_knot(at)?;
            on_change(rod, &map);
            self.protected.push((at, self.params.hysteresis_steps + 1));
            count += 1;
        }
        self.marks = marks;
        Ok(count)
    }

    /// Whether inserting `at` leaves both halves of its span at least `min_span` long
    /// (repeating an existing knot makes no new span and is allowed below the
    /// multiplicity [`Continuity`] allows there: `d` (a corner) on strings, `d − 1`
    /// where bending or twist acts; a criterion never makes the curve discontinuous,
    /// which at `d + 1` — the junction of two rods of `[[rods]]`, a cut — it already is).
    fn room_for(&self, rod: &Rod, at: Real) -> bool {
        let most = self.continuity.max_multiplicity(rod.basis().degree(), at);
        if rod.knot_multiplicity(at) >= most {
            return false;
        }
        let knots = rod.basis().knots();
        let i = knots.partition_point(|&t| t <= at);
        let (Some(&right), Some(&left)) = (knots.get(i), i.checked_sub(1).map(|j| &knots[j]))
        else {
            return false;
        };
        left == at || (at - left >= self.params.min_span && right - at >= self.params.min_span)
    }

    fn remove_round(
        &mut self,
        rod: &mut Rod,
        interactions: &[Real],
        on_change: &mut dyn FnMut(&Rod, &KnotMap),
    ) -> Result<usize, AdaptError> {
        self.collect(rod, interactions);
        let mut knots = std::mem::take(&mut self.removals);
        knots.clear();
        knots.extend(self.marks.iter().filter_map(|m| match m {
            Refinement::Remove { knot } => Some(*knot),
            Refinement::Insert { .. } => None,
        }));
        // Highest index first, so the indices still to visit stay valid.
        knots.sort_unstable_by(|a, b| b.cmp(a));
        knots.dedup();
        // The removals of one adapt step share the tolerance: together they move the
        // curve by at most `shape_tolerance`.
        let mut budget = self.params.shape_tolerance;
        let mut count = 0;
        for &k in &knots {
            if rod.len() <= self.params.min_control_points {
                break;
            }
            if !self.removable(rod, interactions, k) {
                continue;
            }
            let error = rod.basis().removal(k)?.shape_error(&rod.positions);
            if error.is_nan() || error > budget {
                continue;
            }
            let map = rod.remove_knot(k, budget)?;
            on_change(rod, &map);
            budget -= error;
            count += 1;
        }
        // Keep the buffer for the next step (an error above merely drops it).
        self.removals = knots;
        Ok(count)
    }

    fn removable(&self, rod: &Rod, interactions: &[Real], k: usize) -> bool {
        let Some(&value) = rod.basis().knots().get(k) else {
            return false;
        };
        !rod.is_cut_knot(k)
            && !self.protected.iter().any(|&(v, _)| v == value)
            && !self
                .criteria
                .iter()
                .any(|c| c.vetoes_removal(rod, interactions, value))
    }
}
