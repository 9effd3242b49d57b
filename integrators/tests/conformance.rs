//! Every integrator shipped with splinerod passes the conformance suite. Adding an
//! integrator means adding one line to `integrators()`.

use splinerod_integrators::conformance::{
    check_integrator, EnergyBehaviour, Expectations, TestString,
};
use splinerod_integrators::{
    Bdf2, ImplicitEuler, ImplicitMidpoint, Integrator, IntegratorError, NewtonParams,
};

type Make = fn() -> Result<Box<dyn Integrator>, IntegratorError>;

fn integrators() -> Vec<(&'static str, Make, Expectations)> {
    use EnergyBehaviour::*;
    let e = |order, free_flight_lag, energy| Expectations {
        order,
        free_flight_lag,
        energy,
    };
    vec![
        (
            "implicit-euler",
            || Ok(Box::new(ImplicitEuler::new(NewtonParams::default())?)),
            e(1.0, 0.5, Dissipating),
        ),
        (
            "implicit-midpoint",
            || Ok(Box::new(ImplicitMidpoint::new(NewtonParams::default())?)),
            e(2.0, 0.0, Conserving),
        ),
        (
            "bdf2",
            || Ok(Box::new(Bdf2::new(NewtonParams::default())?)),
            e(2.0, 0.0, Dissipating),
        ),
    ]
}

#[test]
fn every_integrator_conforms() {
    for (name, make, expect) in integrators() {
        assert_eq!(make().unwrap().name(), name);
        let report = check_integrator(&make, expect).unwrap_or_else(|e| panic!("{e}"));
        println!("{name}: {report:?}");
    }
}

/// The suite must be able to fail: an integrator that ignores the forces is caught.
#[test]
fn suite_catches_a_wrong_integrator() {
    struct Drift;
    impl Integrator for Drift {
        fn name(&self) -> &str {
            "drift"
        }
        fn step(
            &mut self,
            system: &mut dyn splinerod_integrators::System,
            dt: splinerod_core::Real,
        ) -> Result<splinerod_integrators::StepStats, IntegratorError> {
            let rod = system.rod_mut();
            for (q, v) in rod.positions.iter_mut().zip(&rod.velocities) {
                *q += v * dt;
            }
            Ok(Default::default())
        }
    }
    let expect = Expectations {
        order: 1.0,
        free_flight_lag: 0.5,
        energy: EnergyBehaviour::Dissipating,
    };
    let err = check_integrator(&|| Ok(Box::new(Drift)), expect).unwrap_err();
    assert!(err.contains("free-flight"), "{err}");
}

/// BDF2 keeps its history across a step change up to ×2 (variable-step formula),
/// restarts (midpoint step) when the step changes more or the basis changes, and still
/// conserves momentum.
#[test]
fn bdf2_restarts_on_large_dt_and_basis_changes() {
    let mut sys = TestString::new(9, 20.0, nalgebra::Vector3::zeros()).unwrap();
    for (i, v) in sys.rod.velocities.iter_mut().enumerate() {
        *v = nalgebra::Vector3::new(0.1 * i as f64, 0.3, -0.2 * (i as f64).cos());
    }
    let p0 = sys.rod.linear_momentum();
    let mut bdf2 = Bdf2::new(NewtonParams::default()).unwrap();
    for (k, dt) in [0.01, 0.01, 0.005, 0.005, 0.005, 0.02, 0.01]
        .into_iter()
        .enumerate()
    {
        if k == 4 {
            sys.rod.insert_knot(0.77).unwrap();
        }
        // A fresh midpoint step from the same state: what a restart must give.
        let mut fresh = sys.clone();
        let mut midpoint = ImplicitMidpoint::new(NewtonParams::default()).unwrap();
        midpoint.step(&mut fresh, dt).unwrap();
        bdf2.step(&mut sys, dt).unwrap();
        let same = fresh.rod.positions == sys.rod.positions;
        // Steps 0 (start), 4 (basis changed) and 5 (dt ×4) restart; 2 (dt ×½) and 6
        // (dt ×½) use the variable-step formula.
        assert_eq!(same, [0, 4, 5].contains(&k), "step {k}");
    }
    assert!((sys.rod.linear_momentum() - p0).norm() < 1e-12 * p0.norm());
}
