//! No heap allocation inside a time step once the workspaces are sized: a counting global
//! allocator (per thread) watches 100 steps of each integrator after a warm-up.

use splinerod::prelude::*;
use splinerod::problems::pinned_cable_with;
// The counting allocator the integrators' allocation tests use (one file, included).
#[path = "../integrators/tests/common/counting.rs"]
mod counting;
use counting::allocations_during;

type MakeIntegrator = fn() -> Box<dyn Integrator>;

/// Every combination of three lists' entries, in order.
fn iproduct<'a, A, B, C>(
    a: &'a [A],
    b: &'a [B],
    c: &'a [C],
) -> impl Iterator<Item = (&'a A, &'a B, &'a C)> {
    a.iter()
        .flat_map(move |x| b.iter().flat_map(move |y| c.iter().map(move |z| (x, y, z))))
}

#[test]
fn steps_do_not_allocate_after_warm_up() {
    let integrators: [(&str, MakeIntegrator); 3] = [
        ("implicit-euler", || {
            Box::new(ImplicitEuler::new(NewtonParams::default()).expect("p"))
        }),
        ("implicit-midpoint", || {
            Box::new(ImplicitMidpoint::new(NewtonParams::default()).expect("p"))
        }),
        ("bdf2", || {
            Box::new(Bdf2::new(NewtonParams::default()).expect("p"))
        }),
    ];
    let forms = [
        StretchFormulation::Mixed,
        StretchFormulation::MixedConsistent,
    ];
    for (n, (name, make), form) in iproduct(&[16, 1000], &integrators, &forms) {
        {
            // Slightly stretched, so every step converges the same way.
            let system = pinned_cable_with(*n, 1.05, 100.0, *form).expect("cable");
            let mut sim = Simulation::new(system, make());
            for _ in 0..10 {
                sim.step(1e-3).expect("warm-up step");
            }
            let count = allocations_during(|| {
                for _ in 0..100 {
                    sim.step(1e-3).expect("step");
                }
            });
            assert_eq!(
                count, 0,
                "{name}, {form:?}, {n} control points: {count} allocations in 100 steps"
            );
        }
    }
}

/// The tolerance-driven adapt stage (error estimate, marks) on a steady rod allocates
/// nothing either: the finer copy, its operator and the solver's storage are kept.
#[test]
fn error_estimates_do_not_allocate_after_warm_up() {
    use splinerod::adaptivity::{AdaptParams, Adapter, ToleranceCriterion};
    let forms = [
        StretchFormulation::Mixed,
        StretchFormulation::MixedConsistent,
    ];
    for (n, form) in [16, 200].into_iter().flat_map(|n| forms.map(|f| (n, f))) {
        let system = pinned_cable_with(n, 1.05, 100.0, form).expect("cable");
        let euler = Box::new(ImplicitEuler::new(NewtonParams::default()).expect("p"));
        let params = AdaptParams {
            max_control_points: n,
            min_control_points: n,
            ..AdaptParams::default()
        };
        let criterion = ToleranceCriterion::new(1.0).expect("tolerance");
        let adapter = Adapter::new(params).expect("params").with(criterion);
        let mut sim = Simulation::new(system, euler).with_adapter(adapter);
        for _ in 0..10 {
            sim.step(1e-3).expect("warm-up step");
        }
        let mut estimates = 0;
        let count = allocations_during(|| {
            for _ in 0..200 {
                let report = sim.step(1e-3).expect("step");
                estimates += usize::from(report.error_estimate.is_some());
            }
        });
        assert!(estimates >= 5, "{estimates} estimates");
        assert_eq!(
            count, 0,
            "{form:?}, {n} control points: {count} allocations"
        );
    }
}

/// The batched ensemble step (#17) allocates nothing either: its lane buffers are per
/// thread and kept, and each member's preloaded result reuses its integrator's buffers.
#[test]
fn batched_ensemble_steps_do_not_allocate_after_warm_up() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("pool");
    let count = pool.install(|| {
        let members = (0..8)
            .map(|i| {
                let system = pinned_cable_with(
                    16,
                    1.05,
                    100.0 + 10.0 * i as Real,
                    StretchFormulation::Mixed,
                )
                .expect("cable");
                let euler = ImplicitEuler::new(NewtonParams::default()).expect("p");
                Simulation::new(system, Box::new(euler))
            })
            .collect();
        let mut ensemble = splinerod::Ensemble::new(members);
        for _ in 0..10 {
            ensemble.step(1e-3).expect("warm-up step");
        }
        let mut batched = 0;
        let count = allocations_during(|| {
            for _ in 0..100 {
                ensemble.step(1e-3).expect("step");
                batched += ensemble
                    .reports
                    .iter()
                    .map(|r| r.solver.batched)
                    .sum::<usize>();
            }
        });
        assert_eq!(batched, 800, "every member-step batched");
        count
    });
    assert_eq!(
        count, 0,
        "{count} allocations in 100 batched ensemble steps"
    );
}
