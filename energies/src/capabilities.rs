//! What an [`Energy`] can do besides its mechanical core: small object-safe capability
//! traits, reached through [`Energy::capabilities`] (read) and [`Energy::lifecycle_mut`]
//! (the one capability with state to change).
//!
//! An energy implements the capabilities it has and names them in one struct literal,
//! `Capabilities { summary: Some(self), ..Capabilities::default() }`; every field it
//! leaves out is `None`, which callers read as the old defaults did (no remainder, no
//! tension, admissible everywhere, nothing to save). Methods that must agree live in one
//! trait: [`HessianRemainder`] answers whether there is a remainder and applies it,
//! [`Lifecycle`] holds the pair [`drive`](Lifecycle::drive) /
//! [`time_dependent`](Lifecycle::time_dependent) and the pair
//! [`save_state`](Lifecycle::save_state) / [`load_state`](Lifecycle::load_state).
//!
//! **Adding a capability** (as parameter derivatives were, [`crate::parameters`]) is one trait, one field of
//! [`Capabilities`] (default `None`: no energy changes) and its mapping through a
//! decorator in [`crate::decorate`] (the compiler asks for it: [`Capabilities::through`]
//! lists every field); no decorator is edited by hand.

use crate::{Energy, EnergySummary, LaneTerm};
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{CoreError, KnotMap, Real, Rod, SavedState, StateReader};

/// The capabilities of one energy, each `None` when it does not have it (the default).
#[derive(Clone, Copy, Default)]
pub struct Capabilities<'a> {
    /// Per-step hooks, knot changes, driving, continuation and checkpoint state.
    pub lifecycle: Option<&'a dyn Lifecycle>,
    /// Material points where it acts, line-search barrier, forces on obstacles.
    pub interaction: Option<&'a dyn Interaction>,
    /// A Hessian part that is not banded.
    pub remainder: Option<&'a dyn HessianRemainder>,
    /// An axial tension along the centreline.
    pub tension: Option<&'a dyn Tension>,
    /// A form the batched ensemble step evaluates for several rods at once.
    pub lanes: Option<&'a dyn LaneForm>,
    /// Statistics for reports.
    pub summary: Option<&'a dyn Summary>,
    /// Scalar parameters and the derivative of the gradient by each (sensitivities).
    pub parameters: Option<&'a dyn crate::Parameters>,
    /// The segment of a joined rod this energy acts on alone ([`crate::OnSegment`]);
    /// `None` for an energy of the whole rod.
    pub segment: Option<usize>,
}

/// An energy's life beside its values: per-step hooks, knot changes, time dependence,
/// continuation, checkpoints. Every method defaults to doing nothing; an energy
/// implements the ones it needs and returns itself from both
/// [`Energy::capabilities`] (`lifecycle`) and [`Energy::lifecycle_mut`].
pub trait Lifecycle: Send + Sync {
    /// Called before each integrator step (sub-step) of `dt` seconds, at the state it
    /// starts from: freeze per-step data here (contact freezes its friction anchors).
    fn begin_step(&mut self, rod: &Rod, dt: Real) -> Result<(), CoreError> {
        let _ = (rod, dt);
        Ok(())
    }

    /// Adds the derivative of the gradient by the positions frozen at the step's start
    /// ([`begin_step`](Lifecycle::begin_step)), applied to their derivative
    /// `start_rate` by a parameter (one per control point), to `out`: a run's forward
    /// sensitivities carry the dependence of the frozen data on the parameters this way
    /// (contact: the friction anchors). Default: nothing frozen depends on them.
    fn add_start_rate(&self, rod: &Rod, start_rate: &[Vector3<Real>], out: &mut [Vector3<Real>]) {
        let _ = (rod, start_rate, out);
    }

    /// Called after the rod's knots changed through `map`; update cached data locally.
    fn on_knot_change(&mut self, rod: &Rod, map: &KnotMap) {
        let _ = (rod, map);
    }

    /// Called in the drivers stage of every step (sub-step) with the time `t` the step
    /// ends at (a static solve: its end time): a turning clamp, a moving obstacle set
    /// their state for `t` here. Must do nothing unless
    /// [`time_dependent`](Lifecycle::time_dependent).
    fn drive(&mut self, t: Real) {
        let _ = t;
    }

    /// Called when the gripper holding the clamp at end `end` of the rod (0: `s = 0`,
    /// 1: `s = L`) moved: its `rotation` against its start and its `roll` about the
    /// carried axis (rad, on a continuous branch; [`crate::twisting::grip`]). An energy
    /// measured against the clamps' frames (twist) carries them. Default: nothing.
    fn grip(&mut self, end: usize, rotation: &Matrix3<Real>, roll: Real) {
        let _ = (end, rotation, roll);
    }

    /// Whether [`drive`](Lifecycle::drive) changes this energy (energy-conserving
    /// integrators then count the work it does). Default false.
    fn time_dependent(&self) -> bool {
        false
    }

