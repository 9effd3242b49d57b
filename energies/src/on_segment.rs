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
//! basis is instead given its own copy through [`Energy::for_finer_rod`].
//!
//! **Cost.** A copy of the segment's state per evaluation (O(n_k)) and, for the
//! Hessian, one pass over the inner energy's blocks: small next to the quadrature.

use crate::{Energy, EnergySummary};
use nalgebra::Vector3;
use splinerod_core::{
    BlockBanded, CoreError, HessianKind, KnotMap, KnotOperation, Real, Rod, SavedState, StateReader,
};
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
    scratch: Vec<Real>,
}

impl Local {
    fn of(joined: &Rod, segment: usize) -> Result<Self, CoreError> {
        Ok(Self {
            rod: joined.segment_rod(segment)?,
            epoch: joined.topology_epoch(),
            hessian: BlockBanded::default(),
            scratch: Vec::new(),
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

    /// Start of the segment's parameter interval.
    fn start(&self, joined: &Rod) -> Real {
        joined.segments().get(self.segment).map_or(0.0, |g| g.start)
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

    /// Asked once per Newton iteration: answered on the segment's copy as it is (a
    /// property of the energy, not of the state), without copying the state in.
    fn has_hessian_remainder(&self, _rod: &Rod) -> bool {
        let copies = self.copies.lock().unwrap_or_else(|e| e.into_inner());
        self.inner.has_hessian_remainder(&copies.main.rod)
    }

    fn add_hessian_remainder(
        &self,
        rod: &Rod,
        v: &[Vector3<Real>],
        scale: Real,
        out: &mut [Vector3<Real>],
    ) {
        let first = rod.segment_points(self.segment).start;
        self.with(rod, (), |local| {
            let n = local.rod.len();
            let (v, out) = (&v[first..first + n], &mut out[first..first + n]);
            self.inner.add_hessian_remainder(&local.rod, v, scale, out);
        });
    }

    fn add_tension(&self, rod: &Rod, s: &[Real], out: &mut [Real]) -> bool {
        let start = self.start(rod);
        let end = start
            + rod
                .segments()
                .get(self.segment)
                .map_or(0.0, |g| g.rest_length());
        self.with(rod, false, |local| {
            let mut any = false;
            for (si, oi) in s.iter().zip(out.iter_mut()) {
                if (start..=end).contains(si) {
                    local.scratch.clear();
                    local.scratch.push(0.0);
                    any |= self
                        .inner
                        .add_tension(&local.rod, &[si - start], &mut local.scratch);
                    *oi += local.scratch[0];
                }
            }
            any
        })
    }

    fn update_multipliers(&mut self, rod: &Rod, stiffen: bool) -> Real {
        let copies = self.copies.get_mut().unwrap_or_else(|e| e.into_inner());
        match copy_for(copies, rod, self.segment) {
            Some(local) => self.inner.update_multipliers(&local.rod, stiffen),
            None => 0.0,
        }
    }

    fn set_stiffness_scale(&mut self, scale: Real) -> bool {
        self.inner.set_stiffness_scale(scale)
    }

    fn bandwidth(&self, rod: &Rod) -> usize {
        let d = rod.basis().degree();
        self.with(rod, d, |local| self.inner.bandwidth(&local.rod))
    }

    fn on_knot_change(&mut self, rod: &Rod, map: &KnotMap) {
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
            Ok(local_map) => self.inner.on_knot_change(&local.rod, &local_map),
            // The joined rod made this change, so the same change on the copy cannot
            // fail; should it, rebuild the copy (the inner energy keeps its caches).
            Err(_) => {
                if let Ok(copy) = Local::of(rod, self.segment) {
                    *local = copy;
                }
            }
        }
    }

    fn for_finer_rod(&self, fine: &Rod) -> Option<Box<dyn Energy>> {
        let main = Local::of(fine, self.segment).ok()?;
        let inner = self.inner.for_finer_rod(&main.rod)?;
        Some(Box::new(OnSegment {
            segment: self.segment,
            inner,
            copies: Mutex::new(Copies { main, other: None }),
        }))
    }

    fn save_state(&self, out: &mut SavedState) {
        self.inner.save_state(out);
    }

    fn load_state(&mut self, rod: &Rod, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        let copies = self.copies.get_mut().unwrap_or_else(|e| e.into_inner());
        match copy_for(copies, rod, self.segment) {
            Some(local) => self.inner.load_state(&local.rod, input),
            None => Err(CoreError::StateMismatch("a segment the rod does not have")),
        }
    }

    fn begin_step(&mut self, rod: &Rod, dt: Real) -> Result<(), CoreError> {
        let copies = self.copies.get_mut().unwrap_or_else(|e| e.into_inner());
        match copy_for(copies, rod, self.segment) {
            Some(local) => self.inner.begin_step(&local.rod, dt),
            None => Err(CoreError::InvalidParameter {
                name: "segment",
                value: self.segment as Real,
                reason: "the rod has no such segment, or it changed unheard",
            }),
        }
    }

    fn drive(&mut self, t: Real) {
        self.inner.drive(t);
    }

    fn time_dependent(&self) -> bool {
        self.inner.time_dependent()
    }

    fn interaction_points(&self, rod: &Rod, out: &mut Vec<Real>) -> Result<(), CoreError> {
        let (from, start) = (out.len(), self.start(rod));
        self.with(rod, Ok(()), |local| {
            self.inner.interaction_points(&local.rod, out)
        })?;
        out[from..].iter_mut().for_each(|s| *s += start);
        Ok(())
    }

    fn admissible(&self, rod: &Rod) -> bool {
        self.with(rod, false, |local| self.inner.admissible(&local.rod))
    }

    fn segment(&self) -> Option<usize> {
        Some(self.segment)
    }

    fn summary(&self, rod: &Rod) -> Result<EnergySummary, CoreError> {
        self.with(rod, Ok(EnergySummary::default()), |local| {
            self.inner.summary(&local.rod)
        })
    }
}
