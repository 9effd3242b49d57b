//! Long runs at the command line: `--max-steps`, SIGINT and SIGTERM stop a run at the
//! end of a step with complete outputs (JSON `"interrupted": true`, the stats CSV and the
//! ParaView series ending cleanly, exit 130 for a signal); scenes past the resource
//! limits are refused naming the fields, unless `--allow-large` (and then still when the
//! memory could not exist).

use crate::common;

use common::cli::{fresh_dir as dir, refused, scene_variant, splinerod};
use serde_json::Value;
use splinerod::scene::Limits;
use std::path::{Path, PathBuf};
use std::process::Command;

/// `scenes/NAME` with `from` replaced by `to`, written into `dir`.
fn variant(dir: &Path, name: &str, from: &str, to: &str) -> PathBuf {
    scene_variant(dir, name, &[(from, to)])
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("JSON written")).expect("JSON")
}

/// Rows of a stats CSV after its header.
fn stats_rows(path: &Path) -> usize {
    let text = std::fs::read_to_string(path).expect("stats written");
    assert!(text.ends_with('\n'), "the CSV ends with a whole row");
    text.lines().count() - 1
}

#[test]
fn max_steps_ends_the_run_with_complete_outputs() {
    let d = dir("max-steps");
    let (out, stats) = (d.join("out.json"), d.join("stats.csv"));
    let args = ["run", "scenes/hanging_cable.toml", "--max-steps", "7"];
    let done = splinerod(&[&args[..], &["--json", out.to_str().unwrap()]].concat());
    let done = (
        done,
        splinerod(&[&args[..], &["--stats", stats.to_str().unwrap()]].concat()),
    );
    assert!(done.0.status.success() && done.1.status.success());
    let result = json(&out);
    assert_eq!(result["steps"], 7);
    assert_eq!(result["interrupted"], true);
    assert!((result["time"].as_f64().unwrap() - 7.0 * 0.005).abs() < 1e-12);
    assert_eq!(stats_rows(&stats), 7);
    // A run that ends before the limit is not interrupted: the key is absent.
    let short = variant(
        &d,
        "hanging_cable.toml",
        "duration = 10.0",
        "duration = 0.02",
    );
    let ran = splinerod(&[
        "run",
        short.to_str().unwrap(),
        "--max-steps",
        "100",
        "--json",
        out.to_str().unwrap(),
    ]);
    assert!(ran.status.success());
    let result = json(&out);
    assert_eq!(result["steps"], 4);
    assert!(result.get("interrupted").is_none());
    std::fs::remove_dir_all(&d).ok();
}

/// Starts a long run, waits until it has taken some steps, sends `signal`, and checks
/// the run stopped cleanly.
#[cfg(unix)]
fn interrupted_by(signal: &str, test: &str) {
    let d = dir(test);
    let scene = variant(&d, "knot_tying.toml", "duration = 3.0", "duration = 300.0");
    let (out, stats, vtk) = (d.join("out.json"), d.join("stats.csv"), d.join("vtk"));
    let child = Command::new(env!("CARGO_BIN_EXE_splinerod"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--json",
            out.to_str().unwrap(),
        ])
        .args([
            "--stats",
            stats.to_str().unwrap(),
            "--vtk",
            vtk.to_str().unwrap(),
        ])
        .args(["--every", "10"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    let start = std::time::Instant::now();
    while !vtk.join("centreline_00020.vtp").exists() {
        assert!(start.elapsed().as_secs() < 120, "the run never got going");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let sent = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .expect("kill runs");
    assert!(sent.success());
    let output = child.wait_with_output().expect("the run ends");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(130), "{signal}: {stderr}");
    assert!(stderr.contains("interrupted"), "{stderr}");
    let result = json(&out);
    assert_eq!(result["interrupted"], true);
    let steps = result["steps"].as_u64().unwrap() as usize;
    assert!((20..100_000).contains(&steps), "{steps} steps");
    assert!((result["time"].as_f64().unwrap() - steps as f64 * 1e-3).abs() < 1e-9);
    assert!(result["samples"]["positions"][0][0].is_number());
    assert_eq!(stats_rows(&stats), steps, "one stats row per step taken");
    let pvd = std::fs::read_to_string(vtk.join("rod.pvd")).expect("collection written");
    assert!(pvd.trim_end().ends_with("</VTKFile>"), "{pvd}");
    let listed = pvd.matches("<DataSet").count();
    let end = usize::from(steps % 10 != 0);
    assert_eq!(
        listed,
        1 + steps / 10 + end,
        "the initial state, every 10th step, the end"
    );
    std::fs::remove_dir_all(&d).ok();
}

#[cfg(unix)]
#[test]
fn sigint_stops_the_run_at_the_end_of_a_step() {
    interrupted_by("-INT", "sigint");
}

#[cfg(unix)]
#[test]
fn sigterm_stops_the_run_at_the_end_of_a_step() {
    interrupted_by("-TERM", "sigterm");
}

#[test]
fn scenes_past_the_limits_are_refused_naming_the_fields() {
    let d = dir("limits");
    let cases = [
        (
            "hanging_cable.toml",
            "samples = 41",
            "samples = 1000000000000",
            "`output.samples`",
        ),
        (
            "hanging_cable.toml",
            "dt = 0.005",
            "dt = 1e-300",
            "`solver.duration / solver.dt`",
        ),
        (
            "hanging_cable.toml",
            "duration = 10.0",
            "duration = 1e300",
            "`solver.duration / solver.dt`",
        ),
        (
            "hanging_cable.toml",
            "control_points = 16",
            "control_points = 2000000",
            "`rod.control_points`",
        ),
        (
            "knot_tying_adaptive.toml",
            "max_control_points = 40",
            "max_control_points = 5000000",
            "`adaptivity.max_control_points`",
        ),
        (
            "ensemble_cables.toml",
            "count = 1000",
            "count = 1000000000",
            "ensemble.count ×",
        ),
        (
            "knot_tying.toml",
            "duration = 3.0",
            "duration = 9000.0",
            "control-point steps",
        ),
    ];
    for (name, from, to, named) in cases {
        let scene = variant(&d, name, from, to);
        let line = refused(&["run", scene.to_str().unwrap()]);
        assert!(
            line.contains(named) && line.contains("--allow-large"),
            "{to}: {line}"
        );
        let parsed = splinerod::Scene::load(&scene).expect("valid scene");
        assert!(parsed.check_limits(&Limits::default()).is_err());
    }
    // Past a limit but possible: runs with --allow-large.
    let long = variant(&d, "hanging_cable.toml", "dt = 0.005", "dt = 1e-7");
    let out = splinerod(&[
        "run",
        long.to_str().unwrap(),
        "--allow-large",
        "--max-steps",
        "3",
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Memory that cannot exist is refused even then, before anything is allocated.
    let huge = variant(
        &d,
        "hanging_cable.toml",
        "samples = 41",
        "samples = 1000000000000",
    );
    let line = refused(&["run", huge.to_str().unwrap(), "--allow-large"]);
    assert!(
        line.contains("`output.samples`") && line.contains("more than this machine has"),
        "{line}"
    );
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn every_bundled_scene_is_within_the_limits() {
    for entry in std::fs::read_dir("scenes").expect("scenes/") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|x| x == "toml") {
            let scene = splinerod::Scene::load(&path).expect("bundled scene");
            let r = scene.resources();
            scene
                .check_limits(&Limits::default())
                .unwrap_or_else(|e| panic!("{}: {e} ({r:?})", path.display()));
        }
    }
}
