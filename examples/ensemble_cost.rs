//! Time per rod-step of an ensemble of 16-point cables (one Newton iteration per step,
//! as `bench`'s ensemble figures) against the ensemble's size:
//! `RAYON_NUM_THREADS=1 cargo run --release --example ensemble_cost [STEPS_TOTAL]
//! [alone|batched] [SIZE] [bending|plain] [step]` for one thread (`STEPS_TOTAL` rod-steps
//! per size, 100 000 by default; `alone`: every member stepped on its own, not batched;
//! `SIZE`: that ensemble size only; `bending`: the cables have bending stiffness 1e-3
//! N·m²; `step`: one `Ensemble::step` call per step instead of one `Ensemble::advance`
//! for all, which keeps the lanes of batched groups between steps). Small ensembles stay in
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
    let bending = std::env::args().nth(4).as_deref() == Some("bending");
    let per_step = std::env::args().nth(5).as_deref() == Some("step");
    let counts = only.map_or(vec![10, 100, 1_000, 10_000], |c| vec![c]);
    for count in counts {
        let members = (0..count)
            .map(|_| {
                let system = if bending {
                    bending_cable()?
                } else {
                    pinned_cable(16, 1.05, 100.0)?
                };
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
        if per_step {
            for _ in 0..steps {
                ensemble.step(1e-3)?;
            }
        } else {
            ensemble.advance(1e-3, steps)?;
        }
        let us = t.elapsed().as_secs_f64() / (count * steps) as Real * 1e6;
        println!("{count:>6} members: {us:.2} µs per rod-step");
    }
    Ok(())
}

/// [`pinned_cable`] (16 points, span 1.05 m, EA = 100 N) with bending stiffness 1e-3 N·m²
/// (and the bending rod's quadrature, 5 points per span with second derivatives).
fn bending_cable() -> Result<RodSystem, Error> {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, 16, 1.0)?;
    let end = Vector3::new(1.05, 0.0, 0.0);
    let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end)?
        .with_quadrature_points(5)?;
    let pins = [Pin::here(&rod, 0.0)?, Pin::here(&rod, 1.0)?];
    let bending = Bending::for_rod(1e-3, &rod)?;
    Ok(RodSystem::new(rod)
        .with_energy(Stretching::new(100.0)?)
        .with_energy(Gravity::new(Vector3::new(0.0, -9.81, 0.0))?)
        .with_energy(bending)
        .with_pin(pins[0])
        .with_pin(pins[1]))
}
