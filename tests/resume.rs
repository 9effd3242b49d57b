//! Checkpoints and resume at the command line: a run stopped at any step (by
//! `--max-steps` or a signal) with `--checkpoint DIR` and continued by `splinerod resume
//! DIR` writes the same JSON, stats CSV, ParaView files and USD layer as the run never stopped, bit
//! for bit but for wall-clock times — for every integrator, an adaptive scene, a scene
//! with cuts, contact with friction, twist, several rods, an ensemble (and a shard of
//! it) and a static solve, also when stopped on the step of a cut or of a knot change.
//! Foreign and damaged checkpoints are refused with one line.

use crate::common;

use common::cli::{fresh_dir as dir, ok, refused, scene_variant as variant};
use serde_json::Value;
use std::path::Path;
use std::process::Command;

/// The JSON without its wall-clock fields and the count of symbolic analyses (a
/// resumed process analyses the sparse pattern it meets once more: work, not results).
fn result(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).expect("JSON written");
    let mut v: Value = serde_json::from_str(&text).expect("JSON");
    let map = v.as_object_mut().expect("object");
    for key in ["wall_seconds", "median_step_seconds", "stage_seconds"] {
        map.remove(key);
    }
    if let Some(solver) = map.get_mut("solver").and_then(Value::as_object_mut) {
        solver.remove("symbolic_analyses");
    }
    v
}

/// The stats CSV without its wall-clock columns.
fn stats(path: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(path).expect("stats written");
    let rows: Vec<Vec<&str>> = text.lines().map(|l| l.split(',').collect()).collect();
    let keep: Vec<usize> = (0..rows[0].len())
        .filter(|&i| !rows[0][i].ends_with("seconds"))
        .collect();
    rows.iter()
        .map(|r| keep.iter().map(|&i| r[i].to_string()).collect())
        .collect()
}

/// Runs `scene` whole, and again stopped after each of `stops` steps (each stop resumed
/// from the last checkpoint), with JSON, stats and VTK; the outputs must be equal.
fn resumes_exactly(test: &str, scene: &Path, stops: &[usize]) {
    resumes_exactly_with(test, scene, &[], stops);
}

/// [`resumes_exactly`] with `extra` arguments to both runs.
fn resumes_exactly_with(test: &str, scene: &Path, extra: &[&str], stops: &[usize]) {
    let d = dir(&format!("{test}-runs"));
    let outputs = |tag: &str| {
        let o = d.join(tag);
        std::fs::create_dir_all(&o).expect("dir");
        let args = [
            "--json", "r.json", "--stats", "s.csv", "--vtk", "vtk", "--every", "7", "--usd",
            "u.usda",
        ];
        let args: Vec<String> = args
            .iter()
            .map(|a| match *a {
                "r.json" | "s.csv" | "vtk" | "u.usda" => o.join(a).display().to_string(),
                a => a.to_string(),
            })
            .collect();
        (o, args)
    };
    let scene = scene.to_str().unwrap();
    let (whole, args) = outputs("whole");
    let mut line = vec!["run", scene];
    line.extend(args.iter().map(String::as_str));
    line.extend(extra);
    ok(&line);
    let (parts, args) = outputs("parts");
    let ck = d.join("ck");
    let ck = ck.to_str().unwrap();
    let first = stops[0].to_string();
    let mut line = vec!["run", scene, "--checkpoint", ck, "--max-steps", &first];
    line.extend(args.iter().map(String::as_str));
    line.extend(extra);
    ok(&line);
    for stop in &stops[1..] {
        ok(&["resume", ck, "--max-steps", &stop.to_string()]);
    }
    ok(&["resume", ck]);
    assert_eq!(
        result(&whole.join("r.json")),
        result(&parts.join("r.json")),
        "{test}: JSON"
    );
    assert_eq!(
        stats(&whole.join("s.csv")),
        stats(&parts.join("s.csv")),
        "{test}: stats"
    );
    let files = |o: &Path| {
        let mut names: Vec<_> = std::fs::read_dir(o.join("vtk"))
            .expect("vtk")
            .map(|e| e.expect("entry").file_name())
            .collect();
        names.sort();
        names
    };
    let usd = |o: &Path| std::fs::read(o.join("u.usda")).expect("usd file");
    assert!(usd(&whole) == usd(&parts), "{test}: the USD layer differs");
    assert_eq!(files(&whole), files(&parts), "{test}: VTK files");
    for name in files(&whole) {
        let read = |o: &Path| std::fs::read(o.join("vtk").join(&name)).expect("vtk file");
        assert!(read(&whole) == read(&parts), "{test}: {name:?} differs");
    }
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn implicit_euler_resumes_exactly() {
    resumes_exactly(
        "euler",
        Path::new("scenes/hanging_cable.toml"),
        &[333, 1200],
    );
}

#[test]
fn midpoint_and_bdf2_resume_exactly() {
    let d = dir("schemes");
    resumes_exactly("midpoint", Path::new("scenes/string_midpoint.toml"), &[101]);
    let bdf2 = variant(
        &d,
        "hanging_cable.toml",
        &[
            ("\"implicit-euler\"", "\"bdf2\""),
            ("duration = 10.0", "duration = 3.0"),
        ],
    );
    resumes_exactly("bdf2", &bdf2, &[1, 250]);
}

#[test]
fn a_scene_with_a_rigid_body_resumes_exactly() {
    resumes_exactly("bodies", Path::new("scenes/body_pendulum.toml"), &[300]);
    // BDF2 keeps the bodies' motion a step back in its history: stopped after its
    // Euler start step and in mid-run.
    let d = dir("bodies-bdf2");
    let bdf2 = variant(
        &d,
        "body_pendulum.toml",
        &[
            ("\"implicit-euler\"", "\"bdf2\""),
            ("duration = 4.3", "duration = 1.5"),
        ],
    );
    resumes_exactly("bodies-bdf2", &bdf2, &[1, 170]);
    // Friction on a body's shapes keeps nothing across steps (its contacts are frozen
    // again at every step's start): stopped while the towed block slides.
    resumes_exactly("bodies-friction", Path::new("scenes/body_tow.toml"), &[260]);
}

#[test]
fn static_solve_resumes_exactly() {
    resumes_exactly("static", Path::new("scenes/catenary_static.toml"), &[0]);
}

#[test]
fn adaptive_cut_and_twist_scenes_resume_exactly() {
    resumes_exactly("adaptive", Path::new("scenes/grab_adaptive.toml"), &[377]);
    resumes_exactly("cuts", Path::new("scenes/cut_three.toml"), &[60, 100]);
    let d = dir("twist");
    let twist = variant(
        &d,
        "twist_buckling.toml",
        &[("duration = 11.0", "duration = 2.0")],
    );
    resumes_exactly("twist", &twist, &[123]);
}

/// A free rod with contact and a floor, cut at 0.883 at t = 0.05 s (step 50): the cut
/// changes the contact samples' layout. Here the outputs (the stats' contact energy)
/// detect contact again after the cut; `tests/checkpoints.rs` takes the same checkpoint
/// without outputs, the case that once failed ("contact samples of another rod").
const FREE_CUT: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 0.5
control_points = 10
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.2]
radius = 0.01

