//! A heavy rigid body welded to a light stiff cable hanging from a fixed pin: its
//! small-amplitude period against the physical pendulum's 2π√((I + M l²)/(M g l)).
//! `cargo run --release --example body_pendulum -- [dt] [weld: 1|0] [theta0]`.

use splinerod::{Scene, Simulation};

fn scene(dt: f64, weld: bool, theta: f64) -> String {
    let (s, c) = (theta.sin(), theta.cos());
    let (l, d) = (1.0, 0.1);
    format!(
        r#"
[rod]
rest_length = {l}
linear_density = 0.02
stretch_stiffness = 1e5
bending_stiffness = 100.0
control_points = 10
start = [0.0, 0.0, 0.0]
end = [{x}, {y}, 0.0]

[[pins]]
at = 0.0

[[pins]]
at = 1.0
clamp = {weld}
body = "bob"

[[bodies]]
name = "bob"
mass = 2.0
inertia = [0.01, 0.01, 0.01]
position = [{bx}, {by}, 0.0]

[world]
gravity = [0.0, -9.81, 0.0]

[solver]
method = "implicit-euler"
dt = {dt}
duration = 5.0
"#,
        x = l * s,
        y = -l * c,
        bx = (l + d) * s,
        by = -(l + d) * c,
    )
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let dt: f64 = args.get(1).map_or(Ok(1e-3), |a| a.parse())?;
    let weld = args.get(2).is_none_or(|a| a == "1");
    let theta: f64 = args.get(3).map_or(Ok(0.05), |a| a.parse())?;
    let text = scene(dt, weld, theta);
    let scene = Scene::from_toml(&text)?;
    let mut sim: Simulation = scene.build()?;
    let (mut last, mut crossings, mut iters) =
        (sim.system.bodies.bodies[0].position.x, Vec::new(), 0);
    let steps = (5.0 / dt).round() as usize;
    let start = std::time::Instant::now();
    for _ in 0..steps {
        let t0 = sim.time;
        let report = sim.step(dt)?;
        iters += report.solver.newton_iterations;
        let x = sim.system.bodies.bodies[0].position.x;
        if last > 0.0 && x <= 0.0 {
            crossings.push(t0 + dt * last / (last - x));
        }
        last = x;
    }
    let b = &sim.system.bodies.bodies[0];
    let (m, i, g, l): (f64, f64, f64, f64) = (2.0, 0.01, 9.81, 1.1);
    let exact = 2.0 * std::f64::consts::PI * ((i + m * l * l) / (m * g * l)).sqrt();
    let periods: Vec<f64> = crossings.windows(2).map(|w| w[1] - w[0]).collect();
    let mean = periods.iter().sum::<f64>() / periods.len().max(1) as f64;
    println!("crossings {:?}", crossings);
    println!("period {mean:.6} exact {exact:.6} rel {:.3e}; newton/step {:.2}; {:.2} s; body {:?} w {:?}", mean / exact - 1.0, iters as f64 / steps as f64, start.elapsed().as_secs_f64(), b.position, b.angular_velocity);
    Ok(())
}
