//! Forward sensitivities of runs (#48) against central finite differences of two full
//! runs (two step sizes, extrapolated): a swinging cable and a grabbed cable, each with
//! implicit Euler and BDF2, over 1 s, for EA, EI, the density, the damping, gravity, a
//! point load and the rest length; refused runs and bad parameters named.

use splinerod::sensitivity::{dynamic_sensitivities, set_parameter};
use splinerod::{Real, Scene};

/// A cable pinned at one end, released horizontally under gravity (with a side
/// component), bending, damping and a point load.
const SWINGING: &str = "[rod]\nrest_length = 1.0\nlinear_density = 0.1\n\
    stretch_stiffness = 200.0\nbending_stiffness = 1e-3\ndamping = 0.3\n\
    control_points = 12\nstart = [0.0, 0.0, 0.0]\nend = [1.0, 0.0, 0.0]\n\n\
    [[pins]]\nat = 0.0\n\n[world]\ngravity = [0.5, -9.81, 0.0]\n\n\
    [[loads]]\nat = 0.7\nforce = [0.0, 0.05, 0.02]\n\n\
    [solver]\nmethod = \"METHOD\"\ndt = 0.01\nduration = 1.0\ntolerance = 1e-13\n\n\
    [output]\nsamples = 21\n";

/// A cable pinned at both ends (its span its length), grabbed at 30 % from t = 0.2 s (where the point
/// then is: the grab's start depends on the parameters) and pulled aside by t = 0.6 s.
const GRABBED: &str = "[rod]\nrest_length = 1.0\nlinear_density = 0.1\n\
    stretch_stiffness = 100.0\nbending_stiffness = 2e-3\ndamping = 1.0\n\
    control_points = 14\nstart = [0.0, 0.0, 0.0]\nend = [1.0, 0.0, 0.0]\n\n\
    [[pins]]\nat = 0.0\n\n[[pins]]\nat = 1.0\n\n\
    [world]\ngravity = [0.0, -9.81, 0.0]\n\n\
    [[grabs]]\nat = 0.3\nto = [0.3, -0.25, 0.1]\nstart_time = 0.2\nend_time = 0.6\n\
    stiffness = 500.0\n\n\
    [solver]\nmethod = \"METHOD\"\ndt = 0.01\nduration = 1.0\ntolerance = 1e-13\n\n\
    [output]\nsamples = 21\n";

/// The scene `text` stepped by `method`.
fn scene(text: &str, method: &str) -> Scene {
    Scene::from_toml(&text.replace("METHOD", method)).expect("scene")
}

/// The final samples of a full run of `scene`, then its pin forces (the last step's).
fn samples(scene: &Scene) -> Vec<[Real; 3]> {
    let result = splinerod::run(scene).expect("run");
    let mut out = result.samples.positions;
    out.extend(result.pin_forces);
    out
}

/// The final samples (and pin forces) of `scene` with parameter `path` at `value`.
fn perturbed(scene: &Scene, path: &str, value: Real) -> Vec<[Real; 3]> {
    let mut s = scene.clone();
    set_parameter(&mut s, path, value).expect("set");
    samples(&s)
}

thread_local! {
    /// The differences' relative step: 1e-3, but where a test says otherwise
    /// ([`check_with_step`]).
    static RELATIVE_STEP: std::cell::Cell<Real> = const { std::cell::Cell::new(1e-3) };
}

/// [`check`] with the differences' relative step `step`.
fn check_with_step(scene: &Scene, paths: &[&str], step: Real) -> Real {
    RELATIVE_STEP.with(|r| r.set(step));
    let worst = check(scene, paths);
    RELATIVE_STEP.with(|r| r.set(1e-3));
    worst
}

