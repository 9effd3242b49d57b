//! Batched ensemble steps (#17): members of an ensemble that share a shape are stepped
//! [`LANES`] at a time by the batched implicit Euler
//! ([`splinerod_integrators::lane_euler`]), structure of arrays, one lane per member.
//!
//! The batched step only *solves*: each member's result is handed to its own integrator
//! ([`splinerod_integrators::Batched::preload`]), and the member then takes its step
//! as always — sub-steps, energy hooks, the error estimate, adaptivity, the report — with the integrator taking
//! the preloaded result instead of solving when the step is the one it was computed
//! for. So a batched member goes through exactly the stages of a member stepped alone,
//! and its result equals that member's up to round-off (tested: relative 1e-12 on the
//! hanging cable after 1 000 steps).
//!
//! **Who is batched.** Members are taken in index order, [`LANES`] consecutive ones at a
//! time (so the grouping, and with it every result, is the same for any thread count).
//! Within such a group the lanes are the members that can be batched and have the
//! shape of the first of them (the same knots and pins); a lane left over repeats the
//! first member and its result is dropped, so a group of one member, or a member of a
//! shape of its own, is solved in the lanes too. Whether a member can be batched is
//! decided in one place, [`batching`], from the ensemble's setting, the step's `dt` and
//! the member alone, which returns the reason ([`Unbatched`]) when it cannot: batching
//! is on ([`crate::Ensemble::batched`]), `dt` is finite and positive, its integrator has a batched form
//! ([`splinerod_integrators::Batched::lane_params`], implicit Euler), its step is
//! taken whole (no shorter sub-step pending), it does not adapt its knots (whose decisions a round-off
//! difference could flip), it has no driven pins and no time-dependent energy, and
//! every energy acting on it has a lane form ([`splinerod_energies::LaneForm::lane_term`]:
//! gravity, the lumped mixed stretching and bending); anything else (contact, grabs,
//! loads, clamps, twist) is stepped alone. A batched solve that meets what it does not
//! replicate (see the solver's docs) hands the lane's member back to step alone, with
//! the lane's reason.
//!
//! **Independent of the lane-mates.** Every operation of the batched solve is lane by
//! lane (the potential reports per lane whether it could evaluate it, the solver fails
//! lanes one by one), the lanes of one solve share their shape, settings and forms, and
//! the members' own decisions come first; so a member computes the same bits whichever
//! members share its group — also alone, with its lanes repeated. (Bending's lanes read
//! the first lane's quadrature table: the same bits as every lane's, since the lanes'
//! knots are equal bit for bit and an ensemble's members reach them by the same
//! operations.) That is what makes
//! a shard of an ensemble (`--shard K/N`) compute its members exactly as a run of the
//! whole ensemble, for any shard size.

use crate::world::unbatched::Unbatched;
use crate::Simulation;
use splinerod_core::{Derivatives, Lanes, Real, Rod, LANES};
use splinerod_energies::lanes::add_lanes;
use splinerod_energies::{Energy, LaneTerm};
use splinerod_integrators::lane_euler::{LaneEuler, LanePotential, LaneStep};
use splinerod_integrators::{NewtonParams, System};
use std::cell::RefCell;

/// Most energies a batched member may have.
const MAX_TERMS: usize = 8;

thread_local! {
    /// The batched solver's buffers, one per thread (no allocation once sized).
    pub(crate) static SOLVER: RefCell<LaneEuler> = RefCell::new(LaneEuler::default());
}

/// The potential of the lanes' systems: per energy, its lane terms.
pub(crate) struct Terms<'a> {
    terms: [Option<[LaneTerm<'a>; LANES]>; MAX_TERMS],
}

impl Terms<'_> {
    /// Whether every term stays what it is from one step to the next
    /// ([`LaneTerm::holds_across_steps`]).
    pub(crate) fn hold_across_steps(&self) -> bool {
        let mut terms = self.terms.iter().flatten().flatten();
        terms.all(LaneTerm::holds_across_steps)
    }
}

