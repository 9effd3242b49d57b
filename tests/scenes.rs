//! The cantilever and the midpoint string give their known answers: scene-level checks
//! of bending, clamps and a swapped integrator. (That every bundled scene runs to a
//! finite end is checked on the runs of `snapshots.rs`.)

use splinerod::{run, RunResult, Scene};

fn run_scene(name: &str) -> RunResult {
    let path = format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    run(&scene).unwrap_or_else(|e| panic!("{name}: {e}"))
}

// Every bundled scene runs to its end with finite positions and energies: checked on
// the runs of `snapshots.rs`, which runs them all anyway.

#[test]
fn cantilever_scene_matches_euler_bernoulli() {
    let result = run_scene("cantilever.toml");
    let tip = result.samples.positions.last().expect("tip")[1];
    let exact = 0.1 * 9.81 / (8.0 * 10.0); // q L⁴ / (8 EI)
    let error = (-tip - exact).abs() / exact;
    println!(
        "tip deflection {:.6e} m vs {exact:.6e} m: {error:.2e}",
        -tip
    );
    assert!(error < 1e-2);
}

#[test]
fn midpoint_string_keeps_its_amplitude() {
    let amplitude = |r: &RunResult, from: usize, to: usize| {
        let y = r.probes[0].positions[from..to].iter().map(|p| p[1].abs());
        y.fold(0.0, f64::max)
    };
    let (midpoint, euler) = (
        run_scene("string_midpoint.toml"),
        run_scene("string_modes.toml"),
    );
    let n = midpoint.probes[0].positions.len();
    let kept = amplitude(&midpoint, n - 150, n) / amplitude(&midpoint, 0, 150);
    let lost = amplitude(&euler, n - 150, n) / amplitude(&euler, 0, 150);
    println!("amplitude kept after 1 s: midpoint {kept:.4}, implicit Euler {lost:.4}");
    assert!(kept > 0.99 && lost < 0.5);
}
