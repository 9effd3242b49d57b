//! Bad input in the contact-era scene fields (`rod.radius`, `rod.rest_shape`,
//! `[rod.overhand]` and `[contact]`): one clear error naming the field and the value,
//! never a panic; through the library (`Scene::from_toml`, `Scene::build_system`) and
//! through the `splinerod` command line (exit code 2).

use crate::common;

use common::*;
use splinerod::Scene;
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;

/// A valid straight rod with a radius and contact against a floor; every test alters it
/// by one small substitution.
const BASE: &str = r#"[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 8
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
radius = 0.01

[[pins]]
at = 0.0

[contact]
stiffness = 1e5
floor = -0.4

[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.05
"#;

/// `text` with the `[contact]` table (header and body, up to the next table) removed.
fn without_contact(text: &str) -> String {
    let start = text.find("[contact]\n").expect("a [contact] table");
    let end = start
        + text[start..]
            .find("\n\n")
            .expect("a blank line after [contact]")
        + 2;
    format!("{}{}", &text[..start], &text[end..])
}

// ---------------------------------------------------------------- valid scenes

#[test]
fn bases_are_valid() {
    let scene = accepted(BASE);
    assert_eq!(scene.rod.radius, Some(0.01));
    assert!(has_contact(&scene.build_system().unwrap()));
    let knot = accepted(KNOT);
    assert!(knot.rod.rest_length > 0.5, "{}", knot.rod.rest_length);
    assert_eq!(knot.rod.initial_control_points.as_ref().unwrap().len(), 11);
}

#[test]
fn bundled_contact_scenes_parse_and_build() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    for name in [
        "knot_tying.toml",
        "knot_tying_adaptive.toml",
        "cut_contact.toml",
    ] {
        let path = dir.join(name);
        let scene = Scene::load(&path).unwrap_or_err(name);
        assert!(scene.rod.radius.is_some_and(|r| r > 0.0), "{name}");
        let contact = scene.contact.as_ref().expect(name);
        assert!(contact.enabled, "{name}");
        let system = scene.build_system().unwrap_or_err(name);
        assert!(has_contact(&system), "{name}: contact not built");
    }
}

/// `expect` that shows the error with its `Display` (the one users see).
trait UnwrapOrErr<T> {
    fn unwrap_or_err(self, what: &str) -> T;
}

impl<T> UnwrapOrErr<T> for Result<T, splinerod::Error> {
    fn unwrap_or_err(self, what: &str) -> T {
        self.unwrap_or_else(|e| panic!("{what}: {e}"))
    }
}

#[test]
fn disabled_contact_needs_no_radius() {
    let text = with_line_in(&without_in(BASE, "radius"), "[contact]", "enabled = false");
    let scene = accepted(&text);
    assert!(!scene.contact.as_ref().unwrap().enabled);
    assert!(!has_contact(&scene.build_system().unwrap()));
    // No `[contact]` at all: the radius is optional and has no other effect.
    accepted(&without_contact(&without_in(BASE, "radius")));
    accepted(&without_contact(BASE));
}

#[test]
fn defaults_and_edge_values_are_accepted() {
    for (key, value) in [
        ("floor", "0.0"),
        ("floor", "-1e3"),
        ("floor", "1.5"),
        ("stiffness", "1e-3"),
    ] {
        accepted(&set_in(BASE, key, value));
    }
    for line in [
        "friction = 0.0",
        "exclusion = 0.0",
        "exclusion = 0.5",
        "onset = 1e-4",
        "enabled = true",
    ] {
        accepted(&with_line_in(BASE, "[contact]", line));
    }
    for shape in ["\"arclength\"", "\"initial\""] {
        let scene = accepted(&with_line_in(
            BASE,
            "[rod]",
            &format!("rest_shape = {shape}"),
        ));
        assert_eq!(scene.rod.rest_length, 1.0);
    }
}

// ---------------------------------------------------------------- rod.radius

#[test]
fn bad_radius() {
    assert_needs_positive_in(BASE, "radius", "rod.radius");
    // Also without contact: the radius is range-checked on its own.
    assert_needs_positive_in(&without_contact(BASE), "radius", "rod.radius");
    // A rod is thin: a radius above half the rest length (1 m here) is a typo (the
    // fuzzer's 1e300 made a run that could not finish).
    for value in ["0.6", "1e300"] {
        assert_field(&rejected(&set_in(BASE, "radius", value)), "rod.radius");
    }
    accepted(&set_in(BASE, "radius", "0.5"));
}

