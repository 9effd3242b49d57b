//! Coarse starts (issue #46): a start whose curve overlaps an obstacle, the floor or
//! itself only because its fit is coarse is refined and pushed out, instead of refused.
//!
//! **Coarse or genuine.** A spline smooths its control polygon: a few control points
//! fitted around a capsule give a curve that cuts into it although the points are
//! outside. So the start is judged on its control polygon too
//! (`splinerod_energies::contact::close`): it is *genuinely* overlapping if some place
//! is deeper than [`MIN_START_CLEARANCE`] allows (the rule that refused starts before)
//! on the curve **and** on the control polygon; such a start is left as it is, and the
//! start checks refuse it naming the field. Any other overlap is resolved.
//!
//! **When.** With the barrier (or the adaptive penalty) any place closer than
//! [`ACCEPT`] of the tolerance is resolved — the barrier must start outside its
//! continuation, and a start deep in the layer would be flung apart. With the fixed
//! penalty (`stiffness` alone) only starts the old rule refused are, so nothing that
//! ran before changes.
//!
//! **How**, in rounds until every place is at least [`ACCEPT`] of the layer (the
//! tolerance or onset) from touching:
//!
//! 1. *Refine*: each knot span holding a close place and longer than
//!    [`MIN_SPAN_RADII`] radii is halved by knot insertion — exact, the curve does not
//!    move, but the control polygon comes closer to it and a push moves less rod.
//! 2. *Push*: otherwise each close place asks its side(s) to move by the deficit
//!    \\(D = \tfrac12 \ell - g\\) (half of it each for a pair of strands) along the
//!    direction that opens it; control point `i` moves by the average of what the
//!    places it carries ask, weighted by its basis value there,
//!    \\(\Delta q_i = \sum_p b_i(s_p) D_p n_p / \sum_p b_i(s_p)\\), so the curve near
//!    a place moves by about its deficit (the basis sums to one). Control points that
//!    carry a pin do not move (a pin must agree with the start).
//!
//! At most [`MAX_ROUNDS`] rounds and a budget of control points (four times the
//! scene's, at least 64; the adapter's cap if lower); a start still too close then is
//! returned unchanged, for the start checks to judge. `[[rods]]` scenes resolve each rod
//! against the obstacles, the floor and itself; rods overlapping each other are judged
//! as before.

use crate::scene::build::MIN_START_CLEARANCE;
use crate::scene::Scene;
use crate::Error;
use nalgebra::Vector3;
use splinerod_core::basis::{spans, MAX_ORDER};
use splinerod_core::{Real, Rod};
use splinerod_energies::Contact;

/// Places are resolved to at least this fraction of the layer from touching.
pub const ACCEPT: Real = 0.25;
/// Most rounds of refining and pushing.
pub const MAX_ROUNDS: usize = 60;
/// Knot spans holding a close place are halved down to this length, in radii.
pub const MIN_SPAN_RADII: Real = 4.0;

/// One side of a close place, owned: first control point, basis row, its length.
#[derive(Clone, Copy)]
struct Side {
    s: Real,
    first: usize,
    row: [Real; MAX_ORDER],
    len: usize,
}

/// A close place, owned (see `splinerod_energies::contact::close::Close`).
struct Place {
    gap: Real,
    normal: Vector3<Real>,
    sides: [Option<Side>; 2],
}

impl Scene {
    /// `rod` (as [`Scene::build_rod`] made it), its start refined and pushed out where it
    /// overlaps only because its fit is coarse (module docs); unchanged otherwise.
    pub(crate) fn resolve_coarse_start(&self, rod: Rod) -> Result<Rod, Error> {
        let (Some(contact), Some(layer)) = (self.contact()?, self.contact_layer()) else {
            return Ok(rod);
        };
        let fixed_penalty = self
            .contact
            .as_ref()
            .is_some_and(|c| c.stiffness.is_some() && c.tolerance.is_none());
        let deep = |gap: Real, distance: Real| gap < -(1.0 - MIN_START_CLEARANCE) * distance;
        let (mut needed, mut genuine) = (false, false);
        contact.for_each_close(&rod, ACCEPT * layer, |c| {
            needed |= !fixed_penalty || deep(c.gap, c.distance);
            genuine |= deep(c.gap, c.distance) && deep(c.polygon_gap, c.distance);
        })?;
        if !needed || genuine {
            return Ok(rod);
        }
        Ok(self.pushed_out(&contact, &rod, layer)?.unwrap_or(rod))
    }

