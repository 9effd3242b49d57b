//! Twisting against Kirchhoff rod theory, through the public API:
//!
//! * Greenhill: a rod clamped at both ends (pins + clamps), under tension `T`, turned by
//!   Φ: the straight state loses stability where the linearised equation
//!   \\(B w'''' - i M w''' - T w'' = 0\\), \\(w = w' = 0\\) at both ends, first has a
//!   non-zero solution, with \\(M = GJ\Phi/L\\). The reference \\(m = ML/B\\) is the first
//!   root of that 4×4 determinant (computed below); the measured one is where the
//!   lowest ω² of the modal analysis of the twisted straight state crosses zero.
//!
//! Figures: `cargo test --release --test integration twist:: -- --nocapture`.

use splinerod::energies::{Bending, Clamp, Frame, Stretching, Twisting};
use splinerod::integrators::modal;
use splinerod::prelude::*;

const L: Real = 1.0;
/// Bending stiffness B = EI.
const B: Real = 1.0;
const GJ: Real = 0.8;
const EA: Real = 1e6;

/// The rod of `n` control points clamped at both ends, stretched to tension `tension`
/// and turned by `turn`.
fn twisted(n: usize, tension: Real, turn: Real) -> RodSystem {
    let material = Material {
        rest_length: L,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, L).expect("basis");
    let stretching = Stretching::new(EA).expect("EA");
    // Tension T = EA γ(γ² − 1)/2: solve for the stretch γ by Newton.
    let mut gamma = 1.0;
    for _ in 0..50 {
        gamma -= (stretching.tension(gamma) - tension) / (0.5 * EA * (3.0 * gamma * gamma - 1.0));
    }
    let end = Vector3::new(gamma * L, 0.0, 0.0);
    let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
    let k = Clamp::stiffness_for(B, L);
    let clamps = [
        Clamp::new(0.0, Vector3::x(), k).expect("clamp"),
        Clamp::new(L, Vector3::x(), k).expect("clamp"),
    ];
    let frame = Frame::along(Vector3::x()).expect("frame");
    let mut twisting = Twisting::between_ends(GJ, &rod, frame).expect("twisting");
    twisting.turn = turn;
    let pins = [Pin::here(&rod, 0.0), Pin::here(&rod, L)];
    let bending = Bending::for_rod(B, &rod).expect("bending");
    let mut system = RodSystem::new(rod)
        .with_energy(stretching)
        .with_energy(bending)
        .with_energy(twisting);
    for c in clamps {
        system = system.with_energy(c);
    }
    for p in pins {
        system = system.with_pin(p.expect("pin"));
    }
    system
}

