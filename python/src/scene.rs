//! `Scene`: a scene from TOML (a file or text) or from a dict of the same schema, with
//! the CLI's validation and error messages.

use crate::errors::{scene_error, shield, IntoPyResult};
use crate::interrupt::Interrupt;
use crate::simulation::Simulation;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString, PyTuple};
use splinerod::scene::Problem;
use splinerod::{Error, SceneRun};

/// A validated scene: `Scene.from_toml(path_or_text)` or `Scene(dict)`.
#[pyclass(module = "splinerod", frozen)]
pub struct Scene {
    scene: splinerod::Scene,
    text: String,
}

impl Scene {
    /// The Rust scene.
    pub(crate) fn inner(&self) -> &splinerod::Scene {
        &self.scene
    }
}

#[pymethods]
impl Scene {
    /// A scene from a dict with the TOML file's tables and keys (lists of dicts for
    /// `[[pins]]` and the like; numpy arrays are accepted where lists are). A path or
    /// TOML text raises `TypeError` pointing to `Scene.from_toml`.
    #[new]
    pub(crate) fn new(table: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = table.py();
        let table = table.cast::<PyDict>().map_err(|_| not_a_dict(table))?;
        let value = toml_value(table.as_any(), "")?;
        let text = toml::to_string(&value).map_err(|e| scene_error(py, None, e.to_string()))?;
        shield(|| {
            let interrupt = Interrupt::new();
            let scene = splinerod::Scene::from_toml_cancellable(&text, &interrupt.cancel);
            let scene = interrupt.result(py, scene.map_err(without_position))?;
            Ok(Self { scene, text })
        })
    }

    /// A scene from a TOML file (a path: `str` or `os.PathLike`) or TOML text (a `str`
    /// with a newline or an `=`).
    #[staticmethod]
    pub(crate) fn from_toml(source: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = source.py();
        let interrupt = Interrupt::new();
        let path = match source.cast::<PyString>() {
            Ok(s) => {
                let s = s.to_str()?;
                if s.contains('\n') || s.contains('=') {
                    let scene = shield(|| {
                        let scene = splinerod::Scene::from_toml_cancellable(s, &interrupt.cancel);
                        interrupt.result(py, scene)
                    })?;
                    return Ok(Self {
                        scene,
                        text: s.to_string(),
                    });
                }
                std::path::PathBuf::from(s)
            }
            Err(_) => source.extract::<std::path::PathBuf>()?,
        };
        let scene = shield(|| {
            let scene = splinerod::Scene::load_cancellable(&path, &interrupt.cancel);
            interrupt.result(py, scene)
        })?;
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
        shield(|| {
            if !allow_large {
                let limits = splinerod::scene::Limits::default();
                self.scene.check_limits(&limits).py_err(py)?;
            }
            let run = py.detach(|| SceneRun::new(&self.scene)).py_err(py)?;
            Ok(Simulation::from_scene(run))
        })
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene(duration={}, members={})",
            self.duration(),
            self.members()
        )
    }
}

/// The `TypeError` of `Scene(x)` for an `x` that is not a dict: a path or TOML text is
/// pointed to `Scene.from_toml`.
fn not_a_dict(given: &Bound<'_, PyAny>) -> PyErr {
    let kind = given
        .get_type()
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "object".into());
    let pathlike =
        given.is_instance_of::<PyString>() || given.hasattr("__fspath__").unwrap_or(false);
    let message = if pathlike {
        format!(
            "Scene() takes a dict of the scene's tables, not a {kind}: for a scene file or \
             TOML text use Scene.from_toml(path_or_text)"
        )
    } else {
        format!(
            "Scene() takes a dict of the scene's tables, not a {kind} (Scene.from_toml reads \
             a scene file or TOML text)"
        )
    };
    PyTypeError::new_err(message)
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
        Error::Format { problems, .. } => Error::Format {
            file: None,
            problems: problems
                .into_iter()
                .map(|p| match p {
                    Problem::Wrong { field, message, .. } => Problem::Wrong {
                        field,
                        position: None,
                        message,
                    },
                    missing => missing,
                })
                .collect(),
        },
        other => other,
    }
}

/// Deepest nesting of lists and dicts in a scene dict (a scene needs four).
pub const MAX_DEPTH: usize = 64;

/// `obj` as a TOML value; `SceneError` naming the dotted `path` for anything TOML has
/// no value for (None, objects), a list or dict inside itself, or nesting deeper than
/// [`MAX_DEPTH`] (either would recurse without end).
pub fn toml_value(obj: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
    convert(obj, path, &mut Vec::new())
}

/// [`toml_value`] inside the containers `open` (their addresses, outermost first).
fn convert(obj: &Bound<'_, PyAny>, path: &str, open: &mut Vec<usize>) -> PyResult<toml::Value> {
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
    let container = obj.is_instance_of::<PyDict>()
        || obj.is_instance_of::<PyList>()
        || obj.is_instance_of::<PyTuple>()
        || obj.hasattr("tolist")?;
    if !container {
        let kind = obj.get_type().name()?;
        let message = format!(
            "`{path}`: a {kind} is not a scene value (numbers, strings, booleans, lists, dicts)"
        );
        return Err(scene_error(py, Some(path), message));
    }
    let id = obj.as_ptr() as usize;
    let at = if path.is_empty() { "the scene" } else { path };
    if open.contains(&id) {
        let message =
            format!("`{at}` contains itself: a scene value cannot hold the list or dict it is in");
        return Err(scene_error(py, Some(path), message));
    }
    if open.len() >= MAX_DEPTH {
        let message = format!("`{at}`: lists and dicts nested more than {MAX_DEPTH} deep");
        return Err(scene_error(py, Some(path), message));
    }
    open.push(id);
    let value = container_value(obj, path, open);
    open.pop();
    value
}

/// A dict, list, tuple or numpy value as a TOML value (see [`convert`]).
fn container_value(
    obj: &Bound<'_, PyAny>,
    path: &str,
    open: &mut Vec<usize>,
) -> PyResult<toml::Value> {
    let py = obj.py();
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
            table.insert(key, convert(&value, &inner, open)?);
        }
        return Ok(toml::Value::Table(table));
    }
    if obj.is_instance_of::<PyList>() || obj.is_instance_of::<PyTuple>() {
        let mut values = Vec::new();
        for (i, item) in obj.try_iter()?.enumerate() {
            values.push(convert(&item?, &format!("{path}[{i}]"), open)?);
        }
        return Ok(toml::Value::Array(values));
    }
    // numpy arrays and scalars: their Python equivalents.
    convert(&obj.call_method0("tolist")?, path, open)
}