    /// The rounds of the module docs from `rod`; `None` if they do not get every place
    /// [`ACCEPT`] of the `layer` from touching.
    fn pushed_out(&self, contact: &Contact, rod: &Rod, layer: Real) -> Result<Option<Rod>, Error> {
        let mut rod = rod.clone();
        let radius = contact.params().radius;
        let budget = self.coarse_budget(rod.len());
        let mut places = Vec::new();
        for _ in 0..MAX_ROUNDS {
            places.clear();
            contact.for_each_close(&rod, ACCEPT * layer, |c| places.push(Place::of(c)))?;
            if places.is_empty() {
                return Ok(Some(rod));
            }
            if self.refine_around(&mut rod, &places, MIN_SPAN_RADII * radius, budget)? {
                continue;
            }
            let fixed = self.pinned_points(&rod);
            push(&mut rod, &places, 0.5 * layer, &fixed);
        }
        Ok(None)
    }

    /// Control points the scene may end up with after refining a start of `n`.
    fn coarse_budget(&self, n: usize) -> usize {
        let cap = self.adaptivity.as_ref().filter(|a| a.enabled);
        let budget = (4 * n).max(64);
        cap.map_or(budget, |a| budget.min(a.max_control_points).max(n))
    }

    /// Halves every knot span holding a place that is longer than `shortest`, within
    /// `budget` control points; whether any knot was inserted.
    fn refine_around(
        &self,
        rod: &mut Rod,
        places: &[Place],
        shortest: Real,
        budget: usize,
    ) -> Result<bool, Error> {
        let mut mids: Vec<Real> = spans(rod.basis())
            .filter(|g| g.end - g.start > shortest)
            .filter(|g| {
                let inside = |s: Real| s >= g.start && s < g.end;
                places
                    .iter()
                    .any(|p| p.sides.iter().flatten().any(|d| inside(d.s)))
            })
            .map(|g| 0.5 * (g.start + g.end))
            .collect();
        mids.truncate(budget.saturating_sub(rod.len()));
        for &s in &mids {
            rod.insert_knot(s)?;
        }
        Ok(!mids.is_empty())
    }

    /// Which control points carry a pin (its basis row at the pinned point, and the
    /// next one inwards for a clamp).
    fn pinned_points(&self, rod: &Rod) -> Vec<bool> {
        let mut fixed = vec![false; rod.len()];
        let l = rod.material().rest_length;
        let (start, end) = rod.basis().domain();
        for pin in &self.pins {
            // A closed rod's `at = 1` is its seam, `s = 0`.
            let s = (pin.at * l).clamp(start, end);
            let Ok(b) = rod.basis_at(if s >= end && rod.is_closed() {
                start
            } else {
                s
            }) else {
                continue;
            };
            for k in 0..b.order {
                let clamp = pin.clamp && (k == 1 || k + 2 == b.order);
                if b.value[k] != 0.0 || clamp {
                    fixed[b.first + k] = true;
                }
            }
        }
        fixed
    }
}

impl Place {
    fn of(c: &splinerod_energies::contact::close::Close<'_>) -> Place {
        let side = |d: &splinerod_energies::contact::close::Side<'_>| {
            let mut row = [0.0; MAX_ORDER];
            let len = d.row.len().min(MAX_ORDER);
            row[..len].copy_from_slice(&d.row[..len]);
            Side {
                s: d.s,
                first: d.first,
                row,
                len,
            }
        };
        Place {
            gap: c.gap,
            normal: c.normal,
            sides: [Some(side(&c.a)), c.b.as_ref().map(side)],
        }
    }
}

/// One push (module docs): each place asks for the gap `target`.
fn push(rod: &mut Rod, places: &[Place], target: Real, fixed: &[bool]) {
    let m = rod.distinct_len();
    let mut asked = vec![(Vector3::zeros(), 0.0); m];
    for p in places {
        let pair = p.sides[1].is_some();
        let deficit = (target - p.gap) * if pair { 0.5 } else { 1.0 };
        for (side, sign) in p.sides.iter().zip([1.0, -1.0]) {
            let Some(d) = side else { continue };
            for (k, &b) in d.row[..d.len].iter().enumerate() {
                let a = &mut asked[(d.first + k) % m];
                a.0 += p.normal * (sign * deficit * b);
                a.1 += b;
            }
        }
    }
    for i in 0..rod.len() {
        let (sum, weight) = asked[i % m];
        if weight > 0.0 && !fixed[i] && !fixed[i % m] {
            rod.positions[i] += sum / weight;
        }
    }
}
