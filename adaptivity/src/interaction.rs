//! The interaction criterion: wherever something acts on the rod at a material point —
//! a grab, a point force, a contact — the rod needs a knot there to bend locally. It
//! proposes a knot at each interaction coordinate `s` unless another knot lies within
//! `radius`, and vetoes removing knots within `radius` of an active interaction.
//!
//! With `multiplicity` m > 1 the knot at `s` is repeated up to m times (never more than
//! the degree, which would cut the rod): the curve is then only \(C^{d-m}\) there. A
//! point force on a string makes a corner (m = d represents it exactly); on a rod with
//! bending stiffness a jump of curvature (m = d − 1). The paper uses m = 1.

use crate::{AdaptError, Refinement, RefinementCriterion};
use splinerod_core::{Real, Rod};

/// Refines at interaction points and keeps them refined while the interaction lasts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct InteractionCriterion {
    /// A knot closer than this (m of rest arclength) to an interaction is good enough.
    pub radius: Real,
    /// Multiplicity wanted at the interaction (≥ 1, capped at the degree).
    pub multiplicity: usize,
}

impl InteractionCriterion {
    /// A criterion with the given `radius > 0` (m) and simple knots.
    pub fn new(radius: Real) -> Result<Self, AdaptError> {
        crate::error::positive("interaction_radius", radius)?;
        Ok(Self {
            radius,
            multiplicity: 1,
        })
    }

    /// The same criterion wanting `multiplicity ≥ 1` knots at each interaction.
    pub fn with_multiplicity(mut self, multiplicity: usize) -> Result<Self, AdaptError> {
        if multiplicity == 0 {
            let reason = "must be at least 1";
            return Err(AdaptError::InvalidParameter {
                name: "interaction_multiplicity",
                value: 0.0,
                reason,
            });
        }
        self.multiplicity = multiplicity;
        Ok(self)
    }

    /// Whether an interaction at `s` wants one more knot.
    fn wants_knot(&self, rod: &Rod, s: Real) -> bool {
        let present = rod.knot_multiplicity(s);
        let wanted = self.multiplicity.min(rod.basis().degree());
        if present > 0 {
            present < wanted
        } else {
            !self.knot_near(rod, s)
        }
    }

    fn knot_near(&self, rod: &Rod, s: Real) -> bool {
        let knots = rod.basis().knots();
        let i = knots.partition_point(|&t| t < s);
        let near = |j: usize| knots.get(j).is_some_and(|&t| (t - s).abs() <= self.radius);
        near(i) || (i > 0 && near(i - 1))
    }
}

impl RefinementCriterion for InteractionCriterion {
    fn name(&self) -> &str {
        "interaction"
    }

    fn mark(&self, rod: &Rod, interactions: &[Real], out: &mut Vec<Refinement>) {
        let (start, end) = rod.basis().domain();
        for &s in interactions {
            if s > start && s < end && self.wants_knot(rod, s) {
                out.push(Refinement::Insert { at: s });
            }
        }
    }

    fn vetoes_removal(&self, _rod: &Rod, interactions: &[Real], knot: Real) -> bool {
        interactions
            .iter()
            .any(|&s| (s - knot).abs() <= self.radius)
    }
}