/// `rod.radius` is range-checked whether or not contact uses it (README: finite, > 0),
/// also when the `[contact]` table is present but disabled.
#[test]
fn bad_radius_with_disabled_contact() {
    let disabled = with_line_in(BASE, "[contact]", "enabled = false");
    for value in ["0.0", "-1.0", "nan"] {
        let text = set_in(&disabled, "radius", value);
        let outcome = catch_unwind(AssertUnwindSafe(|| Scene::from_toml(&text)));
        match outcome {
            Err(_) => panic!("radius = {value} with contact disabled panicked"),
            Ok(Ok(_)) => panic!(
                "rod.radius = {value} is accepted when [contact] has enabled = false \
                 (Scene::validate checks rod.radius only when there is no [contact] table, \
                 and ContactSpec::validate returns early when disabled)"
            ),
            Ok(Err(e)) => assert_field_value(&e.to_string(), "rod.radius", &shown(value)),
        }
    }
}

#[test]
fn contact_without_radius() {
    let message = rejected(&without_in(BASE, "radius"));
    assert_field(&message, "rod.radius");
    assert_field(&message, "contact");
    let explicit = with_line_in(&without_in(BASE, "radius"), "[contact]", "enabled = true");
    assert_field(&rejected(&explicit), "rod.radius");
}

// ---------------------------------------------------------------- [contact]

#[test]
fn bad_stiffness_and_tolerance() {
    assert_needs_positive_in(BASE, "stiffness", "contact.stiffness");
    let message = rejected(&set_in(BASE, "stiffness", "\"stiff\""));
    assert_field(&message, "contact.stiffness");
    // Without a stiffness: the barrier (#46), with or without a tolerance.
    let barrier = without_in(BASE, "stiffness");
    accepted(&barrier);
    let tolerance = with_line_in(&barrier, "[contact]", "tolerance = 1e-4");
    accepted(&tolerance);
    assert_needs_positive_in(&tolerance, "tolerance", "contact.tolerance");
    let message = rejected(&set_in(&tolerance, "tolerance", "\"tight\""));
    assert_field(&message, "contact.tolerance");
    // The barrier acts within the tolerance: an onset without a stiffness is named.
    assert_field(
        &rejected(&with_line_in(&barrier, "[contact]", "onset = 1e-3")),
        "contact.onset",
    );
    // With both a stiffness and a tolerance, the onset may not exceed the tolerance.
    let both = with_line_in(BASE, "[contact]", "tolerance = 1e-4");
    accepted(&with_line_in(&both, "[contact]", "onset = 1e-4"));
    assert_field(
        &rejected(&with_line_in(&both, "[contact]", "onset = 1e-3")),
        "contact.onset",
    );
}

#[test]
fn friction_must_be_finite_and_non_negative() {
    for value in ["0.3", "1.0", "1e-9"] {
        accepted(&with_line_in(
            BASE,
            "[contact]",
            &format!("friction = {value}"),
        ));
    }
    for value in ["-1.0", "-0.1", "nan", "-inf", "inf"] {
        let text = with_line_in(BASE, "[contact]", &format!("friction = {value}"));
        assert_field_value(&rejected(&text), "contact.friction", &shown(value));
    }
}

#[test]
fn bad_floor() {
    for value in ["nan", "inf", "-inf"] {
        let message = rejected(&set_in(BASE, "floor", value));
        assert_field_value(&message, "contact.floor", &shown(value));
    }
    assert_field(
        &rejected(&set_in(BASE, "floor", "\"low\"")),
        "contact.floor",
    );
}

#[test]
fn bad_onset() {
    for value in ["0.0", "-0.001", "nan", "inf"] {
        let text = with_line_in(BASE, "[contact]", &format!("onset = {value}"));
        assert_field_value(&rejected(&text), "contact.onset", &shown(value));
    }
}

#[test]
fn bad_exclusion() {
    for value in ["-1.0", "-1e-9", "nan", "inf"] {
        let text = with_line_in(BASE, "[contact]", &format!("exclusion = {value}"));
        assert_field_value(&rejected(&text), "contact.exclusion", &shown(value));
    }
}

#[test]
fn unknown_contact_field() {
    let message = rejected(&with_line_in(BASE, "[contact]", "restitution = 0.5"));
    assert_field(&message, "contact.restitution");
    let message = rejected(&with_line_in(BASE, "[contact]", "enabled = \"yes\""));
    assert_field(&message, "contact.enabled");
}

// ---------------------------------------------------------------- rod.rest_shape

#[test]
fn bad_rest_shape() {
    for value in ["\"bogus\"", "\"Initial\"", "\"\"", "1"] {
        let text = with_line_in(BASE, "[rod]", &format!("rest_shape = {value}"));
        let message = rejected(&text);
        assert_field(&message, "rod.rest_shape");
    }
    let message = rejected(&with_line_in(BASE, "[rod]", "rest_shape = \"bogus\""));
    assert!(message.contains("bogus"), "value not named: {message}");
    assert!(
        message.contains("arclength") && message.contains("initial"),
        "allowed variants not listed: {message}"
    );
}

