//! Batched ensemble steps (#17): members of an ensemble that share a shape are stepped
//! [`LANES`] at a time by the batched implicit Euler
//! ([`splinerod_integrators::lane_euler`]), structure of arrays, one lane per member.
//!
//! The batched step only *solves*: each member's result is handed to its own integrator
//! ([`Integrator::preload`]), and the member then takes its step as always — sub-steps,
//! energy hooks, the error estimate, adaptivity, the report — with the integrator taking
//! the preloaded result instead of solving when the step is the one it was computed
//! for. So a batched member goes through exactly the stages of a member stepped alone,
//! and its result equals that member's up to round-off (tested: relative 1e-12 on the
//! hanging cable after 1 000 steps).
//!
//! **Who is batched.** Members are taken in index order, [`LANES`] consecutive ones at a
//! time (so the grouping, and with it every result, is the same for any thread count).
//! Within such a group the lanes are the members that can be batched and have the
//! shape of the first of them (the same knots and pins); a lane left over repeats the
//! first member and its result is dropped. A member can be batched when its integrator
//! has a batched form ([`Integrator::lane_params`], implicit Euler), its step is taken
//! whole (no shorter sub-step pending), it does not adapt its knots (whose decisions a
//! round-off difference could flip), it has no driven pins and no time-dependent
//! energy, and every energy acting on it has a lane form
//! ([`splinerod_energies::Energy::lane_term`]: gravity, the lumped mixed stretching and
//! bending); anything else (contact, grabs, loads, clamps, twist) is stepped alone. A
//! batched solve that meets what it does not replicate (see the solver's docs) is
//! dropped whole and its members are stepped alone too.

use crate::Simulation;
use splinerod_core::{Derivatives, Lanes, Real, LANES};
use splinerod_energies::lanes::add_lanes;
use splinerod_energies::LaneTerm;
use splinerod_integrators::lane_euler::{LaneEuler, LanePotential};
use splinerod_integrators::{NewtonParams, System};
use std::cell::RefCell;

/// Most energies a batched member may have.
const MAX_TERMS: usize = 8;

thread_local! {
    /// The batched solver's buffers, one per thread (no allocation once sized).
    static SOLVER: RefCell<LaneEuler> = RefCell::new(LaneEuler::default());
}

/// The potential of the lanes' systems: per energy, its lane terms.
struct Terms<'a> {
    terms: [Option<[LaneTerm<'a>; LANES]>; MAX_TERMS],
}

impl LanePotential for Terms<'_> {
    fn add(
        &self,
        q: &[Lanes],
        energy: &mut Lanes,
        mut derivatives: Option<Derivatives<'_>>,
    ) -> bool {
        self.terms.iter().flatten().all(|terms| {
            let d = derivatives.as_mut().map(Derivatives::reborrow);
            add_lanes(terms, q, energy, d)
        })
    }
}

impl Simulation {
    /// The Newton settings of this member's batched step of `dt`, if it can take one
    /// (see the module docs; the energies are checked when the lanes are formed).
    fn lane_params(&self, dt: Real) -> Option<NewtonParams> {
        let params = self.integrator.lane_params()?;
        let whole = self.substep.memory().next.is_none_or(|h| h >= dt);
        let system = &self.system;
        let driven = system.energies.iter().any(|e| e.time_dependent());
        // An adaptive member's knots follow decisions a round-off difference could
        // flip: stepped alone, it keeps exactly its own results.
        let fixed = self.adapter.is_none();
        (whole && fixed && !driven && system.drivers.is_empty()).then_some(params)
    }
}

/// Whether two members have one shape for the batched step: the same knots, pins at
/// the same places and the same Newton matrix bandwidth.
fn same_shape(a: &Simulation, b: &Simulation) -> bool {
    let (ra, rb) = (&a.system.rod, &b.system.rod);
    let (ka, kb) = (ra.basis().knots(), rb.basis().knots());
    let pins = a.system.pins.iter().zip(&b.system.pins).all(|(p, q)| {
        p.at.to_bits() == q.at.to_bits()
            && p.tangent == q.tangent
            && p.slides_along == q.slides_along
    });
    ra.len() == rb.len()
        && ka.len() == kb.len()
        && ka.iter().zip(kb).all(|(x, y)| x.to_bits() == y.to_bits())
        && a.system.pins.len() == b.system.pins.len()
        && pins
        && a.system.hessian_bandwidth() == b.system.hessian_bandwidth()
        && same_forms(a, b)
}

