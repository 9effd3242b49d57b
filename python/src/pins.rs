//! Moving pins between steps: `Simulation.set_pin`, and `Simulation.set_clamp_pose`, a
//! robot's controller moving a clamp's gripper ([`splinerod::world::gripper`]): the
//! clamp point to an absolute position, the gripper turned by a rotation (a 3×3 matrix,
//! or a unit quaternion `(w, x, y, z)`) against its start.

use crate::arrays::{float_array, vector_from};
use crate::driver::Driver;
use crate::errors::{scene_error, shield, to_py, IntoPyResult};
use nalgebra::{Matrix3, Vector3};
use numpy::PyUntypedArrayMethods;
use pyo3::prelude::*;
use splinerod::world::gripper::{check_rotation, quaternion_rotation};
use splinerod::Real;

/// Moves pin `index` to `position` (m) in each member of `members` (a clamp's tangent
/// pin with it); `SceneError` naming `index` or `position`.
pub fn set_pin(
    driver: &mut Driver,
    index: usize,
    position: &Bound<'_, PyAny>,
    members: std::ops::Range<usize>,
) -> PyResult<()> {
    let py = position.py();
    let target = vector_from(position, "position")?;
    for i in members {
        let pins = &driver.sims()[i].system.pins;
        let Some(pin) = pins.get(index).copied() else {
            let message = format!("`index` = {index}: the rod has {} pin(s)", pins.len());
            return Err(scene_error(py, Some("index"), message));
        };
        let shift = target - pin.position;
        if let Some(sim) = driver.sim_mut(i) {
            for (j, p) in sim.system.pins.iter_mut().enumerate() {
                if j == index || (p.tangent && p.at == pin.at) {
                    p.position += shift;
                }
            }
        }
    }
    Ok(())
}

/// The forces member 0's rod puts on its pins' supports (grippers, bodies, fixed points)
/// in the last step, N (a scene: one per `[[pins]]` entry): the opposite of the forces
/// the pins exert on the rod.
pub fn pin_forces(driver: &Driver) -> Vec<Vector3<Real>> {
    let forces = shield(|| {
        Ok(match driver {
            Driver::Scene(run) => run.pin_forces(0).unwrap_or_default(),
            Driver::Code { sim, .. } => on_supports(sim.integrator.pin_forces()),
        })
    });
    forces.unwrap_or_default()
}

/// The forces on the rod `forces` as the forces on the supports, zeros staying `+0`.
fn on_supports(forces: Vec<Vector3<Real>>) -> Vec<Vector3<Real>> {
    forces.into_iter().map(|f| Vector3::zeros() - f).collect()
}

/// The torques member 0's rod puts on the `[[pins]]` entries' supports about their
/// points after the last step, N·m; empty for a simulation built in code.
pub fn pin_torques(py: Python<'_>, driver: &Driver) -> PyResult<Vec<Vector3<Real>>> {
    let torques = match driver {
        Driver::Scene(run) => run.pin_torques(0).transpose().py_err(py)?,
        Driver::Code { .. } => None,
    };
    Ok(torques.unwrap_or_default())
}

/// The rotation `obj` stands for: a `(3, 3)` proper rotation matrix or a quaternion
/// `(w, x, y, z)` (normalised); `SceneError` (a `ValueError`) naming `rotation`
/// otherwise.
pub fn rotation_from(obj: &Bound<'_, PyAny>) -> PyResult<Matrix3<Real>> {
    let py = obj.py();
    let array = float_array(obj, "rotation")?;
    let values: Vec<Real> = array.as_array().iter().copied().collect();
    let rotation = match array.shape() {
        [3, 3] => {
            let matrix = Matrix3::from_row_slice(&values);
            check_rotation(&matrix).map(|_| matrix)
        }
        [4] => quaternion_rotation([values[0], values[1], values[2], values[3]]),
        shape => {
            let message = format!(
                "`rotation` has shape {shape:?}, expected (3, 3) (a rotation matrix) or (4,) (a quaternion w, x, y, z)"
            );
            return Err(scene_error(py, Some("rotation"), message));
        }
    };
    rotation.map_err(|e| to_py(py, e))
}

/// Puts the gripper of clamp `index` (its `[[pins]]` entry) of each member in `members`
/// at `position` turned by `rotation`; `SceneError` naming `index` if that pin is no
/// exact clamp (nothing changes then), or naming what is wrong with the pose.
pub fn set_clamp_pose(
    driver: &mut Driver,
    index: usize,
    position: &Bound<'_, PyAny>,
    rotation: &Bound<'_, PyAny>,
    members: std::ops::Range<usize>,
) -> PyResult<()> {
    let py = position.py();
    let target = vector_from(position, "position")?;
    let rotation = rotation_from(rotation)?;
    let mut poses = Vec::with_capacity(members.len());
    for i in members {
        let system = &driver.sims()[i].system;
        let Some(k) = system.grippers.iter().position(|g| g.pin == index) else {
            let message = format!(
                "`index` = {index}: pins[{index}] is not a clamp held by a gripper (clamp = true at an end, at = 0 or 1, of a rod with clamped knots)"
            );
            return Err(scene_error(py, Some("index"), message));
        };
        let pose = system.grippers[k].pose_at(target, rotation);
        poses.push((i, k, pose.map_err(|e| to_py(py, e))?));
    }
    for (i, k, pose) in poses {
        if let Some(sim) = driver.sim_mut(i) {
            sim.system
                .set_gripper_pose(k, pose)
                .map_err(|e| to_py(py, e))?;
        }
    }
    Ok(())
}
