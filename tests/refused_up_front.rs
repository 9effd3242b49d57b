//! Scenes whose values are each in range but that together have no good run are refused
//! before the first step, naming the field (issue #45's "silent wrong answers" and
//! "failures mid-run"); and what used to fail mid-run now runs.

use crate::common;

use common::*;
use splinerod::Scene;

/// A cable 1 m long between pins 0.8 m apart.
const CABLE: &str = r#"[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 10
start = [0.0, 0.0, 0.0]
end = [0.8, 0.0, 0.0]

[[pins]]
at = 0.0

[[pins]]
at = 1.0

[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.05
"#;

/// Parses, validates and builds the whole simulation (start checks included).
fn built(text: &str) -> Result<(), String> {
    let scene = Scene::from_toml(text).map_err(|e| e.to_string())?;
    scene.build().map(|_| ()).map_err(|e| e.to_string())
}

#[test]
fn an_inextensible_rod_between_pins_it_cannot_reach_is_refused() {
    let inextensible = set_in(CABLE, "stretch_stiffness", "\"inextensible\"");
    // Pins 1.5 m apart (the start is the straight line between them), for 1 m of rod.
    let far = set_in(&inextensible, "end", "[1.5, 0.0, 0.0]");
    let message = rejected(&far);
    assert_field(&message, "rod.end");
    assert!(message.contains("inextensible"), "{message}");
    // A driven pin that pulls it to 1.4 m by t = 1 s.
    let pull = |to: &str| {
        with_line_in(
            &inextensible,
            "[[pins]]\nat = 1.0",
            &format!("path = [[0.0, 0.8, 0.0, 0.0], [1.0, {to}, 0.0, 0.0]]"),
        )
    };
    let message = rejected(&pull("1.4"));
    assert_field(&message, "pins[1].path");
    assert!(message.contains("t = 1 s"), "{message}");
    // Within reach (0.99 m apart) it runs; an elastic rod may be pulled apart.
    accepted(&pull("0.99"));
    accepted(&far.replace("\"inextensible\"", "100.0"));
}

#[test]
fn a_rod_starting_below_the_floor_is_refused() {
    let with_contact = format!("{CABLE}\n[contact]\nstiffness = 1e5\nfloor = 0.5\n");
    let with_contact = set_in(&with_contact, "control_points", "10\nradius = 0.01");
    let message = built(&with_contact).expect_err("start 0.5 m under the floor");
    assert_field_value(&message, "contact.floor", "0.5");
    // Half a radius above floor + r is fine; the floor's contacts count in the statistics.
    let above = with_contact.replace("floor = 0.5", "floor = -0.0105");
    built(&above).expect("starts resting on the floor");
    let result = splinerod::run(&Scene::from_toml(&above).unwrap()).expect("runs");
    let contact = result.contact.expect("contact statistics");
    assert!(contact.max_obstacle_contacts > 0, "{contact:?}");
    let ratio = contact.min_clearance_ratio.expect("floor contacts counted");
    assert!(ratio < 1.1 && ratio > 0.5, "ratio {ratio}");
}

#[test]
fn cuts_that_meet_are_refused() {
    let cut = |at: &str| format!("\n[[cuts]]\nat = {at}\ntime = 0.01\n");
    let twice = format!("{CABLE}{}{}", cut("0.5"), cut("0.5"));
    assert_field_value(&rejected(&twice), "cuts[1].at", "0.5");
    let close = format!("{CABLE}{}{}", cut("0.5"), cut("0.5000000001"));
    assert_field(&rejected(&close), "cuts[1].at");
    accepted(&format!("{CABLE}{}{}", cut("0.5"), cut("0.6")));
    // A ring cut at its seam from both sides: 0 and 1 are one point.
    let ring = r#"[rod]
rest_length = 1.2566370614359172
linear_density = 0.1
stretch_stiffness = 100.0
bending_stiffness = 0.01
control_points = 12
[rod.ring]
radius = 0.2
[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.05
"#;
    let message = rejected(&format!("{ring}{}{}", cut("0.0"), cut("1.0")));
    assert_field(&message, "cuts[1].at");
    assert!(message.contains("closed rod"), "{message}");
}

#[test]
fn an_entry_naming_no_rod_is_refused() {
    let rods = r#"[[rods]]
name = "a"
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 8
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]
[[rods]]
name = "b"
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 8
start = [0.0, 1.0, 0.0]
end = [1.0, 1.0, 0.0]
[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.05
"#;
    let message = rejected(&format!(
        "{rods}[[cuts]]\nrod = \"c\"\nat = 0.5\ntime = 0.0\n"
    ));
    assert_field_value(&message, "rod", "\"c\"");
    let message = rejected(&format!("{rods}[[pins]]\nrod = \"c\"\nat = 0.5\n"));
    assert_field(&message, "rod");
}

#[test]
fn huge_lengths_are_refused_naming_their_own_field() {
    let message = rejected(&set_in(CABLE, "rest_length", "1e308"));
    assert_field_value(&message, "rod.rest_length", "1e308");
    let knot = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/knot_tying.toml"
    ))
    .unwrap();
    let message = rejected(&set_in(&knot, "span", "1e300"));
    assert_field_value(&message, "rod.overhand.span", "1e300");
}

/// Rods of `[[rods]]` with the curvature criterion: insertions never pile a knot on a
/// junction (it failed on step 1: "knot 1 has multiplicity 5").
#[test]
fn several_rods_refine_by_curvature() {
    let scene = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/ropes_crossing.toml"
    ))
    .unwrap();
    let scene = set_in(&scene, "duration", "0.1");
    let scene =
        format!("{scene}\n[adaptivity]\nmax_control_points = 128\ninsert_threshold = 0.01\n");
    let result = splinerod::run(&Scene::from_toml(&scene).unwrap()).expect("runs");
    assert!(
        result.control_points > 36,
        "refined: {}",
        result.control_points
    );
}

/// An energy that fails (NaN) once the rod sags below y = −1 cm.
struct Broken;

impl splinerod::prelude::Energy for Broken {
    fn name(&self) -> &str {
        "broken"
    }
    fn energy(&self, rod: &splinerod::prelude::Rod) -> f64 {
        match rod.positions.iter().any(|p| p.y < -0.01) {
            true => f64::NAN,
            false => 0.0,
        }
    }
    fn add_gradient(
        &self,
        rod: &splinerod::prelude::Rod,
        gradient: &mut [splinerod::prelude::Vector3<f64>],
    ) {
        if rod.positions.iter().any(|p| p.y < -0.01) {
            gradient[0].x = f64::NAN;
        }
    }
}

/// A step that fails on an energy's NaN names the energy (not only "non-finite").
#[test]
fn a_failing_energy_is_named() {
    let scene = format!("{CABLE}\n[world]\ngravity = [0.0, -9.81, 0.0]\n");
    let mut sim = Scene::from_toml(&scene).unwrap().build().unwrap();
    sim.system.energies.push(Box::new(Broken));
    let error = (0..100)
        .find_map(|_| sim.step(0.01).err())
        .expect("the energy fails once the cable sags");
    let message = error.to_string();
    assert!(message.contains("energy `broken`"), "{message}");
    assert!(
        matches!(error, splinerod::Error::EnergyNotFinite { .. }),
        "{error:?}"
    );
}