[[cuts]]
at = 0.883
time = 0.05

[contact]
stiffness = 1e5
floor = -0.05

[solver]
method = "implicit-euler"
dt = 0.001
duration = 0.2
"#;

/// The steps (1-based) after which the control points' count changed, from a run's
/// stats: the first `count` of them.
fn knot_change_steps(test: &str, scene: &Path, count: usize) -> Vec<usize> {
    let d = dir(&format!("{test}-steps"));
    let csv = d.join("s.csv");
    ok(&[
        "run",
        scene.to_str().unwrap(),
        "--stats",
        csv.to_str().unwrap(),
    ]);
    let rows = stats(&csv);
    let column = rows[0].iter().position(|c| c == "control_points");
    let column = column.expect("control_points column");
    let points: Vec<usize> = rows[1..]
        .iter()
        .map(|r| r[column].parse().unwrap())
        .collect();
    let changed = (1..points.len()).filter(|&i| points[i] != points[i - 1]);
    let steps: Vec<usize> = changed.map(|i| i + 1).take(count).collect();
    std::fs::remove_dir_all(&d).ok();
    assert_eq!(steps.len(), count, "{test}: too few knot changes");
    steps
}

#[test]
fn checkpoints_on_the_steps_of_cuts_and_knot_changes_resume_exactly() {
    let d = dir("cut-steps");
    let free = d.join("free_cut.toml");
    std::fs::write(&free, FREE_CUT).expect("scene written");
    resumes_exactly("free-cut", &free, &[49, 50, 51]);
    let contact = variant(
        &d,
        "cut_contact.toml",
        &[("duration = 2.0", "duration = 0.7")],
    );
    resumes_exactly("cut-contact", &contact, &[200, 400, 600]);
    // Insertions and removals (grab), insertions with self-contact (knot).
    let grab = Path::new("scenes/grab_adaptive.toml");
    resumes_exactly("grab-steps", grab, &knot_change_steps("grab", grab, 6));
    let knot = variant(
        &d,
        "knot_tying_adaptive.toml",
        &[("duration = 3.0", "duration = 0.3")],
    );
    resumes_exactly("knot-steps", &knot, &knot_change_steps("knot", &knot, 4));
}

#[test]
fn contact_with_friction_resumes_exactly() {
    let d = dir("friction");
    let pileup = variant(
        &d,
        "rope_pileup.toml",
        &[("duration = 2.5", "duration = 0.6")],
    );
    resumes_exactly("friction", &pileup, &[50, 157, 250]);
    let knot = variant(
        &d,
        "knot_tying_adaptive.toml",
        &[("duration = 3.0", "duration = 0.6")],
    );
    resumes_exactly("knot", &knot, &[120, 299, 450]);
}