/// `rest_shape = "initial"` needs an initial curve with non-zero speed everywhere; the
/// error must name the scene field (not just "rest shape").
#[test]
fn rest_shape_initial_with_degenerate_curve() {
    let straight = without_in(&without_in(BASE, "start"), "end");
    let points = ["[0.0, 0.0, 0.0]"; 8].join(", ");
    let text = with_line_in(
        &straight,
        "[rod]",
        &format!("rest_shape = \"initial\"\ninitial_control_points = [{points}]"),
    );
    let message = rejected(&text);
    assert!(
        message.contains("rod.rest_shape") || message.contains("rod.initial_control_points"),
        "a zero-speed initial curve with rest_shape = \"initial\" is refused (when the \
         system is built) without naming rod.rest_shape or rod.initial_control_points: \
         {message}"
    );
}

// ---------------------------------------------------------------- rod.rest_length

#[test]
fn rest_length_missing_without_overhand() {
    let message = rejected(&without_in(BASE, "rest_length"));
    assert!(message.contains("missing"), "{message}");
    assert_field(&message, "rod.rest_length");
    assert!(
        message.contains("overhand"),
        "overhand not mentioned: {message}"
    );
}

#[test]
fn rest_length_bad_values_are_named() {
    assert_needs_positive_in(BASE, "rest_length", "rod.rest_length");
}

/// Any written `rod.rest_length`, even the most negative float, is a value: reported as
/// out of range (or as a conflict with `rod.overhand`), never as missing.
#[test]
fn rest_length_most_negative_float_is_not_missing() {
    let value = "-1.7976931348623157e308";
    let message = rejected(&set_in(BASE, "rest_length", value));
    assert!(
        !message.contains("missing"),
        "rest_length = {value} is reported as missing instead of out of range: {message}"
    );
    assert_field_value(&message, "rod.rest_length", &shown(value));
    let with_overhand = with_line_in(KNOT, "[rod]", &format!("rest_length = {value}"));
    let outcome = catch_unwind(AssertUnwindSafe(|| Scene::from_toml(&with_overhand)));
    match outcome {
        Err(_) => panic!("rest_length = {value} with rod.overhand panicked"),
        Ok(Ok(scene)) => panic!(
            "rest_length = {value} together with rod.overhand is silently replaced \
             by the knot's length {} instead of being refused as a conflict",
            scene.rod.rest_length
        ),
        Ok(Err(e)) => assert_field(&e.to_string(), "rod.rest_length"),
    }
}

// ---------------------------------------------------------------- [rod.overhand]

#[test]
fn cli_bad_contact_exits_with_2() {
    let stderr = common::cli::refused_scene(
        "friction",
        &with_line_in(BASE, "[contact]", "friction = -0.3"),
    );
    assert_field_value(&stderr, "contact.friction", "-0.3");
    let stderr =
        common::cli::refused_scene("slip", &with_line_in(BASE, "[contact]", "slip_speed = 0.0"));
    assert_field_value(&stderr, "contact.slip_speed", "0");
    let stderr = common::cli::refused_scene("stiffness", &set_in(BASE, "stiffness", "0.0"));
    assert_field_value(&stderr, "contact.stiffness", "0");
    let stderr = common::cli::refused_scene("radius", &without_in(BASE, "radius"));
    assert_field(&stderr, "rod.radius");
    let stderr = common::cli::refused_scene(
        "overhand",
        &with_line_in(KNOT, "[rod]", "rest_length = 1.0"),
    );
    assert_field(&stderr, "rod.rest_length");
}

/// Whether the system has a contact energy.
fn has_contact(system: &splinerod::RodSystem) -> bool {
    system.energies.iter().any(|e| e.name() == "contact")
}

/// A start in deep contact (parts closer than half their contact distance) is refused
/// when the simulation is built, naming the radius: the penalty would push them apart
/// only through tiny sub-steps (the fuzzer's thick rope made six steps take minutes).
#[test]
fn a_start_in_deep_contact_is_refused() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let knot = std::fs::read_to_string(dir.join("knot_tying.toml")).unwrap();
    let thick = knot.replace("radius = 0.003", "radius = 0.1");
    assert_ne!(thick, knot);
    let scene = Scene::from_toml(&thick).unwrap_or_err("thick knot parses");
    let message = refused_build(&scene);
    assert_field(&message, "rod.radius");
    assert!(message.contains("deep contact"), "{message}");
    let ropes = std::fs::read_to_string(dir.join("ropes_crossing.toml")).unwrap();
    let thick = ropes.replacen("radius = 0.006", "radius = 0.3", 1);
    let scene = Scene::from_toml(&thick).unwrap_or_err("thick ropes parse");
    let message = refused_build(&scene);
    assert!(
        message.contains("rods[].radius") && message.contains("deep contact"),
        "{message}"
    );
    // The bundled scenes start apart.
    Scene::from_toml(&knot)
        .unwrap()
        .build()
        .unwrap_or_err("knot_tying builds");
}

/// The error of building `scene`, which must fail.
fn refused_build(scene: &Scene) -> String {
    match scene.build() {
        Ok(_) => panic!("built, but should have been refused"),
        Err(e) => e.to_string(),
    }
}
