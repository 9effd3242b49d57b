//! # splinerod-adaptivity
//!
//! Adaptive resolution (Lenoir et al. 2005, §4): after each integration step, criteria
//! look at the rod and mark knots to insert (where it bends sharply or is touched) and
//! knots to remove (where it is straight); the adapt step applies them through the exact
//! knot maps of `splinerod-core`, so the curve, its motion and every energy are unchanged
//! by an insertion.
//!
//! * [`RefinementCriterion`] — the extension point: look at a rod, mark insertions
//!   and removals, mutate nothing;
//! * [`ToleranceCriterion`] — resolution from an a posteriori error estimate in metres
//!   ([`Estimator`], hierarchical; the mechanics come in through [`FineProblem`]);
//! * [`CurvatureCriterion`] (eq. 13 on the control polygon) and [`InteractionCriterion`]
//!   (knots where the rod is grabbed or touched);
//! * [`Adapter`] — the adapt step with its limits and hysteresis ([`AdaptParams`]) and
//!   the continuity it keeps ([`Continuity`]: corners only where nothing resists bending).
//!
//! ```
//! use splinerod_adaptivity::{Refinement, RefinementCriterion};
//! use splinerod_core::{BSplineSpace, Material, Real, Rod};
//! use nalgebra::Vector3;
//!
//! /// Refines wherever something touches the rod.
//! struct AtInteractions;
//! impl RefinementCriterion for AtInteractions {
//!     fn mark(&self, _rod: &Rod, interactions: &[Real], out: &mut Vec<Refinement>) {
//!         out.extend(interactions.iter().map(|&at| Refinement::Insert { at }));
//!     }
//! }
//!
//! let material = Material { rest_length: 1.0, linear_density: 0.1 };
//! let basis = BSplineSpace::clamped_uniform(3, 6, 1.0)?;
//! let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), Vector3::x())?;
//! let mut marks = Vec::new();
//! AtInteractions.mark(&rod, &[0.3], &mut marks);
//! ().mark(&rod, &[0.3], &mut marks); // the no-op criterion
//! assert_eq!(marks, vec![Refinement::Insert { at: 0.3 }]);
//! # Ok::<(), splinerod_core::CoreError>(())
//! ```
#![warn(missing_docs)]

mod adapter;
pub mod continuity;
pub mod curvature;
mod error;
pub mod estimate;
mod interaction;
mod tolerance;

pub use adapter::{AdaptParams, AdaptReport, Adapter};
pub use continuity::Continuity;
pub use curvature::CurvatureCriterion;
pub use error::AdaptError;
pub use estimate::{ErrorEstimate, Estimator, FineProblem};
pub use interaction::InteractionCriterion;
pub use tolerance::ToleranceCriterion;

use splinerod_core::{Real, Rod};

/// A change of resolution proposed by a criterion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Refinement {
    /// Insert a knot at material coordinate `at` (rest arclength, m).
    Insert {
        /// Where.
        at: Real,
    },
    /// Remove the knot at position `knot` of the knot vector.
    Remove {
        /// Index in the knot vector.
        knot: usize,
    },
}

/// Looks at a rod and marks insertions and removals; mutates nothing.
///
/// Required: [`mark`](RefinementCriterion::mark). `interactions` lists the material
/// coordinates where something acts on the rod (pins, grabs, contacts).
pub trait RefinementCriterion: Send + Sync {
    /// Name used in reports; the type name by default.
    fn name(&self) -> &str {
        std::any::type_name::<Self>()
    }
    /// Appends this criterion's proposals to `out`.
    fn mark(&self, rod: &Rod, interactions: &[Real], out: &mut Vec<Refinement>);
    /// Whether the knot at material coordinate `knot` must stay although another
    /// criterion proposes removing it. Default: no veto.
    fn vetoes_removal(&self, rod: &Rod, interactions: &[Real], knot: Real) -> bool {
        let _ = (rod, interactions, knot);
        false
    }
    /// Whether this criterion reads an error estimate (the caller then computes one and
    /// hands it over through [`observe`](RefinementCriterion::observe)). Default false.
    fn wants_estimate(&self) -> bool {
        false
    }
    /// Receives the error estimate of the rod before an adapt step's marks, or `None`
    /// when no estimate was made for this step. Default: ignored.
    fn observe(&mut self, estimate: Option<&ErrorEstimate>) {
        let _ = estimate;
    }
    /// Whether the step that produced `estimate` should be recomputed from its start on
    /// a basis refined by this criterion's marks ([`Adapter::refine`]). Default false.
    fn rejects(&self, estimate: &ErrorEstimate) -> bool {
        let _ = estimate;
        false
    }
    /// Whether `estimate` is far enough within what this criterion asks that the next
    /// estimates may come less often. Default true.
    fn content(&self, estimate: &ErrorEstimate) -> bool {
        let _ = estimate;
        true
    }
}

/// The criterion that never proposes anything.
impl RefinementCriterion for () {
    fn mark(&self, _rod: &Rod, _interactions: &[Real], _out: &mut Vec<Refinement>) {}
}
