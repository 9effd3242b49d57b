//! Calibration (issue #48, item 3): the sensitivities of a static scene's equilibrium at
//! chosen material coordinates (`Simulation.sensitivities`, through [`sensitivities`])
//! and the fit of a scene's parameters to observations (`splinerod.fit`, wrapping
//! [`fit_json`] into a `FitResult`).

use crate::arrays::{stacked_points, values_array, values_from};
use crate::driver::Driver;
use crate::errors::{scene_error, shield, IntoPyResult};
use crate::scene::Scene;
use nalgebra::Vector3;
use numpy::ndarray::Array4;
use numpy::{IntoPyArray, PyArray1, PyArray3, PyArray4};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};
use splinerod::fit::ObservationFile;
use splinerod::scene::Method;
use splinerod::{sensitivity_at, Real};

/// The derivatives `(len(params), len(s), 3)` of the points at material coordinates
/// `s` (m) of the scene `driver` runs — its equilibrium's for a static scene, the end
/// of its run for implicit Euler or BDF2 — with respect to the scene paths `params`;
/// `SceneError` (a `ValueError`) naming an unknown parameter, a coordinate off the rod,
/// a simulation built in code or a scheme without sensitivities.
pub fn sensitivities<'py>(
    driver: &Driver,
    params: &Bound<'py, PyAny>,
    s: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray3<Real>>> {
    let py = s.py();
    let (scene, paths, values) = request(driver, params, s)?;
    let paths: Vec<&str> = paths.iter().map(String::as_str).collect();
    let positions = if scene.solver.method == Method::Static {
        let found = shield(|| {
            let at = py.detach(|| sensitivity_at::static_sensitivities_at(scene, &paths, &values));
            at.py_err(py)
        })?;
        found.positions
    } else {
        let found = run_history(py, scene, &paths, &values)?;
        found.positions.into_iter().last().unwrap_or_default()
    };
    let members: Vec<Vec<Vector3<Real>>> = positions
        .iter()
        .map(|d| d.iter().map(|p| Vector3::from(*p)).collect())
        .collect();
    Ok(stacked_points(py, &members))
}

/// A run's times and its derivatives after every step (numpy arrays).
pub type History<'py> = (Bound<'py, PyArray1<Real>>, Bound<'py, PyArray4<Real>>);

/// A run's derivatives after every step: the times `(T,)` and the derivatives
/// `(T, len(params), len(s), 3)` of its points at material coordinates `s` (m); errors
/// as [`sensitivities`], and a static scene's (it has no steps).
pub fn sensitivity_history<'py>(
    driver: &Driver,
    params: &Bound<'py, PyAny>,
    s: &Bound<'py, PyAny>,
) -> PyResult<History<'py>> {
    let py = s.py();
    let (scene, paths, values) = request(driver, params, s)?;
    let paths: Vec<&str> = paths.iter().map(String::as_str).collect();
    let found = run_history(py, scene, &paths, &values)?;
    let shape = (found.times.len(), paths.len(), values.len(), 3);
    let flat: Vec<Real> = found
        .positions
        .iter()
        .flatten()
        .flatten()
        .flatten()
        .copied()
        .collect();
    let history = Array4::from_shape_vec(shape, flat).unwrap_or_default();
    Ok((values_array(py, found.times), history.into_pyarray(py)))
}

/// The scene, parameter names and coordinates of a sensitivities request.
fn request<'a>(
    driver: &'a Driver,
    params: &Bound<'_, PyAny>,
    s: &Bound<'_, PyAny>,
) -> PyResult<(&'a splinerod::Scene, Vec<String>, Vec<Real>)> {
    let py = s.py();
    let names = names_from(params)?;
    let (values, _) = values_from(s, "s")?;
    let Driver::Scene(run) = driver else {
        let message = "sensitivities need a scene's simulation (Scene.simulation()), not one \
                       built in code";
        return Err(scene_error(py, None, message));
    };
    Ok((run.scene(), names, values))
}

