//! Decorators: an energy acting through another on a rod of its own, passing every
//! capability on without naming any of them ([`crate::OnSegment`] is one).
//!
//! A decorator implements [`Decorator`]: how to hand its inner energy the rod it sees
//! (a [`Decorator::view`] with the state copied in), where that rod sits in the outer
//! one ([`Placement`]: the first control point and the material coordinates), and how
//! knot changes and finer copies map. Everything else is generic, written once here:
//!
//! - each capability trait has one blanket implementation for every [`Decorator`], which
//!   asks the inner energy's capability on the inner rod and places the result (gradient
//!   slices at `first`, material coordinates shifted by `start`);
//! - [`Capabilities::through`] maps the inner energy's capabilities to the decorator's:
//!   a capability the inner energy has, the decorator has. It destructures every field,
//!   so a new capability does not compile until its mapping is written — here, once for
//!   every decorator.
//!
//! A decorator's own [`Energy::capabilities`] is then
//! `self.inner().capabilities().through(self)` and its [`Energy::lifecycle_mut`] is
//! [`lifecycle_through`]`(self)`. Two capabilities are the decorator's own as well, and
//! always present: the [`Lifecycle`] (its copy must hear of knot changes whatever the
//! inner energy does with them) and the [`Interaction`] (a state in which it cannot
//! place its inner rod is not admissible).
//!
//! One capability does not survive relocation: a [`LaneTerm`] is a form over the whole
//! rod's arrays, so through a decorator [`LaneForm::lane_term`] answers `None` (the
//! batched step then steps the rod on its own, with the same result).

use crate::capabilities::{
    Capabilities, HessianRemainder, Interaction, LaneForm, Lifecycle, Summary, Tension,
};
use crate::{Energy, EnergySummary, LaneTerm, Parameters};
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{CoreError, KnotMap, Real, Rod, SavedState, StateReader};

/// Where a decorator's inner rod sits in the rod it is evaluated on.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Index, in the outer rod, of the inner rod's first control point.
    pub first: usize,
    /// Material coordinate (m), in the outer rod, of the inner rod's start.
    pub start: Real,
    /// Material coordinate (m), in the outer rod, of the inner rod's end.
    pub end: Real,
}

/// An energy that acts through an inner one on a rod of its own (module docs). Its
/// capabilities follow from these methods by the blanket implementations of this
/// module.
pub trait Decorator: Energy {
    /// The energy acting on the inner rod.
    fn inner(&self) -> &dyn Energy;

    /// The inner energy, mutably.
    fn inner_mut(&mut self) -> &mut dyn Energy;

    /// Where the inner rod sits in `rod`.
    fn placement(&self, rod: &Rod) -> Placement;

    /// Runs `f` on the inner energy and the inner rod for `rod` (its state copied in);
    /// `None` if there is no such rod (the outer rod lost the part).
    fn view<R>(&self, rod: &Rod, f: impl FnOnce(&dyn Energy, &Rod) -> R) -> Option<R>;

    /// As [`view`](Decorator::view), with the inner energy mutable.
    fn view_mut<R>(&mut self, rod: &Rod, f: impl FnOnce(&mut dyn Energy, &Rod) -> R) -> Option<R>;

    /// Follows a knot change of the outer rod, and hands the inner energy its own
    /// change, if the inner rod changed, through `f`.
    fn follow_knot_change(
        &mut self,
        rod: &Rod,
        map: &KnotMap,
        f: impl FnOnce(&mut dyn Energy, &Rod, &KnotMap),
    );

    /// This decorator on `fine` (a finer copy of the outer rod) around the inner energy
    /// `f` returns for the matching inner rod; `None` if `f` returns `None`.
    fn on_finer(
        &self,
        fine: &Rod,
        f: impl FnOnce(&dyn Energy, &Rod) -> Option<Box<dyn Energy>>,
    ) -> Option<Box<dyn Energy>>;

    /// The error of a step begun on a rod that has no inner rod for this decorator.
    fn unplaced(&self) -> CoreError;
}

