//! `SceneRun`: a scene driven stage by stage reports what `run` reports, bit for bit but
//! the wall-clock fields, also when its result is taken along the way.

use splinerod::{run, RunResult, Scene, SceneRun};
use std::path::Path;

/// `result` with the wall-clock fields zeroed.
fn timeless(mut result: RunResult) -> RunResult {
    result.wall_seconds = 0.0;
    result.median_step_seconds = 0.0;
    result.stage_seconds = Default::default();
    result
}

fn scene(path: &str) -> Scene {
    Scene::load(Path::new(path)).expect("scene")
}

/// Drives `scene` in chunks of `chunk` stages, taking its result after every chunk, and
/// compares the final result with one `run`.
fn drives_like_run(scene: &Scene, chunk: usize) {
    let expected = timeless(run(scene).expect("run"));
    let mut driven = SceneRun::new(scene).expect("scene run");
    while driven.stages_done() < driven.stage_count() {
        let left = driven.stage_count() - driven.stages_done();
        driven.advance(chunk.min(left)).expect("advance");
        let partial = driven.result().expect("result");
        assert_eq!(
            partial.interrupted,
            driven.stages_done() < driven.stage_count()
        );
    }
    assert_eq!(timeless(driven.result().expect("result")), expected);
}

#[test]
fn a_driven_dynamic_scene_reports_what_run_reports() {
    drives_like_run(&scene("scenes/hanging_cable.toml"), 250);
}

#[test]
fn a_driven_adaptive_scene_with_estimates_reports_what_run_reports() {
    drives_like_run(&scene("scenes/grab_adaptive.toml"), 97);
}

#[test]
fn a_driven_scene_with_cuts_and_a_static_scene_report_what_run_reports() {
    drives_like_run(&scene("scenes/cut_three.toml"), 13);
    drives_like_run(&scene("scenes/catenary_static.toml"), 1);
}

#[test]
fn a_driven_ensemble_reports_what_run_reports() {
    let text = std::fs::read_to_string("scenes/ensemble_cables.toml").expect("scene");
    let text = text
        .replace("count = 1000", "count = 5")
        .replace("duration = 2.0", "duration = 0.3");
    drives_like_run(&Scene::from_toml(&text).expect("scene"), 7);
}

#[test]
fn stages_past_the_duration_and_member_access() {
    let scene = scene("scenes/hanging_cable.toml");
    let mut driven = SceneRun::new(&scene).expect("scene run");
    assert_eq!(driven.members().len(), 1);
    assert!(driven.member_mut(1).is_none());
    let n = driven.stage_count();
    driven.advance(n + 3).expect("advance");
    assert_eq!(driven.members()[0].steps, n + 3);
    assert!(!driven.result().expect("result").interrupted);
    let forces = driven.pin_forces(0).expect("member 0");
    // The cable's weight pulls its pins down.
    let pulled: f64 = forces.iter().map(|f| f.y).sum();
    assert!((pulled + 0.1 * 9.81).abs() < 1e-6, "pins carry {pulled} N");
}
