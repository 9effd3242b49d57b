//! Every long loop stops on a signal (#45): SIGINT sent 0.5 s into a scene's setup (the
//! overhand knot's fit), a long static solve or a friction scene whose steps take
//! seconds ends the run within about a second — the step under way abandoned and
//! rolled back, outputs written where a state exists, exit 130. The sub-stepper never
//! goes below `solver.min_dt`, and a closed standard output is no error.
//!
//! The bound asserted is generous (5 s, for a loaded machine); the measured stop
//! latency is printed (`cargo test --test interrupts -- --nocapture`).

#![cfg(unix)]

mod common;

use common::cli::{fresh_dir as dir, scene_variant, splinerod};
use serde_json::Value;
use std::path::Path;
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Most seconds from the signal to the exit.
const BOUND: f64 = 5.0;

/// Runs the binary with `args`, sends SIGINT `delay` after the start; its output and the
/// seconds from the signal to its exit.
fn interrupted_after(delay: Duration, args: &[&str]) -> (Output, f64) {
    let child = Command::new(env!("CARGO_BIN_EXE_splinerod"))
        .args(args)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    std::thread::sleep(delay);
    let sent = Instant::now();
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    assert!(kill.expect("kill runs").success());
    let out = child.wait_with_output().expect("the run ends");
    (out, sent.elapsed().as_secs_f64())
}

fn json(path: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(path).expect("JSON written")).expect("JSON")
}

/// Checks a run stopped by the signal: exit 130 within [`BOUND`], no panic.
fn stopped(what: &str, out: &Output, latency: f64) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    println!("{what}: stopped {latency:.3} s after SIGINT; stderr: {stderr}");
    assert_eq!(out.status.code(), Some(130), "{what}: {stderr}");
    assert!(latency < BOUND, "{what}: {latency:.2} s after the signal");
    assert!(!stderr.contains("panicked"), "{what}: {stderr}");
    stderr
}

