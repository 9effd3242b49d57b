//! A simulation's state between two steps as plain data, for checkpoints.
//!
//! [`Simulation::save_state`] records what the next steps depend on and the scene does
//! not determine; [`Simulation::restore_state`] puts it into a simulation freshly built
//! from the same scene, after which both step bit for bit alike:
//!
//! * the rod's coefficients, the time, the step count, the sub-stepping controller's
//!   memory and the length of the last step;
//! * the knot changes so far, replayed in order through [`RodSystem::change_knots`]
//!   (every energy hears the same maps, so the rest shapes and caches that follow the
//!   knots come out the same; the coefficients are then overwritten);
//! * the pins' positions, the grabs' springs and the grippers' poses;
//! * each energy's and the integrator's own state ([`splinerod_core::state`]);
//! * the adapter's protected knots and the error estimator's schedule and last estimate.
//!
//! [`RodSystem::change_knots`]: crate::RodSystem::change_knots

use crate::{Error, Simulation};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use splinerod_core::{CoreError, KnotOperation, Real, SavedState};

/// One knot change of the run, in order: an insertion of `value`, or the removal of knot
/// `index`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub enum KnotChange {
    /// A knot inserted at this material coordinate (m).
    Insert(Real),
    /// Knot `index` removed.
    Remove(usize),
}

/// An extension's [`SavedState`] as serialisable data.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct Numbers {
    /// Reals, in order.
    pub reals: Vec<Real>,
    /// Integers, in order.
    pub ints: Vec<u64>,
}

impl From<SavedState> for Numbers {
    fn from(s: SavedState) -> Self {
        Self {
            reals: s.reals,
            ints: s.ints,
        }
    }
}

impl Numbers {
    fn saved(&self) -> SavedState {
        SavedState {
            reals: self.reals.clone(),
            ints: self.ints.clone(),
        }
    }
}

/// A grab's state: its spring's target and where its path starts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GrabState {
    /// The spring's target, m.
    pub target: [Real; 3],
    /// The path's start, once the grab has begun.
    pub from: Option<[Real; 3]>,
}

/// A gripper's pose ([`crate::world::gripper::Pose`]) as plain data.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseState {
    /// Translation of the clamp point, m.
    pub translation: [Real; 3],
    /// Rotation matrix, row by row.
    pub rotation: [Real; 9],
    /// Roll about the carried tangent, rad.
    pub roll: Real,
}

/// The state of a [`Simulation`] between two steps (module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SimulationState {
    /// Simulated time, s.
    pub time: Real,
    /// Steps taken.
    pub steps: usize,
    /// The system's clock, s.
    pub system_time: Real,
    /// Length of the last step, s.
    pub last_dt: Real,
    /// The sub-stepping controller's next length, ceiling and streak.
    pub substep: (Option<Real>, Option<Real>, usize),
    /// Every knot change so far.
    pub knot_changes: Vec<KnotChange>,
    /// Control points, m.
    pub positions: Vec<[Real; 3]>,
    /// Their velocities, m/s.
    pub velocities: Vec<[Real; 3]>,
    /// The velocities at the start of the last step, m/s (the error estimate's inertial
    /// load; empty before the first step).
    pub start_velocities: Vec<[Real; 3]>,
    /// Each pin's position, m.
    pub pins: Vec<[Real; 3]>,
    /// Each grab's state.
    pub grabs: Vec<GrabState>,
    /// Each gripper's pose (`None`: never moved); empty if no gripper moved.
    pub grippers: Vec<Option<PoseState>>,
    /// Each energy's own state, in the system's order.
    pub energies: Vec<Numbers>,
    /// The integrator's own state.
    pub integrator: Numbers,
    /// The adapter's protected knots (coordinate, steps left), if adaptive.
    pub protected: Option<Vec<(Real, usize)>>,
    /// The error estimator's schedule and last estimate, if on.
    pub estimation: Option<Numbers>,
    /// Each rigid body's state.
    pub bodies: Vec<BodyState>,
}

