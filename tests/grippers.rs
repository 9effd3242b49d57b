//! 6-DOF clamps (`[[pins]] clamp = true` with `direction` and `pose`), against exact
//! answers:
//!
//! * a gripper turning 90° about a normal carries a weightless clamped rod, which ends
//!   straight at the rotated position (1e-9 m);
//! * a static horizontal cantilever: the clamp's force is the weight μgL and its torque
//!   the weight's moment μgL²/2 (1e-6 relative), also with a stated `direction` and
//!   with the gripper turned in the plane (moment μgL²/2 · cos α);
//! * a gripper rolled by 2π about the rod's axis twists a rod with `twist_stiffness` by
//!   2π: the twisting moment GJ·2π/L (1e-6 relative), as a `turn` of 2π does;
//! * bad input is refused naming the field, through the library and the command line.
//!
//! Sign convention (as `pin_forces`): `pin_torques` is the torque the rod puts on the
//! gripper about the clamp point (what a wrist's force–torque sensor reads); the clamp
//! exerts its negative on the rod.

use crate::common::cli::refused_scene;
use crate::common::{assert_field, rejected};
use splinerod::{run, Scene};
use std::f64::consts::PI;

/// A weightless rod along x clamped at s = 0, its gripper turning by `rotation` (a
/// rotation vector) over 0.5 s, then held for `duration − 0.5` s.
fn turning(rotation: [f64; 3], duration: f64) -> String {
    format!(
        r#"
[rod]
rest_length = 1.0
linear_density = 0.01
stretch_stiffness = 1e5
bending_stiffness = 100.0
control_points = 12
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]

[[pins]]
at = 0.0
clamp = true
interpolation = "smooth"
pose = [[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0, {}, {}, {}]]

[world]
gravity = [0.0, 0.0, 0.0]

[solver]
method = "implicit-euler"
dt = 0.01
duration = {duration}
"#,
        rotation[0], rotation[1], rotation[2]
    )
}

/// Largest distance of the sampled points from where the rotated rod puts them.
fn off_rotated(text: &str, rotation: [f64; 3]) -> f64 {
    let result = run(&Scene::from_toml(text).expect("scene")).expect("run");
    let r = nalgebra::Rotation3::new(nalgebra::Vector3::from(rotation));
    let s = &result.samples;
    s.s.iter()
        .zip(&s.positions)
        .map(|(s, p)| {
            (r * nalgebra::Vector3::new(*s, 0.0, 0.0) - nalgebra::Vector3::from(*p)).norm()
        })
        .fold(0.0, f64::max)
}

#[test]
fn a_gripper_turned_90_degrees_carries_a_weightless_rod_straight() {
    for rotation in [
        [0.0, 0.0, PI / 2.0],
        [0.0, -PI / 2.0, 0.0],
        [0.0, 0.9, -1.3],
    ] {
        for method in ["implicit-euler", "static"] {
            let text =
                turning(rotation, 2.0).replace("\"implicit-euler\"", &format!("\"{method}\""));
            let off = off_rotated(&text, rotation);
            println!("{method}: gripper turned by {rotation:?}: the rod {off:.2e} m off the rotated line");
            assert!(off < 1e-9, "{method}, {rotation:?}: {off:e}");
        }
    }
    // The clamp at the far end (s = L, at x = 1): the rod turns about it.
    let text = turning([0.0, 0.0, PI / 2.0], 2.0).replace("at = 0.0\nclamp", "at = 1.0\nclamp");
    let result = run(&Scene::from_toml(&text).expect("scene")).expect("run");
    let s = &result.samples;
    let off = s.s.iter().zip(&s.positions).map(|(s, p)| {
        (nalgebra::Vector3::new(1.0, s - 1.0, 0.0) - nalgebra::Vector3::from(*p)).norm()
    });
    let off = off.fold(0.0, f64::max);
    println!("clamp at s = L turned by 90° about z: {off:.2e} m off");
    assert!(off < 1e-9, "{off:e}");
}

