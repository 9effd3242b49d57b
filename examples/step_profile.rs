//! The step `splinerod bench` times as `step_us_16` (16-point cable, one Newton
//! iteration, no line search), repeated, for profilers:
//! `valgrind --tool=callgrind target/release/examples/step_profile [STEPS]
//! [consistent]` (`consistent`: the mixed stretching with the consistent Gram matrix).
use splinerod::prelude::*;
use splinerod::problems::pinned_cable_with;
use std::time::Instant;

fn main() -> Result<(), Error> {
    let steps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(100_000);
    let params = NewtonParams {
        max_iterations: 1,
        line_search: false,
        ..NewtonParams::default()
    };
    let formulation = match std::env::args().nth(2).as_deref() {
        Some("consistent") => StretchFormulation::MixedConsistent,
        _ => StretchFormulation::default(),
    };
    let system = pinned_cable_with(16, 1.05, 100.0, formulation)?;
    let mut sim = Simulation::new(system, Box::new(ImplicitEuler::new(params)?));
    let t = Instant::now();
    let mut cg = 0;
    for _ in 0..steps {
        cg += sim.step(1e-3)?.solver.remainder_iterations;
    }
    let us = t.elapsed().as_secs_f64() / steps as Real * 1e6;
    let cg = cg as Real / steps as Real;
    println!("{steps} steps, {us:.2} µs per step, {cg:.2} conjugate-gradient iterations per step");
    Ok(())
}
