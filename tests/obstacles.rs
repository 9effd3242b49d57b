//! Rigid obstacles in scenes: a rope draped over a sphere or a capsule is held by
//! friction above the capstan threshold (pressing on it with its weight) and slides off
//! below it, without entering the obstacle; bad `[[obstacles]]` entries are refused naming the field.

use crate::common;

use common::{assert_field, rejected};
use splinerod::{run, RunResult, Scene};

fn drape(friction: f64, obstacle: &str) -> RunResult {
    let text = std::fs::read_to_string("scenes/drape_sphere.toml").expect("scene");
    let text = text.replace("friction = 0.5", &format!("friction = {friction}"));
    let text = match obstacle {
        "capsule" => text.replace(
            "kind = \"sphere\"\ncentre = [0.0, 0.0, 0.0]",
            "kind = \"capsule\"\na = [0.0, 0.0, -0.2]\nb = [0.0, 0.0, 0.2]",
        ),
        _ => text,
    };
    run(&Scene::from_toml(&text).expect("drape scene")).expect("drape runs")
}

/// Height of the rope's midpoint at the end, m.
fn middle_height(r: &RunResult) -> f64 {
    let p = &r.probes[1];
    p.positions[p.positions.len() - 1][1]
}

#[test]
fn friction_above_the_capstan_threshold_holds_a_draped_rope() {
    // Threshold ln(1.8)/π = 0.19 (scene comment); 0.3 holds, 0.1 slides off.
    for obstacle in ["sphere", "capsule"] {
        let held = drape(0.3, obstacle);
        assert!(
            middle_height(&held) > 0.05,
            "{obstacle}: {}",
            middle_height(&held)
        );
        assert!(
            held.energy["kinetic"] < 1e-4,
            "{obstacle}: {:?}",
            held.energy
        );
        let c = held.contact.expect("contact statistics");
        let clearance = c.min_clearance_ratio.expect("touching");
        assert!(clearance >= 0.95, "{obstacle}: clearance {clearance}");
        // Held at rest, the rope presses on the obstacle with its whole weight
        // (JSON `obstacle_forces`: penalty and friction).
        let weight = 0.1 * 1.0 * 9.81;
        let [fx, fy, fz] = held.obstacle_forces[0];
        assert!(
            (fy + weight).abs() < 0.01 * weight,
            "{obstacle}: {fy} N vs {weight}"
        );
        assert!(
            fx.hypot(fz) < 0.02 * weight,
            "{obstacle}: sideways {fx}, {fz}"
        );
        let slid = drape(0.1, obstacle);
        assert!(
            middle_height(&slid) < -1.0,
            "{obstacle}: {}",
            middle_height(&slid)
        );
    }
}

const SCENE: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 8
radius = 0.01
[contact]
stiffness = 1e4
[[obstacles]]
kind = "sphere"
centre = [0.0, -0.5, 0.0]
radius = 0.1
[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.1
"#;

#[test]
fn bad_obstacles_name_the_field() {
    let cases = [
        ("radius = 0.1", "radius = -0.1", "obstacles[0].radius"),
        ("radius = 0.1", "radius = nan", "obstacles[0].radius"),
        (
            "radius = 0.1",
            "radius = 0.1\nfriction = -0.2",
            "obstacles[0].friction",
        ),
        (
            "radius = 0.1",
            "radius = 0.1\nfriction = nan",
            "obstacles[0].friction",
        ),
        (
            "centre = [0.0, -0.5, 0.0]",
            "centre = [0.0, inf, 0.0]",
            "obstacles[0].centre",
        ),
        ("kind = \"sphere\"", "kind = \"cube\"", "cube"),
        ("radius = 0.1", "radius = 0.1\ncolour = 2", "colour"),
        (
            "kind = \"sphere\"\ncentre = [0.0, -0.5, 0.0]",
            "kind = \"capsule\"\na = [0.0, 0.0, 0.0]\nb = [0.0, 0.0, 0.0]",
            "obstacles[0].b",
        ),
        (
            "kind = \"sphere\"\ncentre = [0.0, -0.5, 0.0]\nradius = 0.1",
            "kind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 0.0]",
            "obstacles[0].normal",
        ),
        ("[contact]\nstiffness = 1e4\n", "", "obstacles[0]"),
    ];
    for (from, to, field) in cases {
        assert!(SCENE.contains(from), "{from}");
        let message = rejected(&SCENE.replace(from, to));
        assert_field(&message, field);
    }
    assert!(Scene::from_toml(SCENE).is_ok());
}

#[test]
fn a_thread_is_pulled_through_a_ring_of_capsules() {
    let scene = Scene::load("scenes/suture_ring.toml").expect("suture scene");
    let result = run(&scene).expect("suture runs");
    let c = result.contact.expect("contact statistics");
    assert!(c.max_obstacle_contacts > 0, "{c:?}");
    assert!(c.min_clearance_ratio.expect("touching") >= 0.95, "{c:?}");
    // The free end's last passage of the ring's plane x = 0.5 is through its opening
    // (radius 0.03 less the capsules' and the thread's radii), and it stays beyond.
    let free = &result.probes[0];
    let mut last = None;
    for w in free.positions.windows(2) {
        if (w[0][0] - 0.5) * (w[1][0] - 0.5) < 0.0 {
            last = Some(w[1]);
        }
    }
    let through = last.expect("the free end crossed the ring's plane");
    assert!(through[1].hypot(through[2]) < 0.02, "{through:?}");
    let end = free.positions[free.positions.len() - 1];
    assert!(end[0] > 0.55, "{end:?}");
}