impl<'a> Capabilities<'a> {
    /// These capabilities (an inner energy's) as those of the decorator `d`: each one
    /// present is answered by `d`, on the inner rod; the lifecycle and the interaction
    /// always are (module docs).
    pub fn through<D: Decorator>(self, d: &'a D) -> Capabilities<'a> {
        let Capabilities {
            lifecycle: _,
            interaction: _,
            remainder,
            tension,
            lanes,
            summary,
            parameters,
            segment,
        } = self;
        Capabilities {
            lifecycle: Some(d),
            interaction: Some(d),
            remainder: remainder.map(|_| d as &dyn HessianRemainder),
            tension: tension.map(|_| d as &dyn Tension),
            lanes: lanes.map(|_| d as &dyn LaneForm),
            summary: summary.map(|_| d as &dyn Summary),
            parameters: parameters.map(|_| d as &dyn Parameters),
            segment,
        }
    }
}

/// The decorator's [`Lifecycle`], mutably: itself (see [`Capabilities::through`]).
pub fn lifecycle_through<D: Decorator>(d: &mut D) -> Option<&mut dyn Lifecycle> {
    Some(d)
}

impl<D: Decorator> Lifecycle for D {
    fn begin_step(&mut self, rod: &Rod, dt: Real) -> Result<(), CoreError> {
        let step =
            |e: &mut dyn Energy, r: &Rod| e.lifecycle_mut().map_or(Ok(()), |l| l.begin_step(r, dt));
        self.view_mut(rod, step)
            .unwrap_or_else(|| Err(self.unplaced()))
    }

    fn on_knot_change(&mut self, rod: &Rod, map: &KnotMap) {
        self.follow_knot_change(rod, map, |e, r, m| {
            if let Some(l) = e.lifecycle_mut() {
                l.on_knot_change(r, m);
            }
        });
    }

    fn drive(&mut self, t: Real) {
        if let Some(l) = self.inner_mut().lifecycle_mut() {
            l.drive(t);
        }
    }

    fn grip(&mut self, end: usize, rotation: &Matrix3<Real>, roll: Real) {
        if let Some(l) = self.inner_mut().lifecycle_mut() {
            l.grip(end, rotation, roll);
        }
    }

    fn add_start_rate(&self, rod: &Rod, start_rate: &[Vector3<Real>], out: &mut [Vector3<Real>]) {
        let first = self.placement(rod).first;
        self.view(rod, |e, r| {
            let n = r.len();
            let (rate, out) = (&start_rate[first..first + n], &mut out[first..first + n]);
            if let Some(l) = e.capabilities().lifecycle {
                l.add_start_rate(r, rate, out);
            }
        });
    }

    fn time_dependent(&self) -> bool {
        let inner = self.inner().capabilities().lifecycle;
        inner.is_some_and(|l| l.time_dependent())
    }

    fn update_multipliers(&mut self, rod: &Rod, stiffen: bool) -> Real {
        let update = |e: &mut dyn Energy, r: &Rod| {
            e.lifecycle_mut()
                .map_or(0.0, |l| l.update_multipliers(r, stiffen))
        };
        self.view_mut(rod, update).unwrap_or(0.0)
    }

    fn set_stiffness_scale(&mut self, scale: Real) -> bool {
        let inner = self.inner_mut().lifecycle_mut();
        inner.is_some_and(|l| l.set_stiffness_scale(scale))
    }

    fn save_state(&self, out: &mut SavedState) {
        if let Some(l) = self.inner().capabilities().lifecycle {
            l.save_state(out);
        }
    }

    fn load_state(&mut self, rod: &Rod, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        let load = |e: &mut dyn Energy, r: &Rod| {
            e.lifecycle_mut().map_or(Ok(()), |l| l.load_state(r, input))
        };
        let missing = || Err(CoreError::StateMismatch("a segment the rod does not have"));
        self.view_mut(rod, load).unwrap_or_else(missing)
    }

    fn for_finer_rod(&self, fine: &Rod) -> Option<Box<dyn Energy>> {
        self.on_finer(fine, |e, r| e.capabilities().lifecycle?.for_finer_rod(r))
    }

