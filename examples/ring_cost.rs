//! Cost of a closed rod's step against an open rod's with as many stored control points:
//! a 32-point ring and a 35-point open rod (stretching and gravity, implicit midpoint,
//! 4 000 steps of 1 ms), wall time per step and per Newton iteration.
//! `cargo run --release --example ring_cost [STEPS] [false|true]` (the second argument
//! runs only the open or the closed rod, for callgrind).
use splinerod::prelude::*;
use std::f64::consts::TAU;
use std::time::Instant;
fn main() -> Result<(), Box<dyn std::error::Error>> {
    let steps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(4000);
    let only = std::env::args().nth(2);
    for closed in [false, true]
        .into_iter()
        .filter(|c| only.as_deref().is_none_or(|o| o == c.to_string()))
    {
        let material = Material {
            rest_length: TAU * 0.2,
            linear_density: 0.1,
        };
        let rod = if closed {
            let space = PeriodicBSplineSpace::uniform(3, 32, material.rest_length)?;
            Rod::ring(
                material,
                Box::new(space),
                Vector3::zeros(),
                Vector3::z(),
                0.202,
            )?
        } else {
            let space = BSplineSpace::clamped_uniform(3, 35, material.rest_length)?;
            Rod::straight(
                material,
                Box::new(space),
                Vector3::zeros(),
                Vector3::new(1.3, 0.0, 0.0),
            )?
        };
        let system = RodSystem::new(rod)
            .with_energy(Stretching::new(10.0)?)
            .with_energy(Gravity::new(Vector3::new(0.0, 0.0, -9.81))?);
        let mut sim = Simulation::new(
            system,
            Box::new(ImplicitMidpoint::new(NewtonParams::default())?),
        );
        let t = Instant::now();
        let mut iters = 0;
        for _ in 0..steps {
            iters += sim.step(1e-3)?.solver.newton_iterations;
        }
        let el = t.elapsed().as_secs_f64();
        println!(
            "closed {closed}: {:.1} µs/step, {:.2} Newton iterations/step, {:.1} µs/iteration",
            el / steps as f64 * 1e6,
            iters as f64 / steps as f64,
            el / iters as f64 * 1e6
        );
    }
    Ok(())
}
