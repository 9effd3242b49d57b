//! The step `splinerod bench` times as `step_us_16` (16-point cable, one Newton
//! iteration, no line search), repeated, for profilers:
//! `valgrind --tool=callgrind target/release/examples/step_profile [STEPS]
//! [consistent|lumped] [DT] [POINTS]` (`consistent`: the mixed stretching with the
//! consistent Gram matrix; `DT` the time step, 1e-3 s by default; `POINTS` control points,
//! 16 by default).
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
    let points: usize = std::env::args()
        .nth(4)
        .and_then(|a| a.parse().ok())
        .unwrap_or(16);
    let system = pinned_cable_with(points, 1.05, 100.0, formulation)?;
    let mut sim = Simulation::new(system, Box::new(ImplicitEuler::new(params)?));
    let dt: Real = std::env::args()
        .nth(3)
        .and_then(|a| a.parse().ok())
        .unwrap_or(1e-3);
    let t = Instant::now();
    let mut cg = 0;
    for _ in 0..steps {
        cg += sim.step(dt)?.solver.remainder_iterations;
    }
    let us = t.elapsed().as_secs_f64() / steps as Real * 1e6;
    let cg = cg as Real / steps as Real;
    println!("{steps} steps, {us:.2} µs per step, {cg:.2} conjugate-gradient iterations per step");
    Ok(())
}
