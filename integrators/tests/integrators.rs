//! Integrator checks on a test system with a quadratic energy that knows its answers:
//! \\(E = \tfrac{k}{2}\int |C'|^2 ds - \int \mu g \cdot C\, ds\\), whose equilibrium
//! between pins is a parabola (exactly representable by cubics) and whose pinned modes
//! are \\(\omega_j = j\pi/L\,\sqrt{k/\mu}\\).

use nalgebra::Vector3;
use splinerod_core::{Pin, Real};
use splinerod_integrators::{
    modal, ImplicitEuler, Integrator, IntegratorError, LinearSolverKind, NewtonParams,
    StaticParams, StaticSolver, System,
};

/// The suite's test string (quadratic energy), under its historical name here.
use splinerod_integrators::conformance::TestString as Quadratic;

#[test]
fn free_flight_under_gravity_is_reproduced_exactly() {
    // No internal energy: implicit Euler gives v_n = v0 + n h g, q_n = q0 + n h v0 + h² g n(n+1)/2.
    let g = Vector3::new(0.3, -9.81, 0.1);
    let mut sys = Quadratic::new(7, 0.0, g).unwrap();
    let v0 = Vector3::new(1.0, 2.0, -0.5);
    sys.rod.velocities.iter_mut().for_each(|v| *v = v0);
    let q0 = sys.rod.positions.clone();
    let mut euler = ImplicitEuler::new(NewtonParams::default()).unwrap();
    let (h, steps) = (0.01, 50);
    for _ in 0..steps {
        euler.step(&mut sys, h).unwrap();
    }
    let n = steps as Real;
    for (q, q0) in sys.rod.positions.iter().zip(&q0) {
        let exact = q0 + v0 * (n * h) + g * (h * h * n * (n + 1.0) / 2.0);
        assert!((q - exact).norm() < 1e-12, "{}", (q - exact).norm());
    }
}

#[test]
fn internal_forces_conserve_momentum_and_never_add_energy() {
    let mut sys = Quadratic::new(9, 50.0, Vector3::zeros()).unwrap();
    for (i, v) in sys.rod.velocities.iter_mut().enumerate() {
        *v = Vector3::new((i as Real).sin(), 0.5 * (i as Real).cos(), 0.2);
    }
    let p0 = sys.rod.linear_momentum();
    let mut energy = sys.rod.kinetic_energy() + sys.potential_energy();
    let mut euler = ImplicitEuler::new(NewtonParams::default()).unwrap();
    for _ in 0..300 {
        euler.step(&mut sys, 0.005).unwrap();
        let e = sys.rod.kinetic_energy() + sys.potential_energy();
        assert!(e <= energy * (1.0 + 1e-12), "energy grew: {energy} -> {e}");
        energy = e;
    }
    assert!((sys.rod.linear_momentum() - p0).norm() < 1e-12 * p0.norm());
}

#[test]
fn static_solver_finds_the_parabola_and_pin_forces() {
    // k C'' = -μ g with C(0) = 0, C(L) = (L,0,0): C(s) = (s, μ g s (L - s) / (2k)) for g along -y.
    let (k, mu, l) = (3.0, 0.5, 2.0);
    let g = Vector3::new(0.0, -9.81, 0.0);
    let mut sys = Quadratic::new(8, k, g).unwrap().pin_ends().unwrap();
    let mut solver = StaticSolver::new(StaticParams::default()).unwrap();
    let stats = solver.solve(&mut sys).unwrap();
    assert!(stats.converged);
    for i in 0..=40 {
        let s = l * i as Real / 40.0;
        let exact = Vector3::new(s, -mu * 9.81 * s * (l - s) / (2.0 * k), 0.0);
        assert!((sys.rod.point(s).unwrap() - exact).norm() < 1e-12);
    }
    // Each pin carries half the weight: μ L g / 2 upwards.
    for f in solver.pin_forces() {
        assert!((f.y - mu * l * 9.81 / 2.0).abs() < 1e-10, "{f}");
    }
}

