//! How much resolution the hidden-style overhand knot of issue #46 needs
//! (`cargo run --release --example knot_resolution_study -- [seconds]`): the bundled
//! `knot_tying_tolerance.toml` with a 2 mm string, run at uniform resolutions without
//! adaptivity and with the tolerance 2e-4 m at the budgets 64 and 200, to `seconds`
//! (default 1.5; 3 shows the 200-point budget's count falling after its peak).
//!
//! For each run: the largest distance of the 41 output samples from the finest uniform
//! run (200 control points, the scene format's largest), the knot's length (rest
//! arclength between its first and last crossing; tighter is smaller), the adaptive
//! runs' own error estimate and wall time. It answers whether the estimate that keeps
//! the budget full is an honest one: if the uniform runs still move by centimetres
//! between 64 and 200 points, a 0.2 mm tolerance cannot be met at 64 and the adapter
//! is right to keep every point.

use splinerod::{run, Real, RunResult, Scene};
use std::time::Instant;

/// The finest uniform resolution the scene format allows.
const FINEST: usize = 200;

/// The hidden-style knot: the bundled knot with a 2 mm string, run for `seconds`, with
/// `n` control points at the start (the overhand shape is fitted at that resolution).
fn knot(seconds: Real, n: usize) -> Result<Scene, Box<dyn std::error::Error>> {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/knot_tying_tolerance.toml"
    );
    let text = std::fs::read_to_string(path)?;
    let text = text.replace("control_points = 11", &format!("control_points = {n}"));
    let mut scene = Scene::from_toml(&text)?;
    scene.rod.radius = Some(0.002);
    scene.solver.duration = Some(seconds);
    Ok(scene)
}

/// Runs `scene`, returning the result and the wall time.
fn timed(scene: &Scene) -> Result<(RunResult, Real), splinerod::Error> {
    let start = Instant::now();
    let result = run(scene)?;
    Ok((result, start.elapsed().as_secs_f64()))
}

/// The largest distance between two runs' output samples, m.
fn distance(a: &RunResult, b: &RunResult) -> Real {
    let pairs = a.samples.positions.iter().zip(&b.samples.positions);
    pairs.fold(0.0, |worst, (p, q)| {
        let d = (0..3).map(|c| (p[c] - q[c]).powi(2)).sum::<Real>().sqrt();
        worst.max(d)
    })
}

/// The knot's length at the end of `r`, m (NaN if no knot was found).
fn knot_length(r: &RunResult) -> Real {
    let track = r.knot.as_ref();
    let last = track.and_then(|k| k.knot_length.last().copied().flatten());
    last.unwrap_or(Real::NAN)
}

/// The largest control-point count of an adaptive run and the smallest after it.
fn peak_and_least_after(r: &RunResult) -> (usize, usize) {
    let counts: Vec<usize> = r
        .control_points_history
        .iter()
        .map(|c| c[1] as usize)
        .collect();
    let peak = counts.iter().copied().max().unwrap_or(0);
    let at = counts.iter().position(|&c| c == peak).unwrap_or(0);
    (peak, counts[at..].iter().copied().min().unwrap_or(peak))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let seconds: Real = match std::env::args().nth(1) {
        Some(s) => s.parse()?,
        None => 1.5,
    };
    let uniform = |n: usize| -> Result<(RunResult, Real), Box<dyn std::error::Error>> {
        let mut scene = knot(seconds, n)?;
        scene.adaptivity = None;
        Ok(timed(&scene)?)
    };
    let (finest, finest_wall) = uniform(FINEST)?;
    println!("hidden-style knot (r = 2 mm), {seconds} s; distances from uniform {FINEST}");
    println!("| run | control points | distance, m | knot length, m | estimate, m | wall, s |");
    println!("|---|---|---|---|---|---|");
    for n in [32, 64, 96, 128, 160] {
        let (r, wall) = uniform(n)?;
        let d = distance(&r, &finest);
        let l = knot_length(&r);
        println!("| uniform | {n} | {d:.2e} | {l:.3} | – | {wall:.1} |");
    }
    let l = knot_length(&finest);
    println!("| uniform | {FINEST} | 0 | {l:.3} | – | {finest_wall:.1} |");
    for cap in [64, FINEST] {
        let mut scene = knot(seconds, 11)?;
        let a = scene
            .adaptivity
            .as_mut()
            .ok_or("the scene has no [adaptivity]")?;
        a.tolerance = Some(2e-4);
        a.max_control_points = cap;
        let (r, wall) = timed(&scene)?;
        let estimate = r
            .adaptivity
            .as_ref()
            .map_or(Real::NAN, |e| e.estimated_error);
        let (d, l, n) = (distance(&r, &finest), knot_length(&r), r.control_points);
        let (peak, after) = peak_and_least_after(&r);
        println!(
            "| τ = 2e-4, cap {cap} (peak {peak}, least after it {after}) | {n} | {d:.2e} | \
             {l:.3} | {estimate:.2e} | {wall:.1} |"
        );
    }
    Ok(())
}