/// The largest relative error of `exact` (per sample) against the central differences
/// of runs at h and h/2 (relative 1e-3 unless [`check_with_step`]), extrapolated; with `forces`, of the pin forces'
/// derivatives too (each part against its own largest derivative).
fn error_against_runs(
    scene: &Scene,
    path: &str,
    value: Real,
    (exact, forces): (&[[Real; 3]], &[[Real; 3]]),
) -> Real {
    let central = |h: Real| -> Vec<[Real; 3]> {
        let (a, b) = (
            perturbed(scene, path, value + h),
            perturbed(scene, path, value - h),
        );
        let pairs = a.iter().zip(&b);
        pairs
            .map(|(a, b)| std::array::from_fn(|c| (a[c] - b[c]) / (2.0 * h)))
            .collect()
    };
    let h = RELATIVE_STEP.with(|r| r.get()) * value.abs().max(1e-3);
    let (coarse, fine) = (central(h), central(h / 2.0));
    let mut worst: Real = 0.0;
    let mut report = String::new();
    for (part, (exact, offset)) in [(exact, 0), (forces, exact.len())].into_iter().enumerate() {
        let largest = exact
            .iter()
            .flatten()
            .fold(0.0, |m: Real, x| m.max(x.abs()));
        let mut error: Real = 0.0;
        let rows = exact.iter().zip(&coarse[offset..]).zip(&fine[offset..]);
        for ((d, c), f) in rows {
            for i in 0..3 {
                let extrapolated = (4.0 * f[i] - c[i]) / 3.0;
                error = error.max((d[i] - extrapolated).abs() / largest.max(1e-300));
            }
        }
        if !exact.is_empty() {
            let what = ["samples", "pin forces"][part];
            report += &format!(" {what}: up to {largest:.3e}, relative error {error:.2e};");
        }
        worst = worst.max(error);
    }
    println!("{path} = {value}:{report}");
    worst
}

/// Checks the final sensitivities of `scene` to `paths` against runs; the worst error.
fn check(scene: &Scene, paths: &[&str]) -> Real {
    let exact = dynamic_sensitivities(scene, paths).expect("sensitivities");
    let base = samples(scene);
    for (p, q) in exact.at.iter().chain(&exact.forces).zip(&base) {
        let gap = (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, Real::max);
        assert!(gap < 1e-12, "the sensitivities' run is the run: {gap:e}");
    }
    let steps = exact.times.len();
    assert_eq!(steps, scene.step_count(), "one record per step");
    assert!((exact.times[steps - 1].t - 1.0).abs() < 1e-12);
    assert_eq!(exact.times[steps - 1].positions, exact.positions);
    let mut worst: Real = 0.0;
    for (k, path) in paths.iter().enumerate() {
        let value = exact.parameters[k].1;
        let derivatives = (&exact.positions[k][..], &exact.pin_forces[k][..]);
        worst = worst.max(error_against_runs(scene, path, value, derivatives));
    }
    worst
}

const SWINGING_PARAMETERS: [&str; 7] = [
    "rod.stretch_stiffness",
    "rod.bending_stiffness",
    "rod.linear_density",
    "rod.damping",
    "world.gravity[1]",
    "world.gravity[0]",
    "loads[0].force[2]",
];

/// The swinging cable's rest length against differences at a relative step 1e-4: its
/// end is fixed, so a step starts the cable stretched or compressed by it, and at 1e-3
/// the differences' truncation is 7e-5 / 6e-4 of BDF2's samples / pin forces (at 1e-4:
/// 6e-9 / 2e-8).
fn rest_length_error(scene: &Scene) -> Real {
    check_with_step(scene, &["rod.rest_length"], 1e-4)
}

const GRABBED_PARAMETERS: [&str; 4] = [
    "rod.bending_stiffness",
    "rod.linear_density",
    "rod.damping",
    "world.gravity[1]",
];

#[test]
fn a_swinging_cable_s_implicit_euler_sensitivities_match_finite_differences() {
    let swinging = scene(SWINGING, "implicit-euler");
    let error = check(&swinging, &SWINGING_PARAMETERS).max(rest_length_error(&swinging));
    assert!(error < 1e-4, "relative error {error:e}");
}

#[test]
fn a_swinging_cable_s_bdf2_sensitivities_match_finite_differences() {
    let swinging = scene(SWINGING, "bdf2");
    let error = check(&swinging, &SWINGING_PARAMETERS).max(rest_length_error(&swinging));
    assert!(error < 1e-4, "relative error {error:e}");
}

#[test]
fn a_cable_whose_start_follows_its_rest_length_has_its_sensitivities() {
    // Without rod.end the cable starts straight along x for its length: the start moves
    // with the rest length (S_q(0) = (q₀ − start)/L), and so does the mass matrix.
    for method in ["implicit-euler", "bdf2"] {
        let text = SWINGING.replace("end = [1.0, 0.0, 0.0]\n", "");
        let error = check(&scene(&text, method), &["rod.rest_length"]);
        assert!(error < 1e-4, "{method}: relative error {error:e}");
    }
}

