//! Every bundled scene parses, runs and ends in a finite state; the cantilever and the
//! midpoint string give their known answers (scene-level checks of bending, clamps and a
//! swapped integrator).

use splinerod::{run, RunResult, Scene};

fn run_scene(name: &str) -> RunResult {
    let path = format!("{}/scenes/{name}", env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::load(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
    run(&scene).unwrap_or_else(|e| panic!("{name}: {e}"))
}

#[test]
fn every_bundled_scene_runs() {
    let dir = format!("{}/scenes", env!("CARGO_MANIFEST_DIR"));
    let mut names: Vec<String> = std::fs::read_dir(&dir)
        .expect("scenes directory")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".toml"))
        .collect();
    names.sort();
    assert!(names.len() >= 8, "{names:?}");
    for name in names {
        let result = run_scene(&name);
        let finite = result
            .samples
            .positions
            .iter()
            .flatten()
            .all(|x| x.is_finite());
        assert!(
            finite && result.energy.values().all(|e| e.is_finite()),
            "{name}"
        );
    }
}

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
