//! A preloaded step ([`Batched::preload`], the batched ensemble's hand-over) is taken
//! by the next step of the same `dt` from the same state, once, and ignored otherwise.

use nalgebra::Vector3;
use splinerod_core::Real;
use splinerod_integrators::conformance::TestString;
use splinerod_integrators::lane_euler::LaneOutcome;
use splinerod_integrators::{Batched, ImplicitEuler, Integrator, NewtonParams, StepStats};

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
    let batched = scheme.batched().expect("implicit Euler has a batched form");
    assert_eq!(batched.lane_params(), NewtonParams::default());
    batched.preload((&start.0, &start.1), &outcome, dt);
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

/// The 64-bit FNV-style hash that recognised a preloaded start until #47: a sign flip
/// changes only the top bit of its chain, and the multiplications carry a top bit
/// nowhere else, so two sign flips anywhere cancel.
fn old_fingerprint(positions: &[Vector3<Real>], velocities: &[Vector3<Real>]) -> u64 {
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    let mut chains = [0xcbf2_9ce4_8422_2325_u64; 6];
    for (field, chains) in [positions, velocities]
        .iter()
        .zip(chains.chunks_exact_mut(3))
    {
        for p in field.iter() {
            for (h, x) in chains.iter_mut().zip(p.iter()) {
                *h = (*h ^ x.to_bits()).wrapping_mul(PRIME);
            }
        }
    }
    let lengths = (positions.len() as u64) << 32 | velocities.len() as u64;
    chains
        .iter()
        .fold(lengths, |h, &c| (h ^ c).wrapping_mul(PRIME))
}

#[test]
fn a_state_the_old_hash_confused_with_the_start_is_not_taken_for_it() {
    let dt = 1e-3;
    let (q, v, f) = marked(&string());
    let outcome = LaneOutcome {
        positions: &q,
        velocities: &v,
        stats: StepStats {
            batched: 1,
            ..StepStats::default()
        },
        pin_forces: &f,
    };
    // Moving: two interior points with velocities that are not zero.
    let moving = || {
        let mut s = string();
        (s.rod.velocities[3].y, s.rod.velocities[5].y) = (0.5, 0.25);
        s
    };
    let start = {
        let s = moving();
        (s.rod.positions.clone(), s.rod.velocities.clone())
    };
    // Both velocities' signs flipped: another state, the same hash.
    let (mut system, mut scheme) = (moving(), euler());
    let w = &mut system.rod.velocities;
    (w[3].y, w[5].y) = (-w[3].y, -w[5].y);
    assert_ne!(system.rod.velocities, start.1);
    assert_eq!(
        old_fingerprint(&system.rod.positions, &system.rod.velocities),
        old_fingerprint(&start.0, &start.1),
    );
    scheme.preload((&start.0, &start.1), &outcome, dt);
    let stats = scheme.step(&mut system, dt).expect("step");
    assert_eq!(
        stats.batched, 0,
        "a state with the start's hash taken for the start"
    );
    assert_ne!(system.rod.positions, q);

    // The genuine start is.
    let (mut system, mut scheme) = (moving(), euler());
    scheme.preload((&start.0, &start.1), &outcome, dt);
    assert_eq!(scheme.step(&mut system, dt).expect("step").batched, 1);
    assert_eq!(system.rod.positions, q);
}
