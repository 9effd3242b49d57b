//! The capstan law at a full turn: a rope wound once around a horizontal capsule (wrap
//! 2π, the outgoing strand beside the incoming one, so the rope touches itself), 1 N at
//! one end, the other end's load slowly raised; it slips when the ratio passes e^{2πμ}.
//! At 8 control points (a user's coarse fit of the wrap, overlapping the capsule only
//! because it is coarse) the start is refined and pushed out, not refused (#46), and
//! the rope holds below e^{2πμ} and slides above it.
//! Figures: `cargo test --release --test integration capstan_turn:: -- --nocapture`.

use nalgebra::{DMatrix, Vector3};
use splinerod::core::basis::greville;
use splinerod::core::{BSplineSpace, Material, Rod};
use splinerod::energies::Stretching;
use splinerod::Scene;
use std::f64::consts::PI;

/// Capsule radius, rope radius, straight lead length.
const R: f64 = 0.05;
const RADIUS: f64 = 0.005;
const LEAD: f64 = 0.3;
/// The load ratio ramps from 1 at `T0` to 1.5 e^{2πμ} at `T1`.
const T0: f64 = 1.0;
const T1: f64 = 9.0;

/// The wrap: a straight lead along +x above the capsule, one helical turn around it
/// (radius ρ, rising 2δ along the axis), a straight lead on. Returns the point at
/// arclength `s` and the total length.
fn wrap(s: f64) -> (Vector3<f64>, f64) {
    let rho = R + 1.3 * RADIUS;
    let delta = 1.15 * RADIUS;
    let rise = 2.0 * delta / (2.0 * PI);
    let c = (rho * rho + rise * rise).sqrt();
    let turn = 2.0 * PI * c;
    let total = 2.0 * LEAD + turn;
    let point = if s <= LEAD {
        Vector3::new(s - LEAD, rho, -delta)
    } else if s <= LEAD + turn {
        let phi = (s - LEAD) / c;
        Vector3::new(rho * phi.sin(), rho * phi.cos(), -delta + rise * phi)
    } else {
        Vector3::new(s - LEAD - turn, rho, delta)
    };
    (point, total)
}

fn scene(mu: f64) -> Scene {
    let total = wrap(0.0).1;
    let top = 1.5 * (2.0 * PI * mu).exp();
    let text = format!(
        "[rod]\nrest_length = {total}\nlinear_density = 0.01\nstretch_stiffness = 1000.0\n\
         bending_stiffness = 1e-6\ndamping = 5.0\ncontrol_points = 64\nradius = {RADIUS}\n\
         start = [0.0, 0.2, 0.0]\nend = [{total}, 0.2, 0.0]\n\
         [world]\ngravity = [0.0, 0.0, 0.0]\n\
         [contact]\nstiffness = 1e5\nfriction = {mu}\n\
         [[obstacles]]\nkind = \"capsule\"\na = [0.0, 0.0, -0.1]\nb = [0.0, 0.0, 0.1]\nradius = {R}\n\
         [[loads]]\nat = 0.0\nforce = [-1.0, 0.0, 0.0]\n\
         [[loads]]\nat = 1.0\npath = [[0.0, 1.0, 0.0, 0.0], [{T0}, 1.0, 0.0, 0.0], [{T1}, {top}, 0.0, 0.0]]\n\
         [solver]\nmethod = \"implicit-euler\"\ndt = 0.002\nduration = {T1}\n"
    );
    Scene::from_toml(&text).expect("capstan scene")
}

/// The load ratio at which the heavy end starts to slide (faster than 1 cm/s).
/// Also the smallest clearance ratio and the most rope–rope contact pairs seen.
fn slip_ratio(mu: f64) -> (f64, f64, usize) {
    let scene = scene(mu);
    let mut sim = scene.build().expect("simulation");
    let rod = &mut sim.system.rod;
    let l = rod.material().rest_length;
    for i in 0..rod.len() {
        rod.positions[i] = wrap(greville(rod.basis(), i) * wrap(0.0).1 / l).0;
    }
    // The wound shape is the rope's rest state.
    let stretching = Stretching::with_rest_shape(1000.0, &sim.system.rod).expect("stretching");
    let slot = sim
        .system
        .energies
        .iter()
        .position(|e| e.name() == "stretch");
    sim.system.energies[slot.expect("stretching energy")] = Box::new(stretching);
    let threshold = (2.0 * PI * mu).exp();
    let mut before = sim.system.rod.point(l).expect("end");
    let (mut clearance, mut pairs): (f64, usize) = (f64::INFINITY, 0);
    while sim.time < T1 {
        let report = sim.step(0.002).expect("step");
        if let Some(c) = report.energies.contact {
            clearance = clearance.min(c.min_clearance_ratio.unwrap_or(f64::INFINITY));
            pairs = pairs.max(c.pairs);
        }
        let end = sim.system.rod.point(l).expect("end");
        let speed = (end - before).norm() / 0.002;
        before = end;
        if sim.time > T0 + 0.2 && speed > 0.01 {
            let ratio = 1.0 + (1.5 * threshold - 1.0) * (sim.time - T0) / (T1 - T0);
            return (ratio, clearance, pairs);
        }
    }
    panic!("mu {mu}: no slip");
}

#[test]
fn a_rope_wound_a_full_turn_slips_at_the_capstan_ratio() {
    for mu in [0.1, 0.3, 0.5] {
        let threshold = (2.0 * PI * mu).exp();
        let (ratio, clearance, pairs) = slip_ratio(mu);
        let error = ratio / threshold - 1.0;
        eprintln!(
            "mu {mu}: slips at ratio {ratio:.4}, capstan e^(2πμ) = {threshold:.4} ({error:+.4}); \
             min clearance {clearance:.3}, up to {pairs} rope–rope contact pairs"
        );
        assert!(clearance >= 0.95, "{clearance}");
        assert!(error.abs() < 0.03, "mu {mu}: {ratio} against {threshold}");
    }
}