/// The barrier (no `stiffness`) and the adaptive penalty (`stiffness` and `tolerance`)
/// change their stiffness between steps: checkpoints keep it (#46).
#[test]
fn adapting_contact_stiffnesses_resume_exactly() {
    let d = dir("adapting");
    let barrier = variant(
        &d,
        "rope_pileup.toml",
        &[
            ("duration = 2.5", "duration = 0.6"),
            ("stiffness = 1e5\n", ""),
        ],
    );
    resumes_exactly("barrier", &barrier, &[50, 157, 250]);
    let adaptive = variant(
        &d,
        "knot_tying_adaptive.toml",
        &[
            ("duration = 3.0", "duration = 0.6"),
            ("stiffness = 1e4", "stiffness = 1e4\ntolerance = 1.5e-4"),
        ],
    );
    resumes_exactly("adaptive", &adaptive, &[120, 299, 450]);
}

#[test]
fn ensembles_resume_exactly() {
    let d = dir("ensemble");
    let scene = variant(
        &d,
        "ensemble_cables.toml",
        &[("count = 1000", "count = 12")],
    );
    resumes_exactly("ensemble", &scene, &[77]);
    resumes_exactly_with("shard", &scene, &["--shard", "2/3"], &[31, 150]);
}

#[test]
fn several_rods_in_contact_resume_exactly() {
    let d = dir("rods");
    let scene = variant(
        &d,
        "ropes_crossing.toml",
        &[("duration = 3.0", "duration = 0.8")],
    );
    resumes_exactly("rods", &scene, &[45, 111]);
}

#[cfg(unix)]
#[test]
fn an_interrupted_run_leaves_a_checkpoint_to_resume() {
    let d = dir("signal");
    let scene = variant(
        &d,
        "hanging_cable.toml",
        &[("duration = 10.0", "duration = 100.0")],
    );
    let (scene, ck) = (scene.to_str().unwrap(), d.join("ck"));
    let (whole, parts) = (d.join("whole.json"), d.join("parts.json"));
    ok(&["run", scene, "--json", whole.to_str().unwrap()]);
    let child = Command::new(env!("CARGO_BIN_EXE_splinerod"))
        .args(["run", scene, "--json", parts.to_str().unwrap()])
        .args(["--checkpoint", ck.to_str().unwrap(), "--vtk"])
        .arg(d.join("vtk"))
        .args(["--every", "100"])
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("spawn");
    let start = std::time::Instant::now();
    while !d.join("vtk").join("centreline_00002.vtp").exists() {
        assert!(start.elapsed().as_secs() < 120, "the run never got going");
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status();
    assert!(kill.expect("kill").success());
    let out = child.wait_with_output().expect("ends");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(130), "{stderr}");
    assert!(stderr.contains("interrupted: stopped at t = "), "{stderr}");
    let stopped = result(&parts);
    assert_eq!(stopped["interrupted"], true);
    ok(&["resume", ck.to_str().unwrap()]);
    assert_eq!(result(&whole), result(&parts));
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn foreign_and_damaged_checkpoints_are_refused() {
    let d = dir("foreign");
    let ck = d.join("ck");
    let resume = ["resume", ck.to_str().unwrap()];
    let refused = |what: &str| {
        let line = refused(&resume);
        println!("{what}: {line}");
        line
    };
    assert!(refused("missing").contains("checkpoint.bin"));
    std::fs::create_dir_all(&ck).expect("dir");
    std::fs::write(ck.join("checkpoint.bin"), b"PK\x03\x04 not ours").expect("write");
    assert!(refused("foreign").contains("not a splinerod checkpoint"));
    let scene = "scenes/hanging_cable.toml";
    ok(&[
        "run",
        scene,
        "--checkpoint",
        ck.to_str().unwrap(),
        "--max-steps",
        "5",
    ]);
    let path = ck.join("checkpoint.bin");
    let bytes = std::fs::read(&path).expect("checkpoint");
    // The header: the format string (length-prefixed), then the version (a varint).
    let at = 1 + "splinerod-checkpoint".len();
    let version = splinerod::run::checkpoint::VERSION;
    assert_eq!(u32::from(bytes[at]), version, "format version {version}");
    let mut old = bytes.clone();
    old[at] = 3;
    std::fs::write(&path, &old).expect("write");
    let line = refused("old");
    assert!(line.contains("no checksum (older format)") && line.contains("format 3"));
    std::fs::write(&path, &bytes[..bytes.len() / 2]).expect("write");
    assert!(refused("truncated").contains("damaged: checksum mismatch"));
    let mut flipped = bytes.clone();
    flipped[bytes.len() * 2 / 3] ^= 0x10;
    std::fs::write(&path, &flipped).expect("write");
    assert!(refused("one byte").contains("checksum mismatch"));
    // The scene text edited in place (the same length), nothing else.
    let text = std::fs::read_to_string(scene).expect("scene");
    let from = "duration = 10.0";
    assert!(text.contains(from));
    let at = bytes.windows(from.len()).position(|w| w == from.as_bytes());
    let mut edited = bytes.clone();
    let at = at.expect("the scene text in the checkpoint");
    edited[at..at + from.len()].copy_from_slice(b"duration = 90.0");
    std::fs::write(&path, &edited).expect("write");
    assert!(refused("edited scene").contains("scene hash mismatch"));
    std::fs::remove_dir_all(&d).ok();
}
