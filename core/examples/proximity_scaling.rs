//! Timing of the proximity queries (broad + narrow phase) on tight helices with 100 to
//! 100 000 spans: a tightly wound spring whose neighbouring turns are within contact
//! distance, so every span has candidates on the turns above and below it.
//!
//! Run with `cargo run --release -p splinerod-core --example proximity_scaling`.
//! Prints the time per span of each phase; near-constant figures mean linear scaling.

use nalgebra::Vector3;
use splinerod_core::basis::greville;
use splinerod_core::{closest_points, BSplineSpace, CoreError, Material, Rod, SpanBoxes};
use std::f64::consts::TAU;
use std::time::{Duration, Instant};

/// Coil radius, m.
const RADIUS: f64 = 0.05;
/// Rod radius = box margin, m.
const ROD_RADIUS: f64 = 0.003;
/// Rise per turn, m: just above the rod diameter (coils nearly touching).
const PITCH: f64 = 0.0065;
/// Spans per turn.
const SPANS_PER_TURN: usize = 20;

/// A cubic rod with `n` spans whose control points lie on the helix.
fn helix(n: usize) -> Result<Rod, CoreError> {
    let turns = n as f64 / SPANS_PER_TURN as f64;
    let length = turns * (TAU * RADIUS).hypot(PITCH);
    let basis = BSplineSpace::clamped_uniform(3, n + 3, length)?;
    let positions = (0..n + 3)
        .map(|i| {
            let u = greville(&basis, i) / length;
            let a = TAU * turns * u;
            Vector3::new(RADIUS * a.cos(), RADIUS * a.sin(), PITCH * turns * u)
        })
        .collect();
    let material = Material {
        rest_length: length,
        linear_density: 0.01,
    };
    Rod::new(material, Box::new(basis), positions)
}

/// Best of `repeats` runs of `f`.
fn best<T>(
    repeats: usize,
    mut f: impl FnMut() -> Result<T, CoreError>,
) -> Result<Duration, CoreError> {
    let mut best = Duration::MAX;
    for _ in 0..repeats {
        let start = Instant::now();
        std::hint::black_box(f()?);
        best = best.min(start.elapsed());
    }
    Ok(best)
}

fn per_span(d: Duration, n: usize) -> f64 {
    d.as_secs_f64() * 1e9 / n as f64
}

fn main() -> Result<(), CoreError> {
    println!(
        "{:>7} {:>4} {:>8} {:>7} | ns/span: {:>8} {:>8} {:>8} {:>8} {:>8}",
        "spans", "axis", "pairs", "/span", "new", "update", "sweep", "narrow", "total"
    );
    for n in [100, 1_000, 10_000, 100_000] {
        let mut rod = helix(n)?;
        let exclusion = 5.0 * rod.material().rest_length / n as f64;
        let repeats = (1_000_000 / n).clamp(3, 200);
        let cold = best(repeats, || SpanBoxes::new(&rod, ROD_RADIUS))?;
        let mut boxes = SpanBoxes::new(&rod, ROD_RADIUS)?;
        let mut pairs = Vec::new();
        // A small motion, as between two time steps: the warm start has work to do.
        for (i, q) in rod.positions.iter_mut().enumerate() {
            q.z += 2e-4 * (0.7 * i as f64).sin();
        }
        let warm = best(repeats, || boxes.update(&rod, ROD_RADIUS))?;
        let sweep = best(repeats, || boxes.candidate_pairs(exclusion, &mut pairs))?;
        let spans = boxes.spans();
        let narrow = best(repeats, || {
            let mut touching = 0;
            for &(i, j) in &pairs {
                let c = closest_points(&rod, &spans[i], &spans[j])?;
                touching += usize::from(c.distance < 2.0 * ROD_RADIUS);
            }
            Ok(touching)
        })?;
        let total = warm + sweep + narrow;
        println!(
            "{n:>7} {:>4} {:>8} {:>7.1} | ns/span: {:>8.0} {:>8.0} {:>8.0} {:>8.0} {:>8.0}",
            ["x", "y", "z"][boxes.axis()],
            pairs.len(),
            pairs.len() as f64 / n as f64,
            per_span(cold, n),
            per_span(warm, n),
            per_span(sweep, n),
            per_span(narrow, n),
            per_span(total, n),
        );
    }
    Ok(())
}
