//! Per-step statistics, the speed-vs-error report, the CLI's output flags and its
//! summary: files that decode, one CSV row per step, the measured order in the report,
//! clear errors (exit code 2, nothing claiming to be complete) for bad output options,
//! and summary lines only for what acts.

use splinerod::output::stats::StatsWriter;
use splinerod::{run_observed, Observer, Scene};
use std::path::PathBuf;
use std::process::Command;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("splinerod-outputs-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

const CABLE: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 12
end = [0.8, 0.0, 0.0]
[[pins]]
at = 0.0
[[pins]]
at = 1.0
[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.2
"#;

#[test]
fn stats_csv_has_one_row_per_step() {
    let dir = scratch("stats");
    let path = dir.join("stats.csv");
    let scene = Scene::from_toml(CABLE).expect("scene");
    let mut stats = StatsWriter::new(&path).expect("writer");
    let mut observers: [&mut dyn Observer; 1] = [&mut stats];
    let result = run_observed(&scene, &mut observers).expect("run");
    let mut reader = csv::Reader::from_path(&path).expect("csv");
    let header = reader.headers().expect("header").clone();
    for column in [
        "time",
        "control_points",
        "newton_iterations",
        "residual",
        "kinetic",
        "stretch",
        "gravity",
        "wall_seconds",
    ] {
        assert!(
            header.iter().any(|h| h == column),
            "missing column {column}"
        );
    }
    let rows: Vec<_> = reader.records().collect::<Result<_, _>>().expect("rows");
    assert_eq!(rows.len(), result.steps);
    let last_time: f64 = rows[rows.len() - 1][0].parse().expect("time");
    assert!((last_time - result.time).abs() < 1e-12);
    assert!(!dir.join("stats.csv.partial").exists());
}

#[test]
fn quick_report_states_the_order_it_measured() {
    let dir = scratch("report");
    let report = splinerod::report::write_report(&dir, true).expect("report");
    let text = std::fs::read_to_string(dir.join("report.md")).expect("report.md");
    assert!(
        text.contains(&format!("**{:.2}**", report.order)),
        "order missing"
    );
    assert!(report.order > 4.0, "order {}", report.order);
    for plot in [
        "catenary_convergence",
        "pareto",
        "string_modal",
        "string_frequency",
        "string_amplitude",
    ] {
        for ext in ["png", "svg"] {
            let path = dir.join(format!("{plot}.{ext}"));
            assert!(
                std::fs::metadata(&path)
                    .map(|m| m.len() > 100)
                    .unwrap_or(false),
                "{path:?}"
            );
        }
    }
}

fn cli(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_splinerod"))
        .args(args)
        .output()
        .expect("run the CLI");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn bad_output_options_fail_cleanly() {
    let dir = scratch("cli");
    let scene = dir.join("cable.toml");
    std::fs::write(&scene, CABLE).expect("scene file");
    let scene = scene.to_str().expect("path");
    let frames = dir.join("frames");
    let frames = frames.to_str().expect("path");
    let blocker = dir.join("file");
    std::fs::write(&blocker, "not a directory").expect("file");
    let under_file = blocker.join("sub");
    let under_file = under_file.to_str().expect("path");
    let stats_under_file = blocker.join("stats.csv");
    let cases: [(&[&str], &str); 5] = [
        (
            &["run", scene, "--frames", frames, "--every", "0"],
            "--every",
        ),
        (
            &["run", scene, "--frames", frames, "--camera", "bogus"],
            "--camera",
        ),
        (&["run", scene, "--frames", under_file], under_file),
        (&["run", scene, "--vtk", under_file], under_file),
        (
            &[
                "run",
                scene,
                "--stats",
                stats_under_file.to_str().expect("path"),
            ],
            "stats.csv",
        ),
    ];
    for (args, named) in cases {
        let (code, stderr) = cli(args);
        assert_eq!(code, 2, "{args:?}: {stderr}");
        assert!(
            stderr.starts_with("error:") && stderr.contains(named),
            "{args:?}: {stderr}"
        );
        assert!(!stderr.contains("panicked"), "{stderr}");
    }
}

/// `CABLE` with `extra` tables appended.
fn cable_with(extra: &str) -> Scene {
    Scene::from_toml(&format!("{CABLE}{extra}")).expect("the test scene is valid")
}

#[test]
fn summary_leaves_out_energies_that_do_nothing() {
    // A load on for the first 0.05 s only: its energy is exactly zero at the end.
    let scene =
        cable_with("[[loads]]\nat = 0.5\npath = [[0.0, 0.0, 1e-3, 0.0], [0.05, 0.0, 0.0, 0.0]]\n");
    let result = splinerod::run(&scene).expect("the run succeeds");
    assert_eq!(result.energy.get("load"), Some(&0.0), "{:?}", result.energy);
    let summary = result.summary();
    let line = summary
        .lines()
        .find(|l| l.starts_with("energy (J): "))
        .expect(&summary);
    assert!(!line.contains("load"), "{summary}");
    assert!(
        line.contains("stretch ") && line.contains("kinetic "),
        "{summary}"
    );
}

#[test]
fn summary_has_no_contact_line_when_nothing_touched() {
    let text = CABLE.replace(
        "control_points = 12\n",
        "control_points = 12\nradius = 0.005\n",
    );
    let scene = Scene::from_toml(&format!("{text}[contact]\nstiffness = 1e4\n")).expect("valid");
    let result = splinerod::run(&scene).expect("the run succeeds");
    let contact = result.contact.expect("contact statistics");
    assert_eq!((contact.max_pairs, contact.max_obstacle_contacts), (0, 0));
    assert!(
        !result.summary().contains("contact"),
        "{}",
        result.summary()
    );
}

#[test]
fn summary_counts_the_points_on_the_floor() {
    let scene = splinerod::bundled::scene("ring_drop").expect("bundled scene");
    let result = splinerod::run(&scene).expect("the run succeeds");
    let contact = result.contact.expect("contact statistics");
    assert!(result.energy["contact"] > 0.0, "{:?}", result.energy);
    assert!(contact.max_obstacle_contacts > 0, "{contact:?}");
    let summary = result.summary();
    let expected = format!(
        "at most {} points against the floor,",
        contact.max_obstacle_contacts
    );
    assert!(summary.contains(&expected), "{summary}");
    assert!(
        !summary.contains("pairs"),
        "no strand touches another: {summary}"
    );
}

#[test]
fn ensemble_summary_names_its_member_and_spans_all() {
    let scene = cable_with("[ensemble]\ncount = 3\nseed = 1\nlinear_density = [0.05, 0.2]\n");
    let result = splinerod::run(&scene).expect("the run succeeds");
    assert_eq!(result.ensemble.len(), 3);
    let summary = result.summary();
    assert!(summary.contains("energy (J) of member 0: "), "{summary}");
    let sags: Vec<f64> = result.ensemble.iter().map(|m| m.sag).collect();
    let (lo, hi) = sags
        .iter()
        .fold((f64::MAX, f64::MIN), |(a, b), &s| (a.min(s), b.max(s)));
    assert!(hi > lo, "the members differ: {sags:?}");
    let expected = format!("ensemble: 3 members (0 to 2), sag {lo:.4e} to {hi:.4e} m");
    assert!(summary.contains(&expected), "{summary}");
}
