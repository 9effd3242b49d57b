//! Rigid bodies' contact shapes (spheres and capsules) on the floor and obstacles,
//! against exact answers: at rest a shape sinks by the penalty's 1 % of its radius
//! under the weight it carries; with Coulomb friction (`[contact] friction`,
//! `[[obstacles]] friction`):
//!
//! * a block sliding on the floor stops after v₀²/(2μg) (implicit Euler: less v₀h/2);
//! * a ball thrown without spin rolls off at 5/7 of its speed (angular momentum about
//!   the contact point is conserved), with ω r = v;
//! * a block on an incline stays where tan α < μ and slides with g (sin α − μ cos α)
//!   where tan α > μ; without friction it slides with g sin α.

use splinerod::{run, RunResult, Scene};

const G: f64 = 9.81;

/// A 1 kg body with `shapes` at `position` (rotation vector `orientation`), moving at
/// `velocity`, beside a pinned cable it does not touch; `surfaces` (TOML: `[contact]` and
/// `[[obstacles]]`); implicit Euler with `dt` for `duration` s.
fn body_scene(
    shapes: &str,
    (position, orientation, velocity): ([f64; 3], [f64; 3], [f64; 3]),
    surfaces: &str,
    (dt, duration): (f64, f64),
) -> String {
    format!(
        r#"
[rod]
rest_length = 1.0
linear_density = 0.01
stretch_stiffness = 1e4
radius = 0.005
control_points = 8
start = [0.0, 2.0, 5.0]
end = [1.0, 2.0, 5.0]

[[pins]]
at = 0.0

[[pins]]
at = 1.0

[[bodies]]
name = "block"
mass = 1.0
inertia = [0.004, 0.004, 0.004]
position = {position:?}
orientation = {orientation:?}
velocity = {velocity:?}
{shapes}

{surfaces}

[world]
gravity = [0.0, -{G}, 0.0]

[solver]
method = "implicit-euler"
dt = {dt}
duration = {duration}
"#
    )
}

/// Four small spheres (radius 0.02) under the corners of a 0.2 × 0.2 block, 0.05 below
/// its centre of mass: the body rests on a surface a little less than 0.07 below it,
/// each foot sunk by 1 % of its radius under a quarter of the weight
/// ([`rest_height`]).
const FEET: &str = "spheres = [[-0.1, -0.05, -0.1, 0.02], [0.1, -0.05, -0.1, 0.02], \
                    [-0.1, -0.05, 0.1, 0.02], [0.1, -0.05, 0.1, 0.02]]";

/// How far above a surface the block of [`FEET`] rests with `load` of its weight across
/// it (cos α on an incline): the feet's penalty sinks them by 1 % of 0.02 m under the
/// whole weight on one foot.
fn rest_height(load: f64) -> f64 {
    0.07 - 0.01 * 0.02 * load / 4.0
}

fn last(track: &[[f64; 3]]) -> [f64; 3] {
    track[track.len() - 1]
}

fn run_text(text: &str) -> RunResult {
    run(&Scene::from_toml(text).expect("scene")).expect("run")
}

#[test]
fn a_block_sliding_on_the_floor_stops_where_coulomb_says() {
    for (mu, v0, dt) in [(0.5, 1.0, 1e-3), (0.3, 2.0, 5e-4), (0.8, 0.5, 2e-3)] {
        let surfaces = format!("[contact]\nfloor = 0.0\nfriction = {mu}");
        let stop = v0 * v0 / (2.0 * mu * G);
        let text = body_scene(
            FEET,
            ([0.0, rest_height(1.0), 0.0], [0.0; 3], [v0, 0.0, 0.0]),
            &surfaces,
            (dt, 1.5 * v0 / (mu * G) + 0.2),
        );
        let result = run_text(&text);
        let track = &result.bodies[0];
        let (x, v) = (last(&track.position)[0], last(&track.velocity));
        // Implicit Euler's stopping distance: h Σ vₙ = v₀²/(2μg) − v₀h/2.
        let discrete = stop - 0.5 * v0 * dt;
        println!(
            "μ = {mu}, v₀ = {v0}, h = {dt}: stops at {x:.6} m (Coulomb {stop:.6}, implicit Euler {discrete:.6}), v {v:?}"
        );
        assert!((x - discrete).abs() < 2e-3 * stop, "{x} vs {discrete}");
        assert!(v.iter().all(|c| c.abs() < 1e-3), "{v:?}");
    }
}

