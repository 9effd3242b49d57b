//! Checkpoints through the library, with no outputs (so nothing but the run itself
//! detects contact between steps): a checkpoint taken on any step — that of a cut, of an
//! adaptive knot insertion or removal — resumes to the uninterrupted run's result, bit
//! for bit but for wall-clock times.

use splinerod::run::checkpoint::CheckpointPlan;
use splinerod::runner::{resume, run_controlled, RunControl};
use splinerod::{run, RunResult, Scene, SceneRun};
use std::path::{Path, PathBuf};

/// A free rod with contact and a floor, cut at 0.883 at t = 0.05 s (after step 50):
/// the cut changes the contact samples' layout (issue #45: a checkpoint on that step
/// could not be resumed, "contact samples of another rod").
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

/// `result` as JSON (exact: floats round-trip), without the wall-clock fields and the
/// count of symbolic analyses (a resumed run analyses the sparse pattern once more:
/// work, not results).
fn timeless(mut result: RunResult) -> String {
    result.wall_seconds = 0.0;
    result.median_step_seconds = 0.0;
    result.stage_seconds = Default::default();
    result.solver.symbolic_analyses = 0;
    serde_json::to_string(&result).expect("JSON")
}

/// A fresh, empty temporary directory for `test`.
fn fresh_dir(test: &str) -> PathBuf {
    let name = format!("splinerod-{}-checkpoints-{test}", std::process::id());
    let d = std::env::temp_dir().join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// The scene file `name` with each `(from, to)` replaced (each must occur).
fn variant(name: &str, edits: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(Path::new("scenes").join(name)).expect("scene");
    for (from, to) in edits {
        assert!(text.contains(from), "{name} has no `{from}`");
        text = text.replace(from, to);
    }
    text
}

/// Runs the scene of `text` for `steps` steps, writing its checkpoint into `dir`.
fn checkpoint_at(text: &str, dir: &Path, steps: usize) {
    let scene = Scene::from_toml(text).expect("scene");
    let control = RunControl {
        max_steps: Some(steps),
        checkpoint: Some(CheckpointPlan {
            dir: dir.to_path_buf(),
            every_seconds: f64::INFINITY,
            scene: text.to_string(),
            args: Vec::new(),
            shard: None,
        }),
        ..RunControl::default()
    };
    let stopped = run_controlled(&scene, &mut [], &control).expect("run until the stop");
    assert!(stopped.interrupted && stopped.steps == steps);
}

/// The checkpoint in `dir`, resumed to the end.
fn resumed(dir: &Path) -> Result<String, splinerod::Error> {
    resume(dir, &mut [], &RunControl::default()).map(timeless)
}

/// Checkpoints the scene of `text` after each of `stops` steps and resumes each: every
/// resumed run must end as the uninterrupted one.
fn resumes_exactly(test: &str, text: &str, stops: &[usize]) {
    let whole = timeless(run(&Scene::from_toml(text).expect("scene")).expect("run"));
    let d = fresh_dir(test);
    for &stop in stops {
        checkpoint_at(text, &d, stop);
        let resumed = resumed(&d).unwrap_or_else(|e| panic!("{test}: step {stop}: {e}"));
        assert!(
            resumed == whole,
            "{test}: resumed after step {stop} differs"
        );
    }
    std::fs::remove_dir_all(&d).ok();
}

/// The steps (1-based) after which the count of control points changed, the first
/// `count` of them.
fn knot_change_steps(text: &str, count: usize) -> Vec<usize> {
    let scene = Scene::from_toml(text).expect("scene");
    let mut driven = SceneRun::new(&scene).expect("scene run");
    let points = |r: &SceneRun| r.members()[0].system.rod.len();
    let mut steps = Vec::new();
    while steps.len() < count && driven.stages_done() < driven.stage_count() {
        let before = points(&driven);
        driven.advance(1).expect("step");
        if points(&driven) != before {
            steps.push(driven.stages_done());
        }
    }
    assert_eq!(steps.len(), count, "too few knot changes");
    steps
}

#[test]
fn a_checkpoint_on_the_step_of_a_cut_resumes_exactly() {
    resumes_exactly("free-cut", FREE_CUT, &[49, 50, 51, 120]);
    let contact = variant("cut_contact.toml", &[("duration = 2.0", "duration = 0.7")]);
    resumes_exactly("cut-contact", &contact, &[200, 400, 600]);
}

#[test]
fn a_checkpoint_on_the_step_of_a_knot_change_resumes_exactly() {
    // Insertions and removals.
    let grab = variant("grab_adaptive.toml", &[]);
    let steps = knot_change_steps(&grab, 8);
    println!("grab_adaptive: knot changes after steps {steps:?}");
    resumes_exactly("grab", &grab, &steps);
    // Insertions with self-contact.
    let knot = variant(
        "knot_tying_adaptive.toml",
        &[("duration = 3.0", "duration = 0.3")],
    );
    let steps = knot_change_steps(&knot, 4);
    println!("knot_tying_adaptive: knot changes after steps {steps:?}");
    resumes_exactly("knot", &knot, &steps);
}