    /// For energies holding constraints by multipliers (the inextensible rod): one
    /// method-of-multipliers update at the current state, `stiffen`ing the penalty if the
    /// violation fell too slowly (for repeated solves of one equilibrium, not for time
    /// steps); returns the violation before it (dimensionless). Default 0.
    fn update_multipliers(&mut self, rod: &Rod, stiffen: bool) -> Real {
        let _ = (rod, stiffen);
        0.0
    }

    /// Scales the energy's stiffness to `scale` times its own (`1` restores it exactly),
    /// for a static solver's continuation from a soft rod to the real one; returns
    /// whether the energy has such a stiffness (default: no, and nothing changes).
    fn set_stiffness_scale(&mut self, scale: Real) -> bool {
        let _ = scale;
        false
    }

    /// Appends what this energy keeps between steps that the rod does not determine
    /// (multipliers, a transported frame, a neighbour list whose rounding results depend
    /// on), for a checkpoint ([`splinerod_core::state`]). Default: nothing.
    fn save_state(&self, out: &mut SavedState) {
        let _ = out;
    }

    /// Reads back what [`save_state`](Lifecycle::save_state) wrote, into a copy built
    /// like this one and brought to the same knots; `rod` is the restored rod.
    fn load_state(&mut self, rod: &Rod, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        let _ = (rod, input);
        Ok(())
    }

    /// This energy for `fine`, a copy of its rod on a finer basis (the same curve), for
    /// error estimators. An energy whose data follow the rod's coefficients or
    /// quadrature points must return a copy that follows `fine`; `None` (the default)
    /// says it is evaluated on `fine` as it is.
    fn for_finer_rod(&self, fine: &Rod) -> Option<Box<dyn Energy>> {
        let _ = fine;
        None
    }

    /// Whether the energy can act on `rod`: an error naming what it cannot handle (a
    /// closed rod, for an energy defined by the rod's ends). The conformance harness
    /// skips the rods it refuses. Default: every rod.
    fn supports(&self, rod: &Rod) -> Result<(), CoreError> {
        let _ = rod;
        Ok(())
    }
}

/// Where an energy acts locally, what it forbids and what it exerts on obstacles.
pub trait Interaction: Send + Sync {
    /// Appends the material coordinates (m) where this energy acts locally now (both
    /// sides of every contact), for refinement criteria. Default: none.
    fn interaction_points(&self, rod: &Rod, out: &mut Vec<Real>) -> Result<(), CoreError> {
        let _ = (rod, out);
        Ok(())
    }

    /// Whether the rod's state is one Newton's line search may move to (a penalty is a
    /// finite barrier; see `System::admissible`). Default: always.
    fn admissible(&self, rod: &Rod) -> bool {
        let _ = rod;
        true
    }

    /// Appends the force (N) the rod exerts on each rigid obstacle this energy holds.
    /// Default: it holds none.
    fn add_obstacle_forces(
        &self,
        rod: &Rod,
        out: &mut Vec<Vector3<Real>>,
    ) -> Result<(), CoreError> {
        let _ = (rod, out);
        Ok(())
    }
}

/// A part `R` of the Hessian `H + R` that [`Energy::add_hessian`] leaves out because it
/// is not banded (a mixed form's consistent Gram matrix couples every control point
/// with every other). Both methods in one trait, so they cannot disagree.
pub trait HessianRemainder: Send + Sync {
    /// Whether there is a remainder for `rod` now.
    fn has_remainder(&self, rod: &Rod) -> bool;

    /// Adds `scale · R v` to `out`. `R` must be symmetric positive semi-definite and
    /// the same for either [`splinerod_core::HessianKind`]: Newton's method factorises
    /// the banded `H` and corrects its step by conjugate gradients preconditioned with
    /// it. O(n) and allocation-free.
    fn add_remainder(&self, rod: &Rod, v: &[Vector3<Real>], scale: Real, out: &mut [Vector3<Real>]);
}

/// The axial tension an energy carries.
pub trait Tension: Send + Sync {
    /// Adds the axial tension (force along the centreline, N) at the material
    /// coordinates `s` into `out` (same length); returns whether it added any.
    fn add_tension(&self, rod: &Rod, s: &[Real], out: &mut [Real]) -> bool;
}

/// An energy the batched ensemble step can evaluate for several rods at once
/// ([`crate::lanes`]).
pub trait LaneForm: Send + Sync {
    /// This energy on `rod` as a lane term, if it has such a form now; `None` steps the
    /// rod on its own, with the same result. The term must equal [`Energy::energy`] and
    /// the exact [`Energy::add_gradient_and_hessian`] up to round-off, and
    /// [`Lifecycle::begin_step`] must be idempotent for an energy that has one (the
    /// batched step calls it before the member's own step does).
    fn lane_term<'a>(&'a self, rod: &'a Rod) -> Option<LaneTerm<'a>>;
}

/// Statistics an energy reports.
pub trait Summary: Send + Sync {
    /// Statistics of the current state for reports.
    fn summary(&self, rod: &Rod) -> Result<EnergySummary, CoreError>;
}
