//! Criterion benchmark of one knot insertion followed by its exact removal (positions,
//! velocities, quadrature, mass and lumped masses updated locally) at 100 and 100 000
//! control points. The solver's symbolic re-analysis after a basis change is not
//! included: it is measured by the step benchmark's first step after a change.
//!
//! `cargo bench --bench adapt`

// criterion_group! generates undocumented public functions.
#![allow(missing_docs)]

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use splinerod::prelude::*;

fn insert_and_remove(c: &mut Criterion) {
    let mut group = c.benchmark_group("insert_remove_knot");
    for n in [100, 100_000] {
        let material = Material {
            rest_length: 1.0,
            linear_density: 0.1,
        };
        let basis = BSplineSpace::clamped_uniform(3, n, 1.0).unwrap();
        let end = Vector3::new(1.0, 0.0, 0.0);
        let mut rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).unwrap();
        // Midway between two knots near the middle of the rod.
        let h = 1.0 / (n - 3) as Real;
        let s = (((n - 3) / 2) as Real + 0.5) * h;
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                let map = rod.insert_knot(s).unwrap();
                rod.remove_knot(map.knot_index(), 1e-9).unwrap();
            })
        });
    }
    group.finish();
}

criterion_group!(benches, insert_and_remove);
criterion_main!(benches);
