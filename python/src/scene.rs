//! `Scene`: a scene from TOML (a file or text) or from a dict of the same schema, with
//! the CLI's validation and error messages.

use crate::errors::{scene_error, IntoPyResult};
use crate::simulation::Simulation;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use splinerod::{Error, SceneRun};

/// A validated scene: `Scene.from_toml(path_or_text)` or `Scene(dict)`.
#[pyclass(module = "splinerod", frozen)]
pub struct Scene {
    scene: splinerod::Scene,
    text: String,
}

#[pymethods]
impl Scene {
    /// A scene from a dict with the TOML file's tables and keys (lists of dicts for
    /// `[[pins]]` and the like; numpy arrays are accepted where lists are).
    #[new]
    fn new(table: &Bound<'_, PyDict>) -> PyResult<Self> {
        let py = table.py();
        let value = toml_value(table.as_any(), "")?;
        let text = toml::to_string(&value).map_err(|e| scene_error(py, None, e.to_string()))?;
        let scene = splinerod::Scene::from_toml(&text)
            .map_err(without_position)
            .py_err(py)?;
        Ok(Self { scene, text })
    }

    /// A scene from a TOML file (a path: `str` or `os.PathLike`) or TOML text (a `str`
    /// with a newline or an `=`).
    #[staticmethod]
    fn from_toml(source: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = source.py();
        let path = match source.cast::<PyString>() {
            Ok(s) => {
                let s = s.to_str()?;
                if s.contains('\n') || s.contains('=') {
                    let scene = splinerod::Scene::from_toml(s).py_err(py)?;
                    return Ok(Self {
                        scene,
                        text: s.to_string(),
                    });
                }
                std::path::PathBuf::from(s)
            }
            Err(_) => source.extract::<std::path::PathBuf>()?,
        };
        let scene = splinerod::Scene::load(&path).py_err(py)?;
        let text = std::fs::read_to_string(&path).map_err(|e| {
            let error = Error::Io {
                path: path.display().to_string(),
                source: e,
            };
            crate::errors::to_py(py, error)
        })?;
        Ok(Self { scene, text })
    }

    /// The scene's TOML text.
    #[getter]
    fn toml(&self) -> &str {
        &self.text
    }

    /// Simulated duration, s (0 for a static scene).
    #[getter]
    fn duration(&self) -> f64 {
        self.scene.solver.duration.unwrap_or_default()
    }

    /// Number of ensemble members (1 without `[ensemble]`).
    #[getter]
    fn members(&self) -> usize {
        self.scene.ensemble.as_ref().map_or(1, |e| e.count)
    }

    /// A new simulation of this scene at its start. Like `splinerod run`, a scene whose
    /// estimated steps, control points, samples or work pass the documented resource
    /// limits is refused (`SceneError` naming the fields) unless `allow_large=True`.
    #[pyo3(signature = (allow_large = false))]
    fn simulation(&self, py: Python<'_>, allow_large: bool) -> PyResult<Simulation> {
        if !allow_large {
            let limits = splinerod::scene::Limits::default();
            self.scene.check_limits(&limits).py_err(py)?;
        }
        let run = py.detach(|| SceneRun::new(&self.scene)).py_err(py)?;
        Ok(Simulation::from_scene(run))
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene(duration={}, members={})",
            self.duration(),
            self.members()
        )
    }
}

/// A parse error of generated TOML without its line and column (they would point into
/// text the user never saw).
pub fn without_position(error: Error) -> Error {
    match error {
        Error::Parse { message, field, .. } => Error::Parse {
            file: None,
            position: None,
            message,
            field,
        },
        other => other,
    }
}

/// `obj` as a TOML value; `SceneError` naming the dotted `path` for anything TOML has
/// no value for (None, objects).
pub fn toml_value(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
    let py = obj.py();
    if obj.is_instance_of::<PyBool>() {
        return Ok(toml::Value::Boolean(obj.extract()?));
    }
    if obj.is_instance_of::<PyInt>() {
        let value = obj.extract().map_err(|_| {
            let message = format!("`{path}` = {obj}: an integer beyond 64 bits");
            scene_error(py, Some(path), message)
        })?;
        return Ok(toml::Value::Integer(value));
    }
    if obj.is_instance_of::<PyFloat>() {
        return Ok(toml::Value::Float(obj.extract()?));
    }
    if let Ok(s) = obj.cast::<PyString>() {
        return Ok(toml::Value::String(s.to_str()?.to_string()));
    }
    if let Ok(dict) = obj.cast::<PyDict>() {
        let mut table = toml::Table::new();
        for (key, value) in dict.iter() {
            let key: String = key.extract().map_err(|_| {
                let at = if path.is_empty() { "the scene" } else { path };
                let message = format!("key {key} in {at}: keys must be strings");
                scene_error(py, Some(path).filter(|p| !p.is_empty()), message)
            })?;
            let inner = if path.is_empty() {
                key.clone()
            } else {
                format!("{path}.{key}")
            };
            table.insert(key, toml_value(&value, &inner)?);
        }
        return Ok(toml::Value::Table(table));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let items = obj.try_iter()?.enumerate();
        let values = items.map(|(i, item)| toml_value(&item?, &format!("{path}[{i}]")));
        return Ok(toml::Value::Array(values.collect::<PyResult<_>>()?));
    }
    if obj.hasattr("tolist")? {
        // numpy arrays and scalars: their Python equivalents.
        return toml_value(&obj.call_method0("tolist")?, path);
    }
    let kind = obj.get_type().name()?;
    Err(scene_error(
        py,
        Some(path),
        format!(
            "`{path}`: a {kind} is not a scene value (numbers, strings, booleans, lists, dicts)"
        ),
    ))
}
