//! Calibration (issue #48, item 3): the sensitivities of a static scene's equilibrium at
//! chosen material coordinates (`Simulation.sensitivities`, through [`sensitivities`])
//! and the fit of a scene's parameters to observations (`splinerod.fit`, wrapping
//! [`fit_json`] into a `FitResult`).

use crate::arrays::{stacked_points, values_from};
use crate::driver::Driver;
use crate::errors::{scene_error, shield, IntoPyResult};
use crate::scene::Scene;
use nalgebra::Vector3;
use numpy::PyArray3;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString, PyTuple};
use splinerod::fit::ObservationFile;
use splinerod::Real;

/// The derivatives `(len(params), len(s), 3)` of the equilibrium's points at material
/// coordinates `s` (m) of the scene `driver` runs, with respect to the scene paths
/// `params`; `SceneError` (a `ValueError`) naming an unknown parameter, a coordinate off
/// the rod, a simulation built in code or a scene that is not static.
pub fn sensitivities<'py>(
    driver: &Driver,
    params: &Bound<'py, PyAny>,
    s: &Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyArray3<Real>>> {
    let py = s.py();
    let names = names_from(params)?;
    let (values, _) = values_from(s, "s")?;
    let Driver::Scene(run) = driver else {
        let message = "sensitivities need a scene's simulation (Scene.simulation()), not one \
                       built in code";
        return Err(scene_error(py, None, message));
    };
    let scene = run.scene();
    let paths: Vec<&str> = names.iter().map(String::as_str).collect();
    let found = shield(|| {
        let at = py
            .detach(|| splinerod::sensitivity_at::static_sensitivities_at(scene, &paths, &values));
        at.py_err(py)
    })?;
    let members: Vec<Vec<Vector3<Real>>> = found
        .positions
        .iter()
        .map(|d| d.iter().map(|p| Vector3::from(*p)).collect())
        .collect();
    Ok(stacked_points(py, &members))
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