/// A rigid body's state ([`splinerod_core::RigidBody`]; its mass properties come from
/// the scene).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BodyState {
    /// Centre of mass, m.
    pub position: [Real; 3],
    /// Orientation, a unit quaternion `[i, j, k, w]`.
    pub orientation: [Real; 4],
    /// Velocity, m/s.
    pub velocity: [Real; 3],
    /// Angular velocity (world frame), rad/s.
    pub angular_velocity: [Real; 3],
}

fn arrays(vs: &[Vector3<Real>]) -> Vec<[Real; 3]> {
    vs.iter().map(|v| [v.x, v.y, v.z]).collect()
}

fn vectors(xs: &[[Real; 3]]) -> Vec<Vector3<Real>> {
    xs.iter().map(|&x| x.into()).collect()
}

fn mismatch(what: &'static str) -> Error {
    Error::Core(CoreError::StateMismatch(what))
}

impl Simulation {
    /// The state between steps (module docs).
    pub fn save_state(&self) -> SimulationState {
        let system = &self.system;
        let energies = system.energies.iter().map(|e| {
            let mut out = SavedState::default();
            if let Some(l) = e.capabilities().lifecycle {
                l.save_state(&mut out);
            }
            Numbers::from(out)
        });
        let mut integrator = SavedState::default();
        self.integrator.save_state(&mut integrator);
        let memory = self.substep.memory();
        SimulationState {
            time: self.time,
            steps: self.steps,
            system_time: system.time,
            last_dt: self.last_dt,
            substep: (memory.next, memory.ceiling, memory.streak),
            knot_changes: system.knot_changes.clone(),
            positions: arrays(&system.rod.positions),
            velocities: arrays(&system.rod.velocities),
            start_velocities: arrays(&self.saved.1),
            pins: system.pins.iter().map(|p| p.position.into()).collect(),
            grabs: system
                .grabs
                .iter()
                .map(|g| GrabState {
                    target: g.spring.target.into(),
                    from: g.from.map(Into::into),
                })
                .collect(),
            grippers: gripper_states(system),
            energies: energies.collect(),
            integrator: integrator.into(),
            protected: self.adapter.as_ref().map(|a| a.protected().to_vec()),
            estimation: self.estimation.as_ref().map(|e| e.save().into()),
            bodies: system
                .bodies
                .bodies
                .iter()
                .map(|b| BodyState {
                    position: b.position.into(),
                    orientation: b.orientation.coords.into(),
                    velocity: b.velocity.into(),
                    angular_velocity: b.angular_velocity.into(),
                })
                .collect(),
        }
    }

    /// Puts `state` into this simulation, freshly built from the scene `state` was saved
    /// from (module docs). An error if it does not fit; the simulation is then unusable.
    pub fn restore_state(&mut self, state: &SimulationState) -> Result<(), Error> {
        self.replay(&state.knot_changes)?;
        let system = &mut self.system;
        let n = system.rod.len();
        if state.positions.len() != n || state.velocities.len() != n {
            return Err(mismatch("control points of another rod"));
        }
        system.rod.positions = vectors(&state.positions);
        system.rod.velocities = vectors(&state.velocities);
        system.rod.check_finite()?;
        if state.pins.len() != system.pins.len() || state.grabs.len() != system.grabs.len() {
            return Err(mismatch("pins or grabs of another scene"));
        }
        for (pin, &p) in system.pins.iter_mut().zip(&state.pins) {
            pin.position = p.into();
        }
        for (grab, g) in system.grabs.iter_mut().zip(&state.grabs) {
            grab.spring.target = g.target.into();
            grab.from = g.from.map(Into::into);
        }
        restore_grippers(system, &state.grippers)?;
        restore_bodies(system, &state.bodies)?;
        if state.energies.len() != system.energies.len() {
            return Err(mismatch("energies of another scene"));
        }
        let rod = &system.rod;
        for (energy, numbers) in system.energies.iter_mut().zip(&state.energies) {
            let saved = numbers.saved();
            let mut reader = saved.reader();
            if let Some(l) = energy.lifecycle_mut() {
                l.load_state(rod, &mut reader)?;
            }
            reader.finish()?;
        }
        let saved = state.integrator.saved();
        let mut reader = saved.reader();
        self.integrator.load_state(rod, &mut reader)?;
        reader.finish()?;
        self.restore_rest(state)
    }

