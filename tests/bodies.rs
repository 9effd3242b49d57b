//! Rigid bodies (`[[bodies]]`, pins with `body`) against exact answers:
//!
//! * a heavy body (≥ 50 × the cable's mass) welded to a light stiff cable hanging from
//!   a fixed pin swings with the physical pendulum's small-amplitude period
//!   2π√((I + M l²)/(M g l)) within 0.3 % (in the plane and in 3-D with another axis);
//! * a body welded to a horizontal cantilever's tip, static: the tip deflects and turns
//!   as the linear beam under the tip force Mg and moment Mg·d (and the rod's weight)
//!   within 1e-4; the rod's wrench on the body balances its weight;
//! * bad input names the field (library and command line, exit 2).

use crate::common::cli::refused_scene;
use crate::common::{assert_field, rejected};
use splinerod::{run, Scene};
use std::f64::consts::PI;

/// A pendulum: a cable of length `l` (density `mu`) from a fixed pin at the origin,
/// welded to a body (`mass`, principal `inertia`) whose centre of mass is `d` beyond
/// the cable's end; gravity along −`down`, let go `theta` rad towards `side`.
struct Pendulum {
    l: f64,
    mu: f64,
    d: f64,
    mass: f64,
    inertia: [f64; 3],
    down: [f64; 3],
    side: [f64; 3],
    theta: f64,
    dt: f64,
    duration: f64,
    method: &'static str,
}

impl Pendulum {
    fn at(&self, r: f64) -> [f64; 3] {
        let (s, c) = (self.theta.sin(), self.theta.cos());
        let v = |k: usize| r * (s * self.side[k] - c * self.down[k]);
        [v(0), v(1), v(2)]
    }

    fn scene(&self) -> String {
        let (end, com) = (self.at(self.l), self.at(self.l + self.d));
        let g = self.down.map(|x| -9.81 * x);
        format!(
            r#"
[rod]
rest_length = {l}
linear_density = {mu}
stretch_stiffness = 1e5
bending_stiffness = 100.0
control_points = 10
start = [0.0, 0.0, 0.0]
end = {end:?}

[[pins]]
at = 0.0

[[pins]]
at = 1.0
clamp = true
body = "bob"

[[bodies]]
name = "bob"
mass = {mass}
inertia = {inertia:?}
position = {com:?}

[world]
gravity = {g:?}

[solver]
method = "{method}"
dt = {dt}
duration = {duration}
"#,
            l = self.l,
            mu = self.mu,
            mass = self.mass,
            inertia = self.inertia,
            dt = self.dt,
            duration = self.duration,
            method = self.method,
        )
    }

