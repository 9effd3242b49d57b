//! Ensembles that keep their lanes (#47): [`crate::Ensemble::advance`] takes many steps
//! of a group of [`LANES`] members with their state in the batched solver's lanes from
//! one step to the next ([`LaneEuler::step_kept`]), reading the members once at the
//! start and writing them once at the end.
//!
//! **When.** A group keeps its lanes when every member would be batched
//! ([`batching`]) with the same Newton settings and one shape, and nothing happens in
//! its step but the solve: no error estimate, no time tolerance, no grabs or loads,
//! every energy acting and every lane term the same from step to step
//! ([`splinerod_energies::LaneTerm::holds_across_steps`]: not an inextensible rod's
//! stretching, whose multipliers are updated after each step). For such a member a step
//! changes only its state (positions, velocities) and what
//! [`Simulation::count_solved_step`] counts (time, step count, the sub-step
//! controller's next length); the energies' `begin_step` is idempotent for a batched
//! member ([`splinerod_energies::LaneForm::lane_term`]'s contract).
//!
//! **The write-back.** After `k` kept steps each member counts the first `k − 1`, is
//! put back at the start state of the `k`-th, and takes the `k`-th as an ordinary step
//! with the lanes' result preloaded ([`splinerod_integrators::Batched::preload`]): its
//! integrator, report, pin forces and saved start state are then those of a member
//! stepped `k` times, bit for bit (the lanes' arithmetic is the same; see
//! `lane_euler/kept.rs`). When a lane fails (its step must be solved alone), the run
//! stops there: the members are written back, the failing step is taken by
//! [`step_group`] as [`crate::Ensemble::step`] takes it, and the lanes start again.

use crate::world::ensemble::{step_group, Failure};
use crate::world::lanes::{batching, lane_step, lane_terms, same_shape, SOLVER};
use crate::world::unbatched::Unbatched;
use crate::{Error, Simulation, StepReport};
use nalgebra::Vector3;
use splinerod_core::{Real, LANES};
use splinerod_integrators::lane_euler::LaneOutcome;
use splinerod_integrators::NewtonParams;

/// `steps` steps of `dt` (`(dt, steps)`) of the group of members starting at `first`:
/// kept in the lanes where it can, else [`step_group`] step by step; the error of the
/// group's first failing member (by step, then by index).
pub(crate) fn advance_group(
    first: usize,
    members: &mut [Simulation],
    reports: &mut [StepReport],
    (dt, steps): (Real, usize),
    batched: bool,
) -> Failure {
    let mut failed = None;
    // Plain steps to take before trying the lanes again (doubling while the group cannot
    // keep them: a member sub-steps, is adaptive, a lane fails its first step, ...).
    let (mut done, mut wait, mut backoff) = (0, 0, 1);
    while done < steps {
        if wait == 0 {
            let (taken, written) = keep_lanes(members, reports, dt, steps - done, batched);
            if let Err((i, e)) = written {
                return failed.or(Some((first + i, e)));
            }
            done += taken.unwrap_or(0);
            if done == steps {
                break;
            }
            (wait, backoff) = match taken {
                None | Some(0) => (backoff, 2 * backoff),
                Some(_) => (1, 1),
            };
        }
        if let Some(e) = step_group(first, members, reports, dt, batched) {
            failed.get_or_insert(e);
        }
        done += 1;
        wait -= 1;
    }
    failed
}

