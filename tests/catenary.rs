//! The elastic catenary against `tests/data/catenary_L1_D0.8_mu0.1_EA100.json`:
//! material-point positions after a static solve, the convergence order of the cubic
//! Galerkin discretisation, and the same equilibrium reached by damped time stepping.

use splinerod::problems::{
    catenary_error, catenary_reference, catenary_scene, catenary_scene_with,
};
use splinerod::{run, Real};

fn static_error(n: usize, formulation: &str) -> Real {
    let scene = catenary_scene_with(n, 0.0, r#"method = "static""#, formulation).expect("scene");
    let result = run(&scene).expect("static solve");
    let reference = catenary_reference().expect("reference");
    for (a, b) in result.samples.s.iter().zip(&reference.s) {
        assert!((a - b).abs() < 1e-14, "sample {a} vs reference {b}");
    }
    catenary_error(&result).expect("error")
}

/// Both formulations against the EA = 100 N reference (a stretchy rod, strain ≈ 1 %).
/// The mixed form's lumped tension projection costs accuracy here (O(h²) where the
/// strain varies; measured 1.45e-5 / 2.82e-6 m), the pointwise form keeps its
/// fourth-order Galerkin error (2.07e-5 / 2.16e-7 m).
#[test]
fn static_catenary_matches_reference() {
    for (formulation, tol32) in [("pointwise", 2e-6), ("mixed", 5e-6)] {
        let e16 = static_error(16, formulation);
        let e32 = static_error(32, formulation);
        println!("{formulation}: max error 16 cps {e16:.3e} m, 32 cps {e32:.3e} m");
        assert!(e16 <= 5e-5, "{formulation}, 16 control points: {e16:.3e} m");
        assert!(
            e32 <= tol32,
            "{formulation}, 32 control points: {e32:.3e} m"
        );
    }
}

/// Observed order between 12 and 24 control points: 4 for the pointwise (Galerkin)
/// form, 2 for the mixed form on this stretchy rod (its stiff-rod order is checked in
/// `tests/locking.rs`).
#[test]
fn static_catenary_converges_at_the_formulations_order() {
    // Knot spacing h = L / (n - d) for clamped uniform cubic knots.
    let (n1, n2) = (12, 24);
    let h = |n: usize| 1.0 / (n - 3) as Real;
    for (formulation, least) in [("pointwise", 4.0), ("mixed", 1.9)] {
        let (e1, e2) = (static_error(n1, formulation), static_error(n2, formulation));
        let order = (e1 / e2).ln() / (h(n1) / h(n2)).ln();
        println!("{formulation}: errors {e1:.3e} -> {e2:.3e}, observed order {order:.2}");
        assert!(order >= least, "{formulation}: observed order {order:.2}");
    }
}

#[test]
fn damped_dynamics_settles_on_the_static_equilibrium() {
    let n = 16;
    let statics = catenary_scene(n, 0.0, r#"method = "static""#).expect("scene");
    let statics = run(&statics).expect("static");
    let solver = "method = \"implicit-euler\"\ndt = 0.01\nduration = 6.0";
    let dynamic = run(&catenary_scene(n, 4.0, solver).expect("scene")).expect("dynamic");
    let gap = statics
        .samples
        .positions
        .iter()
        .zip(&dynamic.samples.positions)
        .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<Real>().sqrt())
        .fold(0.0, Real::max);
    println!(
        "dynamic vs static: {gap:.3e} m after {} steps ({} sub-steps split while \
         compressed), kinetic {:.3e} J",
        dynamic.steps, dynamic.solver.rejected_steps, dynamic.energy["kinetic"]
    );
    assert_eq!(dynamic.solver.unconverged_steps, 0);
    assert!(dynamic.energy["kinetic"] < 1e-12, "not at rest");
    assert!(gap <= 1e-5, "dynamic equilibrium differs by {gap:.3e} m");
}

#[test]
fn settled_dynamics_report_the_static_pin_forces() {
    let statics =
        run(&catenary_scene(16, 0.0, r#"method = "static""#).expect("scene")).expect("static");
    let weight = 0.1 * 1.0 * 9.81;
    // The rod's weight pulls its supports down (`pin_forces`: the rod's force on them).
    let total_y: Real = statics.pin_forces.iter().map(|f| f[1]).sum();
    assert!(
        (total_y + weight).abs() < 1e-9,
        "pins carry {total_y} N of {weight} N"
    );
    // The midpoint rule needs Newton to converge on the stiff compressed start (1 ms
    // steps) and damps the stiff axial modes only through α, so it takes longer to rest.
    let runs = [
        ("implicit-euler", 0.01, 8.0),
        ("implicit-midpoint", 0.001, 16.0),
        ("bdf2", 0.01, 8.0),
    ];
    for (method, dt, duration) in runs {
        let solver = format!("method = \"{method}\"\ndt = {dt}\nduration = {duration}");
        let dynamic = run(&catenary_scene(16, 4.0, &solver).expect("scene")).expect("dynamic");
        assert_eq!(dynamic.pin_forces.len(), 2, "{method}");
        let pairs = statics
            .samples
            .positions
            .iter()
            .zip(&dynamic.samples.positions);
        let moved = pairs.map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, Real::max));
        println!(
            "{method}: t = {} s, shape {:.1e} m from static, kinetic {:.1e} J",
            dynamic.time,
            moved.fold(0.0, Real::max),
            dynamic.energy["kinetic"]
        );
        for (a, b) in statics.pin_forces.iter().zip(&dynamic.pin_forces) {
            let gap = (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, Real::max);
            println!("{method}: pin force {b:?} N, {gap:.1e} N from static");
            assert!(gap < 1e-6, "{method}: {a:?} vs {b:?}");
        }
    }
}

/// The exact elastic catenary solver reproduces the embedded reference (EA = 100 N):
/// tension and every material point.
#[test]
fn exact_elastic_catenary_matches_the_reference() {
    use splinerod::elastic_catenary::ElasticCatenary;
    let reference = catenary_reference().expect("reference");
    let exact = ElasticCatenary::new(1.0, 0.8, 0.1 * 9.81, 100.0).expect("solve");
    let dh = (exact.horizontal_tension - reference.h).abs() / reference.h;
    let worst = reference
        .s
        .iter()
        .zip(&reference.xy)
        .map(|(&s, r)| {
            let p = exact.point(s);
            (p[0] - r[0]).hypot(p[1] - r[1])
        })
        .fold(0.0, Real::max);
    println!("H relative gap {dh:.2e}, largest point gap {worst:.2e} m");
    assert!(dh < 1e-9 && worst < 1e-9, "H {dh:e}, points {worst:e} m");
    // The inextensible limit: the classical catenary's length and sag.
    let rigid = ElasticCatenary::new(1.0, 0.8, 0.981, f64::INFINITY).expect("solve");
    let end = rigid.point(1.0);
    assert!(
        (end[0] - 0.8).abs() < 1e-12 && end[1].abs() < 1e-12,
        "{end:?}"
    );
}

/// The JSON tension samples of both formulations against the exact elastic catenary's
/// √(H² + V²) at EA = 100 N (32 control points). The mixed form's tension is its own
/// field (measured 1.1e-5 relative); the pointwise form's is EA·ε recovered from the
/// curve's derivative, an order less accurate (measured 3.6e-3).
#[test]
fn tension_samples_match_the_exact_tension() {
    use splinerod::elastic_catenary::ElasticCatenary;
    let exact = ElasticCatenary::new(1.0, 0.8, 0.1 * 9.81, 100.0).expect("exact");
    for (formulation, tol) in [("pointwise", 1e-2), ("mixed", 1e-4)] {
        let scene =
            catenary_scene_with(32, 0.0, r#"method = "static""#, formulation).expect("scene");
        let result = run(&scene).expect("static solve");
        let worst = exact.tension_error(&result.samples);
        println!("{formulation}: tension within {worst:.2e} relative");
        assert!(worst <= tol, "{formulation}: {worst:.2e}");
    }
}