#[test]
fn a_ball_thrown_without_spin_rolls_off_at_five_sevenths_of_its_speed() {
    // The scene's body (1 kg, inertia 0.004) is a solid ball of radius 0.1: 2/5 M r².
    let r = 0.1;
    let shapes = format!("spheres = [[0.0, 0.0, 0.0, {r}]]");
    let text = body_scene(
        &shapes,
        ([0.0, r, 0.0], [0.0; 3], [2.0, 0.0, 0.0]),
        "[contact]\nfloor = 0.0\nfriction = 0.4",
        (1e-3, 1.0),
    );
    let result = run_text(&text);
    let track = &result.bodies[0];
    let (v, w) = (last(&track.velocity), last(&track.angular_velocity));
    let exact = 2.0 * 5.0 / 7.0;
    println!(
        "rolls at {v:?} m/s, ω {w:?} rad/s (5/7 v₀ = {exact:.9}, ω r = {:.9})",
        -w[2] * r
    );
    assert!((v[0] - exact).abs() < 1e-4 * exact, "{v:?}");
    assert!(
        (-w[2] * r - v[0]).abs() < 1e-4 * exact,
        "ω r = {} vs v = {}",
        -w[2] * r,
        v[0]
    );
    assert!(w[0].abs() + w[1].abs() + v[2].abs() < 1e-9, "{v:?} {w:?}");
}

/// A body with `shapes` resting `height` above a plane through the origin tilted by
/// `alpha` about z, friction `mu`, released at rest; its displacement along the slope
/// (up positive) after `t` s.
fn on_incline(shapes: &str, height: f64, (alpha, mu): (f64, f64), (t, dt): (f64, f64)) -> f64 {
    let (s, c) = alpha.sin_cos();
    let normal = [-s, c, 0.0];
    let surfaces = format!(
        "[contact]\nfriction = {mu}\n\n[[obstacles]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = {normal:?}"
    );
    let start = normal.map(|n| height * n);
    let text = body_scene(
        shapes,
        (start, [0.0, 0.0, alpha], [0.0; 3]),
        &surfaces,
        (dt, t),
    );
    let result = run_text(&text);
    let end = last(&result.bodies[0].position);
    (0..3).map(|k| (end[k] - start[k]) * [c, s, 0.0][k]).sum()
}

#[test]
fn a_block_on_an_incline_sticks_below_the_friction_angle_and_slides_above() {
    let (t, dt) = (1.0, 1e-3);
    for (alpha, mu) in [
        (0.35_f64, 0.5),
        (0.2, 0.25),
        (0.6, 0.5),
        (0.5, 0.0),
        (0.7, 0.3),
    ] {
        let (s, c) = alpha.sin_cos();
        let moved = on_incline(FEET, rest_height(c), (alpha, mu), (t, dt));
        if alpha.tan() < mu {
            // Stuck, creeping at about slip_speed · tan α / μ (1e-3 m/s by default).
            let creep = 1e-3 * t * alpha.tan() / mu;
            println!("α = {alpha}, μ = {mu}: moved {moved:.3e} m (stuck, creep {creep:.3e})");
            assert!(moved.abs() < 1.5 * creep, "{moved}");
        } else {
            let a = G * (s - mu * c);
            // Implicit Euler from rest: h² a N(N+1)/2 = a t (t + h)/2.
            let exact = -0.5 * a * t * (t + dt);
            println!("α = {alpha}, μ = {mu}: slid {moved:.6} m (exact {exact:.6})");
            // Released, the block rocks forward on its compliant feet (the penalty's 1 %
            // sink; 1.4e-4 rad at α = 0.6), its feet sticking meanwhile: it gains about
            // 2 mm/s on the rigid block in the first steps, 0.2–0.4 % of the distance
            // after 1 s (dt 2e-3 … 2.5e-4). Without friction there is no rocking.
            let tolerance = if mu == 0.0 { 1e-9 } else { 5e-3 };
            assert!(
                (moved - exact).abs() < tolerance * exact.abs(),
                "{moved} vs {exact}"
            );
        }
    }
}

#[test]
fn a_ball_rolls_down_an_incline_at_five_sevenths_of_g_sin_alpha() {
    // Rolling without slipping needs μ ≥ (2/7) tan α; then a = (5/7) g sin α, whatever μ.
    let r = 0.1; // a solid ball, as in the test above
    let shapes = format!("spheres = [[0.0, 0.0, 0.0, {r}]]");
    let (t, dt) = (1.0, 1e-3);
    for (alpha, mu) in [(0.3_f64, 0.5), (0.5, 0.3)] {
        let rest = r - 0.01 * r * alpha.cos();
        let moved = on_incline(&shapes, rest, (alpha, mu), (t, dt));
        let exact = -0.5 * (5.0 / 7.0) * G * alpha.sin() * t * (t + dt);
        println!("α = {alpha}, μ = {mu}: rolled {moved:.7} m (exact {exact:.7})");
        assert!(
            (moved - exact).abs() < 1e-3 * exact.abs(),
            "{moved} vs {exact}"
        );
    }
}