#[test]
fn a_grabbed_cable_s_implicit_euler_sensitivities_match_finite_differences() {
    let error = check(&scene(GRABBED, "implicit-euler"), &GRABBED_PARAMETERS);
    assert!(error < 1e-4, "relative error {error:e}");
}

#[test]
fn a_grabbed_cable_s_bdf2_sensitivities_match_finite_differences() {
    let error = check(&scene(GRABBED, "bdf2"), &GRABBED_PARAMETERS);
    assert!(error < 1e-4, "relative error {error:e}");
}

#[test]
fn the_recorded_times_carry_the_derivatives_of_the_trajectory() {
    // At t = 0.5 s: the record against runs of half the duration.
    let full = scene(SWINGING, "bdf2");
    let exact = dynamic_sensitivities(&full, &["rod.bending_stiffness"]).expect("run");
    let half = &exact.times[49];
    assert!((half.t - 0.5).abs() < 1e-12);
    let mut short = full.clone();
    short.solver.duration = Some(0.5);
    let error = error_against_runs(
        &short,
        "rod.bending_stiffness",
        exact.parameters[0].1,
        (&half.positions[0], &[]),
    );
    assert!(error < 1e-4, "relative error {error:e}");
    // During the grab's pull (from its start at 0.2 s to 0.6 s), whose start point moves
    // with the parameters.
    let grabbed = scene(GRABBED, "implicit-euler");
    let exact_grab = dynamic_sensitivities(&grabbed, &["rod.linear_density"]).expect("run");
    let mut short = grabbed.clone();
    short.solver.duration = Some(0.4);
    let pulled = &exact_grab.times[39];
    assert!((pulled.t - 0.4).abs() < 1e-12);
    let value = exact_grab.parameters[0].1;
    let derivatives = (&pulled.positions[0][..], &[][..]);
    let error = error_against_runs(&short, "rod.linear_density", value, derivatives);
    assert!(error < 1e-4, "relative error {error:e}");
    let json = exact.json();
    let times = json["times"].as_array().expect("times");
    assert_eq!(times.len(), 100);
    assert!(times[49]["positions"]["rod.bending_stiffness"][20][1].is_number());
}