/// Up to `steps` steps of `dt` kept in the lanes, written back: how many were taken
/// (`None` when the group cannot keep its lanes, see the module docs; 0 when a lane
/// failed the first step), and the member whose write-back failed, if one did.
fn keep_lanes(
    members: &mut [Simulation],
    reports: &mut [StepReport],
    dt: Real,
    steps: usize,
    batched: bool,
) -> (Option<usize>, Result<(), (usize, Error)>) {
    let Some(params) = settings(members, dt, batched) else {
        return (None, Ok(()));
    };
    let Some(done) = run_lanes(members, &params, dt, steps) else {
        return (None, Ok(()));
    };
    if done == 0 {
        return (Some(0), Ok(()));
    }
    let mut failed = Ok(());
    SOLVER.with(|solver| {
        let mut solver = solver.borrow_mut();
        for (l, (sim, report)) in members.iter_mut().zip(reports.iter_mut()).enumerate() {
            let written = match solver.kept(l) {
                Ok((start, outcome)) => write_back(sim, dt, done, start, &outcome),
                Err(_) => Err(kept_state_lost()),
            };
            match written {
                Ok(r) => *report = r,
                Err(e) if failed.is_ok() => failed = Err((l, e)),
                Err(_) => {}
            }
        }
    });
    (Some(done), failed)
}

/// The group's common Newton settings if it can keep its lanes (module docs).
fn settings(members: &mut [Simulation], dt: Real, batched: bool) -> Option<NewtonParams> {
    if members.is_empty() || members.len() > LANES {
        return None;
    }
    let mut common = None;
    for sim in members.iter_mut() {
        let params = batching(sim, dt, batched).ok()?;
        if !only_solves(sim) || common.is_some_and(|c| c != params) {
            return None;
        }
        common = Some(params);
    }
    if !members.iter().all(|m| same_shape(m, &members[0])) {
        return None;
    }
    common
}

/// Whether a batched member's step does nothing but the solve (module docs).
fn only_solves(sim: &Simulation) -> bool {
    let system = &sim.system;
    sim.estimation.is_none()
        && sim.control.time_tolerance.is_none()
        && !sim.integrator.conserves_energy()
        && system.grabs.is_empty()
        && system.loads.is_empty()
        && system.acting().count() == system.energies.len()
}

/// Up to `steps` kept steps of the members (each its own lane; lanes left over repeat
/// the first); how many completed in every lane (`None`: the lanes cannot be kept).
fn run_lanes(
    members: &[Simulation],
    params: &NewtonParams,
    dt: Real,
    steps: usize,
) -> Option<usize> {
    let sims: [&Simulation; LANES] =
        std::array::from_fn(|l| &members[if l < members.len() { l } else { 0 }]);
    let potential = lane_terms(sims).filter(|t| t.hold_across_steps())?;
    let step = lane_step(sims, &potential, params, dt);
    SOLVER.with(|solver| {
        let mut solver = solver.borrow_mut();
        let mut done = 0;
        while done < steps && !members.iter().any(|m| m.system.cancel.abandon()) {
            match solver.step_kept(&step, done == 0) {
                Ok(true) => done += 1,
                Ok(false) => break,
                Err(_) => return None,
            }
        }
        Some(done)
    })
}

/// Writes `done` kept steps of `dt` back into `sim`: the first `done − 1` counted, the
/// last taken as an ordinary step from its `start` state with the lanes' `outcome`
/// preloaded; its report.
fn write_back(
    sim: &mut Simulation,
    dt: Real,
    done: usize,
    (q, v): (&[Vector3<Real>], &[Vector3<Real>]),
    outcome: &LaneOutcome<'_>,
) -> Result<StepReport, Error> {
    for _ in 1..done {
        sim.count_solved_step(dt);
    }
    let rod = &mut sim.system.rod;
    if rod.positions.len() != q.len() || rod.velocities.len() != v.len() {
        return Err(kept_state_lost());
    }
    rod.positions.copy_from_slice(q);
    rod.velocities.copy_from_slice(v);
    if let Some(scheme) = sim.integrator.batched() {
        scheme.preload((q, v), outcome, dt);
    }
    let mut report = sim.step(dt)?;
    report.unbatched = Unbatched::of_step(None, report.solver.batched > 0);
    Ok(report)
}

/// The error of a write-back without the lanes' state to write (not expected: the
/// lanes are written back right after the run that kept them).
fn kept_state_lost() -> Error {
    let state = splinerod_integrators::IntegratorError::SolverState("the lanes' kept state");
    Error::Integrator(state)
}