impl LanePotential for Terms<'_> {
    fn add(
        &self,
        q: &[Lanes],
        energy: &mut Lanes,
        mut derivatives: Option<Derivatives<'_>>,
    ) -> [bool; LANES] {
        let mut evaluated = [true; LANES];
        for terms in self.terms.iter().flatten() {
            let d = derivatives.as_mut().map(Derivatives::reborrow);
            let lanes = add_lanes(terms, q, energy, d);
            for (e, ok) in evaluated.iter_mut().zip(lanes) {
                *e &= ok;
            }
        }
        evaluated
    }
}

/// The batching decision of one member for its step of `dt`, before any lanes are
/// formed, and the only one: the Newton settings of its batched step, or why it steps
/// alone. `enabled` is the ensemble's setting ([`crate::Ensemble::batched`]: off, every
/// member steps alone, [`Unbatched::Off`]); a `dt` that is not finite and positive is
/// no step the lanes take ([`Unbatched::Solver`]); past those only the member's own
/// state decides (see the module docs). The step's own `begin_step` is idempotent
/// (`LaneForm::lane_term`'s contract), so calling it here changes nothing. The solve can
/// still hand a member back ([`Unbatched::Terms`], [`Unbatched::Solver`] and the lane
/// failures, from [`solve_lanes`]), and the member's step record one it did not take
/// ([`Unbatched::of_step`]).
pub(crate) fn batching(
    sim: &mut Simulation,
    dt: Real,
    enabled: bool,
) -> Result<NewtonParams, Unbatched> {
    if !enabled {
        return Err(Unbatched::Off);
    }
    if !(dt.is_finite() && dt > 0.0) {
        return Err(Unbatched::Solver);
    }
    let scheme = sim.integrator.batched().ok_or(Unbatched::Scheme)?;
    let params = scheme.lane_params();
    if !sim.substep.memory().next.is_none_or(|h| h >= dt) {
        return Err(Unbatched::SubStep);
    }
    // An adaptive member's knots follow decisions a round-off difference could flip:
    // stepped alone, it keeps exactly its own results.
    if sim.adapter.is_some() {
        return Err(Unbatched::Adaptive);
    }
    let system = &sim.system;
    let driven = system.energies.iter().any(|e| {
        let lifecycle = e.capabilities().lifecycle;
        lifecycle.is_some_and(|l| l.time_dependent())
    });
    if !system.drivers.is_empty() || driven {
        return Err(Unbatched::Driven);
    }
    if sim.system.begin_step(dt).is_err() {
        return Err(Unbatched::Setup);
    }
    let rod = &sim.system.rod;
    if let Some(e) = sim.system.acting().find(|e| lane_term(*e, rod).is_none()) {
        return Err(if e.name() == "stretch" {
            Unbatched::StretchingForm
        } else {
            Unbatched::Energy
        });
    }
    Ok(params)
}