#[test]
fn sigint_during_the_knot_fit_stops_the_setup() {
    let d = dir("int-setup");
    let out_json = d.join("out.json");
    let args = ["run", "scenes/knot_pulled_fixed.toml", "--json"];
    let (out, latency) = interrupted_after(
        Duration::from_millis(500),
        &[&args[..], &[out_json.to_str().unwrap()]].concat(),
    );
    let stderr = stopped("knot fit", &out, latency);
    assert!(stderr.contains("setup"), "{stderr}");
    assert!(!out_json.exists(), "no state, no JSON");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn sigint_during_a_long_static_solve_writes_the_start() {
    let d = dir("int-static");
    // 1500 control points squeezed to 0.3 m: a static solve of about 20 s.
    let scene = scene_variant(
        &d,
        "catenary_static.toml",
        &[
            ("control_points = 16", "control_points = 1500"),
            ("stretch_stiffness = 100.0", "stretch_stiffness = 1e4"),
            ("end = [0.8, 0.0, 0.0]", "end = [0.3, 0.0, 0.0]"),
        ],
    );
    let out_json = d.join("out.json");
    let (out, latency) = interrupted_after(
        Duration::from_millis(500),
        &[
            "run",
            scene.to_str().unwrap(),
            "--json",
            out_json.to_str().unwrap(),
        ],
    );
    let stderr = stopped("static solve", &out, latency);
    assert!(stderr.contains("abandoned"), "{stderr}");
    let result = json(&out_json);
    assert_eq!(result["interrupted"], true);
    assert_eq!(result["solver"]["newton_iterations"], 0, "rolled back");
    assert_eq!(result["pin_forces"], Value::Array(Vec::new()), "no forces");
    let first = &result["samples"]["positions"][0];
    assert_eq!(first, &serde_json::json!([0.0, 0.0, 0.0]));
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn sigint_stops_a_scene_with_huge_friction() {
    let d = dir("int-friction");
    let friction = [("[contact]\n", "[contact]\nfriction = 1099511627776.0\n")];
    let scene = scene_variant(&d, "rubber_band.toml", &friction);
    let out_json = d.join("out.json");
    let path = [
        scene.to_str().unwrap(),
        "--json",
        out_json.to_str().unwrap(),
    ];
    let (out, latency) =
        interrupted_after(Duration::from_millis(500), &[&["run"][..], &path].concat());
    stopped("friction 2^40", &out, latency);
    assert_eq!(json(&out_json)["interrupted"], true);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn an_abandoned_step_is_undone_exactly_and_checkpointed() {
    let d = dir("int-undo");
    // Steps of 0.1 s under friction 2^40: the first takes many seconds.
    let edits = [
        ("[contact]\n", "[contact]\nfriction = 1099511627776.0\n"),
        ("dt = 0.001", "dt = 0.1"),
    ];
    let scene = scene_variant(&d, "rubber_band.toml", &edits);
    let scene = scene.to_str().unwrap();
    let (start, stopped_json) = (d.join("start.json"), d.join("stopped.json"));
    let ck = d.join("ck");
    let ran = splinerod(&[
        "run",
        scene,
        "--max-steps",
        "0",
        "--json",
        start.to_str().unwrap(),
    ]);
    assert!(ran.status.success());
    let args = [
        "run",
        scene,
        "--json",
        stopped_json.to_str().unwrap(),
        "--checkpoint",
        ck.to_str().unwrap(),
    ];
    let (out, latency) = interrupted_after(Duration::from_millis(500), &args);
    let stderr = stopped("abandoned step", &out, latency);
    assert!(stderr.contains("abandoned"), "{stderr}");
    assert!(!stderr.contains("not updated"), "{stderr}");
    let (a, b) = (json(&start), json(&stopped_json));
    for key in ["time", "steps", "samples", "energy", "knots", "contact"] {
        assert_eq!(a[key], b[key], "{key}: the state before the step");
    }
    // The checkpoint at the stop resumes to the same state.
    let kept = d.join("kept.json");
    std::fs::copy(&stopped_json, &kept).expect("copy");
    let resumed = splinerod(&["resume", ck.to_str().unwrap(), "--max-steps", "0"]);
    assert!(resumed.status.success(), "{:?}", resumed);
    let (b, c) = (json(&kept), json(&stopped_json));
    for key in ["time", "steps", "samples", "energy", "knots", "interrupted"] {
        assert_eq!(b[key], c[key], "{key}: resumed from the stop");
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_tolerance_too_tight_for_min_dt_fails_the_step_naming_it() {
    let d = dir("int-min-dt");
    let edits = [(
        "duration = 10.0",
        "duration = 10.0\ntime_tolerance = 1e-20\nmin_dt = 1e-5",
    )];
    let scene = scene_variant(&d, "hanging_cable.toml", &edits);
    let start = Instant::now();
    let out = splinerod(&["run", scene.to_str().unwrap()]);
    let seconds = start.elapsed().as_secs_f64();
    let stderr = String::from_utf8_lossy(&out.stderr);
    println!("min_dt: failed in {seconds:.3} s: {stderr}");
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("`solver.min_dt` = 1e-5"), "{stderr}");
    assert!(stderr.contains("solver.time_tolerance"), "{stderr}");
    assert!(seconds < BOUND, "{seconds} s");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_closed_standard_output_is_not_an_error() {
    let d = dir("int-pipe");
    let out_json = d.join("out.json");
    let mut child = Command::new(env!("CARGO_BIN_EXE_splinerod"))
        .args(["run", "scenes/hanging_cable.toml", "--max-steps", "20"])
        .args(["--json", out_json.to_str().unwrap()])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn");
    // The reader goes away before anything is printed (as `| head -0` would).
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("ends");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(json(&out_json)["steps"], 20, "the files are still written");
    std::fs::remove_dir_all(&d).ok();
}