#[test]
fn a_clamp_direction_bends_the_rod_into_it() {
    // A weightless rod along x whose clamp holds (1, 1, 0): straight along it at rest.
    let base = turning([0.0; 3], 2.0);
    let lines = base
        .lines()
        .filter(|l| !l.starts_with("pose") && !l.starts_with("interp"));
    let text = lines
        .collect::<Vec<_>>()
        .join("\n")
        .replace("clamp = true", "clamp = true\ndirection = [1.0, 1.0, 0.0]")
        .replace("\"implicit-euler\"", "\"static\"");
    let off = off_rotated(&text, [0.0, 0.0, PI / 4.0]);
    println!("clamp direction (1, 1, 0): the rod {off:.2e} m off the line along it");
    assert!(off < 1e-9, "{off:e}");
}

/// A horizontal cantilever along x under gravity −y, clamped at s = 0, solved static.
fn cantilever(extra: &str) -> String {
    stiff_cantilever(extra, 1e8)
}

/// [`cantilever`] of stretching stiffness `ea`.
fn stiff_cantilever(extra: &str, ea: f64) -> String {
    format!(
        r#"
[rod]
rest_length = {L}
linear_density = {MU}
stretch_stiffness = {ea:e}
bending_stiffness = 1e4
control_points = 16
start = [0.0, 0.0, 0.0]
end = [{L}, 0.0, 0.0]

[[pins]]
at = 0.0
clamp = true
{extra}

[world]
gravity = [0.0, -{G}, 0.0]

[solver]
method = "static"
"#
    )
}

const L: f64 = 1.5;
const MU: f64 = 0.2;
const G: f64 = 9.81;

#[test]
fn a_static_cantilever_clamp_holds_the_weight_and_its_moment() {
    let weight = MU * G * L;
    let moment = MU * G * L * L / 2.0;
    for extra in ["", "direction = [2.0, 0.0, 0.0]"] {
        let result = run(&Scene::from_toml(&cantilever(extra)).expect("scene")).expect("run");
        let (force, torque) = (result.pin_forces[0], result.pin_torques[0]);
        println!("`{extra}`: clamp force {force:?} (weight {weight}), torque {torque:?} (exact {moment})");
        // The rod's wrench on the gripper: its weight, down, and the weight's moment
        // about the clamp, −μgL²/2 ẑ (the rod lies along +x).
        assert!((force[1] + weight).abs() < 1e-9 * weight, "{force:?}");
        assert!(force[0].abs() + force[2].abs() < 1e-9 * weight, "{force:?}");
        assert!(
            (torque[2] + moment).abs() < 1e-6 * moment,
            "{torque:?} vs {moment}"
        );
        assert!(
            torque[0].abs() + torque[1].abs() < 1e-9 * moment,
            "{torque:?}"
        );
    }
    // The gripper turned up by α in a static solve: the moment is μgL²/2 · cos α, to the
    // deflection across the rod, which now shortens the arm at first order (δ/L ≈ 4e-5).
    // The force balance of a static solve of a rod that is not horizontal holds to
    // about 5e-7 relative (as without a gripper: a plain clamp on a rod laid out at α
    // gives the same), not to round-off as in the horizontal case.
    let alpha = 0.4_f64;
    let pose = format!(
        "pose = [[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0, 0.0, 0.0, {alpha}]]"
    );
    let result =
        run(&Scene::from_toml(&stiff_cantilever(&pose, 1e6)).expect("scene")).expect("run");
    let (force, torque) = (result.pin_forces[0], result.pin_torques[0]);
    let exact = moment * alpha.cos();
    println!("turned by {alpha}: clamp force {force:?}, torque {torque:?} (exact {exact})");
    assert!((force[1] + weight).abs() < 1e-6 * weight, "{force:?}");
    assert!(
        (torque[2] + exact).abs() < 1e-4 * exact,
        "{torque:?} vs {exact}"
    );
}

/// A straight rod along x clamped at both ends, with twist; the end clamp rolled by
/// `roll` (rad) about x by its gripper (`pose`) or by `turn`, over 1 s.
fn rolled(roll: f64, by_pose: bool, method: &str) -> String {
    let end = if by_pose {
        format!(
            "pose = [[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0, {roll}, 0.0, 0.0]]"
        )
    } else {
        format!("turn = [[0.0, 0.0], [1.0, {roll}]]")
    };
    format!(
        r#"
[rod]
rest_length = 0.8
linear_density = 0.05
stretch_stiffness = 1e5
bending_stiffness = 2.0
twist_stiffness = 1.3
control_points = 12
start = [0.0, 0.0, 0.0]
end = [0.8, 0.0, 0.0]

[[pins]]
at = 0.0
clamp = true

[[pins]]
at = 1.0
clamp = true
{end}

[world]
gravity = [0.0, 0.0, 0.0]

[solver]
method = "{method}"
dt = 0.02
duration = 1.2
"#
    )
}