    /// The mean period of the body's swing (times its offset along `side` falls through
    /// zero), and the formula's.
    fn periods(&self, axis: usize) -> (f64, f64) {
        let result = run(&Scene::from_toml(&self.scene()).expect("scene")).expect("run");
        let track = &result.bodies[0];
        let offset = |p: &[f64; 3]| (0..3).map(|k| p[k] * self.side[k]).sum::<f64>();
        let mut crossings = Vec::new();
        for (w, t) in track.position.windows(2).zip(track.t.windows(2)) {
            let (a, b) = (offset(&w[0]), offset(&w[1]));
            if a > 0.0 && b <= 0.0 {
                crossings.push(t[0] + (t[1] - t[0]) * a / (a - b));
            }
        }
        assert!(crossings.len() >= 2, "{crossings:?}");
        let measured =
            (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as f64;
        let arm = self.l + self.d;
        let i = self.inertia[axis] + self.mass * arm * arm;
        (measured, 2.0 * PI * (i / (self.mass * 9.81 * arm)).sqrt())
    }

    /// The largest swing (offset along `side`) in the first and in the last period.
    fn amplitudes(&self, period: f64) -> (f64, f64) {
        let result = run(&Scene::from_toml(&self.scene()).expect("scene")).expect("run");
        let track = &result.bodies[0];
        let offset = |p: &[f64; 3]| (0..3).map(|k| p[k] * self.side[k]).sum::<f64>();
        let end = track.t[track.t.len() - 1];
        let swing = |from: f64, to: f64| {
            let samples = track.t.iter().zip(&track.position);
            let inside = samples.filter(|(t, _)| (from..to).contains(*t));
            inside.map(|(_, p)| offset(p).abs()).fold(0.0, f64::max)
        };
        (swing(0.0, period), swing(end - period, end + 1.0))
    }

    /// The period of the rigid compound of the body and the cable (a uniform rod).
    fn compound(&self, axis: usize) -> f64 {
        let (arm, m) = (self.l + self.d, self.mu * self.l);
        let i = self.inertia[axis] + self.mass * arm * arm + m * self.l * self.l / 3.0;
        let k = 9.81 * (self.mass * arm + m * self.l / 2.0);
        2.0 * PI * (i / k).sqrt()
    }
}

/// The planar pendulum: a 1 kg body 0.1 m beyond a 1 m cable of 0.02 kg/m (50 × its
/// mass), let go 0.04 rad from the vertical, implicit Euler with 2 ms steps for 4.6 s.
fn planar() -> Pendulum {
    Pendulum {
        l: 1.0,
        mu: 0.02,
        d: 0.1,
        mass: 1.0,
        inertia: [0.01, 0.01, 0.01],
        down: [0.0, 1.0, 0.0],
        side: [1.0, 0.0, 0.0],
        theta: 0.04,
        dt: 2e-3,
        duration: 4.6,
        method: "implicit-euler",
    }
}

#[test]
fn a_heavy_body_on_a_light_cable_swings_as_a_physical_pendulum() {
    let planar = planar();
    let spatial = Pendulum {
        l: 0.6,
        mu: 0.05,
        d: 0.25,
        mass: 5.0,
        inertia: [0.02, 0.01, 0.03],
        down: [0.0, 0.0, 1.0],
        side: [0.0, 1.0, 0.0],
        theta: 0.03,
        dt: 1e-3,
        duration: 3.6,
        method: "implicit-euler",
    };
    for (name, p, axis) in [("planar", planar, 2), ("spatial", spatial, 0)] {
        let (measured, exact) = p.periods(axis);
        let (error, compound) = (measured / exact - 1.0, measured / p.compound(axis) - 1.0);
        println!(
            "{name}: period {measured:.6} s, formula {exact:.6} s, relative {error:.2e}; \
             against the rigid compound with the cable's mass {compound:.2e}"
        );
        assert!(error.abs() < 3e-3, "{name}: {measured} vs {exact}");
        assert!(compound.abs() < 5e-4, "{name}: {compound}");
    }
}

#[test]
fn bdf2_swings_the_pendulum_on_with_its_period_and_amplitude() {
    // The planar pendulum of the test above (h = 5 ms) with BDF2: the same period (its
    // 2e-4 from the rigid compound is the cable's compliance, not the time step), and
    // the swing kept where implicit Euler's numerical damping eats 11 % in 3 periods.
    let euler = Pendulum {
        dt: 5e-3,
        duration: 6.5,
        ..planar()
    };
    let bdf2 = Pendulum {
        method: "bdf2",
        ..euler
    };
    let mut kept = [0.0; 2];
    let mut off = [0.0; 2];
    for (k, p) in [euler, bdf2].iter().enumerate() {
        let (measured, _) = p.periods(2);
        off[k] = measured / p.compound(2) - 1.0;
        let (first, last) = p.amplitudes(measured);
        kept[k] = last / first;
        println!(
            "{}: period {measured:.6} s, against the compound {:.2e}; swing {first:.6} → {last:.6} m ({:.4} kept after 3 periods)",
            p.method, off[k], kept[k]
        );
    }
    assert!(off[1].abs() < 5e-4, "bdf2 period: {}", off[1]);
    assert!((off[1] - off[0]).abs() < 5e-5, "{off:?}");
    assert!(kept[1] > 0.999, "bdf2 keeps {}", kept[1]);
    assert!(kept[0] < 0.95, "{kept:?}");
}

/// A horizontal cantilever (length 1.5, EI 1e3, density `mu`) clamped at x = 0 with a
/// body (`mass`) welded to its tip, its centre of mass `d` beyond the tip; gravity
/// along −`down` (y or z); static.
fn cantilever(mass: f64, d: f64, points: usize, down: usize) -> String {
    let mut g = [0.0; 3];
    g[down] = -9.81;
    format!(
        r#"
[rod]
rest_length = 1.5
linear_density = 0.01
stretch_stiffness = 1e7
bending_stiffness = 1e3
control_points = {points}
start = [0.0, 0.0, 0.0]
end = [1.5, 0.0, 0.0]

[[pins]]
at = 0.0
clamp = true

[[pins]]
at = 1.0
clamp = true
body = "block"

[[bodies]]
name = "block"
mass = {mass}
inertia = [[0.001, 0.0, 0.0], [0.0, 0.002, 0.0], [0.0, 0.0, 0.002]]
position = [{x}, 0.0, 0.0]

[world]
gravity = {g:?}

[solver]
method = "static"
"#,
        x = 1.5 + d
    )
}

#[test]
fn a_body_welded_to_a_cantilever_deflects_it_as_the_linear_beam() {
    let (l, mu, ei, g) = (1.5_f64, 0.01, 1e3, 9.81);
    for (mass, d, points, down) in [(0.05, 0.2, 12, 1), (0.1, -0.1, 20, 1), (0.03, 0.3, 7, 2)] {
        let result = run(&Scene::from_toml(&cantilever(mass, d, points, down)).expect("scene"))
            .expect("run");
        let (f, moment, w) = (mass * g, mass * g * d, mu * g);
        let deflection =
            f * l.powi(3) / (3.0 * ei) + moment * l * l / (2.0 * ei) + w * l.powi(4) / (8.0 * ei);
        let slope = f * l * l / (2.0 * ei) + moment * l / ei + w * l.powi(3) / (6.0 * ei);
        let tip = result.samples.positions.last().expect("tip");
        let track = &result.bodies[0];
        let turn = track.orientation.last().expect("pose");
        // Gravity along −y turns the tip about −z; along −z, about +y.
        let angle = if down == 1 { -turn[2] } else { turn[1] };
        let (de, se) = (-tip[down] / deflection - 1.0, angle / slope - 1.0);
        let force = track.force.last().expect("force");
        let torque = track.torque.last().expect("torque");
        println!(
            "M {mass}, d {d}, {points} points: deflection {:.9e} (beam {deflection:.9e}, {de:.1e}), \
             turn {angle:.9e} (beam {slope:.9e}, {se:.1e}); wrench {force:?} {torque:?}",
            -tip[down]
        );
        assert!(de.abs() < 1e-4 && se.abs() < 1e-4, "{de} {se}");
        // The rod holds the body's weight at its centre of mass: no torque about it.
        assert!((force[down] - f).abs() < 1e-9 * f, "{force:?}");
        let torque = torque.iter().map(|t| t.abs()).fold(0.0, f64::max);
        assert!(torque < 1e-8 * f * l, "{torque}");
    }
}

/// The pendulum scene with `from` replaced by `to`.
fn pendulum_with(from: &str, to: &str) -> String {
    let text = std::fs::read_to_string("scenes/body_pendulum.toml").expect("scene");
    assert!(text.contains(from), "{from}");
    text.replacen(from, to, 1)
}

#[test]
fn bad_bodies_are_refused_naming_the_field() {
    let cases = [
        ("mass = 2.0", "mass = 0.0", "bodies[0].mass"),
        ("mass = 2.0", "mass = -1.0", "bodies[0].mass"),
        (
            "inertia = [0.01, 0.01, 0.01]",
            "inertia = [0.01, 0.0, 0.01]",
            "bodies[0].inertia",
        ),
        (
            "inertia = [0.01, 0.01, 0.01]",
            "inertia = [0.01, 0.01, 0.03]",
            "bodies[0].inertia",
        ),
        (
            "inertia = [0.01, 0.01, 0.01]",
            "inertia = [[0.01, 0.005, 0.0], [0.0, 0.01, 0.0], [0.0, 0.0, 0.01]]",
            "bodies[0].inertia",
        ),
        (
            "position = [0.054977086197746166",
            "position = [nan",
            "bodies[0].position",
        ),
        ("body = \"bob\"", "body = \"bub\"", "pins[1].body"),
        (
            "inertia = [0.01, 0.01, 0.01]",
            "inertia = [0.01, 0.01]",
            "bodies[0].inertia",
        ),
        (
            "name = \"bob\"",
            "name = \"bob\"\norientation = [1e308, 1e308, 0.0]",
            "bodies[0].orientation",
        ),
        (
            "method = \"implicit-euler\"",
            "method = \"implicit-midpoint\"",
            "solver.method",
        ),
        ("name = \"bob\"", "name = \"\"", "bodies[0].name"),
        (
            "mass = 2.0",
            "mass = 2.0\nspheres = [[0.0, 0.0, 0.0, 0.0]]",
            "bodies[0].spheres[0][3]",
        ),
        (
            "mass = 2.0",
            "mass = 2.0\ncapsules = [[0.0, nan, 0.0, 0.1, 0.0, 0.0, 0.1]]",
            "bodies[0].capsules[0]",
        ),
        (
            "clamp = true\n",
            "clamp = true\npath = [[0.0, 0.05, -1.0, 0.0]]\n",
            "pins[1].body",
        ),
    ];
    for (from, to, field) in cases {
        let text = pendulum_with(from, to);
        assert_field(&rejected(&text), field);
        let line = refused_scene("bodies-bad-input", &text);
        assert_field(&line, field);
    }
}

#[test]
fn sensitivities_of_a_scene_with_bodies_are_refused_naming_them() {
    let out = std::env::temp_dir().join(format!("splinerod-bodies-{}.json", std::process::id()));
    let out = out.to_str().expect("a UTF-8 path");
    let args = [
        "sensitivities",
        "scenes/body_pendulum.toml",
        "--params",
        "rod.bending_stiffness",
        "--json",
        out,
    ];
    let line = crate::common::cli::refused(&args);
    assert_field(&line, "bodies[0]");
}

#[test]
fn a_load_on_a_body_acts_at_its_centre_of_mass() {
    // The welded cantilever with 0.2 N more on the block: the beam under the tip force
    // Mg + F and the moment (Mg + F)·d.
    let (l, mu, ei, g, mass, d, extra) = (1.5_f64, 0.01, 1e3, 9.81, 0.05, 0.2, 0.2);
    let loaded = format!(
        "{}\n[[loads]]\nbody = \"block\"\nforce = [0.0, -{extra}, 0.0]\n",
        cantilever(mass, d, 12, 1)
    );
    let result = run(&Scene::from_toml(&loaded).expect("scene")).expect("run");
    let f = mass * g + extra;
    let deflection =
        f * l.powi(3) / (3.0 * ei) + f * d * l * l / (2.0 * ei) + mu * g * l.powi(4) / (8.0 * ei);
    let tip = result.samples.positions.last().expect("tip");
    let error = -tip[1] / deflection - 1.0;
    println!(
        "loaded block: deflection {:.9e} (beam {deflection:.9e}, {error:.1e})",
        -tip[1]
    );
    assert!(error.abs() < 1e-4, "{error}");
    let force = result.bodies[0].force.last().expect("force");
    assert!((force[1] - f).abs() < 1e-9 * f, "{force:?}");
    // A body's load takes no material point.
    let at = loaded.replace(
        "body = \"block\"\nforce",
        "body = \"block\"\nat = 0.5\nforce",
    );
    assert_field(&rejected(&at), "loads[0].body");
}

#[test]
fn a_clamp_a_body_holds_cannot_be_posed() {
    let scene = Scene::from_toml(&pendulum_with("", "")).expect("scene");
    let mut system = scene.build_system().expect("system");
    let k = system
        .grippers
        .iter()
        .position(|g| g.pin == 1)
        .expect("gripper");
    let pose = splinerod::world::gripper::Pose::from_rotation_vector(
        nalgebra::Vector3::new(0.1, 0.0, 0.0),
        nalgebra::Vector3::zeros(),
        &system.grippers[k].axis,
    );
    let before = system.pins.clone();
    let e = system
        .set_gripper_pose(k, pose)
        .expect_err("the body holds it");
    assert_eq!(e.field_name(), Some("pins[1].body"));
    assert!(e.to_string().contains("bob"), "{e}");
    assert_eq!(system.pins, before, "nothing moved");
}
