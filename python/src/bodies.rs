//! `Simulation.bodies`: member 0's rigid bodies (`[[bodies]]`) now, one dict each, with
//! the numbers the JSON's `bodies[i]` records for that time (bit for bit: the same
//! state, the orientation as the same rotation vector).

use crate::arrays::{points_array, values_array};
use nalgebra::Vector3;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use splinerod::Real;

/// `x` as a `(3,)` float array.
fn vector<'py>(py: Python<'py>, x: &Vector3<Real>) -> Bound<'py, PyAny> {
    values_array(py, vec![x.x, x.y, x.z]).into_any()
}

/// The bodies of `sim`: `name`, `mass` (kg), `inertia` (`(3, 3)`, kg m², about the
/// centre of mass in the body frame), `position` (centre of mass, m), `orientation`
/// (rotation vector from the world frame, rad), `velocity` (m/s) and
/// `angular_velocity` (world frame, rad/s).
pub fn bodies<'py>(py: Python<'py>, sim: &splinerod::Simulation) -> PyResult<Bound<'py, PyList>> {
    let bodies = &sim.system.bodies;
    let list = PyList::empty(py);
    for (name, b) in bodies.names.iter().zip(&bodies.bodies) {
        let d = PyDict::new(py);
        d.set_item("name", name)?;
        d.set_item("mass", b.mass)?;
        let rows: Vec<Vector3<Real>> = (0..3).map(|i| b.inertia.row(i).transpose()).collect();
        d.set_item("inertia", points_array(py, &rows))?;
        d.set_item("position", vector(py, &b.position))?;
        d.set_item("orientation", vector(py, &b.orientation.scaled_axis()))?;
        d.set_item("velocity", vector(py, &b.velocity))?;
        d.set_item("angular_velocity", vector(py, &b.angular_velocity))?;
        list.append(d)?;
    }
    Ok(list)
}
