//! `splinerod bench [--quick] [--json OUT]`: the figures of speed a user can reproduce on
//! their own machine (medians, so one noisy sample does not move them):
//!
//! * one implicit Euler step (1 Newton iteration, no line search; stretching, gravity,
//!   two end pins) of a 16-point cable, and one Newton iteration of the static solver;
//! * time per control point per step at 1 000, 10 000 and 100 000 points and the ratio of
//!   the largest to the smallest (O(n) means close to 1);
//! * ensemble throughput, rod-steps per second, for many 16-point cables on 1 thread and
//!   on all threads, and the parallel efficiency;
//! * resident memory per control point of the 100 000-point cable and its solver;
//! * wall time to settle the stiff (EA = 10⁴ N) catenary, released straight, to within
//!   2.2·10⁻⁵ m of its equilibrium (the accuracy lumped peers reach with 80 elements);
//! * the cost of the tolerance-driven adapt stage ([`crate::bench::adapt`]);
//! * the cost of several rods in one system ([`crate::bench::world`]);
//! * the median step of the knot-tying scene, contact included ([`crate::bench::knot`]).

pub mod adapt;
pub mod checkpoint;
pub mod knot;
mod summary;
pub mod twist;
pub mod world;

use crate::problems::pinned_cable;
use crate::{Ensemble, Error, RodSystem, Simulation};
use serde::Serialize;
use splinerod_core::Real;
use splinerod_energies::StretchFormulation;
use splinerod_integrators::{ImplicitEuler, Integrator, NewtonParams, StaticParams, StaticSolver};
use std::collections::BTreeMap;
use std::time::Instant;

/// Everything `bench` measures (JSON keys as in the issue).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct BenchResult {
    /// Median implicit Euler step, 16 control points, µs (the lumped mixed form).
    pub step_us_16: Real,
    /// The same step with the consistent mixed form (what `"auto"` takes for this soft
    /// cable in a scene), µs.
    pub step_us_16_consistent: Real,
    /// Median implicit Euler step of a 16-point rod clamped at both ends with stretching
    /// and bending, µs ([`crate::bench::twist`]).
    pub step_us_16_bending: Real,
    /// The same with the twisting energy, µs.
    pub step_us_16_twist: Real,
    /// Median step of 8 independent 16-point cables in one system over 8 times one
    /// cable's ([`crate::bench::world`]).
    pub world_overhead_8: Real,
    /// Median step of `knot_tying_adaptive.toml` over its first 0.5 s, µs
    /// ([`crate::bench::knot`]).
    pub knot_step_us: Real,
    /// Median static Newton iteration, 16 control points, µs.
    pub static_newton_us_16: Real,
    /// Median step time per control point, ns, by size.
    pub per_cp_ns: BTreeMap<String, Real>,
    /// Largest over smallest of `per_cp_ns`.
    pub per_cp_flatness: Real,
    /// Ensemble rod-steps per second on one thread (batched, the default).
    pub ensemble_rod_steps_per_s_1: Real,
    /// The same ensemble with every member stepped alone ([`crate::Ensemble::batched`]
    /// off), one thread.
    pub ensemble_rod_steps_per_s_alone_1: Real,
    /// `ensemble_rod_steps_per_s_1 / ensemble_rod_steps_per_s_alone_1`: what solving
    /// members four at a time gains.
    pub batched_speedup: Real,
    /// Ensemble rod-steps per second on all threads.
    pub ensemble_rod_steps_per_s_all: Real,
    /// `all / (1 · threads)`.
    pub parallel_efficiency: Real,
    /// Threads used for `all`.
    pub threads: usize,
    /// Resident bytes per control point of the 100 000-point cable (peak growth).
    pub bytes_per_cp: Real,
    /// Wall time to settle the EA = 10⁴ N catenary to 2.2e-5 m, s.
    pub stiff_catenary_settle_s: Real,
    /// Control points used for that, the error reached (m) and the steps taken (dt = 0.02 s).
    pub stiff_catenary: (usize, Real, usize),
    /// Cases of [`crate::problems::hard_cases`] that ran with every step converged
    /// (`None` with `--quick`, which leaves the suite to `tests/hard_cases.rs`).
    pub hard_cases_converged: Option<usize>,
    /// Cases in the hard-case suite.
    pub hard_cases_total: usize,
    /// Mean Newton iterations per step on the default scene (`scenes/hanging_cable.toml`).
    pub newton_per_step_default: Real,
    /// The adapt stage (tolerance-driven: estimate, marks, maps) over the step, at 16
    /// control points.
    pub adapt_fraction_16: Real,
    /// The adapt stage's time per control point, ns, by size (1 000 and 100 000).
    pub adapt_ns_per_cp: BTreeMap<String, Real>,
    /// Writing a checkpoint of the default scene after 100 steps, µs (median; encoding,
    /// writing, `fsync`, rename).
    pub checkpoint_us_16: Real,
    /// That checkpoint's size, bytes.
    pub checkpoint_bytes_16: Real,
}