/// The run of `scene` with its derivatives at `values` after every step.
fn run_history(
    py: Python<'_>,
    scene: &splinerod::Scene,
    paths: &[&str],
    values: &[Real],
) -> PyResult<sensitivity_at::RunSensitivitiesAt> {
    shield(|| {
        let found = py.detach(|| sensitivity_at::run_sensitivities_at(scene, paths, values));
        found.py_err(py)
    })
}

/// Parameter names: a list of strings, or one string of comma-separated names;
/// `SceneError` naming `params` for anything else or for no name at all.
fn names_from(params: &Bound<'_, PyAny>) -> PyResult<Vec<String>> {
    let py = params.py();
    let names: Vec<String> = match params.cast::<PyString>() {
        Ok(s) => s
            .to_str()?
            .split(',')
            .map(|n| n.trim().to_string())
            .collect(),
        Err(_) => params.extract().map_err(|_| {
            scene_error(
                py,
                Some("params"),
                "`params`: a list of scene paths (strings), or one comma-separated string",
            )
        })?,
    };
    if names.is_empty() || names.iter().any(String::is_empty) {
        let message = format!("`params` = {names:?}: every parameter needs a scene path");
        return Err(scene_error(py, Some("params"), message));
    }
    Ok(names)
}

/// The fit of the parameters `params` (scene paths) of `scene` (a `Scene`, a dict, a
/// path or TOML text) to `observations` (a list whose entries are paths of observation
/// CSV files, CSV text, or `(label, csv_text)` pairs): the JSON of `splinerod fit` with
/// `warnings` added (one line per group of parameters the observations cannot
/// separate). Bad input raises `SceneError`; a file that cannot be read, `OSError`.
#[pyfunction]
pub fn fit_json(
    scene: &Bound<'_, PyAny>,
    observations: &Bound<'_, PyAny>,
    params: &Bound<'_, PyAny>,
) -> PyResult<String> {
    let py = scene.py();
    let owned;
    let scene = match scene.cast::<Scene>() {
        Ok(s) => s.get(),
        Err(_) if scene.is_instance_of::<PyDict>() => {
            owned = Scene::new(scene)?;
            &owned
        }
        Err(_) => {
            owned = Scene::from_toml(scene)?;
            &owned
        }
    };
    let names = names_from(params)?;
    let files = observation_files(observations)?;
    shield(|| {
        let paths: Vec<&str> = names.iter().map(String::as_str).collect();
        let inner = scene.inner();
        let fitted = py.detach(|| splinerod::fit::command::fit_scene(inner, &files, &paths));
        let fitted = fitted.py_err(py)?;
        let mut json = fitted.json();
        json["warnings"] = serde_json::json!(fitted.warnings());
        Ok(json.to_string())
    })
}

/// The observation files `observations` lists (see [`fit_json`]).
fn observation_files(observations: &Bound<'_, PyAny>) -> PyResult<Vec<ObservationFile>> {
    let py = observations.py();
    let list = observations
        .cast::<PyList>()
        .map(|l| l.iter().collect::<Vec<_>>())
        .or_else(|_| {
            observations
                .cast::<PyTuple>()
                .map(|t| t.iter().collect::<Vec<_>>())
        })
        .map_err(|_| {
            let message = "`observations`: a list of observation files (paths, CSV text or \
                           (label, csv_text) pairs)";
            scene_error(py, Some("observations"), message)
        })?;
    if list.is_empty() {
        let message = "`observations` is empty: the fit needs at least one observation file";
        return Err(scene_error(py, Some("observations"), message));
    }
    list.iter()
        .enumerate()
        .map(|(i, item)| {
            if let Ok((label, text)) = item.extract::<(String, String)>() {
                return ObservationFile::parse(&label, &text).py_err(py);
            }
            if let Ok(text) = item.cast::<PyString>() {
                let text = text.to_str()?;
                if text.contains('\n') {
                    return ObservationFile::parse(&format!("observations[{i}]"), text).py_err(py);
                }
            }
            let path: std::path::PathBuf = item.extract().map_err(|_| {
                let message = format!(
                    "`observations[{i}]`: not a path, CSV text or a (label, csv_text) pair"
                );
                scene_error(py, Some("observations"), message)
            })?;
            ObservationFile::read(&path).py_err(py)
        })
        .collect()
}
