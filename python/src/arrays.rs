//! numpy arrays in and out: one copy each way, never element by element through
//! Python objects. Input accepts anything numpy can turn into a float array (lists,
//! tuples, integer arrays); a wrong shape or a non-finite value raises `SceneError`
//! naming the argument.

use crate::errors::scene_error;
use nalgebra::Vector3;
use numpy::ndarray::{Array1, Array2, Array3};
use numpy::PyUntypedArrayMethods;
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArray3, PyArrayLikeDyn};
use pyo3::prelude::*;
use splinerod::Real;

/// `points` as an `(n, 3)` float array.
pub fn points_array<'py>(py: Python<'py>, points: &[Vector3<Real>]) -> Bound<'py, PyArray2<Real>> {
    let flat: Vec<Real> = points.iter().flat_map(|p| [p.x, p.y, p.z]).collect();
    let shaped = Array2::from_shape_vec((points.len(), 3), flat);
    // The shape is the length of the data by construction.
    shaped.unwrap_or_default().into_pyarray(py)
}

/// Stacked `(m, n, 3)` points of `m` members with `n` each.
pub fn stacked_points<'py>(
    py: Python<'py>,
    members: &[Vec<Vector3<Real>>],
) -> Bound<'py, PyArray3<Real>> {
    let n = members.first().map_or(0, Vec::len);
    let flat: Vec<Real> = members
        .iter()
        .flat_map(|m| m.iter().flat_map(|p| [p.x, p.y, p.z]))
        .collect();
    let shaped = Array3::from_shape_vec((members.len(), n, 3), flat);
    shaped.unwrap_or_default().into_pyarray(py)
}

/// `values` as a 1-D float array.
pub fn values_array<'py>(py: Python<'py>, values: Vec<Real>) -> Bound<'py, PyArray1<Real>> {
    Array1::from_vec(values).into_pyarray(py)
}

/// The float array `obj` (any array-like), or `SceneError` naming `field`.
pub(crate) fn float_array<'py>(
    obj: &Bound<'py, PyAny>,
    field: &str,
) -> PyResult<PyArrayLikeDyn<'py, Real, AllowTypeChange>> {
    let py = obj.py();
    obj.extract::<PyArrayLikeDyn<Real, AllowTypeChange>>()
        .map_err(|e| {
            scene_error(
                py,
                Some(field),
                format!("`{field}`: not an array of numbers ({e})"),
            )
        })
}

/// An `(n, 3)` array-like as points, `n` = `expected` if given; `SceneError` naming
/// `field` for another shape or a non-finite value.
pub fn points_from(
    obj: &Bound<'_, PyAny>,
    field: &str,
    expected: Option<usize>,
) -> PyResult<Vec<Vector3<Real>>> {
    let py = obj.py();
    let array = float_array(obj, field)?;
    let shape = array.shape().to_vec();
    let rows_ok = expected.is_none_or(|n| shape.first() == Some(&n));
    if shape.len() != 2 || shape[1] != 3 || !rows_ok {
        let want = expected.map_or("(n, 3)".to_string(), |n| format!("({n}, 3)"));
        return Err(scene_error(
            py,
            Some(field),
            format!("`{field}` has shape {shape:?}, expected {want}"),
        ));
    }
    let view = array.as_array();
    let points: Vec<Vector3<Real>> = view
        .rows()
        .into_iter()
        .map(|r| Vector3::new(r[0], r[1], r[2]))
        .collect();
    check_finite(py, field, points.iter().flat_map(|p| p.iter().copied()))?;
    Ok(points)
}

/// A length-3 array-like as a vector; `SceneError` naming `field` otherwise.
pub fn vector_from(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<Vector3<Real>> {
    let py = obj.py();
    let array = float_array(obj, field)?;
    let values: Vec<Real> = array.as_array().iter().copied().collect();
    if array.shape() != [3] {
        return Err(scene_error(
            py,
            Some(field),
            format!("`{field}` has shape {:?}, expected (3,)", array.shape()),
        ));
    }
    check_finite(py, field, values.iter().copied())?;
    Ok(Vector3::new(values[0], values[1], values[2]))
}

/// A scalar or 1-D array-like as values, and whether it was a scalar; `SceneError`
/// naming `field` otherwise.
pub fn values_from(obj: &Bound<'_, PyAny>, field: &str) -> PyResult<(Vec<Real>, bool)> {
    let py = obj.py();
    let array = float_array(obj, field)?;
    let scalar = match array.ndim() {
        0 => true,
        1 => false,
        _ => {
            return Err(scene_error(
                py,
                Some(field),
                format!(
                    "`{field}` has shape {:?}, expected a number or a 1-D array",
                    array.shape()
                ),
            ))
        }
    };
    let values: Vec<Real> = array.as_array().iter().copied().collect();
    check_finite(py, field, values.iter().copied())?;
    Ok((values, scalar))
}

/// `SceneError` naming `field` unless every value is finite.
pub fn check_finite(
    py: Python<'_>,
    field: &str,
    values: impl IntoIterator<Item = Real>,
) -> PyResult<()> {
    match values.into_iter().find(|v| !v.is_finite()) {
        Some(v) => Err(scene_error(
            py,
            Some(field),
            format!("`{field}` contains {v}: every value must be finite"),
        )),
        None => Ok(()),
    }
}

/// A finite number, or `SceneError` naming `field`.
pub fn finite(py: Python<'_>, field: &str, v: Real) -> PyResult<Real> {
    check_finite(py, field, [v]).map(|()| v)
}

/// Material points of `sim` at `s` (m); `SceneError` naming `s` outside the rod.
pub fn points_at(
    py: Python<'_>,
    sim: &splinerod::Simulation,
    s: &[Real],
) -> PyResult<Vec<Vector3<Real>>> {
    let rod = &sim.system.rod;
    s.iter()
        .map(|&x| {
            rod.point(x)
                .map_err(|e| scene_error(py, Some("s"), e.to_string()))
        })
        .collect()
}
