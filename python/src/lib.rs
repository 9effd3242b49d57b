//! splinerod for Python: the extension module `splinerod._splinerod`, re-exported by the
//! `splinerod` package (python/splinerod/__init__.py).
//!
//! Thin over the Rust API: a `Scene` from TOML or a dict, its `Simulation` stepped with
//! the GIL released, state as numpy arrays (one copy per call); rods built in code from
//! `Material`, `BSplineSpace`, `Rod`, `Pin`, energies and integrators. Errors surface as
//! `SceneError` (bad input, with the field named), `SplinerodError` (the run could not
//! go on, or an internal panic, never `PanicException`), `OSError` and, on Ctrl-C
//! during a long call, `KeyboardInterrupt` (see `errors`, `interrupt`).

mod adaptivity;
mod arrays;
mod bodies;
mod bundled;
mod calibration;
mod driver;
mod errors;
mod integrator;
mod interrupt;
mod model;
mod pins;
mod scene;
mod simulation;
mod stepping;
mod system;

use pyo3::prelude::*;

/// The kernel set this process computes with, `"portable"` or `"avx2-fma"` (chosen once
/// from the environment variable `SPLINEROD_KERNELS`: `auto`, `portable` or
/// `avx2-fma`); results are bit-identical only under one set. Raises `ValueError`
/// naming the variable when its value is not understood (the fastest set runs then).
#[pyfunction]
fn kernels() -> PyResult<&'static str> {
    match splinerod::kernels::setting_error() {
        Some(message) => Err(pyo3::exceptions::PyValueError::new_err(message)),
        None => Ok(splinerod::kernels::name()),
    }
}

/// The compiled core of the `splinerod` package.
#[pymodule]
fn _splinerod(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("SceneError", py.get_type::<errors::SceneError>())?;
    m.add("SplinerodError", py.get_type::<errors::SplinerodError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<simulation::Simulation>()?;
    m.add_class::<model::Material>()?;
    m.add_class::<model::BSplineSpace>()?;
    m.add_class::<model::PeriodicBSplineSpace>()?;
    m.add_class::<model::Rod>()?;
    m.add_class::<model::Pin>()?;
    m.add_class::<system::RodSystem>()?;
    m.add_class::<system::Energy>()?;
    m.add_class::<system::Stretching>()?;
    m.add_class::<system::Bending>()?;
    m.add_class::<system::Gravity>()?;
    m.add_class::<system::PointSpring>()?;
    m.add_class::<system::PointForce>()?;
    m.add_class::<system::Clamp>()?;
    m.add_class::<integrator::Integrator>()?;
    m.add_class::<integrator::ImplicitEuler>()?;
    m.add_class::<integrator::ImplicitMidpoint>()?;
    m.add_class::<integrator::Bdf2>()?;
    m.add_class::<integrator::StaticSolver>()?;
    m.add_class::<adaptivity::Adaptivity>()?;
    m.add_function(wrap_pyfunction!(kernels, m)?)?;
    m.add_function(wrap_pyfunction!(calibration::fit_json, m)?)?;
    m.add_function(wrap_pyfunction!(bundled::bundled_scene, m)?)?;
    m.add_function(wrap_pyfunction!(bundled::bundled_scenes, m)?)?;
    Ok(())
}
