//! Tolerance-driven adaptivity (issue #13) on the problems of
//! `splinerod::adaptive_study`: the grabbed string against a 253-point run, the hanging
//! cable settled from a straight start against the exact elastic catenary. Errors are the
//! largest material-point distance; the effectivity index is estimate / true error.

use splinerod::adaptive_study::{
    adaptive_start, adaptivity_table, scene, study_run, Answer, Problem, StudyRun,
};
use splinerod::prelude::*;
use splinerod::problems::crossing::{self, Resolution, Variant, REFERENCE_POINTS};

/// The uniform count (interpolated in log–log between measured runs) that reaches `error`.
fn uniform_count_for(error: Real, uniform: &[(usize, Real)]) -> Real {
    for w in uniform.windows(2) {
        let ((n0, e0), (n1, e1)) = (w[0], w[1]);
        if e1 <= error && error <= e0 {
            let f = (error / e0).ln() / (e1 / e0).ln();
            return (n0 as Real) * (n1 as Real / n0 as Real).powf(f);
        }
    }
    Real::NAN
}

fn print(r: &StudyRun) {
    println!(
        "tol {:?}: error {:.2e}, estimate {:.2e} (effectivity {:.2}), {} control points (most {})",
        r.tolerance,
        r.error,
        r.estimate,
        r.effectivity(),
        r.control_points,
        r.most_control_points
    );
}

#[test]
fn bundled_grab_scene_with_default_adaptivity_is_within_a_millimetre() {
    let mut grab = Scene::load("scenes/grab_adaptive.toml").expect("scene");
    let a = grab.adaptivity.as_ref().expect("[adaptivity]");
    assert!(
        a.tolerance.is_none() && a.insert_threshold.is_none(),
        "defaults only"
    );
    grab.output.samples = 201;
    let run = splinerod::run(&grab).expect("run");
    let error = Answer::of(Problem::Grab).expect("reference").error(&run);
    let knots = &run.knots;
    let at_grab = knots.iter().filter(|&&k| (k - 0.3).abs() < 1e-12).count();
    println!(
        "error {error:.2e} m with {} control points, knot multiplicity {at_grab} at the grab",
        run.control_points
    );
    assert!(error <= 1e-3, "{error:e}");
    assert_eq!(
        at_grab, 3,
        "the kink at the grab gets a triple knot: {knots:?}"
    );
    let estimate = run.adaptivity.expect("estimate").estimated_error;
    assert!(estimate <= 2e-4 && estimate > 0.0, "{estimate:e}");
}

#[test]
fn cable_sweep_meets_its_tolerances_with_honest_estimates() {
    let answer = Answer::of(Problem::Cable).expect("catenary");
    let uniform: Vec<(usize, Real)> = [4, 6, 8, 12, 16, 24, 32, 64]
        .into_iter()
        .map(|n| {
            let r = study_run(Problem::Cable, &answer, None, n).expect("uniform");
            print(&r);
            let e = r.effectivity();
            assert!(
                (1.0 / 3.0..=3.0).contains(&e),
                "uniform {n}: effectivity {e}"
            );
            (n, r.error)
        })
        .collect();
    for tol in [1e-2, 1e-3, 1e-4, 1e-5] {
        let r = study_run(
            Problem::Cable,
            &answer,
            Some(tol),
            adaptive_start(Problem::Cable),
        );
        let r = r.expect("adaptive");
        print(&r);
        assert!(r.error <= 2.0 * tol, "tol {tol}: error {:e}", r.error);
        let e = r.effectivity();
        assert!((1.0 / 3.0..=3.0).contains(&e), "tol {tol}: effectivity {e}");
        // No more than 1.6 × the uniform rod of the same error (where the sweep has one;
        // 1.5 before #46: the trades at the 200-point cap during the straight start's
        // transient leave a placement the settled rod improves only by trades at rest;
        // measured 0.97, 1.34, 1.24, 1.54 for 1e-2 … 1e-5).
        let needed = uniform_count_for(r.error, &uniform);
        if needed.is_finite() {
            let ratio = r.control_points as Real / needed;
            println!("  uniform rod of that error: {needed:.1} control points, ratio {ratio:.2}");
            assert!(ratio <= 1.6, "tol {tol}: ratio {ratio}");
        }
    }
}

#[test]
fn grab_sweep_meets_its_tolerances_with_a_quarter_of_the_uniform_points() {
    let answer = Answer::of(Problem::Grab).expect("reference");
    let start = adaptive_start(Problem::Grab);
    let mut at_1e4 = None;
    for tol in [1e-2, 1e-3, 1e-4, 1e-5] {
        let r = study_run(Problem::Grab, &answer, Some(tol), start).expect("adaptive");
        print(&r);
        assert!(r.error <= 2.0 * tol, "tol {tol}: error {:e}", r.error);
        let e = r.effectivity();
        assert!((1.0 / 3.0..=3.0).contains(&e), "tol {tol}: effectivity {e}");
        if tol == 1e-4 {
            at_1e4 = Some(r);
        }
    }
    // Uniform rods do not resolve the kink: even 128 points stay far above the adaptive
    // error, so the uniform rod of that error has more than 128 points.
    let adaptive = at_1e4.expect("tolerance 1e-4");
    let uniform = study_run(Problem::Grab, &answer, None, 128).expect("uniform");
    print(&uniform);
    assert!(uniform.error > adaptive.error);
    assert!(
        4 * adaptive.control_points <= 128,
        "{}",
        adaptive.control_points
    );
}

