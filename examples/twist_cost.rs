//! The cost of twist in a step: runs `STEPS` (default 100 000) one-iteration implicit
//! Euler steps of the bench's clamped 16-point rod, with stretching and bending only or
//! (argument `twist`) with the twisting energy too, and prints the mean wall time per
//! step. On a noisy machine compare instruction counts instead:
//!
//! `STEPS=3000 valgrind --tool=callgrind ./target/release/examples/twist_cost [twist]`
//!
//! `cargo run --release --example twist_cost -- twist`

use splinerod::Error;
use std::time::Instant;

fn main() -> Result<(), Error> {
    let twist = std::env::args().nth(1).as_deref() == Some("twist");
    let steps: usize = std::env::var("STEPS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(100_000);
    let mut sim = splinerod::bench_twist::simulation(twist)?;
    let start = Instant::now();
    for _ in 0..steps {
        sim.step(1e-3)?;
    }
    let per_step = start.elapsed().as_secs_f64() / steps as f64;
    let energies = if twist {
        "stretching, bending and twist"
    } else {
        "stretching and bending"
    };
    println!("{energies}: {:.2} µs per step", per_step * 1e6);
    Ok(())
}