#[test]
fn pins_hold_their_targets_and_may_move() {
    let mut sys = Quadratic::new(8, 10.0, Vector3::new(0.0, -9.81, 0.0)).unwrap();
    sys.pins = vec![
        Pin::here(&sys.rod, 0.0).unwrap(),
        Pin::here(&sys.rod, 0.7).unwrap(),
    ];
    let mut euler = ImplicitEuler::new(NewtonParams::default()).unwrap();
    for step in 0..20 {
        sys.pins[1].position = Vector3::new(0.7, 0.01 * step as Real, 0.0);
        euler.step(&mut sys, 0.01).unwrap();
        for pin in &sys.pins {
            assert!(pin.violation(&sys.rod).unwrap().norm() < 1e-12);
        }
    }
}

#[test]
fn modes_of_the_pinned_string() {
    // ω_j = jπ/L √(k/μ) for the continuum; cubic Galerkin with 30 control points.
    let (k, mu, l) = (4.0, 0.5, 2.0);
    let sys = Quadratic::new(30, k, Vector3::zeros())
        .unwrap()
        .pin_ends()
        .unwrap();
    let modes = modal::modes(&sys, 9).unwrap();
    // Each frequency is threefold (x, y, z move independently for this energy).
    for j in 1..=3 {
        let exact = j as Real * std::f64::consts::PI / l * (k / mu).sqrt();
        for m in &modes[3 * (j - 1)..3 * j] {
            // Galerkin error ∝ (jπh/L)^6: about 3e-8 at j = 3 here; 1e-6 still catches any
            // mis-scaled mass or stiffness (those are O(1) errors).
            assert!(
                (m.omega - exact).abs() < 1e-6 * exact,
                "mode {j}: {} vs {exact}",
                m.omega
            );
        }
    }
}

#[test]
fn a_non_finite_step_is_rolled_back() {
    let mut sys = Quadratic::new(8, 10.0, Vector3::zeros()).unwrap();
    sys.rod.velocities[3] = Vector3::new(0.0, 1.0, 0.0);
    let mut euler = ImplicitEuler::new(NewtonParams::default()).unwrap();
    euler.step(&mut sys, 0.01).unwrap();
    let (q, v) = (sys.rod.positions.clone(), sys.rod.velocities.clone());
    sys.poison = true;
    let err = euler.step(&mut sys, 0.01).unwrap_err();
    assert!(matches!(err, IntegratorError::NonFinite { .. }), "{err}");
    assert_eq!(sys.rod.positions, q);
    assert_eq!(sys.rod.velocities, v);
}

#[test]
fn symbolic_analysis_only_after_a_basis_change() {
    // The sparse (faer) path analyses once per basis; the banded path never needs to.
    for (kind, analyses) in [(LinearSolverKind::Sparse, 1), (LinearSolverKind::Banded, 0)] {
        let mut sys = Quadratic::new(8, 10.0, Vector3::new(0.0, -1.0, 0.0))
            .unwrap()
            .pin_ends()
            .unwrap();
        let params = NewtonParams {
            linear_solver: kind,
            ..NewtonParams::default()
        };
        let mut euler = ImplicitEuler::new(params).unwrap();
        assert_eq!(
            euler.step(&mut sys, 0.01).unwrap().symbolic_analyses,
            analyses
        );
        assert_eq!(euler.step(&mut sys, 0.01).unwrap().symbolic_analyses, 0);
        sys.rod.insert_knot(0.77).unwrap();
        assert_eq!(
            euler.step(&mut sys, 0.01).unwrap().symbolic_analyses,
            analyses
        );
        assert_eq!(euler.step(&mut sys, 0.01).unwrap().symbolic_analyses, 0);
    }
}

#[test]
fn banded_and_sparse_factorisations_agree() {
    let run = |kind| {
        let mut sys = Quadratic::new(12, 10.0, Vector3::new(0.0, -9.81, 0.0))
            .unwrap()
            .pin_ends()
            .unwrap();
        let params = NewtonParams {
            linear_solver: kind,
            ..NewtonParams::default()
        };
        let mut euler = ImplicitEuler::new(params).unwrap();
        for _ in 0..20 {
            euler.step(&mut sys, 0.01).unwrap();
        }
        sys.rod.positions
    };
    let (banded, sparse) = (run(LinearSolverKind::Banded), run(LinearSolverKind::Sparse));
    for (a, b) in banded.iter().zip(&sparse) {
        assert!((a - b).norm() < 1e-12, "{a} vs {b}");
    }
}

