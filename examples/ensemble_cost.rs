//! Time per rod-step of an ensemble of 16-point cables (one Newton iteration per step,
//! as `bench`'s ensemble figures) against the ensemble's size:
//! `RAYON_NUM_THREADS=1 cargo run --release --example ensemble_cost [STEPS_TOTAL]
//! [alone|batched] [SIZE]` for one thread (`STEPS_TOTAL` rod-steps per size, 100 000 by
//! default; `alone`: every member stepped on its own, not batched; `SIZE`: that ensemble
//! size only). Small ensembles stay in
//! the caches; from about a thousand members each step streams every member's matrices
//! and tables from memory, which is what batching members that share a basis (one table
//! for many rods, #17) would cut.
use splinerod::prelude::*;
use splinerod::problems::pinned_cable;
use splinerod::Ensemble;
use std::time::Instant;

fn main() -> Result<(), Error> {
    let total: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(100_000);
    let params = NewtonParams {
        max_iterations: 1,
        line_search: false,
        ..NewtonParams::default()
    };
    let only: Option<usize> = std::env::args().nth(3).and_then(|a| a.parse().ok());
    let counts = only.map_or(vec![10, 100, 1_000, 10_000], |c| vec![c]);
    for count in counts {
        let members = (0..count)
            .map(|_| {
                let system = pinned_cable(16, 1.05, 100.0)?;
                Ok(Simulation::new(
                    system,
                    Box::new(ImplicitEuler::new(params)?),
                ))
            })
            .collect::<Result<Vec<_>, Error>>()?;
        let mut ensemble = Ensemble::new(members);
        ensemble.batched = std::env::args().nth(2).as_deref() != Some("alone");
        ensemble.step(1e-3)?;
        let steps = (total / count).max(1);
        let t = Instant::now();
        for _ in 0..steps {
            ensemble.step(1e-3)?;
        }
        let us = t.elapsed().as_secs_f64() / (count * steps) as Real * 1e6;
        println!("{count:>6} members: {us:.2} µs per rod-step");
    }
    Ok(())
}