#[test]
fn unsupported_runs_and_parameters_are_named() {
    let base = scene(SWINGING, "implicit-euler");
    let midpoint = scene(SWINGING, "implicit-midpoint");
    let e = dynamic_sensitivities(&midpoint, &["rod.damping"]).expect_err("midpoint");
    assert!(e.to_string().contains("solver.method"), "{e}");
    let mut tolerance = base.clone();
    tolerance.solver.time_tolerance = Some(1e-4);
    let e = dynamic_sensitivities(&tolerance, &["rod.damping"]).expect_err("tolerance");
    assert!(e.to_string().contains("solver.time_tolerance"), "{e}");
    let adaptive = Scene::load(format!(
        "{}/scenes/grab_adaptive.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("scene");
    let e = dynamic_sensitivities(&adaptive, &["rod.damping"]).expect_err("adaptive");
    assert!(e.to_string().contains("adaptivity"), "{e}");
    // A slack cable released straight (compressed): its first step needs sub-steps.
    let slack = GRABBED
        .replace("METHOD", "implicit-euler")
        .replace("end = [1.0, 0.0, 0.0]", "end = [0.8, 0.0, 0.0]");
    let slack = Scene::from_toml(&slack).expect("scene");
    let e = dynamic_sensitivities(&slack, &["rod.damping"]).expect_err("sub-steps");
    assert!(
        e.to_string().contains("solver.dt") && e.to_string().contains("sub-steps"),
        "{e}"
    );
    for (path, words) in [
        ("rod.radius", "not a rod parameter"),
        ("rod.twist_stiffness", "no energy"),
        ("loads[1].force[0]", "1 [[loads]]"),
        ("world.gravity", "not a scalar parameter"),
    ] {
        let e = dynamic_sensitivities(&base, &[path])
            .expect_err(path)
            .to_string();
        assert!(e.contains(path) && e.contains(words), "{path}: {e}");
    }
}

#[test]
fn the_command_line_writes_a_run_s_sensitivities_and_names_bad_input() {
    use crate::common::cli::{fresh_dir, ok, refused};
    let dir = fresh_dir("dynamic_sensitivities");
    let path = dir.join("swinging.toml");
    let short = SWINGING
        .replace("METHOD", "bdf2")
        .replace("duration = 1.0", "duration = 0.1");
    std::fs::write(&path, short).expect("scene written");
    let (scene, json) = (path.to_str().unwrap(), dir.join("s.json"));
    let json = json.to_str().unwrap();
    let params = "--params=rod.damping,loads[0].force[1]";
    ok(&["sensitivities", scene, params, "--json", json]);
    let text = std::fs::read_to_string(json).expect("written");
    let value: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    assert_eq!(value["parameters"][0]["name"], "rod.damping");
    let times = value["times"].as_array().expect("times");
    assert_eq!(times.len(), 10);
    let last = &times[9];
    assert!((last["t"].as_f64().unwrap() - 0.1).abs() < 1e-12);
    assert_eq!(
        last["positions"]["loads[0].force[1]"],
        value["positions"]["loads[0].force[1]"]
    );
    assert_eq!(
        value["positions"]["rod.damping"].as_array().unwrap().len(),
        21
    );
    let line = refused(&["sensitivities", scene, "--params=rod.colour"]);
    assert!(line.contains("rod.colour"), "{line}");
    let midpoint = dir.join("midpoint.toml");
    let text = SWINGING.replace("METHOD", "implicit-midpoint");
    std::fs::write(&midpoint, text).expect("scene written");
    let midpoint = midpoint.to_str().unwrap();
    let line = refused(&["sensitivities", midpoint, "--params=rod.damping"]);
    assert!(line.contains("solver.method"), "{line}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_cable_swinging_onto_a_plane_s_sensitivities_are_close_to_finite_differences() {
    // The swinging cable's end sweeps down onto a plane (the barrier contact, whose
    // stiffness follows the loads; no friction). Not exact (measured: samples 1e-5 …
    // 4e-5, pin forces up to 4e-4, against 1e-9 without contact): the barrier adapts its
    // stiffness at every step's start from the smallest gap, a dependence on the state
    // the forward step holds fixed — the likely cause, not fully diagnosed (with an
    // explicit stiffness EA's error falls to 1e-7, the density's stays 2e-5).
    let text = SWINGING
        .replace("METHOD", "implicit-euler")
        .replace("control_points = 12", "control_points = 12\nradius = 0.01")
        .replace("dt = 0.01", "dt = 0.002")
        + "\n[contact]\n\n[[obstacles]]\nkind = \"plane\"\n\
           point = [0.0, -0.7, 0.0]\nnormal = [0.0, 1.0, 0.0]\n";
    let scene = Scene::from_toml(&text).expect("scene");
    let free = samples(&self::scene(SWINGING, "implicit-euler"));
    let moved = samples(&scene)
        .iter()
        .zip(&free)
        .map(|(a, b)| (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, Real::max))
        .fold(0.0, Real::max);
    assert!(moved > 1e-2, "the plane changes the run: {moved} m");
    let error = check(
        &scene,
        &["rod.stretch_stiffness", "rod.linear_density", "rod.damping"],
    );
    assert!(error < 1e-3, "relative error {error:e}");
}

#[test]
fn a_cable_pinned_between_control_points_matches_finite_differences() {
    // A pin at a material point that is no control point goes through the Schur
    // complement: its force's derivative comes from the whole matrix with the mixed
    // stretching's remainder (from the banded step alone it was 4.6e-2 off).
    let text = SWINGING
        .replace("METHOD", "bdf2")
        .replace("[[pins]]\nat = 0.0", "[[pins]]\nat = 0.37");
    let scene = Scene::from_toml(&text).expect("scene");
    let error = check(&scene, &["rod.linear_density", "world.gravity[1]"]);
    assert!(error < 1e-4, "relative error {error:e}");
}

#[test]
fn a_run_s_pin_position_sensitivities_match_finite_differences() {
    // The pinned end held away from where it starts: the first step moves it there
    // (the start does not depend on the parameter), every step's constraint follows.
    for method in ["implicit-euler", "bdf2"] {
        let swinging = scene(SWINGING, method);
        let error = check(&swinging, &["pins[0].position[1]", "pins[0].position[2]"]);
        assert!(error < 1e-4, "{method}: relative error {error:e}");
        // The grabbed cable's far end moved along the span and across (the span set
        // at z = 0 by a shifted start: the differences' step is then 1e-6 m).
        let grabbed = GRABBED
            .replace("start = [0.0, 0.0, 0.0]", "start = [-1.0, 0.0, 0.0]")
            .replace("end = [1.0, 0.0, 0.0]", "end = [0.0, 0.0, 0.0]")
            .replace("to = [0.3, -0.25, 0.1]", "to = [-0.7, -0.25, 0.1]");
        let error = check(
            &scene(&grabbed, method),
            &["pins[1].position[0]", "pins[1].position[1]"],
        );
        assert!(error < 1e-4, "{method}: relative error {error:e}");
    }
    // A driven pin: the parameter offsets its whole path.
    let driven = SWINGING.replace(
        "[[pins]]\nat = 0.0",
        "[[pins]]\nat = 0.0\npath = [[0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.1, 0.05]]",
    );
    let error = check(&scene(&driven, "bdf2"), &["pins[0].position[0]"]);
    assert!(error < 1e-4, "driven: relative error {error:e}");
}

/// A cable lying on a plane with friction (a fixed contact stiffness), pinned at one
/// end, its free end pulled across the plane: it turns about the pin, sliding.
const ON_PLANE: &str = "[rod]\nrest_length = 1.0\nlinear_density = 0.1\n\
    stretch_stiffness = 200.0\nbending_stiffness = 1e-3\ndamping = 0.3\nradius = 0.01\n\
    control_points = 12\nstart = [0.0, 0.0105, 0.0]\nend = [1.0, 0.0105, 0.0]\n\n\
    [[pins]]\nat = 0.0\n\n[world]\ngravity = [0.0, -9.81, 0.0]\n\n\
    [[loads]]\nat = 1.0\nforce = [0.0, 0.0, 0.4]\n\n\
    [contact]\nfriction = 0.3\nstiffness = 1e4\n\n\
    [[obstacles]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\n\n\
    [solver]\nmethod = \"METHOD\"\ndt = 0.005\nduration = 1.0\ntolerance = 1e-13\n\n\
    [output]\nsamples = 21\n";

#[test]
fn a_cable_sliding_on_a_plane_s_friction_sensitivities_match_finite_differences() {
    // The lagged friction's anchors and normal forces follow the state at each step's
    // start (`Friction::add_start_rate`): without them the density's derivative was 2.6
    // off, with the anchors alone 1.9e-3. The differences' step is 1e-5: the friction
    // potential's Hessian jumps where a contact passes from sticking to sliding, and
    // steps of 1e-3 straddle such switches (errors 1e-4 … 2e-2 at 1e-3, 1e-10 … 1e-5
    // at 1e-5).
    for method in ["implicit-euler", "bdf2"] {
        let sliding = scene(ON_PLANE, method);
        let paths = [
            "contact.friction",
            "rod.linear_density",
            "pins[0].position[2]",
        ];
        let error = check_with_step(&sliding, &paths, 1e-5);
        assert!(error < 1e-4, "{method}: relative error {error:e}");
    }
}

#[test]
fn friction_paths_of_static_scenes_and_per_surface_friction_are_named() {
    let sliding = scene(ON_PLANE, "implicit-euler");
    let mut own = sliding.clone();
    own.rod.friction = Some(0.2);
    let e = dynamic_sensitivities(&own, &["contact.friction"]).expect_err("own");
    assert!(e.to_string().contains("rod.friction is set"), "{e}");
    let e = dynamic_sensitivities(&sliding, &["obstacles[0].friction"]).expect_err("obstacle");
    assert!(e.to_string().contains("per-surface"), "{e}");
    let mut none = sliding.clone();
    if let Some(c) = none.contact.as_mut() {
        c.friction = 0.0;
    }
    let e = dynamic_sensitivities(&none, &["contact.friction"]).expect_err("zero");
    assert!(e.to_string().contains("friction = 0"), "{e}");
    let mut resting = sliding.clone();
    resting.solver.method = splinerod::scene::Method::Static;
    let e = splinerod::sensitivity::static_sensitivities(&resting, &["contact.friction"])
        .expect_err("static");
    assert!(e.to_string().contains("only in runs"), "{e}");
    for path in [
        "pins[7].position[0]",
        "pins[0].position[3]",
        "rods[0].rest_length",
    ] {
        let e = dynamic_sensitivities(&sliding, &[path]).expect_err(path);
        assert!(e.to_string().contains(path), "{e}");
    }
}
