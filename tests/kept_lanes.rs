//! Ensembles that keep their lanes (#47): `Ensemble::advance(dt, steps)` against
//! `steps` calls of `Ensemble::step(dt)` — every member's state, clock, step count, last
//! report and pin forces equal bit for bit, and still after one more ordinary step (the
//! integrators' and sub-step controllers' memories agree too); groups that cannot keep
//! their lanes (adaptive members, other shapes, an inextensible rod), lanes that fail
//! mid-run (line-search steps) and any thread count.

use crate::batched::{bending_cables, hanging_cables, members};
use splinerod::{Ensemble, Simulation};

/// Everything a user reads of a member, with the floats as bits.
fn observed(sim: &Simulation) -> Vec<u64> {
    let rod = &sim.system.rod;
    let points = rod.positions.iter().chain(&rod.velocities);
    let forces = sim.integrator.pin_forces();
    let mut bits: Vec<u64> = points
        .chain(&forces)
        .flat_map(|p| [p.x, p.y, p.z])
        .map(f64::to_bits)
        .collect();
    bits.extend([
        sim.time.to_bits(),
        sim.system.time.to_bits(),
        sim.steps as u64,
    ]);
    bits
}

/// The part of a step report that does not time anything.
fn counted(e: &Ensemble) -> Vec<String> {
    e.reports
        .iter()
        .map(|r| {
            let mut r = *r;
            r.stages = Default::default();
            format!("{r:?}")
        })
        .collect()
}

/// `text`'s members after `steps` steps of `dt` taken one call each and in one
/// `advance`, then one more `step` each: asserts the two agree bit for bit after both;
/// returns the members' batched steps over the last call of the stepped run.
fn assert_advance_matches(text: &str, steps: usize, dt: f64, threads: usize) -> usize {
    assert_members_match(&|| members(text), steps, dt, threads)
}

/// [`assert_advance_matches`] for the members `make` makes.
fn assert_members_match(
    make: &(dyn Fn() -> Vec<Simulation> + Sync),
    steps: usize,
    dt: f64,
    threads: usize,
) -> usize {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let mut stepped = Ensemble::new(make());
        let mut advanced = Ensemble::new(make());
        let mut batched = 0;
        for _ in 0..steps {
            stepped.step(dt).expect("step");
            batched += stepped
                .reports
                .iter()
                .map(|r| r.solver.batched)
                .sum::<usize>();
        }
        advanced.advance(dt, steps).expect("advance");
        for round in ["advance", "one more step"] {
            for (i, (a, b)) in stepped.members.iter().zip(&advanced.members).enumerate() {
                assert_eq!(observed(a), observed(b), "member {i} after {round}");
            }
            assert_eq!(
                counted(&stepped),
                counted(&advanced),
                "reports after {round}"
            );
            stepped.step(dt).expect("step");
            advanced.step(dt).expect("step");
        }
        batched
    })
}

#[test]
fn advancing_in_kept_lanes_equals_stepping_bit_for_bit() {
    // 10 cables: groups of four, four and two (lanes repeated).
    let batched = assert_advance_matches(&hanging_cables(10), 60, 0.005, 2);
    assert!(batched >= 10 * 55, "{batched}");
    // With bending, one thread, and a single member (its lanes repeated).
    assert_advance_matches(&bending_cables(6), 40, 0.005, 1);
    assert_advance_matches(&bending_cables(1), 40, 0.005, 1);
}

#[test]
fn lanes_that_fail_mid_run_hand_their_step_over_and_results_stay_the_same() {
    // Long steps from a crumpled start: Newton needs line-search cuts and sub-steps,
    // which the lanes hand to each member's own solver, then the settled steps are kept
    // in the lanes again. With a shake of 0.5 m one group's lanes fail after six kept
    // steps (a run cut short, written back, the step taken as `step` takes it).
    for (shake, dt) in [(0.3, 0.05), (0.5, 0.01)] {
        let text = hanging_cables(8)
            .replace("perturbation = 0.01", &format!("perturbation = {shake}"))
            .replace("dt = 0.005", &format!("dt = {dt}"));
        let batched = assert_advance_matches(&text, 80, dt, 2);
        assert!(0 < batched && batched < 8 * 80, "{batched}");
    }
}

#[test]
fn groups_that_cannot_keep_their_lanes_step_as_always() {
    let adaptive = hanging_cables(6).replace(
        "[output]",
        "[adaptivity]\ntolerance = 1e-4\nmax_control_points = 40\n\n[output]",
    );
    assert_advance_matches(&adaptive, 30, 0.005, 2);
    let clamped = bending_cables(5).replace("at = 0.0\n", "at = 0.0\nclamp = true\n");
    assert_advance_matches(&clamped, 30, 0.005, 2);
    // An inextensible rod's multipliers are updated after every step: batched, but its
    // lanes are not kept.
    let inextensible = hanging_cables(5)
        .replace(
            "stretch_stiffness = 100.0\n",
            "stretch_stiffness = \"inextensible\"\n",
        )
        .replace("stretch_stiffness = [50.0, 400.0]\n", "");
    assert_advance_matches(&inextensible, 30, 0.005, 2);
    // Members of two shapes and an adaptive one in each group.
    let (cables, sized) = (
        hanging_cables(3),
        hanging_cables(3).replace("control_points = 16", "control_points = 12"),
    );
    let mixed = || {
        let mut all = members(&cables);
        all.extend(members(&sized));
        all.extend(members(&adaptive));
        all.swap(1, 4);
        all
    };
    assert_members_match(&mixed, 30, 0.005, 2);
}

#[test]
fn a_shard_advances_its_members_as_the_whole_ensemble_does() {
    let text = hanging_cables(10).replace("perturbation = 0.01", "perturbation = 0.2");
    let mut whole = Ensemble::new(members(&text));
    let mut part = Ensemble::new(members(&text).into_iter().skip(3).collect());
    part.first_index = 3;
    whole.advance(0.01, 50).expect("advance");
    part.advance(0.01, 50).expect("advance");
    for (a, b) in whole.members[3..].iter().zip(&part.members) {
        assert_eq!(observed(a), observed(b));
    }
}
