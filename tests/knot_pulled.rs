//! An overhand knot tied by pulling its ends apart (`scenes/knot_pulled.toml`, and
//! `knot_pulled_fixed.toml` at a fixed 100 control points): either way it pulls tight —
//! knot length below 0.1 m — while it stays an overhand knot (determinant 3 at every record) and its strands never overlap by more
//! than 5 % of the diameter.

use splinerod::{run, Scene};

#[test]
fn pulling_the_ends_apart_ties_the_knot_tight() {
    let result = pulled("scenes/knot_pulled.toml");
    assert!(result.control_points > 11, "adaptivity refined the knot");
}

#[test]
fn a_fixed_resolution_ties_it_tight_too() {
    let result = pulled("scenes/knot_pulled_fixed.toml");
    assert_eq!(result.control_points, 100);
}

/// Runs `path` and checks the knot's lines: determinant 3 throughout, from a loose
/// knot (> 0.6 m) to below 0.1 m, strands never closer than 0.95 diameters.
fn pulled(path: &str) -> splinerod::RunResult {
    let scene = Scene::load(path).expect("scene");
    let result = run(&scene).expect("runs");
    let knot = result.knot.as_ref().expect("knot track");
    assert!(
        knot.determinant.iter().all(|&d| d == 3),
        "{:?}",
        knot.determinant
    );
    let end = knot
        .knot_length
        .last()
        .copied()
        .flatten()
        .expect("knot length");
    assert!(end < 0.1, "knot length {end} m");
    let start = knot.knot_length[0].expect("initial knot length");
    assert!(start > 0.6, "{start}");
    let c = result.contact.expect("contact statistics");
    let clearance = c.min_clearance_ratio.expect("strands touch");
    assert!(clearance >= 0.95, "clearance {clearance}");
    result
}
