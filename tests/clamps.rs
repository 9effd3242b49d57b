//! Exact clamps and sliding pins (projected constraints):
//!
//! * a clamp at an end of a rod with clamped knots holds the tangent's direction
//!   exactly (to round-off) through a dynamic run and a static solve, and the clamp's
//!   force is the rod's weight and its moment the weight's, W L / 2;
//! * a pin sliding along an axis moves freely along it and holds across it: a rod pulled
//!   by an end load along a rail stretches to the Green–Lagrange tension, the rail takes
//!   no force along itself; across the rail the same load is held by the pin.

use splinerod::{run, Scene};

const CANTILEVER: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 1e4
bending_stiffness = 10.0
control_points = 12
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]

[[pins]]
at = 0.0
clamp = true

[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.5
"#;

/// Largest sideways component of the unit tangent at s = 0 over a run (from the
/// sampled positions: the first two control points are the first samples' chord).
fn tangent_deviation(text: &str) -> (f64, splinerod::RunResult) {
    let scene = Scene::from_toml(text).expect("scene");
    let mut sim = scene.build().expect("simulation");
    let mut worst: f64 = 0.0;
    let steps = if scene.solver.method == splinerod::scene::Method::Static {
        1
    } else {
        50
    };
    for _ in 0..steps {
        if steps == 1 {
            sim.settle().expect("settle");
        } else {
            sim.step(0.01).expect("step");
        }
        let t = sim.system.rod.tangent(0.0).expect("tangent").normalize();
        worst = worst.max(t.y.hypot(t.z));
    }
    (worst, run(&scene).expect("run"))
}

#[test]
fn an_exact_clamp_holds_the_tangent_to_round_off() {
    for method in ["implicit-euler", "implicit-midpoint", "bdf2", "static"] {
        let text = CANTILEVER.replace("\"implicit-euler\"", &format!("\"{method}\""));
        let (deviation, result) = tangent_deviation(&text);
        let (forces, positions) = (&result.pin_forces, &result.samples.positions);
        let tip = positions[positions.len() - 1];
        println!(
            "{method}: tangent off its axis by {deviation:.1e}, tip y {:.6e}, clamp force {:?}",
            tip[1], forces[0]
        );
        assert!(deviation < 1e-12, "{method}: {deviation:e}");
        assert_eq!(forces.len(), 1);
        if method == "static" {
            // The rod's weight pulls the clamp down; the tip sags q L⁴/(8 EI)
            // (Euler–Bernoulli).
            assert!((forces[0][1] + 0.981).abs() < 1e-9, "{:?}", forces[0]);
            let exact = 0.981 / (8.0 * 10.0);
            assert!(
                (tip[1] + exact).abs() < 1e-3 * exact,
                "{} vs {exact}",
                tip[1]
            );
            // The rod's weight turns the clamp by its moment, −W L / 2 about z.
            let torque = result.pin_torques[0];
            println!("clamp moment {torque:?} (−W L / 2 = −0.4905)");
            assert!((torque[2] + 0.4905).abs() < 1e-3 * 0.4905, "{torque:?}");
            assert!(torque[0].abs() + torque[1].abs() < 1e-9, "{torque:?}");
        }
    }
}

const RAIL: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 8
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.0]

[[pins]]
at = 0.0

[[pins]]
at = 1.0
slides_along = [1.0, 0.0, 0.0]

[[loads]]
at = 1.0
force = [2.0, 0.0, 0.0]

[world]
gravity = [0.0, 0.0, 0.0]

[solver]
method = "static"
"#;

#[test]
fn a_sliding_pin_is_free_along_its_rail_and_holds_across_it() {
    use splinerod::energies::Stretching;
    let result = run(&Scene::from_toml(RAIL).expect("scene")).expect("run");
    // Tension T = EA γ(γ² − 1)/2 = 2 N: solve for the stretch γ.
    let stretching = Stretching::new(100.0).expect("EA");
    let mut gamma: f64 = 1.0;
    for _ in 0..50 {
        gamma -= (stretching.tension(gamma) - 2.0) / (50.0 * (3.0 * gamma * gamma - 1.0));
    }
    let end = result.samples.positions[result.samples.positions.len() - 1];
    let rail = result.pin_forces[1];
    println!(
        "sliding end at x = {:.12} (exact γL = {gamma:.12}); rail force {rail:?}",
        end[0]
    );
    assert!((end[0] - gamma).abs() < 1e-9, "{} vs {gamma}", end[0]);
    assert!(rail.iter().all(|f| f.abs() < 1e-9), "{rail:?}");
    // Across the rail the pin holds the load and the rod does not stretch.
    let across = RAIL.replace(
        "slides_along = [1.0, 0.0, 0.0]",
        "slides_along = [0.0, 1.0, 0.0]",
    );
    let result = run(&Scene::from_toml(&across).expect("scene")).expect("run");
    let end = result.samples.positions[result.samples.positions.len() - 1];
    let held = result.pin_forces[1];
    assert!(
        (end[0] - 1.0).abs() < 1e-12 && end[1].abs() < 1e-12,
        "{end:?}"
    );
    // The rod pulls its support with the 2 N the load pulls the rod.
    assert!((held[0] - 2.0).abs() < 1e-9, "{held:?}");
}

#[test]
fn a_bad_rail_names_the_field() {
    for (axis, field) in [
        ("[0.0, 0.0, 0.0]", "pins[1].slides_along"),
        ("[nan, 0.0, 0.0]", "pins[1].slides_along"),
    ] {
        let text = RAIL.replace(
            "slides_along = [1.0, 0.0, 0.0]",
            &format!("slides_along = {axis}"),
        );
        let error = Scene::from_toml(&text)
            .and_then(|s| run(&s))
            .expect_err(axis)
            .to_string();
        assert!(error.contains(field), "{axis}: {error}");
    }
}
