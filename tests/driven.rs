//! Pins driven along keyframed paths: the point is exactly on its path at every step,
//! a static solve uses the path's end, the midpoint rule's energy guard counts the
//! pins' work, and bad paths are refused naming the field.

use crate::common;

use common::{assert_field, rejected, sample_gap};
use nalgebra::Vector3;
use splinerod::path::{Interpolation, Path};
use splinerod::{run, Scene};

const SCENE: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 1.0
control_points = 12
end = [1.0, 0.0, 0.0]

[[pins]]
at = 0.0

[[pins]]
at = 1.0
path = [[0.0, 1.0, 0.0, 0.0], [0.5, 0.8, 0.1, 0.0], [1.0, 0.6, 0.2, 0.1]]
interpolation = "smooth"

[solver]
method = "implicit-euler"
dt = 0.01
duration = 1.5

[output]
probes = [1.0]
"#;

fn path_of(text: &str) -> Path {
    let scene = Scene::from_toml(text).expect("scene");
    let keyframes = scene.pins[1].path.clone().expect("path");
    Path::new(&keyframes, scene.pins[1].interpolation, "path").expect("path")
}

#[test]
fn a_driven_end_is_on_its_path_after_every_step() {
    for (method, interpolation) in [
        ("implicit-euler", "smooth"),
        ("bdf2", "linear"),
        ("implicit-midpoint", "smooth"),
    ] {
        let text = SCENE
            .replace("implicit-euler", method)
            .replace("\"smooth\"", &format!("\"{interpolation}\""));
        let path = path_of(&text);
        let result = run(&Scene::from_toml(&text).expect("scene")).expect("runs");
        let probe = &result.probes[0];
        let worst = probe
            .t
            .iter()
            .zip(&probe.positions)
            .map(|(&t, p)| (Vector3::from(*p) - path.at(t)).norm())
            .fold(0.0, f64::max);
        assert!(worst < 1e-9, "{method}: {worst:e} m off the path");
        // The energy guard of the midpoint rule counts the pin's work: with it 10 of
        // 150 sub-steps are rejected (the rule's own energy error under a pulled,
        // stiffening cable), without it 96. The other schemes have no guard.
        let held = text.replace(
            "path = [[0.0, 1.0, 0.0, 0.0], [0.5, 0.8, 0.1, 0.0], [1.0, 0.6, 0.2, 0.1]]",
            "",
        );
        let held = run(&Scene::from_toml(&held).expect("scene")).expect("runs");
        let (driven, still) = (result.solver.rejected_steps, held.solver.rejected_steps);
        assert!(
            driven <= still + 20,
            "{method}: {driven} rejected, {still} held still"
        );
    }
}

#[test]
fn a_static_solve_holds_the_driven_pin_at_the_path_end() {
    let text = SCENE.replace(
        "method = \"implicit-euler\"\ndt = 0.01\nduration = 1.5",
        "method = \"static\"",
    );
    let driven = run(&Scene::from_toml(&text).expect("scene")).expect("static runs");
    assert_eq!(driven.time, 1.0);
    // The same equilibrium as a cable pinned there from the start.
    let direct = SCENE
        .replace("end = [1.0, 0.0, 0.0]", "end = [0.6, 0.2, 0.1]")
        .replace(
            "path = [[0.0, 1.0, 0.0, 0.0], [0.5, 0.8, 0.1, 0.0], [1.0, 0.6, 0.2, 0.1]]\ninterpolation = \"smooth\"\n",
            "",
        )
        .replace(
            "method = \"implicit-euler\"\ndt = 0.01\nduration = 1.5",
            "method = \"static\"",
        );
    let direct = run(&Scene::from_toml(&direct).expect("scene")).expect("static runs");
    let gap = sample_gap(&driven, &direct);
    assert!(gap < 1e-8, "{gap:e}");
}

#[test]
fn paths_pass_through_their_keyframes_smoothly() {
    let keyframes = [
        [0.0, 0.0, 0.0, 0.0],
        [1.0, 1.0, 0.0, 0.0],
        [3.0, 1.0, 2.0, 0.0],
    ];
    for interpolation in [Interpolation::Linear, Interpolation::Smooth] {
        let path = Path::new(&keyframes, interpolation, "p").expect("path");
        for k in keyframes {
            let p = path.at(k[0]);
            assert!((p - Vector3::new(k[1], k[2], k[3])).norm() < 1e-15);
        }
        assert_eq!(path.at(-1.0), Vector3::zeros());
        assert_eq!(path.at(9.0), Vector3::new(1.0, 2.0, 0.0));
    }
    // Smooth: the velocity is continuous at the inner keyframe and zero at the ends.
    let smooth = Path::new(&keyframes, Interpolation::Smooth, "p").expect("path");
    let v = |t: f64| (smooth.at(t + 1e-7) - smooth.at(t - 1e-7)) / 2e-7;
    let (before, after) = (v(1.0 - 1e-4), v(1.0 + 1e-4));
    assert!((before - after).norm() < 1e-3, "{before:?} {after:?}");
    assert!(v(1e-4).norm() < 1e-3 && v(3.0 - 1e-4).norm() < 1e-3);
}

#[test]
fn bad_paths_name_the_field() {
    let path = "path = [[0.0, 1.0, 0.0, 0.0], [0.5, 0.8, 0.1, 0.0], [1.0, 0.6, 0.2, 0.1]]";
    let cases = [
        (
            "[0.5, 0.8, 0.1, 0.0]",
            "[0.5, nan, 0.1, 0.0]",
            "pins[1].path[1]",
        ),
        (
            "[1.0, 0.6, 0.2, 0.1]",
            "[0.4, 0.6, 0.2, 0.1]",
            "pins[1].path[2]",
        ),
        (
            "[0.0, 1.0, 0.0, 0.0]",
            "[0.1, 1.0, 0.0, 0.0]",
            "pins[1].path[0]",
        ),
        (
            "[0.0, 1.0, 0.0, 0.0]",
            "[0.0, 0.7, 0.0, 0.0]",
            "pins[1].path[0]",
        ),
        (path, "path = []", "pins[1].path"),
        (
            "interpolation = \"smooth\"",
            "interpolation = \"wavy\"",
            "wavy",
        ),
    ];
    for (from, to, field) in cases {
        assert!(SCENE.contains(from), "{from}");
        assert_field(&rejected(&SCENE.replace(from, to)), field);
    }
}

#[test]
fn only_stages_with_work_are_timed() {
    // A driven pin: the drivers stage has work and is timed.
    let driven = run(&Scene::from_toml(SCENE).expect("scene")).expect("run");
    assert!(
        driven.stage_seconds.drivers > 0.0,
        "{:?}",
        driven.stage_seconds
    );
    // Nothing driven, no estimator, no adapter: those stages read no clock and stay
    // at zero; the solves are still timed.
    let still = SCENE.replace(
        "path = [[0.0, 1.0, 0.0, 0.0], [0.5, 0.8, 0.1, 0.0], [1.0, 0.6, 0.2, 0.1]]\ninterpolation = \"smooth\"\n",
        "",
    );
    assert_ne!(still, SCENE);
    let s = run(&Scene::from_toml(&still).expect("scene"))
        .expect("run")
        .stage_seconds;
    assert_eq!((s.drivers, s.adapt), (0.0, 0.0), "{s:?}");
    assert!(s.integrate > 0.0 && s.setup > 0.0, "{s:?}");
}
