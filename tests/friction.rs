//! Coulomb friction on the floor: a rod sliding on it stops after v²/(2 μ g), and does
//! not move at all when μ is large enough to hold it on a slope.

use splinerod::{Real, Scene};

/// A 0.2 m rod of radius 1 cm lying on the floor y = −1 (at its resting gap), gravity
/// `g`, friction `mu`.
fn rod_on_floor(mu: Real, gravity: [Real; 3]) -> Scene {
    let (k, r, y) = (1e5, 0.01, resting_height());
    let text = format!(
        "[rod]\nrest_length = 0.2\nlinear_density = 0.1\nstretch_stiffness = 1000.0\n\
         control_points = 6\nstart = [0.0, {y}, 0.0]\nend = [0.2, {y}, 0.0]\nradius = {r}\n\
         [world]\ngravity = {gravity:?}\n\
         [contact]\nstiffness = {k}\nfloor = -1.0\nfriction = {mu}\n\
         [solver]\nmethod = \"implicit-euler\"\ndt = 0.001\nduration = 1.0\n"
    );
    Scene::from_toml(&text).unwrap()
}

/// Height of the rod of [`rod_on_floor`] at rest on the floor y = −1: the penalty's
/// onset layer carries the weight, (k/2δ)(δ − g)² = μg·2r.
fn resting_height() -> Real {
    let (k, delta, r): (Real, Real, Real) = (1e5, 1e-3, 0.01);
    let weight = 0.1 * 9.81 * 2.0 * r;
    -1.0 + r + delta - (2.0 * delta * weight / k).sqrt()
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

/// A rod resting on a plane obstacle (y = −1) on the 10° slope of the test above, with
/// `[contact] friction = mu` and the extra lines `rod` and `obstacle` in their tables; how far
/// its middle moves in 0.3 s and where its control points end.
fn on_a_slope(mu: Real, rod: &str, obstacle: &str) -> (Real, Vec<[Real; 3]>) {
    let angle: Real = 10f64.to_radians();
    let g = [9.81 * angle.sin(), -9.81 * angle.cos(), 0.0];
    let y = resting_height();
    let text = format!(
        "[rod]\nrest_length = 0.2\nlinear_density = 0.1\nstretch_stiffness = 1000.0\n\
         control_points = 6\nstart = [0.0, {y}, 0.0]\nend = [0.2, {y}, 0.0]\nradius = 0.01\n{rod}\n\
         [world]\ngravity = {g:?}\n[contact]\nstiffness = 1e5\nfriction = {mu}\n\
         [[obstacles]]\nkind = \"plane\"\npoint = [0.0, -1.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\n{obstacle}\n\
         [solver]\nmethod = \"implicit-euler\"\ndt = 0.001\nduration = 0.3\n"
    );
    let scene = Scene::from_toml(&text).unwrap();
    let mut sim = scene.build().unwrap();
    let start = sim.system.rod.point(0.1).unwrap().x;
    for _ in 0..300 {
        sim.step(0.001).unwrap();
    }
    let moved = sim.system.rod.point(0.1).unwrap().x - start;
    let end = sim
        .system
        .rod
        .positions
        .iter()
        .map(|p| [p.x, p.y, p.z])
        .collect();
    (moved, end)
}

/// #49 item 5: friction per surface. Each obstacle and each rod may have its own
/// coefficient (default `[contact] friction`) and a contact takes the smaller of its two
/// surfaces': on the 10° slope (tan 10° = 0.176) μ = 0.3 holds the rod, an obstacle or
/// a rod of μ = 0.1 lets it slide whatever `[contact]` says, and the coefficients given
/// per surface act exactly (bit for bit, the two runs under one kernel set, either) as
/// the same coefficient given once.
#[test]
fn each_surface_has_its_own_friction_and_a_contact_takes_the_smaller() {
    let own = |mu: Real| format!("friction = {mu}");
    let (held, reference) = on_a_slope(0.3, "", "");
    let (obstacle, _) = on_a_slope(0.3, "", &own(0.1));
    let (rod, _) = on_a_slope(0.3, &own(0.1), "");
    let (both, same) = on_a_slope(0.0, &own(0.3), &own(0.3));
    let (larger, _) = on_a_slope(0.1, &own(0.3), &own(0.8));
    println!("moved: μ 0.3 {held:.2e}, obstacle 0.1 {obstacle:.2e}, rod 0.1 {rod:.2e}, both own 0.3 {both:.2e}, own 0.8/0.3 {larger:.2e} m");
    assert!(held.abs() < 1e-3, "μ = 0.3 moved {held}");
    assert!(
        obstacle > 0.02 && rod > 0.02,
        "μ = 0.1 on one surface: {obstacle}, {rod}"
    );
    assert!(
        larger.abs() < 1e-3,
        "own 0.8 and 0.3 over [contact] 0.1: moved {larger}"
    );
    assert_eq!(
        same, reference,
        "coefficients per surface differ from one coefficient"
    );
}
