//! The rigid bodies' tracks: JSON `bodies[i]`, each body's pose, velocities and the
//! rods' wrench on it at every recorded time (the start, then after every stage).
//!
//! The wrench is the negative of the held pins' forces on the rods, at the rods' held
//! points, about the centre of mass ([`crate::RodSystem::body_wrench`]); it is zero at
//! the start (no step has solved the pins' forces yet).

use crate::{RodSystem, Simulation};
use serde::{Deserialize, Serialize};
use splinerod_core::Real;

/// One body's track.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct BodyTrack {
    /// The body's name (`[[bodies]] name`).
    pub name: String,
    /// Mass, kg.
    pub mass: Real,
    /// Times, s (the initial state first).
    pub t: Vec<Real>,
    /// Centre of mass, m.
    pub position: Vec<[Real; 3]>,
    /// Orientation as a rotation vector (axis × angle, rad) from the world frame.
    pub orientation: Vec<[Real; 3]>,
    /// Velocity of the centre of mass, m/s.
    pub velocity: Vec<[Real; 3]>,
    /// Angular velocity in the world frame, rad/s.
    pub angular_velocity: Vec<[Real; 3]>,
    /// The rods' force on the body, N.
    pub force: Vec<[Real; 3]>,
    /// The rods' torque on the body about its centre of mass, N m.
    pub torque: Vec<[Real; 3]>,
}

/// The bodies' tracks at the start of a run.
pub(crate) fn tracks_at_start(system: &RodSystem) -> Vec<BodyTrack> {
    let mut tracks: Vec<BodyTrack> = system
        .bodies
        .names
        .iter()
        .zip(&system.bodies.bodies)
        .map(|(name, b)| BodyTrack {
            name: name.clone(),
            mass: b.mass,
            ..BodyTrack::default()
        })
        .collect();
    record(&mut tracks, system, &[], 0.0);
    tracks
}

/// Appends the bodies' state of `sim` at its time.
pub(crate) fn record_simulation(tracks: &mut [BodyTrack], sim: &Simulation) {
    if tracks.is_empty() {
        return;
    }
    let forces = sim.integrator.pin_forces();
    record(tracks, &sim.system, &forces, sim.time);
}

/// Appends each body's state at time `t`, with the wrench of `pin_forces`.
fn record(
    tracks: &mut [BodyTrack],
    system: &RodSystem,
    pin_forces: &[nalgebra::Vector3<Real>],
    t: Real,
) {
    for (k, (track, b)) in tracks.iter_mut().zip(&system.bodies.bodies).enumerate() {
        let (force, torque) = system.body_wrench(k, pin_forces);
        track.t.push(t);
        track.position.push(b.position.into());
        track.orientation.push(b.orientation.scaled_axis().into());
        track.velocity.push(b.velocity.into());
        track.angular_velocity.push(b.angular_velocity.into());
        track.force.push(force.into());
        track.torque.push(torque.into());
    }
}

/// The bodies' energies for the JSON's `energy` (none without bodies): their kinetic
/// energy and the potential of their external forces, \(-\sum F\cdot x\) (gravity).
pub(crate) fn energies(system: &RodSystem) -> Vec<(String, Real)> {
    let bodies = &system.bodies.bodies;
    if bodies.is_empty() {
        return Vec::new();
    }
    let kinetic = bodies.iter().map(|b| b.kinetic_energy()).sum();
    let potential = bodies.iter().map(|b| -b.force.dot(&b.position)).sum();
    vec![
        ("bodies_kinetic".to_string(), kinetic),
        ("bodies_potential".to_string(), potential),
    ]
}
