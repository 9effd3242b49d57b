//! [`OnSegment`]: any energy acting on one rod of a joined rod ([`Rod::join`]).
//!
//! A joined rod puts several rods end to end in parameter space, separated by cuts, so
//! that one Newton matrix and one contact detection serve them all. Each rod keeps its
//! own energies — its stiffnesses, its rest shape, its twist, or an energy a user wrote
//! for one rod — and none of them needs to know it is part of a whole: `OnSegment`
//! keeps a copy of segment `k` as a rod of its own ([`Rod::segment_rod`]), copies the
//! segment's positions and velocities into it before every evaluation, and shifts what
//! the inner energy returns (gradient entries, Hessian blocks, material coordinates)
//! to the segment's place in the whole. The copy's knots are the joined rod's, shifted
//! by the segment's start, so that
//!
//! \\[ E_{\text{joined}}(q) = E_{\text{inner}}\big(q_{\text{first}\,..\,\text{first}+n_k}\big) \\]
//!
//! exactly, and the gradient and Hessian are the inner energy's, placed at control
//! point `first` of the segment.
//!
//! **Knot changes.** Every insertion or removal of the joined rod inside the segment is
//! replayed on the copy, and the inner energy hears of it with the copy's own
//! [`KnotMap`]; a change elsewhere only moves where the segment's control points start.
//!
//! **Other rods.** Evaluated on a rod that is not the joined rod it follows (an error
//! estimator's refined copy, whose topology epoch differs), it builds a second copy of
//! the segment from that rod and evaluates there; an inner energy whose data follow the
//! basis is instead given its own copy through [`Lifecycle::for_finer_rod`].
//!
//! **Capabilities.** `OnSegment` forwards none by hand: it is a [`Decorator`] (how its
//! copy stands for the joined rod: [`Decorator::view`], [`Placement`], the knot replay,
//! the finer copy), and every capability of the inner energy passes through the
//! generic implementations of [`crate::decorate`] — a capability added later passes
//! through without a change here.
//!
//! **Cost.** A copy of the segment's state per evaluation (O(n_k)) and, for the
//! Hessian, one pass over the inner energy's blocks: small next to the quadrature.

use crate::capabilities::{Capabilities, Lifecycle};
use crate::decorate::{lifecycle_through, Decorator, Placement};
use crate::Energy;
use nalgebra::Vector3;
use splinerod_core::{BlockBanded, CoreError, HessianKind, KnotMap, KnotOperation, Real, Rod};
use std::sync::Mutex;

/// An energy of one segment of a joined rod (module docs).
pub struct OnSegment {
    /// Index of the segment ([`Rod::segments`]).
    segment: usize,
    inner: Box<dyn Energy>,
    copies: Mutex<Copies>,
}

/// The segment of the joined rod followed, and of another rod evaluated on.
struct Copies {
    main: Local,
    other: Option<Local>,
}

/// The segment as a rod of its own, the joined rod's epoch it mirrors, and buffers.
struct Local {
    rod: Rod,
    epoch: u64,
    hessian: BlockBanded,
}

impl Local {
    fn of(joined: &Rod, segment: usize) -> Result<Self, CoreError> {
        Ok(Self {
            rod: joined.segment_rod(segment)?,
            epoch: joined.topology_epoch(),
            hessian: BlockBanded::default(),
        })
    }
}

impl OnSegment {
    /// `inner` acting on segment `segment` of `joined`.
    pub fn new(joined: &Rod, segment: usize, inner: Box<dyn Energy>) -> Result<Self, CoreError> {
        let main = Local::of(joined, segment)?;
        Ok(Self {
            segment,
            inner,
            copies: Mutex::new(Copies { main, other: None }),
        })
    }

    /// The segment's index.
    pub fn segment(&self) -> usize {
        self.segment
    }

    /// The energy acting on it.
    pub fn inner(&self) -> &dyn Energy {
        self.inner.as_ref()
    }

    /// Runs `f` on the copy of the segment of `joined` (state copied in) and the index
    /// of its first control point in `joined`; `fallback` if no copy can be made.
    fn with<R>(&self, joined: &Rod, fallback: R, f: impl FnOnce(&mut Local) -> R) -> R {
        let mut copies = self.copies.lock().unwrap_or_else(|e| e.into_inner());
        let local = match copy_for(&mut copies, joined, self.segment) {
            Some(local) => local,
            None => return fallback,
        };
        f(local)
    }

    /// Where the segment cannot be evaluated (the rod has no such segment any more):
    /// NaN in its part of `gradient` (all of it if the part is not there), so the
    /// failure is seen — as the NaN energy is — instead of a gradient with nothing added.
    fn poison(&self, joined: &Rod, gradient: &mut [Vector3<Real>]) {
        let range = joined.segment_points(self.segment);
        let part = match gradient.get_mut(range) {
            Some(part) if !part.is_empty() => part,
            _ => gradient,
        };
        part.fill(Vector3::repeat(Real::NAN));
    }
}

/// The copy following `joined` (the main one, or the other rebuilt for a foreign rod),
/// with the segment's state copied in; `None` if `joined` has no such segment.
fn copy_for<'a>(copies: &'a mut Copies, joined: &Rod, k: usize) -> Option<&'a mut Local> {
    let local = if copies.main.epoch == joined.topology_epoch() {
        &mut copies.main
    } else {
        let stale = copies
            .other
            .as_ref()
            .is_none_or(|o| o.epoch != joined.topology_epoch());
        if stale {
            copies.other = Some(Local::of(joined, k).ok()?);
        }
        copies.other.as_mut()?
    };
    let range = joined.segment_points(k);
    if range.len() != local.rod.len() {
        return None;
    }
    local
        .rod
        .positions
        .copy_from_slice(&joined.positions[range.clone()]);
    local
        .rod
        .velocities
        .copy_from_slice(&joined.velocities[range]);
    Some(local)
}