    fn supports(&self, rod: &Rod) -> Result<(), CoreError> {
        let supports =
            |e: &dyn Energy, r: &Rod| e.capabilities().lifecycle.map_or(Ok(()), |l| l.supports(r));
        self.view(rod, supports)
            .unwrap_or_else(|| Err(self.unplaced()))
    }
}

impl<D: Decorator> Interaction for D {
    fn interaction_points(&self, rod: &Rod, out: &mut Vec<Real>) -> Result<(), CoreError> {
        let (from, start) = (out.len(), self.placement(rod).start);
        let points = |e: &dyn Energy, r: &Rod| {
            let inner = e.capabilities().interaction;
            inner.map_or(Ok(()), |i| i.interaction_points(r, out))
        };
        self.view(rod, points).unwrap_or(Ok(()))?;
        out[from..].iter_mut().for_each(|s| *s += start);
        Ok(())
    }

    fn admissible(&self, rod: &Rod) -> bool {
        let admissible = |e: &dyn Energy, r: &Rod| {
            let inner = e.capabilities().interaction;
            inner.is_none_or(|i| i.admissible(r))
        };
        self.view(rod, admissible).unwrap_or(false)
    }

    fn add_obstacle_forces(
        &self,
        rod: &Rod,
        out: &mut Vec<Vector3<Real>>,
    ) -> Result<(), CoreError> {
        let forces = |e: &dyn Energy, r: &Rod| {
            let inner = e.capabilities().interaction;
            inner.map_or(Ok(()), |i| i.add_obstacle_forces(r, out))
        };
        self.view(rod, forces).unwrap_or(Ok(()))
    }
}

impl<D: Decorator> HessianRemainder for D {
    fn has_remainder(&self, rod: &Rod) -> bool {
        let has = |e: &dyn Energy, r: &Rod| {
            let inner = e.capabilities().remainder;
            inner.is_some_and(|h| h.has_remainder(r))
        };
        self.view(rod, has).unwrap_or(false)
    }

    fn add_remainder(
        &self,
        rod: &Rod,
        v: &[Vector3<Real>],
        scale: Real,
        out: &mut [Vector3<Real>],
    ) {
        let first = self.placement(rod).first;
        self.view(rod, |e, r| {
            let n = r.len();
            let (v, out) = (&v[first..first + n], &mut out[first..first + n]);
            if let Some(h) = e.capabilities().remainder {
                h.add_remainder(r, v, scale, out);
            }
        });
    }
}

impl<D: Decorator> Tension for D {
    fn add_tension(&self, rod: &Rod, s: &[Real], out: &mut [Real]) -> bool {
        let Placement { start, end, .. } = self.placement(rod);
        let tension = |e: &dyn Energy, r: &Rod| {
            let Some(inner) = e.capabilities().tension else {
                return false;
            };
            let mut any = false;
            for (si, oi) in s.iter().zip(out.iter_mut()) {
                if (start..=end).contains(si) {
                    let mut one = [0.0];
                    any |= inner.add_tension(r, &[si - start], &mut one);
                    *oi += one[0];
                }
            }
            any
        };
        self.view(rod, tension).unwrap_or(false)
    }
}

impl<D: Decorator> LaneForm for D {
    /// None: a lane term is a form over the whole rod's arrays (module docs).
    fn lane_term<'a>(&'a self, rod: &'a Rod) -> Option<LaneTerm<'a>> {
        let _ = rod;
        None
    }
}

impl<D: Decorator> Summary for D {
    fn summary(&self, rod: &Rod) -> Result<EnergySummary, CoreError> {
        let summary = |e: &dyn Energy, r: &Rod| {
            let inner = e.capabilities().summary;
            inner.map_or(Ok(EnergySummary::default()), |s| s.summary(r))
        };
        self.view(rod, summary)
            .unwrap_or(Ok(EnergySummary::default()))
    }
}

impl<D: Decorator> Parameters for D {
    fn parameter_names(&self) -> &[&'static str] {
        self.inner()
            .capabilities()
            .parameters
            .map_or(&[], |p| p.parameter_names())
    }

    fn add_gradient_derivative(
        &self,
        rod: &Rod,
        name: &str,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError> {
        let first = self.placement(rod).first;
        let derivative = |e: &dyn Energy, r: &Rod| {
            let out = &mut out[first..first + r.len()];
            e.capabilities()
                .parameters
                .map_or(Ok(false), |p| p.add_gradient_derivative(r, name, out))
        };
        self.view(rod, derivative).unwrap_or(Ok(false))
    }
}
