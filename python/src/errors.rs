//! Errors across the boundary: every splinerod error becomes a Python exception, and a
//! Rust panic becomes one too instead of unwinding into the interpreter.
//!
//! * `SceneError` (a `ValueError`): bad input — a scene value out of range, an unknown
//!   or missing field, a value of the wrong type, an array of the wrong shape. Its
//!   `field` attribute is the dotted path of the field (`rod.rest_length`,
//!   `velocities`), `None` when no single field is to blame.
//! * `SplinerodError` (a `RuntimeError`): the simulation could not go on (a step that
//!   did not converge down to the smallest step, a knot change the rod refused). The
//!   state is the one before the failing step.
//! * `OSError`: a scene file could not be read.
//! * `KeyboardInterrupt`: Ctrl-C during a long call ([`crate::interrupt`]); the state is
//!   the one after the last completed step.
//! * A panic inside splinerod (a bug) raises `SplinerodError` saying so, never pyo3's
//!   `PanicException` (every entry point that reaches the library runs under
//!   [`guard`] or [`shield`]); an object a panic interrupted refuses further use, since
//!   its state may be half updated.

use pyo3::exceptions::{PyKeyboardInterrupt, PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use splinerod::Error;
use std::panic::{catch_unwind, AssertUnwindSafe};

pyo3::create_exception!(
    splinerod,
    SceneError,
    PyValueError,
    "Bad input: a scene or argument value out of range, an unknown or missing field, a \
     value of the wrong type or an array of the wrong shape. `field` names the field \
     (dotted path), `None` when no single field is to blame."
);
pyo3::create_exception!(
    splinerod,
    SplinerodError,
    PyRuntimeError,
    "The simulation could not go on (a step that did not converge down to the smallest \
     step, a refused knot change, an internal error); the state is the one before the \
     failing step."
);

/// A `SceneError` with message `message` naming `field`.
pub fn scene_error(py: Python<'_>, field: Option<&str>, message: impl Into<String>) -> PyErr {
    let err = SceneError::new_err(message.into());
    // Setting an attribute on a fresh exception instance cannot fail short of memory
    // exhaustion, which Python reports on its own.
    let _ = err.value(py).setattr("field", field);
    err
}

/// The Python exception for a splinerod error.
pub fn to_py(py: Python<'_>, error: Error) -> PyErr {
    // The CLI's advice, in this API's words.
    let message = error.to_string().replace(
        "pass --allow-large to run it anyway",
        "pass allow_large=True to Scene.simulation() to run it anyway",
    );
    if let Some(io) = io_error(&error) {
        return PyOSError::new_err((io.raw_os_error().unwrap_or(0), message));
    }
    if error.is_interrupted() {
        return PyKeyboardInterrupt::new_err(message);
    }
    if is_input_error(&error) {
        return scene_error(py, error.field_name(), message);
    }
    SplinerodError::new_err(message)
}

/// The I/O error behind `error`, if that is what it is.
fn io_error(error: &Error) -> Option<&std::io::Error> {
    match error {
        Error::Io { source, .. } => Some(source),
        Error::Member { source, .. } => io_error(source),
        _ => None,
    }
}

/// Whether `error` is about the input (a scene or argument) rather than the run.
fn is_input_error(error: &Error) -> bool {
    match error {
        Error::Parse { .. }
        | Error::Format { .. }
        | Error::MissingField { .. }
        | Error::InvalidField { .. }
        | Error::TooLarge { .. }
        | Error::OutOfMemory { .. } => true,
        Error::Member { source, .. } => is_input_error(source),
        _ => false,
    }
}

/// Extension: `?` on splinerod results inside binding code.
pub trait IntoPyResult<T> {
    /// The result with a splinerod error turned into its Python exception.
    fn py_err(self, py: Python<'_>) -> PyResult<T>;
}

impl<T> IntoPyResult<T> for Result<T, Error> {
    fn py_err(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| to_py(py, e))
    }
}

impl<T> IntoPyResult<T> for Result<T, splinerod::core::CoreError> {
    fn py_err(self, py: Python<'_>) -> PyResult<T> {
        self.map_err(|e| {
            let field = match &e {
                splinerod::core::CoreError::InvalidParameter { name, .. } => Some(*name),
                _ => None,
            };
            scene_error(py, field, e.to_string())
        })
    }
}

/// Runs `f`, turning a panic into `SplinerodError` and setting `*poisoned`.
pub fn guard<T>(poisoned: &mut bool, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    if *poisoned {
        return Err(SplinerodError::new_err(
            "this object is unusable: an internal error (a panic) interrupted an earlier \
             call and may have left its state half updated",
        ));
    }
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|payload| {
        *poisoned = true;
        Err(panic_error(payload.as_ref()))
    })
}

/// Runs `f`, turning a panic into `SplinerodError` (never pyo3's `PanicException`):
/// for calls that change no existing object (constructors, reads).
pub fn shield<T>(f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    catch_unwind(AssertUnwindSafe(f)).unwrap_or_else(|payload| Err(panic_error(payload.as_ref())))
}

/// The `SplinerodError` of a panic with `payload`.
fn panic_error(payload: &(dyn std::any::Any + Send)) -> PyErr {
    let what = payload
        .downcast_ref::<&str>()
        .map(|s| s.to_string())
        .or_else(|| payload.downcast_ref::<String>().cloned())
        .unwrap_or_else(|| "unknown panic".to_string());
    SplinerodError::new_err(format!(
        "internal error in splinerod (a bug, please report it): {what}"
    ))
}