/// Lowest ω² sign change in the turn: the critical twisting moment `m = M L / B`.
fn measured_critical_moment(n: usize, tau: Real) -> Real {
    let tension = tau * B / (L * L);
    let stable = |turn: Real| {
        let system = twisted(n, tension, turn);
        modal::modes(&system, 1).expect("modes")[0].omega > 0.0
    };
    let (mut lo, mut hi) = (0.0, 30.0 * B / GJ);
    assert!(stable(lo) && !stable(hi));
    for _ in 0..40 {
        let mid = 0.5 * (lo + hi);
        if stable(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    GJ * 0.5 * (lo + hi) / B * L / L
}

/// First root of the Greenhill determinant for τ = T L²/B (m = M L/B).
fn greenhill(tau: Real) -> Real {
    let g = |m: Real| greenhill_determinant(m, tau);
    let mut m = 0.5;
    let mut previous = g(m);
    loop {
        let next = m + 0.01;
        let value = g(next);
        if value * previous < 0.0 {
            let (mut a, mut b) = (m, next);
            for _ in 0..60 {
                let c = 0.5 * (a + b);
                if g(a) * g(c) <= 0.0 {
                    b = c;
                } else {
                    a = c;
                }
            }
            return 0.5 * (a + b);
        }
        m = next;
        previous = value;
    }
}

/// The clamped–clamped determinant for \\(w = c_0 + c_1 s + c_2 e^{r_1 s} + c_3 e^{r_2 s}\\),
/// \\(r_{1,2} = (i m \pm \sqrt{4\tau - m^2})/2\\) (L = B = 1), times \\(e^{-im/2}\\) and
/// divided by the square root: a real function of `m`, continuous through \\(m^2 = 4\tau\\).
fn greenhill_determinant(m: Real, tau: Real) -> Real {
    use nalgebra::{Complex, Matrix4};
    let disc = Complex::new(4.0 * tau - m * m, 0.0).sqrt();
    let i = Complex::new(0.0, 1.0);
    let (r1, r2) = ((i * m + disc) * 0.5, (i * m - disc) * 0.5);
    let (e1, e2) = (r1.exp(), r2.exp());
    let (one, zero) = (Complex::new(1.0, 0.0), Complex::new(0.0, 0.0));
    let a = Matrix4::new(
        one,
        zero,
        one,
        one, //
        zero,
        one,
        r1,
        r2, //
        one,
        one,
        e1,
        e2, //
        zero,
        one,
        r1 * e1,
        r2 * e2,
    );
    (a.determinant() * (-i * m * 0.5).exp() / disc).re
}

#[test]
fn the_greenhill_reference_is_the_classical_value() {
    // Clamped ends without tension: M L / B = 2.861 π.
    let m = greenhill(1e-8);
    assert!((m / std::f64::consts::PI - 2.8606).abs() < 1e-4, "{m}");
}

#[test]
fn greenhill_critical_twist_matches_the_linearised_equation() {
    for tau in [0.0_f64, 10.0, 50.0] {
        let exact = greenhill(tau.max(1e-8));
        for n in [8, 16, 32] {
            let m = measured_critical_moment(n, tau);
            let error = m / exact - 1.0;
            println!("τ = {tau:>4}: n = {n:>2}  m = {m:.5}  exact {exact:.5}  error {error:+.2e}");
            if n >= 16 {
                assert!(error.abs() < 0.01, "τ = {tau}, n = {n}: {m} vs {exact}");
            }
        }
    }
}

/// Largest sideways distance of the centreline from the axis.
fn deflection(system: &RodSystem) -> Real {
    (0..=40)
        .map(|k| {
            let p = system.rod.point(L * k as Real / 40.0).expect("point");
            (p.y * p.y + p.z * p.z).sqrt()
        })
        .fold(0.0, Real::max)
}

/// Implicit Euler from a slightly bent twisted rod: returns the deflection after `steps`
/// and the largest Newton iteration count of a step.
fn evolve(turn: Real, steps: usize) -> (Real, usize) {
    use splinerod::integrators::{ImplicitEuler, Integrator, NewtonParams};
    let mut system = twisted(16, 0.0, turn);
    for (i, q) in system.rod.positions.iter_mut().enumerate() {
        let s = i as Real / 15.0;
        q.y += 1e-4 * (std::f64::consts::PI * s).sin().powi(2);
    }
    system.rod.damping = 1.0;
    let mut euler = ImplicitEuler::new(NewtonParams::default()).expect("integrator");
    let mut worst = 0;
    for _ in 0..steps {
        system.begin_step(2e-3).expect("begin step");
        let stats = euler.step(&mut system, 2e-3).expect("step");
        assert!(stats.converged);
        worst = worst.max(stats.newton_iterations);
    }
    (deflection(&system), worst)
}

#[test]
fn a_rod_twisted_past_greenhill_buckles_and_below_it_straightens() {
    let critical = greenhill(1e-8) * B / GJ;
    let (below, iterations_below) = evolve(0.8 * critical, 300);
    let (above, iterations_above) = evolve(1.3 * critical, 300);
    println!(
        "deflection from 1e-4 m: {below:.2e} m at 0.8 Φc ({iterations_below} Newton iterations \
         at most), {above:.2e} m at 1.3 Φc ({iterations_above})"
    );
    assert!(below < 1e-4, "{below}");
    assert!(above > 1e-3, "{above}");
}

/// A straight rod of `n` control points between clamps, the end clamp turned to `turn`
/// over 0.5 s, `method` as given.
fn torsion_scene(n: usize, turn: Real, method: &str) -> String {
    format!(
        "[rod]\nrest_length = 1.5\nlinear_density = 0.1\nstretch_stiffness = 1e4\n\
         bending_stiffness = 0.3\ntwist_stiffness = 0.2\ncontrol_points = {n}\n\
         start = [0.0, 0.0, 0.0]\nend = [0.0, 0.0, 1.5]\n\n\
         [[pins]]\nat = 0.0\nclamp = true\n\n\
         [[pins]]\nat = 1.0\nclamp = true\nturn = [[0.0, 0.0], [0.5, {turn:?}]]\ninterpolation = \"smooth\"\n\n\
         [world]\ngravity = [0.0, 0.0, 0.0]\n\n\
         [solver]\nmethod = \"{method}\"\ndt = 0.01\nduration = 0.6\n"
    )
}

#[test]
fn uniform_torsion_gives_the_exact_torque_and_energy() {
    let (gj, l) = (0.2, 1.5);
    for method in ["static", "implicit-euler", "implicit-midpoint", "bdf2"] {
        for (n, turn) in [(8, 1.0), (13, -4.0)] {
            let scene = Scene::from_toml(&torsion_scene(n, turn, method)).expect("scene");
            let result = splinerod::runner::run(&scene).expect("run");
            let (moment, energy) = (gj * turn / l, gj * turn * turn / (2.0 * l));
            let torques = &result.pin_torques;
            let twist = result.twist.expect("twist");
            let e = result.energy["twist"];
            println!(
                "{method:>17}, n = {n:>2}, Φ = {turn:>4}: torque {:.12} (exact {moment:.12}), energy {e:.12} ({energy:.12})",
                torques[1][2]
            );
            assert!((twist.turn - turn).abs() < 1e-12);
            // The rod resists the turn: −M on the turned clamp, +M on the other.
            assert!(
                (torques[1][2] + moment).abs() <= 1e-9 * moment.abs(),
                "{method}"
            );
            assert!(
                (torques[0][2] - moment).abs() <= 1e-9 * moment.abs(),
                "{method}"
            );
            assert!((e - energy).abs() <= 1e-9 * energy, "{method}");
        }
    }
}

#[test]
fn bad_twist_input_names_the_field() {
    let cases = [
        (
            "twist_stiffness = 0.2",
            "twist_stiffness = -1.0",
            "rod.twist_stiffness",
        ),
        (
            "twist_stiffness = 0.2",
            "twist_stiffness = nan",
            "rod.twist_stiffness",
        ),
        (
            "at = 1.0\nclamp = true\n",
            "at = 1.0\n",
            "rod.twist_stiffness",
        ),
        ("[0.5, 2.0]]", "[0.5, 2.0], [0.4, 1.0]]", "pins[1].turn[2]"),
        ("[0.5, 2.0]]", "[0.5, inf]]", "pins[1].turn[1]"),
    ];
    for (from, to, field) in cases {
        let text = torsion_scene(8, 2.0, "static").replace(from, to);
        assert_ne!(text, torsion_scene(8, 2.0, "static"), "{to}");
        let error = Scene::from_toml(&text)
            .and_then(|s| splinerod::runner::run(&s))
            .expect_err(to)
            .to_string();
        assert!(error.contains(field), "{to}: {error}");
    }
    // A turn on a pin that is not a clamp at an end.
    let text = torsion_scene(8, 2.0, "static") + "\n[[pins]]\nat = 0.5\nturn = [[0.0, 1.0]]\n";
    let error = Scene::from_toml(&text).expect_err("turn").to_string();
    assert!(error.contains("pins[2].turn"), "{error}");
}

/// Largest sideways distance of the probed midpoint from the x axis over `[t0, t1]`.
fn probe_deflection(result: &splinerod::RunResult, t0: Real, t1: Real) -> Real {
    let probe = &result.probes[0];
    probe
        .t
        .iter()
        .zip(&probe.positions)
        .filter(|(t, _)| **t >= t0 && **t <= t1)
        .map(|(_, p)| p[1].hypot(p[2]))
        .fold(0.0, Real::max)
}

#[test]
fn the_twist_buckling_scene_buckles_where_greenhill_says() {
    let scene = Scene::load("scenes/twist_buckling.toml").expect("scene");
    let result = splinerod::runner::run(&scene).expect("run");
    // Critical turn at τ = 5: 9.718 EI/GJ = 12.6 rad, reached at t = 6.3 s.
    let critical = greenhill(5.0) * 0.01 / 0.0077;
    let crossing = critical / 2.0;
    let before = probe_deflection(&result, 3.0, crossing - 0.5);
    let after = probe_deflection(&result, 9.0, 11.0);
    let twist = result.twist.expect("twist");
    println!(
        "critical turn {critical:.3} rad (t = {crossing:.2} s): deflection {before:.1e} m before, \
         {after:.1e} m after; Tw = {:.4} rad, Wr = {:.4}, Lk = {:.6} turns for {:.6} imposed",
        twist.twist,
        twist.writhe,
        twist.link,
        twist.turn / (2.0 * std::f64::consts::PI)
    );
    assert!(before < 1e-4, "{before}");
    assert!(after > 1e-2, "{after}");
    let turns = twist.turn / (2.0 * std::f64::consts::PI);
    assert!(
        (twist.link - turns).abs() < 1e-3,
        "{} vs {turns}",
        twist.link
    );
}

#[test]
fn the_plectoneme_trades_twist_for_writhe_without_passing_through_itself() {
    let scene = Scene::load("scenes/plectoneme.toml").expect("scene");
    let result = splinerod::runner::run(&scene).expect("run");
    let twist = result.twist.expect("twist");
    let clearance = result
        .contact
        .and_then(|c| c.min_clearance_ratio)
        .expect("the rod touches itself");
    let turns = twist.turn / (2.0 * std::f64::consts::PI);
    println!(
        "Tw = {:.4} rad ({:.4} turns), Wr = {:.4} turns, Lk = {:.6} for {turns:.6} imposed; \
         min clearance {:.4}",
        twist.twist,
        twist.twist / (2.0 * std::f64::consts::PI),
        twist.writhe,
        twist.link,
        clearance
    );
    assert!(clearance >= 0.95, "{clearance}");
    assert!(twist.writhe > 1.0, "writhe {}", twist.writhe);
    assert!(
        (twist.link - turns).abs() < 1e-3,
        "{} vs {turns}",
        twist.link
    );
}

#[test]
fn the_vtk_output_carries_the_material_frame() {
    use splinerod::output::vtk::VtkWriter;
    let dir = std::env::temp_dir().join(format!("splinerod_twist_vtk_{}", std::process::id()));
    let scene = Scene::from_toml(&torsion_scene(8, 2.0, "static")).expect("scene");
    let mut writer = VtkWriter::new(&dir, 1).expect("writer");
    splinerod::run_observed(&scene, &mut [&mut writer]).expect("run");
    let text = std::fs::read_to_string(dir.join("centreline_00001.vtp")).expect("equilibrium file");
    let array = text
        .split(r#"Name="material_director" NumberOfComponents="3" format="ascii">"#)
        .nth(1)
        .and_then(|rest| rest.split("</DataArray>").next())
        .expect("material_director array");
    let values: Vec<Real> = array
        .split_whitespace()
        .map(|v| v.parse().expect("number"))
        .collect();
    let _ = std::fs::remove_dir_all(&dir);
    // A straight rod along z turned by 2 rad: the director turns from x by Φ s/L.
    let first = Vector3::new(values[0], values[1], values[2]);
    let n = values.len();
    let last = Vector3::new(values[n - 3], values[n - 2], values[n - 1]);
    assert!((first - Vector3::x()).norm() < 1e-12, "{first:?}");
    assert!(
        (last - Vector3::new(2.0_f64.cos(), 2.0_f64.sin(), 0.0)).norm() < 1e-9,
        "{last:?}"
    );
}
