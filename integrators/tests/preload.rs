//! A preloaded step ([`Integrator::preload`], the batched ensemble's hand-over) is taken
//! by the next step of the same `dt` from the same state, once, and ignored otherwise.

use nalgebra::Vector3;
use splinerod_core::Real;
use splinerod_integrators::conformance::TestString;
use splinerod_integrators::lane_euler::LaneOutcome;
use splinerod_integrators::{ImplicitEuler, Integrator, NewtonParams, StepStats};

fn string() -> TestString {
    let g = Vector3::new(0.0, -9.81, 0.0);
    TestString::new(8, 3.0, g)
        .expect("string")
        .pin_ends()
        .expect("pins")
}

fn euler() -> ImplicitEuler {
    ImplicitEuler::new(NewtonParams::default()).expect("params")
}

/// A field of 3-vectors.
type Field = Vec<Vector3<Real>>;

/// An outcome no solver would produce (every point moved up by 1 m): positions,
/// velocities, pin forces.
fn marked(system: &TestString) -> (Field, Field, Field) {
    let up = Vector3::new(0.0, 1.0, 0.0);
    let q = system.rod.positions.iter().map(|p| p + up).collect();
    (q, system.rod.velocities.clone(), vec![Vector3::zeros(); 2])
}

#[test]
fn a_preloaded_step_is_taken_once_and_only_from_its_start() {
    let dt = 1e-3;
    let (q, v, f) = marked(&string());
    let stats = StepStats {
        batched: 1,
        ..StepStats::default()
    };
    let outcome = LaneOutcome {
        positions: &q,
        velocities: &v,
        stats,
        pin_forces: &f,
    };
    // From its start and dt: taken, with its counters and pin forces.
    let (mut system, mut scheme) = (string(), euler());
    let start = (system.rod.positions.clone(), system.rod.velocities.clone());
    scheme.preload((&start.0, &start.1), &outcome, dt);
    let taken = scheme.step(&mut system, dt).expect("step");
    assert_eq!(taken.batched, 1);
    assert_eq!(system.rod.positions, q);
    assert_eq!(scheme.pin_forces(), f);
    // Once: the next step solves.
    assert_eq!(scheme.step(&mut system, dt).expect("step").batched, 0);

    // Another dt, or another start: ignored, and the step solves as without it.
    let (mut reference, mut plain) = (string(), euler());
    plain.step(&mut reference, dt).expect("step");
    for (start_dt, moved) in [(2e-3, false), (dt, true)] {
        let (mut system, mut scheme) = (string(), euler());
        let mut start = (system.rod.positions.clone(), system.rod.velocities.clone());
        if moved {
            start.0[3].y += 1e-12;
        }
        scheme.preload((&start.0, &start.1), &outcome, start_dt);
        let stats = scheme.step(&mut system, dt).expect("step");
        assert_eq!(stats.batched, 0);
        assert_eq!(system.rod.positions, reference.rod.positions);
    }
}
