//! Moving obstacles: a rope lying across a conveyor (a plane sliding along itself at
//! 0.1 m/s) is carried along by friction at the belt's speed, and stays put without
//! friction; a sphere driven into a hanging rope pushes it aside without passing through.
//! Figures: `cargo test --release --test integration moving_obstacles:: -- --nocapture`.

use splinerod::{run, Scene};

const BELT: f64 = 0.1;

fn conveyor(friction: f64) -> String {
    format!(
        "[rod]\nrest_length = 0.5\nlinear_density = 0.05\nstretch_stiffness = 200.0\n\
         bending_stiffness = 1e-4\ndamping = 0.5\ncontrol_points = 12\nradius = 0.005\n\
         start = [0.0, 0.005, -0.25]\nend = [0.0, 0.005, 0.25]\n\
         [contact]\nstiffness = 1e4\nfriction = {friction}\n\
         [[obstacles]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\n\
         path = [[0.0, 0.0, 0.0, 0.0], [0.5, 0.0, 0.0, 0.0], [3.5, {end}, 0.0, 0.0]]\n\
         [solver]\nmethod = \"implicit-euler\"\ndt = 0.005\nduration = 3.5\n\
         [output]\nprobes = [0.5]\n",
        end = BELT * 3.0
    )
}

/// Speed along x of the probed midpoint over the last 0.5 s, and where it ended.
fn carried(friction: f64) -> (f64, f64) {
    let result = run(&Scene::from_toml(&conveyor(friction)).expect("scene")).expect("run");
    let probe = &result.probes[0];
    let n = probe.t.len();
    let (t0, t1) = (probe.t[n - 101], probe.t[n - 1]);
    let (x0, x1) = (probe.positions[n - 101][0], probe.positions[n - 1][0]);
    ((x1 - x0) / (t1 - t0), x1)
}

#[test]
fn a_conveyor_carries_a_rope_by_friction() {
    let (speed, x) = carried(0.5);
    let (still, x_still) = carried(0.0);
    println!(
        "with friction 0.5: {speed:.6} m/s (belt {BELT}), at x = {x:.4} m; without: {still:.2e} m/s at x = {x_still:.2e} m"
    );
    assert!((speed / BELT - 1.0).abs() < 0.01, "{speed}");
    assert!(x > 0.25, "{x}");
    assert!(
        still.abs() < 1e-6 && x_still.abs() < 1e-6,
        "{still}, {x_still}"
    );
}

#[test]
fn a_moving_sphere_pushes_a_hanging_rope_aside() {
    let text = "[rod]\nrest_length = 1.0\nlinear_density = 0.05\nstretch_stiffness = 500.0\n\
        bending_stiffness = 1e-4\ndamping = 1.0\ncontrol_points = 24\nradius = 0.005\n\
        start = [0.0, 0.0, 0.0]\nend = [0.0, -1.0, 0.0]\n\
        [[pins]]\nat = 0.0\n\
        [contact]\nstiffness = 1e5\nfriction = 0.2\n\
        [[obstacles]]\nkind = \"sphere\"\ncentre = [-0.2, -0.6, 0.0]\nradius = 0.05\n\
        path = [[0.0, 0.0, 0.0, 0.0], [2.0, 0.4, 0.0, 0.0]]\ninterpolation = \"smooth\"\n\
        [solver]\nmethod = \"implicit-euler\"\ndt = 0.005\nduration = 2.0\n\
        [output]\nsamples = 41\n";
    let result = run(&Scene::from_toml(text).expect("scene")).expect("run");
    let clearance = result
        .contact
        .and_then(|c| c.min_clearance_ratio)
        .expect("the sphere touches the rope");
    // The sphere ends at x = 0.2: the rope's lower part is pushed to its right side.
    let bottom = result.samples.positions[40];
    println!(
        "min clearance {clearance:.3}; rope end at x = {:.3} m",
        bottom[0]
    );
    assert!(clearance >= 0.95, "{clearance}");
    assert!(bottom[0] > 0.2, "{bottom:?}");
    // Bad input names the field.
    let bad = text.replace("[2.0, 0.4, 0.0, 0.0]", "[-1.0, 0.4, 0.0, 0.0]");
    let error = Scene::from_toml(&bad)
        .and_then(|s| run(&s))
        .expect_err("bad path")
        .to_string();
    assert!(error.contains("obstacles[0].path[1]"), "{error}");
}
