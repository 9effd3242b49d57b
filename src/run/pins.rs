//! The forces and torques of a scene's `[[pins]]` entries at the end of a run, read from
//! the integrator's pin forces: one per entry, an exact clamp's tangent pin folded into
//! its clamp.
//!
//! Sign: what a run reports is the wrench the rod puts on each pin's support (the
//! gripper, the body, the fixed point), the opposite of the integrators' pin forces
//! (the multipliers' forces on the rod): \\(F_j = -\sum_{i \in j} f_i\\). A force sensor
//! in a gripper reads this; the rod's weight hanging from a pin pulls it down.

use crate::scene::Scene;
use crate::{Error, Simulation};
use splinerod_core::Real;

/// One force per `[[pins]]` entry: an exact clamp's tangent pin (after them in the
/// system) adds its force to its clamp's ([`pin_force_of`]).
pub(crate) fn scene_pin_forces(scene: &Scene, sim: &Simulation) -> Vec<[Real; 3]> {
    fold_pin_forces(scene, sim, sim.integrator.pin_forces())
}

/// `forces`, one per pin of the system (or their derivatives), as one per `[[pins]]`
/// entry ([`scene_pin_forces`]).
pub(crate) fn fold_pin_forces(
    scene: &Scene,
    sim: &Simulation,
    forces: Vec<nalgebra::Vector3<Real>>,
) -> Vec<[Real; 3]> {
    let count = scene.pins.len().min(forces.len());
    let pins = &sim.system.pins;
    (0..count)
        .map(|j| pin_force_of(scene, pins, &forces, j).into())
        .collect()
}

/// The force the rod puts on `[[pins]]` entry `j`'s support from `forces`, the forces
/// on the rod of each pin of the system `pins` (or their derivatives): minus its pin's,
/// plus an exact clamp's tangent pin's (the pair's net force; their moment is the
/// clamp's bending moment). Zero for a pin beyond `forces`.
pub(crate) fn pin_force_of(
    scene: &Scene,
    pins: &[splinerod_core::Pin],
    forces: &[nalgebra::Vector3<Real>],
    j: usize,
) -> nalgebra::Vector3<Real> {
    let own = forces.get(j).copied().unwrap_or_default();
    let tangents = clamp_tangents(scene, pins, forces.len()).filter(|&(_, c)| c == j);
    opposite(tangents.fold(own, |f, (i, _)| f + forces[i]))
}

/// `(i, j)` for every exact clamp: its tangent pin `i` among the system's `pins` (below
/// `count`) and its `[[pins]]` entry `j`.
pub(crate) fn clamp_tangents<'a>(
    scene: &'a Scene,
    pins: &'a [splinerod_core::Pin],
    count: usize,
) -> impl Iterator<Item = (usize, usize)> + 'a {
    (scene.pins.len()..count.min(pins.len())).filter_map(move |i| {
        let pin = &pins[i];
        let clamp = scene.pins.iter().position(|p| {
            p.clamp
                && matches!(scene.entry_coordinate(p.rod.as_deref(), p.at), Ok(s) if s == pin.at)
        });
        clamp.filter(|_| pin.tangent).map(|j| (i, j))
    })
}

/// One torque per `[[pins]]` entry (N·m, about the pinned point), the rod's on the
/// support: minus the torque the pin exerts on the rod, the twisting moment at the end
/// clamps ([`crate::run::twist::pin_torques`]) plus, at an exact clamp, the bending
/// moment of its pin pair, \\((q_1 - q_0) \times F_1\\) with \\(F_1\\) the force on the
/// control point next to the end. Empty when no pin carries a torque.
pub(crate) fn pin_torques(scene: &Scene, sim: &Simulation) -> Result<Vec<[Real; 3]>, Error> {
    let mut torques = crate::run::twist::pin_torques(scene, &sim.system)?;
    let forces = sim.integrator.pin_forces();
    let rod = &sim.system.rod;
    for (i, j) in clamp_tangents(scene, &sim.system.pins, forces.len()) {
        let pin = &sim.system.pins[i];
        let next = pin.row(rod)?.first;
        let points = rod.segment_points(rod.segment_at(pin.at));
        let end = if next == points.start + 1 {
            points.start
        } else {
            points.end - 1
        };
        let moment = (rod.positions[next] - rod.positions[end]).cross(&forces[i]);
        torques.resize(scene.pins.len(), [0.0; 3]);
        torques[j] = (nalgebra::Vector3::from(torques[j]) + moment).into();
    }
    let on_support = torques.into_iter().map(|t| opposite(t.into()).into());
    Ok(on_support.collect())
}

/// `-v`, with a zero component staying `+0` (so that a JSON reads `0.0`, not `-0.0`).
fn opposite(v: nalgebra::Vector3<Real>) -> nalgebra::Vector3<Real> {
    nalgebra::Vector3::zeros() - v
}