/// The README's default scene, embedded.
const DEFAULT_SCENE: &str = include_str!("../../scenes/hanging_cable.toml");

/// Mean Newton iterations per step of the default scene.
fn newton_per_step_default() -> Result<Real, Error> {
    let result = crate::run(&crate::Scene::from_toml(DEFAULT_SCENE)?)?;
    Ok(result.solver.newton_iterations as Real / result.steps.max(1) as Real)
}

pub(crate) fn one_iteration() -> Result<Box<dyn Integrator>, Error> {
    let p = NewtonParams {
        max_iterations: 1,
        line_search: false,
        ..NewtonParams::default()
    };
    Ok(Box::new(ImplicitEuler::new(p)?))
}

pub(crate) fn median(mut v: Vec<Real>) -> Real {
    v.sort_by(Real::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Median wall time (s) of one step of an `n`-point stretched cable.
fn step_seconds(n: usize, reps: usize) -> Result<Real, Error> {
    step_seconds_with(n, reps, StretchFormulation::Mixed)
}

/// [`step_seconds`] with the stretching `form`.
fn step_seconds_with(n: usize, reps: usize, form: StretchFormulation) -> Result<Real, Error> {
    let cable = crate::problems::pinned_cable_with(n, 1.05, 100.0, form)?;
    median_step_seconds(Simulation::new(cable, one_iteration()?), reps)
}

/// Median wall time (s) of one 1 ms step of `sim` over `reps` steps, after five.
pub(crate) fn median_step_seconds(mut sim: Simulation, reps: usize) -> Result<Real, Error> {
    for _ in 0..5 {
        sim.step(1e-3)?;
    }
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        let t = Instant::now();
        sim.step(1e-3)?;
        times.push(t.elapsed().as_secs_f64());
    }
    Ok(median(times))
}

fn static_newton_seconds(reps: usize) -> Result<Real, Error> {
    let mut solver = StaticSolver::new(StaticParams::default())?;
    let mut times = Vec::with_capacity(reps);
    for _ in 0..reps {
        let mut system = pinned_cable(16, 0.8, 100.0)?;
        let t = Instant::now();
        let stats = solver.solve(&mut system)?;
        times.push(t.elapsed().as_secs_f64() / stats.newton_iterations.max(1) as Real);
    }
    Ok(median(times))
}

/// A field of `/proc/self/status` in bytes (Linux; 0 elsewhere).
fn status_bytes(field: &str) -> Real {
    let text = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let line = text.lines().find(|l| l.starts_with(field));
    let kb = line.and_then(|l| l.split_whitespace().nth(1)?.parse::<Real>().ok());
    kb.unwrap_or(0.0) * 1024.0
}

/// Median time per control point (ns) at `n`, and for the largest size the resident
/// growth per control point (bytes).
fn per_cp(n: usize, reps: usize) -> Result<(Real, Real), Error> {
    let before = status_bytes("VmRSS:");
    let ns = step_seconds(n, reps)? * 1e9 / n as Real;
    let grown = status_bytes("VmHWM:") - before;
    Ok((ns, grown / n as Real))
}

/// Rod-steps per second of `count` 16-point cables stepped together on `threads` threads
/// (`batched`: members solved four at a time, [`crate::Ensemble::batched`]), the steps
/// taken by one [`crate::Ensemble::advance`] (batched groups keep their lanes).
fn ensemble_rate(count: usize, steps: usize, threads: usize, batched: bool) -> Result<Real, Error> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::ThreadPool(e.to_string()))?;
    pool.install(|| {
        let members = (0..count)
            .map(|_| {
                Ok(Simulation::new(
                    pinned_cable(16, 1.05, 100.0)?,
                    one_iteration()?,
                ))
            })
            .collect::<Result<Vec<_>, Error>>()?;
        let mut ensemble = Ensemble::new(members);
        ensemble.batched = batched;
        ensemble.step(1e-3)?;
        let t = Instant::now();
        // One call for all the steps: batched groups keep their lanes between steps.
        ensemble.advance(1e-3, steps)?;
        Ok((count * steps) as Real / t.elapsed().as_secs_f64())
    })
}

