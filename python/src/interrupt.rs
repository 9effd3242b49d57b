//! Ctrl-C during a long call: `KeyboardInterrupt`, promptly, the state intact.
//!
//! Python runs its signal handlers only when asked (`PyErr_CheckSignals`, on the main
//! thread). A long call (`Simulation.step`, `run`, a scene's knot fit) hands the run a
//! [`Cancel`] whose hook asks, from the calling thread, at most every 20 ms while the
//! solvers poll there and between steps ([`splinerod::core::cancel`]); a handler that
//! raises (the default SIGINT handler raises `KeyboardInterrupt`) raises the request,
//! the run stops between steps or abandons the step under way (after the CLI's grace,
//! [`splinerod::run::control::STOP_GRACE`]) and is put back as it stood after the last
//! completed step, and the call raises the handler's exception. An ensemble's members
//! are stepped on worker threads, where the hook cannot run: it then notices Ctrl-C
//! between steps (within a step only once a poll on the calling thread has raised it).

use crate::errors::to_py;
use pyo3::exceptions::PyKeyboardInterrupt;
use pyo3::prelude::*;
use splinerod::core::Cancel;
use splinerod::run::control::STOP_GRACE;
use splinerod::Error;
use std::sync::{Arc, Mutex};

/// A stop request raised by Python's signal handlers during one call.
pub struct Interrupt {
    /// The request the run polls.
    pub cancel: Cancel,
    /// The exception a signal handler raised.
    caught: Arc<Mutex<Option<PyErr>>>,
}

impl Interrupt {
    /// A request whose hook runs Python's signal handlers on the thread that makes it
    /// (only there: [`Cancel::with_hook`]).
    pub fn new() -> Self {
        let caught = Arc::new(Mutex::new(None));
        let slot = caught.clone();
        let hook = move || {
            Python::attach(|py| match py.check_signals() {
                Ok(()) => false,
                Err(e) => {
                    *slot.lock().unwrap_or_else(|p| p.into_inner()) = Some(e);
                    true
                }
            })
        };
        let cancel = Cancel::new().with_grace(STOP_GRACE).with_hook(hook);
        Self { cancel, caught }
    }

    /// The Python exception for `error` from a call under this request: for the
    /// interruption, the exception the signal handler raised (or `KeyboardInterrupt`);
    /// otherwise the error's own.
    pub fn error(&self, py: Python<'_>, error: Error) -> PyErr {
        if !error.is_interrupted() {
            return to_py(py, error);
        }
        let caught = self.caught.lock().unwrap_or_else(|p| p.into_inner()).take();
        if let Some(e) = caught {
            return e;
        }
        match py.check_signals() {
            Err(e) => e,
            Ok(()) => PyKeyboardInterrupt::new_err(error.to_string()),
        }
    }

    /// `result` with its error turned into the Python exception ([`Interrupt::error`]).
    pub fn result<T>(&self, py: Python<'_>, result: Result<T, Error>) -> PyResult<T> {
        result.map_err(|e| self.error(py, e))
    }
}