/// Whether two members have one shape for the batched step: the same knots, pins at
/// the same places and the same Newton matrix bandwidth.
pub(crate) fn same_shape(a: &Simulation, b: &Simulation) -> bool {
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

/// Whether the energies acting on both members have the same lane forms, in order.
fn same_forms(a: &Simulation, b: &Simulation) -> bool {
    let (ra, rb) = (&a.system.rod, &b.system.rod);
    a.system.acting().count() == b.system.acting().count()
        && a.system.acting().zip(b.system.acting()).all(|(x, y)| {
            match (lane_term(x, ra), lane_term(y, rb)) {
                (Some(x), Some(y)) => x.same_form(&y),
                _ => false,
            }
        })
}

/// Solves the step of `dt` of the members of `group` (at most [`LANES`], consecutive)
/// that can be batched ([`batching`], with the ensemble's setting `enabled`), [`LANES`] of one shape at a time, and preloads each
/// one's integrator with its result; `alone[i]` is set to why member `i` steps alone,
/// `None` for a member preloaded. A member's result does not depend on the others in
/// its group: lanes never mix, a lane that fails leaves only its own member to step
/// alone, and lanes left over repeat a member (so a member with no lane-mates, a group
/// of one, is solved in the lanes too). Members left out are untouched: their own step
/// solves as usual.
pub(crate) fn preload_group(
    group: &mut [Simulation],
    dt: Real,
    enabled: bool,
    alone: &mut [Option<Unbatched>],
) {
    let mut params = [None; LANES];
    if group.len() > LANES || alone.len() != group.len() {
        // A caller's error, not a member's: no lanes for a group that does not fit.
        alone.fill(Some(Unbatched::Solver));
        return;
    }
    for ((p, sim), why) in params
        .iter_mut()
        .zip(group.iter_mut())
        .zip(alone.iter_mut())
    {
        match batching(sim, dt, enabled) {
            Ok(settings) => (*p, *why) = (Some(settings), None),
            Err(reason) => *why = Some(reason),
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
            solve_lanes(group, (lanes, count), &settings, dt, alone);
        }
    }
}

/// The batched solve of the members `lanes.0` (the first `lanes.1` distinct, the rest
/// repeats of the first) of `group`, preloading each member whose lane succeeded and
/// setting `alone` for those whose lane did not.
fn solve_lanes(
    group: &mut [Simulation],
    (lanes, count): ([usize; LANES], usize),
    params: &NewtonParams,
    dt: Real,
    alone: &mut [Option<Unbatched>],
) {
    let members: [&Simulation; LANES] = std::array::from_fn(|l| &group[lanes[l]]);
    let Some(potential) = lane_terms(members) else {
        lanes[..count]
            .iter()
            .for_each(|&i| alone[i] = Some(Unbatched::Terms));
        return;
    };
    let step = lane_step(members, &potential, params, dt);
    let solved = SOLVER.with(|solver| solver.borrow_mut().step(&step));
    if solved.is_err() {
        lanes[..count]
            .iter()
            .for_each(|&i| alone[i] = Some(Unbatched::Solver));
        return;
    }
    SOLVER.with(|solver| {
        let solver = solver.borrow();
        for (l, &i) in lanes.iter().enumerate().take(count) {
            let outcome = match solver.outcome(l) {
                Ok(outcome) => outcome,
                Err(why) => {
                    alone[i] = Some(Unbatched::of_lane(why.0));
                    continue;
                }
            };
            let sim = &mut group[i];
            let rod = &sim.system.rod;
            let start = (rod.positions.as_slice(), rod.velocities.as_slice());
            if let Some(scheme) = sim.integrator.batched() {
                scheme.preload(start, &outcome, dt);
            }
        }
    });
}

/// The batched step of `dt` of `members` (one per lane) with their `potential`.
pub(crate) fn lane_step<'a>(
    members: [&'a Simulation; LANES],
    potential: &'a Terms<'a>,
    params: &'a NewtonParams,
    dt: Real,
) -> LaneStep<'a> {
    LaneStep {
        rods: members.map(|m| &m.system.rod),
        pins: members.map(|m| m.system.pins.as_slice()),
        potential,
        bandwidth: members[0].system.hessian_bandwidth(),
        params,
        dt,
    }
}

/// The lane terms of every energy acting on the members, if they all have one and
/// agree in form and shape.
pub(crate) fn lane_terms(members: [&Simulation; LANES]) -> Option<Terms<'_>> {
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
            *term = lane_term(energies.next()?, &m.system.rod);
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

/// `energy`'s lane term on `rod`, if it has a [`splinerod_energies::LaneForm`] and the
/// form applies now.
fn lane_term<'a>(energy: &'a dyn Energy, rod: &'a Rod) -> Option<LaneTerm<'a>> {
    energy.capabilities().lanes?.lane_term(rod)
}