#[test]
fn a_resolved_rod_has_a_vanishing_estimate() {
    // A straight string stretched between its pins, no gravity: the cubic curve is the
    // exact equilibrium, so a finer basis changes nothing.
    let text = adaptivity_table(1e-6);
    let mut taut = scene(Problem::Cable, 8, None, &text).expect("scene");
    taut.world.gravity = [0.0; 3];
    taut.rod.end = Some([1.05, 0.0, 0.0]);
    taut.solver.duration = Some(0.05);
    let run = splinerod::run(&taut).expect("run");
    let estimate = run.adaptivity.expect("estimate").estimated_error;
    println!(
        "straight taut string: estimate {estimate:e} m, {} control points",
        run.control_points
    );
    assert!(estimate < 1e-12, "{estimate:e}");
    // Nothing to refine; the straight line needs only the 4 points of one cubic span.
    let most = run
        .control_points_history
        .iter()
        .map(|h| h[1] as usize)
        .max();
    assert_eq!(most, Some(8), "no insertion");
    assert_eq!(run.control_points, 4, "coarsened to one span");
}

#[test]
fn estimates_are_deterministic() {
    let grab = || {
        let s = scene(Problem::Grab, 8, None, &adaptivity_table(1e-4)).expect("scene");
        splinerod::run(&s).expect("run")
    };
    let (a, b) = (grab(), grab());
    let (ea, eb) = (a.adaptivity.expect("a"), b.adaptivity.expect("b"));
    assert_eq!(ea.history, eb.history);
    assert_eq!(a.samples.positions, b.samples.positions);
}

/// `[output] error_estimate` on a static solve: the equilibrium's estimate against the
/// exact elastic catenary, at fixed resolutions.
#[test]
fn static_solves_report_an_honest_estimate() {
    for n in [8, 16, 32] {
        let mut scene =
            splinerod::problems::catenary_scene(n, 0.0, "method = \"static\"").expect("scene");
        scene.output.error_estimate = true;
        let run = splinerod::run(&scene).expect("static solve");
        let error = splinerod::problems::catenary_error(&run).expect("error");
        let estimate = run.adaptivity.expect("estimate").estimated_error;
        let e = estimate / error;
        println!("static, {n} points: error {error:.2e}, estimate {estimate:.2e} ({e:.2})");
        assert!((0.5..=2.0).contains(&e), "{n} points: effectivity {e}");
    }
}

/// The lift of the crossing ropes at `resolution`, with the ropes of `variant`.
fn lift(resolution: Resolution, variant: Variant) -> Real {
    crossing::run(resolution, Some(variant)).expect("run").0
}

/// #46: two pinned ropes crossing, both with bending. Tolerance adaptivity from 16
/// control points per rope (default tolerance, knots at the contact stay C¹) gets the
/// lift within twice the error of a uniform 64, on the bundled ropes and two variants;
/// 256 per rope is the reference. Uniform 16 is allowed to be worse (measured 2–7 %).
#[test]
fn crossing_lift_from_16_adaptive_is_within_twice_the_uniform_64_error() {
    let variants = [
        (1e-3, 2e-4, 0.01, 0.006),
        (1e-4, 5e-5, 0.008, 0.004),
        (3e-3, 1e-3, 0.012, 0.01),
    ];
    for (ei_lower, ei_upper, r_lower, r_upper) in variants {
        let v = Variant {
            ei_lower,
            ei_upper,
            r_lower,
            r_upper,
        };
        let exact = lift(Resolution::Uniform(REFERENCE_POINTS), v);
        let error = |r| (lift(r, v) - exact).abs() / exact;
        let adaptive = Resolution::Adaptive {
            start: 16,
            tolerance: None,
        };
        let (uniform_16, uniform_64, adaptive) = (
            error(Resolution::Uniform(16)),
            error(Resolution::Uniform(64)),
            error(adaptive),
        );
        println!(
            "{v:?}: lift {exact:.5}; error uniform 16 {uniform_16:.2e}, uniform 64 \
             {uniform_64:.2e}, adaptive from 16 {adaptive:.2e}"
        );
        assert!(
            adaptive <= 2.0 * uniform_64,
            "{v:?}: {adaptive} vs {uniform_64}"
        );
    }
}

/// #46: adaptivity never makes a hinge (a knot of multiplicity d) on a rod with bending:
/// the crossing ropes with their free upper rope falling onto the lower one, adaptive
/// from 16 points, where the corner criterion used to raise the contact knots to d.
#[test]
fn adaptivity_makes_no_hinge_on_rods_with_bending() {
    let mut scene = Scene::load("scenes/ropes_crossing.toml").expect("scene");
    for rod in &mut scene.rods {
        rod.control_points = 16;
    }
    scene.solver.duration = Some(0.3);
    let table = "[adaptivity]\ntolerance = 1e-3";
    scene.adaptivity = Some(splinerod::scene::AdaptivitySpec::from_toml(table).expect("table"));
    let r = splinerod::run(&scene).expect("run");
    assert!(r.solver.knots_inserted > 0, "no refinement to test");
    assert_eq!(r.hinge_steps, 0);
    let d = 3;
    let knots = &r.knots;
    for (i, &t) in knots.iter().enumerate() {
        let m = knots.iter().filter(|&&x| x == t).count();
        let interior = t > 0.0 && t < 1.0 && knots[..i].iter().all(|&x| x != t);
        assert!(!interior || m != d, "knot {t} of multiplicity {m}");
    }
}