#[test]
fn a_gripper_rolled_a_full_turn_twists_the_rod_a_full_turn() {
    let exact = 1.3 * 2.0 * PI / 0.8;
    for method in ["static", "implicit-euler"] {
        let posed =
            run(&Scene::from_toml(&rolled(2.0 * PI, true, method)).expect("scene")).expect("run");
        let turned =
            run(&Scene::from_toml(&rolled(2.0 * PI, false, method)).expect("scene")).expect("run");
        let twist = posed.twist.expect("twist");
        println!(
            "{method}: rolled 2π: twist {:.12}, moment {:.12} (exact {exact:.12}); turned: moment {:.12}; torques {:?}",
            twist.twist,
            twist.moment,
            turned.twist.expect("twist").moment,
            posed.pin_torques
        );
        assert!(
            (twist.moment - exact).abs() < 1e-6 * exact,
            "{}",
            twist.moment
        );
        assert!((twist.twist - 2.0 * PI).abs() < 1e-6 * 2.0 * PI);
        // The rod resists the roll: −GJ·2π/L about x on the rolled gripper, +GJ·2π/L
        // on the fixed one.
        assert!((posed.pin_torques[1][0] + exact).abs() < 1e-6 * exact);
        assert!((posed.pin_torques[0][0] - exact).abs() < 1e-6 * exact);
        let gap = crate::common::sample_gap(&posed, &turned);
        assert!(gap < 1e-9, "{method}: pose and turn differ by {gap:e} m");
    }
}

#[test]
fn bad_clamp_poses_name_the_field() {
    let pose = |rows: &str| cantilever(&format!("pose = [{rows}]"));
    let rest = "[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]";
    let cases = [
        (
            pose(&format!("{rest}, [1.0, 0.0, 0.0, 0.0, nan, 0.0, 0.0]")),
            "pins[0].pose[1][4]",
        ),
        (
            pose(&format!("{rest}, [1.0, 0.0, inf, 0.0, 0.0, 0.0, 0.0]")),
            "pins[0].pose[1][2]",
        ),
        (
            pose(&format!(
                "{rest}, [1.0, 0.0, 0.0, 0.0, 0.1, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0, 0.2, 0.0, 0.0]"
            )),
            "pins[0].pose[2][0]",
        ),
        (
            pose("[0.0, 0.1, 0.0, 0.0, 0.0, 0.0, 0.0]"),
            "pins[0].pose[0]",
        ),
        (
            cantilever("direction = [0.0, 0.0, 0.0]"),
            "pins[0].direction",
        ),
        (
            cantilever("direction = [nan, 1.0, 0.0]"),
            "pins[0].direction",
        ),
        // Finite, but the length under- or overflows: no direction, no angle.
        (
            cantilever("direction = [1e-320, 0.0, 0.0]"),
            "pins[0].direction",
        ),
        (
            pose(&format!("{rest}, [1.0, 0.0, 0.0, 0.0, 1e300, 1e300, 0.0]")),
            "pins[0].pose[1]",
        ),
        (
            cantilever(&format!("path = [[0.0, 0.0, 0.0, 0.0]]\npose = [{rest}]")),
            "pins[0].pose",
        ),
        (
            cantilever("").replace("clamp = true", &format!("pose = [{rest}]")),
            "pins[0].pose",
        ),
        (
            cantilever("").replace(
                "at = 0.0\nclamp = true",
                &format!("at = 0.5\nclamp = true\npose = [{rest}]"),
            ),
            "pins[0].pose",
        ),
    ];
    for (text, field) in &cases {
        let error = rejected(text);
        println!("{field}: {error}");
        assert_field(&error, field);
    }
    // Through the command line: exit 2 and one line naming the field.
    let (text, field) = &cases[0];
    assert_field(&refused_scene("bad_pose", text), field);
}

#[test]
fn a_clamp_on_a_closed_rod_is_refused() {
    let text = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 1e3
bending_stiffness = 0.1
control_points = 12

[rod.ring]
radius = 0.15

[[pins]]
at = 0.0
clamp = true
pose = [[0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]]

[solver]
method = "static"
"#;
    let error = refused_scene("closed_clamp", text);
    assert!(error.contains("pins[0]."), "{error}");
}
