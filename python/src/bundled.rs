//! The scenes bundled with the package (`scenes/` of the repository, compiled into the
//! extension by `splinerod::bundled`): `bundled_scene(name)` loads one from anywhere,
//! without the repository at hand; `bundled_scenes()` lists their names.

use crate::errors::IntoPyResult;
use crate::scene::Scene;
use pyo3::prelude::*;
use pyo3::types::PyString;

/// The bundled scene `name` (a file stem of the repository's `scenes/`, e.g.
/// `"hanging_cable"`), as `Scene.from_toml` of its text. An unknown name raises
/// `SceneError` listing the bundled ones.
#[pyfunction]
pub fn bundled_scene(py: Python<'_>, name: &str) -> PyResult<Scene> {
    let text = splinerod::bundled::scene_text(name).py_err(py)?;
    Scene::from_toml(PyString::new(py, text).as_any())
}

/// The names of the bundled scenes, sorted.
#[pyfunction]
pub fn bundled_scenes() -> Vec<&'static str> {
    splinerod::bundled::names().collect()
}