/// The full turn as a user would write it at 8 control points: the wrap fitted by
/// least squares (clamped uniform cubic, 400 points of the wrap), given as
/// `initial_control_points`, its rest state the start (`rest_shape = "initial"`), no
/// contact stiffness (the barrier), the loads `1 N` and `ratio` N held from the start.
fn coarse_scene(mu: f64, ratio: f64, duration: f64) -> String {
    let total = wrap(0.0).1;
    let n = 8;
    let basis = BSplineSpace::clamped_uniform(3, n, total).expect("basis");
    let rod = Rod::straight(
        Material {
            rest_length: total,
            linear_density: 0.01,
        },
        Box::new(basis),
        Vector3::zeros(),
        Vector3::x() * total,
    )
    .expect("rod");
    let (mut a, mut rhs) = (DMatrix::<f64>::zeros(n, n), DMatrix::<f64>::zeros(n, 3));
    for j in 0..400 {
        let s = total * (j as f64 + 0.5) / 400.0;
        let b = rod.basis_at(s).expect("basis row");
        let p = wrap(s).0;
        for i in 0..b.order {
            for k in 0..b.order {
                a[(b.first + i, b.first + k)] += b.value[i] * b.value[k];
            }
            for c in 0..3 {
                rhs[(b.first + i, c)] += b.value[i] * p[c];
            }
        }
    }
    let q = a.lu().solve(&rhs).expect("least squares");
    let points: Vec<String> = (0..n)
        .map(|i| format!("[{}, {}, {}]", q[(i, 0)], q[(i, 1)], q[(i, 2)]))
        .collect();
    format!(
        "[rod]\nrest_length = {total}\nlinear_density = 0.01\nstretch_stiffness = 1000.0\n\
         bending_stiffness = 1e-6\ndamping = 5.0\ncontrol_points = {n}\nradius = {RADIUS}\n\
         rest_shape = \"initial\"\ninitial_control_points = [{}]\n\
         [world]\ngravity = [0.0, 0.0, 0.0]\n\
         [contact]\nfriction = {mu}\n\
         [[obstacles]]\nkind = \"capsule\"\na = [0.0, 0.0, -0.1]\nb = [0.0, 0.0, 0.1]\nradius = {R}\n\
         [[loads]]\nat = 0.0\nforce = [-1.0, 0.0, 0.0]\n\
         [[loads]]\nat = 1.0\nforce = [{ratio}, 0.0, 0.0]\n\
         [solver]\nmethod = \"implicit-euler\"\ndt = 0.002\nduration = {duration}\n",
        points.join(", ")
    )
}

/// Runs the coarse full turn with the load ratio `ratio` for `duration` s: whether the
/// heavy end slid faster than 1 cm/s in the last half second, the control points the
/// start was refined to, and the smallest clearance seen.
fn coarse_slides(mu: f64, ratio: f64, duration: f64) -> (bool, usize, f64) {
    let scene = Scene::from_toml(&coarse_scene(mu, ratio, duration)).expect("scene");
    let mut sim = scene
        .build()
        .expect("the coarse start is refined, not refused");
    let points = sim.system.rod.len();
    let l = sim.system.rod.material().rest_length;
    let (mut before, mut fastest, mut clearance) =
        (sim.system.rod.point(l).expect("end"), 0.0, f64::INFINITY);
    while sim.time < duration - 1e-9 {
        let report = sim.step(0.002).expect("step");
        if let Some(c) = report.energies.contact {
            clearance = clearance.min(c.min_clearance_ratio.unwrap_or(f64::INFINITY));
        }
        let end = sim.system.rod.point(l).expect("end");
        if sim.time > duration - 0.5 {
            fastest = f64::max(fastest, (end - before).norm() / 0.002);
        }
        before = end;
    }
    (fastest > 0.01, points, clearance)
}

#[test]
fn a_full_turn_fitted_with_eight_control_points_runs_and_holds_below_the_capstan_ratio() {
    let mu = 0.3;
    let threshold = (2.0 * PI * mu).exp();
    let (held_slides, points, held_clearance) = coarse_slides(mu, 0.75 * threshold, 2.5);
    let (slid, _, slid_clearance) = coarse_slides(mu, 1.33 * threshold, 2.5);
    eprintln!(
        "8 control points refined to {points}: at 0.75 e^(2πμ) slides {held_slides} (clearance {held_clearance:.3}), at 1.33 e^(2πμ) slides {slid} (clearance {slid_clearance:.3})"
    );
    assert!(points > 8, "the coarse start was not refined");
    assert!(!held_slides, "slides below the capstan ratio");
    assert!(slid, "holds above the capstan ratio");
    assert!(held_clearance.min(slid_clearance) >= 0.95);
}

#[test]
fn a_start_through_the_capsule_is_still_refused_naming_the_field() {
    // The rope laid straight through the capsule: its control polygon overlaps too.
    let text = coarse_scene(0.3, 1.0, 0.1);
    let start = text.find("initial_control_points").expect("points");
    let end = start + text[start..].find('\n').expect("line");
    let straight = format!(
        "{}start = [-0.3, 0.0, 0.0]\nend = [0.6, 0.0, 0.0]{}",
        &text[..start],
        &text[end..]
    )
    .replace("rest_shape = \"initial\"\n", "");
    let error = Scene::from_toml(&straight).and_then(|s| s.build().map(|_| ()));
    let message = format!("{:?}", error.expect_err("refused"));
    assert!(message.contains("rod.radius"), "{message}");
}