/// Whether every energy acting on the member has a lane form now.
fn has_lane_form(sim: &Simulation) -> bool {
    let rod = &sim.system.rod;
    sim.system.acting().all(|e| e.lane_term(rod).is_some())
}

/// Whether the energies acting on both members have the same lane forms, in order.
fn same_forms(a: &Simulation, b: &Simulation) -> bool {
    let (ra, rb) = (&a.system.rod, &b.system.rod);
    a.system.acting().count() == b.system.acting().count()
        && a.system.acting().zip(b.system.acting()).all(|(x, y)| {
            match (x.lane_term(ra), y.lane_term(rb)) {
                (Some(x), Some(y)) => x.same_form(&y),
                _ => false,
            }
        })
}

/// Solves the step of `dt` of the members of `group` (at most [`LANES`], consecutive)
/// that can be batched, [`LANES`] of one shape at a time, and preloads each one's
/// integrator with its result. A member's result does not depend on the others in its
/// group: lanes never mix, a lane that fails leaves only its own member to step alone,
/// and lanes left over repeat a member. Members left out are untouched: their own step
/// solves as usual.
pub(crate) fn preload_group(group: &mut [Simulation], dt: Real) {
    if !(dt.is_finite() && dt > 0.0) || group.len() > LANES {
        return;
    }
    let mut params = [None; LANES];
    for (p, sim) in params.iter_mut().zip(group.iter_mut()) {
        *p = sim.lane_params(dt);
        // The step's own begin_step is idempotent (Energy::lane_term's contract).
        if p.is_some() && (sim.system.begin_step(dt).is_err() || !has_lane_form(sim)) {
            *p = None;
        }
    }
    while let Some(lead) = (0..group.len()).find(|&i| params[i].is_some()) {
        let mut lanes = [lead; LANES];
        let mut count = 0;
        for i in lead..group.len() {
            if params[i].is_some()
                && params[i] == params[lead]
                && same_shape(&group[i], &group[lead])
            {
                lanes[count] = i;
                count += 1;
            }
        }
        let settings = params[lead];
        for &i in &lanes[..count] {
            params[i] = None;
        }
        if let Some(settings) = settings {
            solve_lanes(group, lanes, count, &settings, dt);
        }
    }
}

/// The batched solve of the members `lanes` (the first `count` distinct, the rest
/// repeats) of `group`, preloading each member whose lane succeeded.
fn solve_lanes(
    group: &mut [Simulation],
    lanes: [usize; LANES],
    count: usize,
    params: &NewtonParams,
    dt: Real,
) {
    let members: [&Simulation; LANES] = std::array::from_fn(|l| &group[lanes[l]]);
    let Some(potential) = lane_terms(members) else {
        return;
    };
    let rods = members.map(|m| &m.system.rod);
    let pins = members.map(|m| m.system.pins.as_slice());
    let bandwidth = members[0].system.hessian_bandwidth();
    let solved = SOLVER.with(|solver| {
        let mut solver = solver.borrow_mut();
        solver.step(rods, pins, &potential, bandwidth, params, dt)
    });
    if solved.is_err() {
        return;
    }
    SOLVER.with(|solver| {
        let solver = solver.borrow();
        for (l, &i) in lanes.iter().enumerate().take(count) {
            let Ok(outcome) = solver.outcome(l) else {
                continue;
            };
            let sim = &mut group[i];
            let rod = &sim.system.rod;
            let start = (rod.positions.as_slice(), rod.velocities.as_slice());
            sim.integrator.preload(start, &outcome, dt);
        }
    });
}

/// The lane terms of every energy acting on the members, if they all have one and
/// agree in form and shape.
fn lane_terms(members: [&Simulation; LANES]) -> Option<Terms<'_>> {
    let count = members[0].system.acting().count();
    if count > MAX_TERMS || members.iter().any(|m| m.system.acting().count() != count) {
        return None;
    }
    let (n, bw) = (
        members[0].system.rod.len(),
        members[0].system.hessian_bandwidth(),
    );
    let mut terms = Terms {
        terms: [None; MAX_TERMS],
    };
    let mut acting = members.map(|m| m.system.acting());
    for slot in terms.terms.iter_mut().take(count) {
        let mut lane = [None; LANES];
        for ((term, energies), m) in lane.iter_mut().zip(acting.iter_mut()).zip(members) {
            *term = energies.next()?.lane_term(&m.system.rod);
        }
        let mut all = [lane[0]?; LANES];
        for (to, from) in all.iter_mut().zip(lane) {
            *to = from?;
        }
        if !LaneTerm::compatible(&all, n, bw) {
            return None;
        }
        *slot = Some(all);
    }
    Some(terms)
}