#[test]
fn bad_parameters_are_errors() {
    let mut sys = Quadratic::new(8, 10.0, Vector3::zeros()).unwrap();
    let mut euler = ImplicitEuler::new(NewtonParams::default()).unwrap();
    for dt in [0.0, -1.0, Real::NAN, Real::INFINITY] {
        assert!(matches!(
            euler.step(&mut sys, dt),
            Err(IntegratorError::InvalidParameter { name: "dt", .. })
        ));
    }
    sys.rod.damping = -1.0;
    assert!(matches!(
        euler.step(&mut sys, 0.1),
        Err(IntegratorError::InvalidParameter {
            name: "damping",
            ..
        })
    ));
    let bad = NewtonParams {
        max_iterations: 0,
        ..NewtonParams::default()
    };
    assert!(ImplicitEuler::new(bad).is_err());
    // Two pins on the same point are redundant.
    let mut sys = Quadratic::new(8, 10.0, Vector3::zeros()).unwrap();
    sys.pins = vec![
        Pin::here(&sys.rod, 0.5).unwrap(),
        Pin::here(&sys.rod, 0.5).unwrap(),
    ];
    assert!(matches!(
        euler.step(&mut sys, 0.01),
        Err(IntegratorError::RedundantPins)
    ));
}

#[test]
fn end_pins_are_eliminated_consistently_with_interior_pins() {
    // Pins at both clamped ends (eliminated), one whose row overlaps the first end's
    // control point, and one inside (both by Schur complement): at equilibrium the pins
    // hold, and the pin forces balance the internal and gravity forces at every control
    // point: ∇E = Σ_p G_pᵀ f_p.
    let g = Vector3::new(0.0, -9.81, 0.0);
    let mut sys = Quadratic::new(10, 3.0, g).unwrap();
    sys.pins = [0.0, 0.05, 1.3, 2.0]
        .iter()
        .map(|&s| Pin::here(&sys.rod, s).unwrap())
        .collect();
    let mut solver = StaticSolver::new(StaticParams::default()).unwrap();
    assert!(solver.solve(&mut sys).unwrap().converged);
    for pin in &sys.pins {
        assert!(pin.violation(&sys.rod).unwrap().norm() < 1e-12);
    }
    let mut balance = vec![Vector3::zeros(); sys.rod.len()];
    sys.add_potential_gradient(&mut balance);
    for (pin, force) in sys.pins.iter().zip(solver.pin_forces()) {
        let row = pin.row(&sys.rod).unwrap();
        for k in 0..row.order {
            balance[row.first + k] -= force * row.value[k];
        }
    }
    let weight = 0.5 * 2.0 * 9.81;
    let worst = balance.iter().map(|v| v.amax()).fold(0.0, Real::max);
    assert!(worst < 1e-10 * weight, "force imbalance {worst:e}");
}

#[test]
fn an_absurd_newton_step_is_rejected_as_divergence() {
    // A step that would move points by ~1e9 rest lengths is not motion but divergence.
    let mut sys = Quadratic::new(7, 0.0, Vector3::new(0.0, -1e10, 0.0)).unwrap();
    let q0 = sys.rod.positions.clone();
    let mut euler = ImplicitEuler::new(NewtonParams::default()).unwrap();
    let err = euler.step(&mut sys, 1.0).unwrap_err();
    assert!(matches!(err, IntegratorError::Diverged { .. }), "{err}");
    assert_eq!(sys.rod.positions, q0, "state rolled back");
    // Ordinary free flight is far below the limit.
    let mut sys = Quadratic::new(7, 0.0, Vector3::new(0.0, -9.81, 0.0)).unwrap();
    assert!(euler.step(&mut sys, 1.0).is_ok());
}