impl Energy for OnSegment {
    fn name(&self) -> &str {
        self.inner.name()
    }

    fn energy(&self, rod: &Rod) -> Real {
        self.with(rod, Real::NAN, |local| self.inner.energy(&local.rod))
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let first = rod.segment_points(self.segment).start;
        let done = self.with(rod, false, |local| {
            let n = local.rod.len();
            self.inner
                .add_gradient(&local.rod, &mut gradient[first..first + n]);
            true
        });
        if !done {
            self.poison(rod, gradient);
        }
    }

    fn add_hessian(&self, rod: &Rod, kind: HessianKind, hessian: &mut BlockBanded) {
        let first = rod.segment_points(self.segment).start;
        self.with(rod, (), |local| {
            let (part, h) = (&local.rod, &mut local.hessian);
            h.reset(part.len(), self.inner.bandwidth(part));
            self.inner.add_hessian(part, kind, h);
            hessian.add_shifted(h, first);
        });
    }

    fn add_gradient_and_hessian(
        &self,
        rod: &Rod,
        kind: HessianKind,
        gradient: &mut [Vector3<Real>],
        hessian: &mut BlockBanded,
    ) {
        let first = rod.segment_points(self.segment).start;
        let done = self.with(rod, false, |local| {
            let (part, h) = (&local.rod, &mut local.hessian);
            h.reset(part.len(), self.inner.bandwidth(part));
            let g = &mut gradient[first..first + part.len()];
            self.inner.add_gradient_and_hessian(part, kind, g, h);
            hessian.add_shifted(h, first);
            true
        });
        if !done {
            self.poison(rod, gradient);
        }
    }

    fn bandwidth(&self, rod: &Rod) -> usize {
        let d = rod.basis().degree();
        self.with(rod, d, |local| self.inner.bandwidth(&local.rod))
    }

    /// The inner energy's capabilities, answered on the segment (generic:
    /// [`crate::decorate`]).
    fn capabilities(&self) -> Capabilities<'_> {
        Capabilities {
            segment: Some(self.segment),
            ..self.inner.capabilities().through(self)
        }
    }

    fn lifecycle_mut(&mut self) -> Option<&mut dyn Lifecycle> {
        lifecycle_through(self)
    }
}

/// How the segment's copy stands for the joined rod; every capability follows from it.
impl Decorator for OnSegment {
    fn inner(&self) -> &dyn Energy {
        self.inner.as_ref()
    }

    fn inner_mut(&mut self) -> &mut dyn Energy {
        self.inner.as_mut()
    }

    fn placement(&self, rod: &Rod) -> Placement {
        let segment = rod.segments().get(self.segment);
        let start = segment.map_or(0.0, |g| g.start);
        Placement {
            first: rod.segment_points(self.segment).start,
            start,
            end: start + segment.map_or(0.0, |g| g.rest_length()),
        }
    }

    fn view<R>(&self, rod: &Rod, f: impl FnOnce(&dyn Energy, &Rod) -> R) -> Option<R> {
        self.with(rod, None, |local| Some(f(self.inner.as_ref(), &local.rod)))
    }

    fn view_mut<R>(&mut self, rod: &Rod, f: impl FnOnce(&mut dyn Energy, &Rod) -> R) -> Option<R> {
        let copies = self.copies.get_mut().unwrap_or_else(|e| e.into_inner());
        let local = copy_for(copies, rod, self.segment)?;
        Some(f(self.inner.as_mut(), &local.rod))
    }

    /// Replays a change inside the segment on the copy (module docs).
    fn follow_knot_change(
        &mut self,
        rod: &Rod,
        map: &KnotMap,
        f: impl FnOnce(&mut dyn Energy, &Rod, &KnotMap),
    ) {
        let copies = self.copies.get_mut().unwrap_or_else(|e| e.into_inner());
        let local = &mut copies.main;
        local.epoch = rod.topology_epoch();
        let Some(g) = rod.segments().get(self.segment).copied() else {
            return;
        };
        let value = map.value();
        if !(value > g.start && value < g.end) {
            return;
        }
        let replayed = match map.operation() {
            KnotOperation::Insert => local.rod.insert_knot(value - g.start),
            KnotOperation::Remove => {
                // Knot indices of the segment start where its control points do.
                let index = map.knot_index() - rod.segment_points(self.segment).start;
                local.rod.remove_knot(index, Real::MAX)
            }
        };
        match replayed {
            Ok(local_map) => f(self.inner.as_mut(), &local.rod, &local_map),
            // The joined rod made this change, so the same change on the copy cannot
            // fail; should it, rebuild the copy (the inner energy keeps its caches).
            Err(_) => {
                if let Ok(copy) = Local::of(rod, self.segment) {
                    *local = copy;
                }
            }
        }
    }

    fn on_finer(
        &self,
        fine: &Rod,
        f: impl FnOnce(&dyn Energy, &Rod) -> Option<Box<dyn Energy>>,
    ) -> Option<Box<dyn Energy>> {
        let main = Local::of(fine, self.segment).ok()?;
        let inner = f(self.inner.as_ref(), &main.rod)?;
        Some(Box::new(OnSegment {
            segment: self.segment,
            inner,
            copies: Mutex::new(Copies { main, other: None }),
        }))
    }

    fn unplaced(&self) -> CoreError {
        CoreError::InvalidParameter {
            name: "segment",
            value: self.segment as Real,
            reason: "the rod has no such segment, or it changed unheard",
        }
    }
}
