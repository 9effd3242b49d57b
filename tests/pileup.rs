//! A rope lowered onto the floor faster than it can lie down piles up without passing
//! through itself (`scenes/rope_pileup.toml`): clearance ≥ 0.95 of the diameter
//! throughout, the rope ends on the floor in a compact pile with strands lying on
//! strands. Figures: `cargo test --release --test integration pileup:: -- --nocapture`.

use splinerod::{run, Scene};

const RADIUS: f64 = 0.005;

#[test]
fn a_rope_lowered_fast_piles_up_without_passing_through_itself() {
    let scene = Scene::load("scenes/rope_pileup.toml").expect("scene");
    let result = run(&scene).expect("run");
    let clearance = result
        .contact
        .and_then(|c| c.min_clearance_ratio)
        .expect("the rope touches itself");
    let (s, points) = (&result.samples.s, &result.samples.positions);
    let lowest = points.iter().map(|p| p[1]).fold(f64::INFINITY, f64::min);
    // The part on the floor (within 3r of it) and its horizontal extent.
    let on_floor: Vec<usize> = (0..points.len())
        .filter(|&i| points[i][1] < 3.0 * RADIUS)
        .collect();
    let extent = |axis: usize| {
        let v = on_floor.iter().map(|&i| points[i][axis]);
        v.clone().fold(f64::NEG_INFINITY, f64::max) - v.fold(f64::INFINITY, f64::min)
    };
    let floor_length = on_floor.len() as f64 / (points.len() - 1) as f64;
    // Strands lying on strands: far apart along the rope, over each other (horizontal
    // distance below r), one at least 1.8 r above the other.
    let mut stacked = 0;
    for i in 0..points.len() {
        for j in 0..points.len() {
            let (a, b) = (points[i], points[j]);
            let across = (a[0] - b[0]).hypot(a[2] - b[2]);
            if (s[i] - s[j]).abs() > 0.1
                && across < RADIUS
                && a[1] - b[1] > 1.8 * RADIUS
                && a[1] < 5.0 * RADIUS
            {
                stacked += 1;
            }
        }
    }
    println!(
        "min clearance {clearance:.4}; lowest point {:.2} r above the floor; {:.0} % of the rope \
         on the floor within {:.3} × {:.3} m; {stacked} sample pairs stacked",
        lowest / RADIUS,
        100.0 * floor_length,
        extent(0),
        extent(2)
    );
    assert!(clearance >= 0.95, "{clearance}");
    assert!(lowest >= 0.95 * RADIUS, "{lowest}");
    assert!(floor_length > 0.7, "{floor_length}");
    assert!(
        extent(0).max(extent(2)) < 0.4,
        "{} × {}",
        extent(0),
        extent(2)
    );
    assert!(stacked > 0, "no strand lies on another");
}