/// Settles the EA = 10⁴ N catenary released straight with damped implicit Euler, at the
/// coarsest resolution whose equilibrium is within 1.5e-5 m of a 64-point reference;
/// returns (wall seconds to reach 2.2e-5 m of it and rest, control points, error, steps).
fn stiff_catenary() -> Result<(Real, usize, Real, usize), Error> {
    const TARGET: Real = 2.2e-5;
    // Static reference by continuation: the soft cable's equilibrium starts the stiff solve.
    let solve = |n: usize| -> Result<RodSystem, Error> {
        let mut soft = pinned_cable(n, 0.8, 100.0)?;
        StaticSolver::new(StaticParams::default())?.solve(&mut soft)?;
        let mut system = pinned_cable(n, 0.8, 1e4)?;
        system.rod.positions.clone_from(&soft.rod.positions);
        StaticSolver::new(StaticParams::default())?.solve(&mut system)?;
        Ok(system)
    };
    let reference = solve(64)?;
    let distance = |system: &RodSystem| -> Result<Real, Error> {
        (0..=40).try_fold(0.0, |worst: Real, k| {
            let s = k as Real / 40.0;
            let d = (system.rod.point(s)? - reference.rod.point(s)?).norm();
            Ok(worst.max(d))
        })
    };
    let mut n = 12;
    while n < 64 && distance(&solve(n)?)? > 1.5e-5 {
        n += 4;
    }
    let mut system = pinned_cable(n, 0.8, 1e4)?;
    system.rod.damping = 4.0;
    let mut sim = Simulation::new(
        system,
        Box::new(ImplicitEuler::new(NewtonParams::default())?),
    );
    let start = Instant::now();
    let mut error = Real::INFINITY;
    while sim.time < 30.0 {
        sim.step(0.02)?;
        error = distance(&sim.system)?;
        let speed = sim.system.rod.max_speed();
        if error <= TARGET && speed < 1e-3 {
            break;
        }
    }
    Ok((start.elapsed().as_secs_f64(), n, error, sim.steps))
}

/// Runs every measurement (`quick`: fewer repetitions and a smaller ensemble).
pub fn measure(quick: bool) -> Result<BenchResult, Error> {
    let scale = |full: usize, short: usize| if quick { short } else { full };
    let step_us_16 = step_seconds(16, scale(20_000, 2_000))? * 1e6;
    let consistent = StretchFormulation::MixedConsistent;
    let step_us_16_consistent = step_seconds_with(16, scale(20_000, 2_000), consistent)? * 1e6;
    let static_newton_us_16 = static_newton_seconds(scale(200, 20))? * 1e6;
    let step_us_16_bending = crate::bench::twist::step_seconds(false, scale(20_000, 2_000))? * 1e6;
    let step_us_16_twist = crate::bench::twist::step_seconds(true, scale(20_000, 2_000))? * 1e6;
    let mut per_cp_ns = BTreeMap::new();
    let mut bytes_per_cp = 0.0;
    for (n, reps) in [
        (1_000, scale(200, 20)),
        (10_000, scale(40, 5)),
        (100_000, scale(10, 3)),
    ] {
        let (ns, bytes) = per_cp(n, reps)?;
        per_cp_ns.insert(n.to_string(), ns);
        bytes_per_cp = bytes;
    }
    let (lo, hi) = per_cp_ns
        .values()
        .fold((Real::INFINITY, 0.0), |(a, b): (Real, Real), &v| {
            (a.min(v), b.max(v))
        });
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    // 100 steps: a run, not its start (the lanes are read and written back once per call).
    let (count, steps) = (scale(10_000, 1_000), scale(100, 10));
    let alone = ensemble_rate(count, steps, 1, false)?;
    let one = ensemble_rate(count, steps, 1, true)?;
    let all = ensemble_rate(count, steps, threads, true)?;
    let (settle, n, error, steps) = stiff_catenary()?;
    let hard_cases_total = crate::problems::hard_cases::hard_cases()?.len();
    let (checkpoint_s, checkpoint_bytes) =
        crate::bench::checkpoint::checkpoint_cost(scale(200, 20))?;
    Ok(BenchResult {
        checkpoint_us_16: checkpoint_s * 1e6,
        checkpoint_bytes_16: checkpoint_bytes as Real,
        step_us_16,
        step_us_16_consistent,
        step_us_16_bending,
        step_us_16_twist,
        world_overhead_8: crate::bench::world::world_overhead(8, scale(4_000, 400))?,
        knot_step_us: crate::bench::knot::knot_step_seconds()? * 1e6,
        static_newton_us_16,
        per_cp_ns,
        per_cp_flatness: hi / lo,
        ensemble_rod_steps_per_s_1: one,
        ensemble_rod_steps_per_s_alone_1: alone,
        batched_speedup: one / alone,
        ensemble_rod_steps_per_s_all: all,
        parallel_efficiency: all / (one * threads as Real),
        threads,
        bytes_per_cp,
        stiff_catenary_settle_s: settle,
        stiff_catenary: (n, error, steps),
        hard_cases_converged: match quick {
            true => None,
            false => Some(crate::problems::hard_cases::count_converged()?),
        },
        hard_cases_total,
        newton_per_step_default: newton_per_step_default()?,
        adapt_fraction_16: crate::bench::adapt::adapt_fraction_16(scale(20_000, 2_000))?,
        adapt_ns_per_cp: [(1_000, scale(640, 64)), (100_000, scale(64, 32))]
            .into_iter()
            .map(|(n, reps)| {
                Ok((
                    n.to_string(),
                    crate::bench::adapt::adapt_ns_per_cp(n, reps)?,
                ))
            })
            .collect::<Result<_, Error>>()?,
    })
}
