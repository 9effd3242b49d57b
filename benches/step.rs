//! Criterion benchmarks of one implicit Euler step (one Newton iteration, no line
//! search): stretching, gravity and two end pins, at 16, 1 000, 10 000 and 100 000
//! control points; and one static Newton solve of the reference catenary.
//!
//! The stepped cable is pinned 1.05 m apart (slightly stretched): a compressed string has
//! no bending stiffness to resist buckling, and at 100 000 control points its shortest
//! waves grow faster than one linearised step can follow.
//!
//! `cargo bench --bench step` (time per control point = median / n).

// criterion_group! generates undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use splinerod::prelude::*;

fn cable(n: usize, span: Real) -> RodSystem {
    splinerod::problems::pinned_cable(n, span, 100.0).unwrap()
}

fn one_newton_iteration() -> ImplicitEuler {
    ImplicitEuler::new(NewtonParams {
        max_iterations: 1,
        line_search: false,
        ..NewtonParams::default()
    })
    .unwrap()
}

fn implicit_euler_step(c: &mut Criterion) {
    let mut group = c.benchmark_group("implicit_euler_step");
    for n in [16, 1_000, 10_000, 100_000] {
        let mut system = cable(n, 1.05);
        let mut euler = one_newton_iteration();
        for _ in 0..20 {
            euler.step(&mut system, 1e-3).unwrap(); // warm up: falling, symbolic analysis done
        }
        group.throughput(Throughput::Elements(n as u64));
        if n >= 10_000 {
            group.sample_size(20);
        }
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| euler.step(&mut system, 1e-3).unwrap())
        });
    }
    group.finish();
}

fn static_solve(c: &mut Criterion) {
    let mut solver = StaticSolver::new(StaticParams::default()).unwrap();
    c.bench_function("static_solve_16", |b| {
        b.iter_batched_ref(
            || cable(16, 0.8),
            |s| solver.solve(s).unwrap(),
            criterion::BatchSize::SmallInput,
        )
    });
}

criterion_group!(benches, implicit_euler_step, static_solve);
criterion_main!(benches);
