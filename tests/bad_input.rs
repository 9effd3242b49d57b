//! Bad scenes are rejected with an error that names the field and the value, never a
//! panic, through the library (`Scene::from_toml`, `Scene::build_system`, `run`); the
//! command line's side is `bad_input_cli.rs`.

use crate::common;

use common::*;
use splinerod::Scene;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// A valid scene that every test alters by one small substitution.
pub(crate) const BASE: &str = r#"[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 0.5
control_points = 6
degree = 3
start = [0.0, 0.0, 0.0]
end = [0.8, 0.0, 0.0]

[[pins]]
at = 0.0
position = [0.0, 0.0, 0.0]

[[pins]]
at = 1.0

[world]
gravity = [0.0, -9.81, 0.0]

[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.05
newton_iterations = 10
tolerance = 1e-10

[output]
samples = 11
probes = [0.5]
"#;

/// The base scene with the value of `key` replaced.
pub(crate) fn set(key: &str, value: &str) -> String {
    set_in(BASE, key, value)
}

/// The base scene without the line that sets `key`.
fn without(key: &str) -> String {
    without_in(BASE, key)
}

/// The base scene with `line` added after the header `table`.
pub(crate) fn with_line(table: &str, line: &str) -> String {
    with_line_in(BASE, table, line)
}

/// Parses and validates `text`, which must pass; only building it (or running it) fails.
fn rejected_when_built(text: &str) -> String {
    let scene = Scene::from_toml(text).expect("valid until built");
    let run = catch_unwind(AssertUnwindSafe(|| splinerod::run(&scene))).expect("run panicked");
    let run_error = run.expect_err("run accepted the scene").to_string();
    assert_eq!(rejected(text), run_error);
    run_error
}

/// Negative, zero and non-finite values of `key` are rejected naming `field`.
fn assert_needs_positive(key: &str, field: &str) {
    assert_needs_positive_in(BASE, key, field);
}

#[test]
fn base_scene_is_valid() {
    let scene = Scene::from_toml(BASE).unwrap();
    scene.build_system().unwrap();
    assert_eq!(splinerod::run(&scene).unwrap().steps, 5);
}

#[test]
fn missing_required_field() {
    for (key, field) in [
        ("rest_length", "rod.rest_length"),
        ("linear_density", "rod.linear_density"),
        ("stretch_stiffness", "rod.stretch_stiffness"),
        ("control_points", "rod.control_points"),
        ("method", "solver.method"),
    ] {
        let message = rejected(&without(key));
        assert_field(&message, &format!("missing field `{field}`"));
    }
    let no_solver = BASE.split("[solver]").next().unwrap();
    assert_field(&rejected(no_solver), "missing table [solver]");
}

#[test]
fn unknown_field() {
    let message = rejected(&with_line("[rod]", "colour = \"red\""));
    assert_field(&message, "unknown field `rod.colour`");
    let message = rejected(&with_line("[solver]", "newton_iteration = 5"));
    assert_field(&message, "unknown field `solver.newton_iteration`");
    assert_field(&message, "newton_iterations"); // the valid names are listed
    let message = rejected(&with_line("[world]", "gravty = [0.0, 0.0, 0.0]"));
    assert_field(&message, "unknown field `world.gravty`");
}

#[test]
fn wrong_type_names_the_field() {
    let message = rejected(&set("linear_density", "\"heavy\""));
    assert_field(&message, "rod.linear_density");
    let message = rejected(&set("control_points", "-6"));
    assert_field(&message, "rod.control_points");
    let message = rejected(&set("method", "\"explicit\""));
    assert_field(&message, "solver.method");
}

#[test]
fn non_positive_linear_density() {
    assert_needs_positive("linear_density", "rod.linear_density");
}

#[test]
fn non_positive_stretch_stiffness() {
    assert_needs_positive("stretch_stiffness", "rod.stretch_stiffness");
}

#[test]
fn non_positive_rest_length() {
    assert_needs_positive("rest_length", "rod.rest_length");
}

#[test]
fn non_positive_dt() {
    assert_needs_positive("dt", "solver.dt");
    // Also when the static solver ignores it.
    let static_scene = set_in(&set("method", "\"static\""), "dt", "-0.01");
    assert_field_value(&rejected(&static_scene), "solver.dt", "-0.01");
}

#[test]
fn non_positive_duration() {
    assert_needs_positive("duration", "solver.duration");
}

#[test]
fn non_positive_tolerance() {
    assert_needs_positive("tolerance", "solver.tolerance");
}

#[test]
fn negative_or_non_finite_damping() {
    for value in ["-0.5", "-1e-9", "nan", "inf"] {
        assert_field_value(
            &rejected(&set("damping", value)),
            "rod.damping",
            &shown(value),
        );
    }
    Scene::from_toml(&set("damping", "0.0")).expect("zero damping is allowed");
}

#[test]
fn too_few_control_points() {
    for (degree, count) in [("3", "3"), ("3", "0"), ("1", "1"), ("5", "5")] {
        let text = set_in(&set("degree", degree), "control_points", count);
        assert_field_value(&rejected(&text), "rod.control_points", count);
    }
    Scene::from_toml(&set("control_points", "4")).expect("degree + 1 points suffice");
}

#[test]
fn degree_out_of_range() {
    for degree in ["0", "10"] {
        assert_field_value(&rejected(&set("degree", degree)), "rod.degree", degree);
    }
}

#[test]
fn non_finite_scalars() {
    for (key, field) in [
        ("linear_density", "rod.linear_density"),
        ("stretch_stiffness", "rod.stretch_stiffness"),
        ("rest_length", "rod.rest_length"),
        ("damping", "rod.damping"),
        ("dt", "solver.dt"),
        ("tolerance", "solver.tolerance"),
    ] {
        for value in ["nan", "inf", "-inf", "+nan"] {
            assert_field_value(&rejected(&set(key, value)), field, &shown(value));
        }
    }
}

#[test]
fn non_finite_rod_start_and_end() {
    let message = rejected(&set("start", "[nan, 0.0, 0.0]"));
    assert_field_value(&message, "rod.start", "[NaN, 0.0, 0.0]");
    let message = rejected(&set("end", "[0.8, inf, 0.0]"));
    assert_field_value(&message, "rod.end", "[0.8, inf, 0.0]");
    let message = rejected(&set("end", "[0.8, 0.0, -inf]"));
    assert_field_value(&message, "rod.end", "[0.8, 0.0, -inf]");
}

#[test]
fn non_finite_gravity() {
    for (value, display) in [
        ("[0.0, -inf, 0.0]", "[0.0, -inf, 0.0]"),
        ("[nan, -9.81, 0.0]", "[NaN, -9.81, 0.0]"),
        ("[0.0, 0.0, inf]", "[0.0, 0.0, inf]"),
    ] {
        assert_field_value(&rejected(&set("gravity", value)), "world.gravity", display);
    }
}

#[test]
fn non_finite_pin_position() {
    let message = rejected(&set("position", "[nan, 0.0, 0.0]"));
    assert_field_value(&message, "pins[0].position", "[NaN, 0.0, 0.0]");
    let message = rejected(&set("position", "[0.0, inf, 0.0]"));
    assert_field_value(&message, "pins[0].position", "[0.0, inf, 0.0]");
}

#[test]
fn pin_outside_the_rod() {
    for value in ["-0.1", "1.5", "nan", "inf"] {
        let text = BASE.replacen("at = 1.0", &format!("at = {value}"), 1);
        assert_field_value(&rejected(&text), "pins[1].at", &shown(value));
    }
}

#[test]
fn probe_outside_the_rod() {
    for value in ["-0.3", "1.2", "nan"] {
        let text = set("probes", &format!("[0.5, {value}]"));
        assert_field_value(&rejected(&text), "output.probes[1]", &shown(value));
    }
}

#[test]
fn initial_control_points_count_mismatch() {
    let points =
        "[[0.0, 0.0, 0.0], [0.2, 0.0, 0.0], [0.4, 0.0, 0.0], [0.6, 0.0, 0.0], [0.8, 0.0, 0.0]]";
    let explicit = BASE.replacen(line_of(BASE, "start"), "", 1).replacen(
        line_of(BASE, "end"),
        &format!("initial_control_points = {points}"),
        1,
    );
    let message = rejected(&explicit);
    assert_field_value(&message, "rod.initial_control_points", "5 points");
    assert!(message.contains("6"), "expected count not given: {message}");
    // With start/end as well it is ambiguous.
    let both = with_line("[rod]", &format!("initial_control_points = {points}"));
    assert_field(&rejected(&both), "rod.initial_control_points");
}

#[test]
fn explicit_knots_unsorted() {
    let knots = "knots = [0.0, 0.0, 0.0, 0.0, 0.6, 0.4, 1.0, 1.0, 1.0, 1.0]";
    let message = rejected_when_built(&with_line("[rod]", knots));
    assert_field_value(
        &message,
        "rod.knots",
        "[0.0, 0.0, 0.0, 0.0, 0.6, 0.4, 1.0, 1.0, 1.0, 1.0]",
    );
    assert!(message.contains("not sorted"), "{message}");
}

#[test]
fn explicit_knots_wrong_length() {
    let knots = "knots = [0.0, 0.0, 0.0, 0.0, 0.5, 1.0, 1.0, 1.0, 1.0]";
    let message = rejected(&with_line("[rod]", knots));
    assert_field_value(&message, "rod.knots", "9 values");
    assert!(
        message.contains("10"),
        "expected length not given: {message}"
    );
}

#[test]
fn explicit_knots_non_finite() {
    let knots = "knots = [0.0, 0.0, 0.0, 0.0, nan, 0.6, 1.0, 1.0, 1.0, 1.0]";
    let message = rejected_when_built(&with_line("[rod]", knots));
    assert_field(&message, "rod.knots");
    assert!(message.contains("NaN"), "{message}");
}

#[test]
fn named_knots_unknown() {
    let message = rejected(&with_line("[rod]", "knots = \"bogus\""));
    assert_field_value(&message, "rod.knots", "\"bogus\"");
}

#[test]
fn pin_position_disagreeing_with_initial_shape() {
    let message = rejected_when_built(&set("position", "[0.0, 0.1, 0.0]"));
    assert_field_value(&message, "pins[0].position", "[0.0, 0.1, 0.0]");
    let pinned_end = BASE.replacen("at = 1.0", "at = 1.0\nposition = [1.0, 0.0, 0.0]", 1);
    let message = rejected_when_built(&pinned_end);
    assert_field_value(&message, "pins[1].position", "[1.0, 0.0, 0.0]");
}

#[test]
fn implicit_euler_without_dt_or_duration() {
    assert_field_value(&rejected(&without("dt")), "solver.dt", "missing");
    let message = rejected(&without("duration"));
    assert_field_value(&message, "solver.duration", "missing");
    let static_scene = without("dt");
    Scene::from_toml(&set_in(&static_scene, "method", "\"static\"")).expect("static needs no dt");
}

#[test]
fn zero_newton_iterations() {
    let message = rejected(&set("newton_iterations", "0"));
    assert_field_value(&message, "solver.newton_iterations", "0");
}

#[test]
fn too_few_samples() {
    for samples in ["1", "0"] {
        let message = rejected(&set("samples", samples));
        assert_field_value(&message, "output.samples", samples);
    }
}

#[test]
fn sub_stepping_settings_out_of_range() {
    let with = |line: &str| with_line("[solver]", line);
    assert_needs_positive_in(&with("min_dt = 1e-4"), "min_dt", "solver.min_dt");
    let text = with("time_tolerance = 1e-4");
    assert_needs_positive_in(&text, "time_tolerance", "solver.time_tolerance");
    let message = rejected(&with("min_dt = 0.02"));
    assert_field_value(&message, "solver.min_dt", "0.02");
    assert!(message.contains("solver.dt"), "{message}");
    accepted(&with("min_dt = 0.01"));
    let stderr = common::cli::refused_scene("min_dt", &with("min_dt = 0.5"));
    assert!(stderr.contains("solver.min_dt"), "{stderr}");
    let stderr = common::cli::refused_scene("time_tolerance", &with("time_tolerance = nan"));
    assert!(stderr.contains("solver.time_tolerance"), "{stderr}");
    let message = rejected(&with("accept_unconverged = 1"));
    assert!(message.contains("accept_unconverged"), "{message}");
}

#[test]
fn stretch_formulation_and_inextensible_are_checked() {
    let e = rejected(&with_line("[rod]", "stretch_formulation = \"reduced\""));
    assert!(e.contains("stretch_formulation"), "{e}");
    let e = rejected(&set("stretch_stiffness", "\"rigid\""));
    assert!(
        e.contains("rod.stretch_stiffness") && e.contains("inextensible"),
        "{e}"
    );
    let both = with_line("[rod]", "stretch_formulation = \"pointwise\"").replace(
        "stretch_stiffness = 100.0",
        "stretch_stiffness = \"inextensible\"",
    );
    let e = rejected(&both);
    assert!(e.contains("rod.stretch_formulation"), "{e}");
    let fine = set("stretch_stiffness", "\"inextensible\"");
    Scene::from_toml(&fine)
        .and_then(|s| s.build_system().map(|_| ()))
        .expect("an inextensible rod is a valid scene");
}

/// A thin rod's bending and twisting stiffnesses are at most EA·L² (100 N·m² here):
/// beyond, the Newton matrix mixes stiffnesses no double resolves (the fuzzer's
/// EI = 9.2e18 made a run that could not finish).
#[test]
fn bending_and_twist_stiffness_at_most_ea_l_squared() {
    for key in ["bending_stiffness", "twist_stiffness"] {
        let field = format!("rod.{key}");
        for value in ["101.0", "9223372036854775807"] {
            let text = with_line_in(BASE, "[rod]", &format!("{key} = {value}"));
            let message = rejected(&text);
            assert_field(&message, &field);
            assert!(
                message.contains("stretch_stiffness × rest_length²"),
                "{message}"
            );
        }
    }
    accepted(&with_line_in(BASE, "[rod]", "bending_stiffness = 100.0"));
}

/// A rod may not start squeezed below a tenth of its rest length (the fuzzer's 478.8 m
/// plectoneme laid out straight over 1 m put a quarter of a million contact samples
/// within reach of each other): the straight start–end line and the control polygon
/// (at least as long as the curve) are measured.
#[test]
fn a_rod_squeezed_at_the_start_is_refused() {
    let short = set_in(BASE, "end", "[0.09, 0.0, 0.0]");
    let message = rejected(&short);
    assert_field(&message, "rod.end");
    assert!(message.contains("stretch 9.000e-2"), "{message}");
    accepted(&set_in(BASE, "end", "[0.1, 0.0, 0.0]"));
    let polygon = without_in(&without_in(BASE, "start"), "end");
    let points = (0..6).map(|i| format!("[{}, 0.0, 0.0]", 0.01 * i as f64));
    let line = format!(
        "initial_control_points = [{}]",
        points.collect::<Vec<_>>().join(", ")
    );
    let message = rejected(&with_line_in(&polygon, "[rod]", &line));
    assert_field(&message, "rod.initial_control_points");
}
