//! Coulomb friction on the floor: a rod sliding on it stops after v²/(2 μ g), and does
//! not move at all when μ is large enough to hold it on a slope.

use splinerod::{Real, Scene};

/// A 0.2 m rod of radius 1 cm lying on the floor y = −1 (at its resting gap), gravity
/// `g`, friction `mu`.
fn rod_on_floor(mu: Real, gravity: [Real; 3]) -> Scene {
    // Resting gap: the penalty's onset layer carries the weight, (k/2δ)(δ − g)² = μg·2r.
    let (k, delta, r): (Real, Real, Real) = (1e5, 1e-3, 0.01);
    let weight = 0.1 * 9.81 * 2.0 * r;
    let y = -1.0 + r + delta - (2.0 * delta * weight / k).sqrt();
    let text = format!(
        "[rod]\nrest_length = 0.2\nlinear_density = 0.1\nstretch_stiffness = 1000.0\n\
         control_points = 6\nstart = [0.0, {y}, 0.0]\nend = [0.2, {y}, 0.0]\nradius = {r}\n\
         [world]\ngravity = {gravity:?}\n\
         [contact]\nstiffness = {k}\nfloor = -1.0\nfriction = {mu}\n\
         [solver]\nmethod = \"implicit-euler\"\ndt = 0.001\nduration = 1.0\n"
    );
    Scene::from_toml(&text).unwrap()
}

#[test]
fn a_sliding_rod_stops_after_the_coulomb_distance() {
    let (mu, v0, g) = (0.3, 0.5, 9.81);
    let scene = rod_on_floor(mu, [0.0, -g, 0.0]);
    let mut sim = scene.build().unwrap();
    sim.system.rod.velocities.iter_mut().for_each(|v| v.x = v0);
    let start = sim.system.rod.point(0.1).unwrap().x;
    let mut stopped_at = None;
    for _ in 0..1000 {
        sim.step(0.001).unwrap();
        let v = sim.system.rod.velocity(0.1).unwrap().x;
        if v.abs() < 1e-2 && stopped_at.is_none() {
            stopped_at = Some(sim.time);
        }
    }
    let travelled = sim.system.rod.point(0.1).unwrap().x - start;
    let expected = v0 * v0 / (2.0 * mu * g);
    println!(
        "slid {travelled:.5} m (Coulomb: {expected:.5} m), stopped at t = {:?} s (Coulomb: {:.4} s)",
        stopped_at,
        v0 / (mu * g)
    );
    assert!(
        (travelled - expected).abs() <= 0.02 * expected,
        "{travelled} vs {expected}"
    );
    let t = stopped_at.expect("never stopped");
    assert!((t - v0 / (mu * g)).abs() <= 0.03 * v0 / (mu * g), "{t}");
}

#[test]
fn friction_holds_a_rod_on_a_slope_and_without_it_the_rod_slides() {
    // Gravity tilted by 10° along x: tan 10° = 0.176 < μ = 0.3 holds, μ = 0 does not.
    let angle: Real = 10f64.to_radians();
    let g = [9.81 * angle.sin(), -9.81 * angle.cos(), 0.0];
    for (mu, holds) in [(0.3, true), (0.0, false)] {
        let scene = rod_on_floor(mu, g);
        let mut sim = scene.build().unwrap();
        let start = sim.system.rod.point(0.1).unwrap().x;
        for _ in 0..300 {
            sim.step(0.001).unwrap();
        }
        let moved = sim.system.rod.point(0.1).unwrap().x - start;
        println!("μ = {mu}: moved {moved:.2e} m in 0.3 s");
        // Sliding freely it moves g sin θ t²/2 = 0.077 m.
        if holds {
            assert!(moved.abs() < 1e-3, "μ = {mu}: moved {moved}");
        } else {
            assert!(moved > 0.05, "μ = {mu}: moved only {moved}");
        }
    }
}
