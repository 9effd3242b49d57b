//! Cost of one error estimate per control point, and how many estimates the schedule
//! makes in 256 steady steps: `cargo run --release --example estimate_cost`.
use splinerod::adaptivity::{AdaptParams, Adapter, ToleranceCriterion};
use std::time::Instant;
fn main() -> Result<(), splinerod::Error> {
    for n in [1_000, 10_000, 100_000] {
        let p = splinerod::NewtonParams {
            max_iterations: 1,
            line_search: false,
            ..Default::default()
        };
        let params = AdaptParams {
            max_control_points: n,
            min_control_points: n,
            ..AdaptParams::default()
        };
        let adapter = Adapter::new(params)?.with(ToleranceCriterion::new(1.0)?);
        let system = splinerod::problems::pinned_cable(n, 1.05, 100.0)?;
        let mut sim =
            splinerod::Simulation::new(system, Box::new(splinerod::ImplicitEuler::new(p)?))
                .with_adapter(adapter);
        for _ in 0..10 {
            sim.step(1e-3)?;
        }
        let t = Instant::now();
        for _ in 0..5 {
            sim.estimate_now()?;
        }
        let per = t.elapsed().as_secs_f64() / 5.0;
        let mut count = 0;
        for _ in 0..256 {
            count += usize::from(sim.step(1e-3)?.error_estimate.is_some());
        }
        println!(
            "estimate {:.2e}",
            sim.error_estimate().map_or(0.0, |e| e.max())
        );
        println!(
            "n {n}: one estimate {:.1} ns/cp; {count} estimates in 256 steps",
            per * 1e9 / n as f64
        );
    }
    Ok(())
}