    /// The clocks, the controller, the adapter and the estimator.
    fn restore_rest(&mut self, state: &SimulationState) -> Result<(), Error> {
        (self.time, self.steps, self.last_dt) = (state.time, state.steps, state.last_dt);
        self.saved.1 = vectors(&state.start_velocities);
        self.system.time = state.system_time;
        let (next, ceiling, streak) = state.substep;
        self.substep.restore(crate::world::substep::SubstepMemory {
            next,
            ceiling,
            streak,
        });
        match (&mut self.adapter, &state.protected) {
            (Some(a), Some(p)) => a.set_protected(p),
            (None, None) => {}
            _ => return Err(mismatch("adaptivity of another scene")),
        }
        match (&mut self.estimation, &state.estimation) {
            (Some(e), Some(numbers)) => e.load(&numbers.saved()),
            (None, None) => Ok(()),
            _ => Err(mismatch("an error estimate of another scene")),
        }
    }

    /// Applies `changes` to the freshly built rod, every energy hearing each map.
    fn replay(&mut self, changes: &[KnotChange]) -> Result<(), Error> {
        if !self.system.knot_changes.is_empty() {
            return Err(mismatch("a simulation that has changed its knots already"));
        }
        for &change in changes {
            self.system.change_knots(|rod, heard| {
                let map = match change {
                    KnotChange::Insert(s) => rod.insert_knot(s)?,
                    KnotChange::Remove(index) => rod.remove_knot(index, Real::MAX)?,
                };
                heard(rod, &map);
                Ok::<(), CoreError>(())
            })?;
        }
        Ok(())
    }
}

/// The grippers' poses, or nothing if none moved.
fn gripper_states(system: &crate::RodSystem) -> Vec<Option<PoseState>> {
    if system.grippers.iter().all(|g| g.held.is_none()) {
        return Vec::new();
    }
    let state = |p: &crate::world::gripper::Pose| {
        let mut rotation = [0.0; 9];
        for (k, r) in rotation.iter_mut().enumerate() {
            *r = p.rotation[(k / 3, k % 3)];
        }
        PoseState {
            translation: p.translation.into(),
            rotation,
            roll: p.roll,
        }
    };
    system
        .grippers
        .iter()
        .map(|g| g.held.as_ref().map(state))
        .collect()
}

/// Puts the saved poses back on the grippers, their pins and energies (before the
/// energies read their own state, which already counts the rolls).
fn restore_grippers(
    system: &mut crate::RodSystem,
    saved: &[Option<PoseState>],
) -> Result<(), Error> {
    if saved.is_empty() {
        return Ok(());
    }
    if saved.len() != system.grippers.len() {
        return Err(mismatch("grippers of another scene"));
    }
    for (k, s) in saved.iter().enumerate() {
        if let Some(s) = s {
            let pose = crate::world::gripper::Pose {
                translation: s.translation.into(),
                rotation: nalgebra::Matrix3::from_row_slice(&s.rotation),
                roll: s.roll,
            };
            system.set_gripper_pose(k, pose)?;
        }
    }
    Ok(())
}

/// Puts the saved states back on the bodies (and their pins on them).
fn restore_bodies(system: &mut crate::RodSystem, saved: &[BodyState]) -> Result<(), Error> {
    if saved.len() != system.bodies.bodies.len() {
        return Err(mismatch("bodies of another scene"));
    }
    for (b, s) in system.bodies.bodies.iter_mut().zip(saved) {
        b.position = s.position.into();
        let q = nalgebra::Quaternion::from(nalgebra::Vector4::from(s.orientation));
        b.orientation = nalgebra::UnitQuaternion::new_normalize(q);
        b.velocity = s.velocity.into();
        b.angular_velocity = s.angular_velocity.into();
        b.check()?;
    }
    system.follow_bodies();
    Ok(())
}

/// The change a knot map made, for the log.
pub(crate) fn change_of(map: &splinerod_core::KnotMap) -> KnotChange {
    match map.operation() {
        KnotOperation::Insert => KnotChange::Insert(map.value()),
        KnotOperation::Remove => KnotChange::Remove(map.knot_index()),
    }
}
