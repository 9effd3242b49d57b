//! Factorisation and solve of four 16-block Newton-shaped bands (bandwidth 5, as the
//! mixed stretching's), one at a time with the banded Cholesky against all four at once
//! with the structure-of-arrays `BatchedBandedCholesky` (#17):
//! `cargo run --release --example batched_cholesky [REPS] [scalar|batched]` (one mode:
//! for `valgrind --tool=callgrind`).
use nalgebra::Matrix3;
use splinerod::Real;
use splinerod_core::BlockBanded;
use splinerod_integrators::batched::{BatchedBandedCholesky, Lanes, LANES};
use splinerod_integrators::{BandedCholesky, IntegratorError};
use std::time::Instant;

const POINTS: usize = 16;
const BANDWIDTH: usize = 5;

/// A diagonally dominant block band, different per `seed`.
fn band(seed: Real) -> BlockBanded {
    let mut a = BlockBanded::zeros(POINTS, BANDWIDTH);
    for i in 0..POINTS {
        for j in i..(i + BANDWIDTH + 1).min(POINTS) {
            let b =
                Matrix3::from_fn(|r, c| ((i * 31 + j * 17 + r * 7 + c * 3) as Real * seed).sin());
            let b = if i == j {
                b + b.transpose() + Matrix3::identity() * 60.0
            } else {
                b
            };
            a.add_block(i, j, &b);
        }
    }
    a
}

fn main() -> Result<(), IntegratorError> {
    let reps: usize = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(100_000);
    let mode = std::env::args().nth(2);
    let mats: Vec<BlockBanded> = (0..LANES).map(|l| band(0.3 + l as Real)).collect();
    let rhs = |l: usize, k: usize| ((k * 13 + l * 5) as Real * 0.7).cos();
    let mut seconds = [0.0; 2];
    if mode.as_deref() != Some("batched") {
        let mut solver = BandedCholesky::new();
        let mut x = vec![0.0; 3 * POINTS];
        let t = Instant::now();
        for _ in 0..reps {
            for (l, m) in mats.iter().enumerate() {
                solver.factor(m)?;
                x.iter_mut().enumerate().for_each(|(k, x)| *x = rhs(l, k));
                solver.solve_in_place(&mut x)?;
            }
        }
        seconds[0] = t.elapsed().as_secs_f64();
    }
    if mode.as_deref() != Some("scalar") {
        let mut solver = BatchedBandedCholesky::default();
        let mut x: Vec<Lanes> = vec![[0.0; LANES]; 3 * POINTS];
        let t = Instant::now();
        for _ in 0..reps {
            solver.factor([&mats[0], &mats[1], &mats[2], &mats[3]])?;
            for (k, x) in x.iter_mut().enumerate() {
                *x = std::array::from_fn(|l| rhs(l, k));
            }
            solver.solve_in_place(&mut x)?;
        }
        seconds[1] = t.elapsed().as_secs_f64();
    }
    let per = |s: Real| s / (reps * LANES) as Real * 1e9;
    println!(
        "per matrix: one at a time {:.0} ns, four at once {:.0} ns",
        per(seconds[0]),
        per(seconds[1])
    );
    Ok(())
}