#[test]
fn the_towed_block_slides_with_coulomb_friction_step_by_step() {
    // scenes/body_tow.toml: M = 2 kg, μ = 0.4, h = 5 ms. While the block slides its
    // equation of motion along x is M (v₊ − v)/h = F_x + μ (M g − F_y)·sign, with F the
    // cable's pull at the step's end and the normal force lagged by a step.
    let text = std::fs::read_to_string("scenes/body_tow.toml").expect("scene");
    let result = run_text(&text);
    let track = &result.bodies[0];
    let (mass, mu, h) = (2.0, 0.4, 0.005);
    let mut worst: f64 = 0.0;
    let mut checked = 0;
    for k in 2..track.t.len() - 1 {
        let (v, next) = (track.velocity[k][0], track.velocity[k + 1][0]);
        if v.abs() < 0.05 || next.abs() < 0.05 {
            continue; // starting or stopping: the feet may stick
        }
        let normal = mass * G - track.force[k][1];
        let friction = mu * normal * -v.signum();
        let inertia = mass * (next - v) / h;
        let off = (inertia - track.force[k + 1][0] - friction).abs() / (mu * mass * G);
        worst = worst.max(off);
        checked += 1;
    }
    let end = last(&track.position)[0];
    println!("{checked} sliding steps: Coulomb balance within {worst:.2e} of μMg; the block ends at x = {end:.5} m");
    assert!(checked > 300, "{checked}");
    assert!(worst < 1e-4, "{worst}");
    assert!((end + 0.6).abs() < 0.01, "{end}");
}

/// A body with `shapes` (TOML lines) dropped from `height` onto the floor at y = 0 beside
/// a cable pinned at both ends (which it does not touch); implicit Euler for 3 s.
fn dropped(shapes: &str, height: f64, orientation: [f64; 3]) -> RunResult {
    run_text(&dropped_text(shapes, height, orientation))
}

/// The scene of [`dropped`].
fn dropped_text(shapes: &str, height: f64, orientation: [f64; 3]) -> String {
    let start = ([3.0, height, 0.0], orientation, [0.0; 3]);
    body_scene(shapes, start, "[contact]\nfloor = 0.0", (0.002, 3.0))
}

#[test]
fn bodies_come_to_rest_on_the_floor_on_their_contact_shapes() {
    // A sphere of radius 0.1 at the centre of mass: at rest its weight sinks it by 1 %
    // of its radius (the penalty's stiffness), so the centre rests at 0.099 m.
    let ball = dropped("spheres = [[0.0, 0.0, 0.0, 0.1]]", 0.3, [0.0; 3]);
    let track = &ball.bodies[0];
    let (y, v) = (
        track.position.last().unwrap()[1],
        track.velocity.last().unwrap(),
    );
    println!("sphere: rests at {y:.9} m, velocity {v:?}");
    assert!(
        (y - 0.099).abs() < 1e-6 && v.iter().all(|c| c.abs() < 1e-5),
        "{y} {v:?}"
    );
    // A capsule dropped tilted lands on one end and settles flat on both: each end
    // carries half the weight, sinking by 0.5 % of the radius.
    let capsule = dropped(
        "capsules = [[-0.2, 0.0, 0.0, 0.2, 0.0, 0.0, 0.05]]",
        0.3,
        [0.0, 0.0, 0.2],
    );
    let track = &capsule.bodies[0];
    let (y, turn) = (
        track.position.last().unwrap()[1],
        track.orientation.last().unwrap(),
    );
    let v = track.velocity.last().unwrap();
    println!("capsule: rests at {y:.9} m, orientation {turn:?}, velocity {v:?}");
    assert!((y - 0.04975).abs() < 1e-6, "{y}");
    assert!(turn.iter().all(|c| c.abs() < 1e-6), "{turn:?}");
    // It fell straight down: no sideways force from a frictionless floor.
    assert!((track.position.last().unwrap()[0] - 3.0).abs() < 1e-9);
    // A static solve finds the same rest, from a start 1 cm up.
    let text = dropped_text("spheres = [[0.0, 0.0, 0.0, 0.1]]", 0.11, [0.0; 3])
        .replace("method = \"implicit-euler\"", "method = \"static\"");
    let result = run_text(&text);
    let y = result.bodies[0].position.last().unwrap()[1];
    println!("sphere, static: rests at {y:.12} m");
    assert!((y - 0.099).abs() < 1e-9, "{y}");
    // On obstacles: a capsule across a horizontal capsule obstacle (axis along z, top at
    // 0.6 m) rests on its middle, 0.6 + 0.05 − 0.0005 m; a ball on a sphere obstacle
    // (top at 0.6 m) at 0.6 + 0.1 − 0.001 m.
    for (shape, obstacle, rest) in [
        (
            "capsules = [[-0.2, 0.0, 0.0, 0.2, 0.0, 0.0, 0.05]]",
            "kind = \"capsule\"\na = [3.0, 0.5, -1.0]\nb = [3.0, 0.5, 1.0]\nradius = 0.1",
            0.6495,
        ),
        (
            "spheres = [[0.0, 0.0, 0.0, 0.1]]",
            "kind = \"sphere\"\ncentre = [3.0, 0.4, 0.0]\nradius = 0.2",
            0.699,
        ),
    ] {
        let text = format!(
            "{}\n[[obstacles]]\n{obstacle}\n",
            dropped_text(shape, 0.9, [0.0; 3])
        );
        let result = run_text(&text);
        let y = result.bodies[0].position.last().unwrap()[1];
        println!("{shape} on {obstacle:?}: rests at {y:.9} m");
        assert!((y - rest).abs() < 1e-6, "{y} vs {rest}");
    }
}
