//! An overhand knot tied by pulling its ends apart (`scenes/knot_pulled.toml`): with
//! adaptive resolution it pulls tight — knot length below 0.1 m — while it stays an
//! overhand knot (determinant 3 at every record) and its strands never overlap by more
//! than 5 % of the diameter.

use splinerod::{run, Scene};

#[test]
fn pulling_the_ends_apart_ties_the_knot_tight() {
    let scene = Scene::load("scenes/knot_pulled.toml").expect("scene");
    let result = run(&scene).expect("runs");
    let knot = result.knot.expect("knot track");
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
    assert!(start > 0.7, "{start}");
    let c = result.contact.expect("contact statistics");
    let clearance = c.min_clearance_ratio.expect("strands touch");
    assert!(clearance >= 0.95, "clearance {clearance}");
    assert!(result.control_points > 11, "adaptivity refined the knot");
}
