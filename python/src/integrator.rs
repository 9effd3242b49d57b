//! Integrators for rods built in code: `ImplicitEuler`, `ImplicitMidpoint`, `Bdf2` and
//! `Static`, each holding its Newton settings; the Rust integrator is made when a
//! `Simulation` is built.

use crate::errors::scene_error;
use crate::system::positive;
use pyo3::prelude::*;
use splinerod::{Integrator as RustIntegrator, Real};

/// Which integrator, with its Newton settings.
#[derive(Clone, Copy, Debug)]
enum Method {
    ImplicitEuler,
    ImplicitMidpoint,
    Bdf2,
    Static,
}

/// A time integrator or the static solver (base class of `ImplicitEuler`, ...).
#[pyclass(module = "splinerod", subclass, frozen)]
pub struct Integrator {
    method: Method,
    max_iterations: usize,
    tolerance: Real,
    line_search: bool,
}

impl Integrator {
    /// The Rust integrator.
    pub fn build(&self, py: Python<'_>) -> PyResult<Box<dyn RustIntegrator>> {
        use splinerod::integrators as i;
        let newton = splinerod::NewtonParams {
            max_iterations: self.max_iterations,
            tolerance: self.tolerance,
            line_search: self.line_search,
            ..Default::default()
        };
        let statics = splinerod::StaticParams {
            max_iterations: self.max_iterations,
            tolerance: self.tolerance,
            ..Default::default()
        };
        let built: Result<Box<dyn RustIntegrator>, i::IntegratorError> = match self.method {
            Method::ImplicitEuler => i::ImplicitEuler::new(newton).map(|x| Box::new(x) as _),
            Method::ImplicitMidpoint => i::ImplicitMidpoint::new(newton).map(|x| Box::new(x) as _),
            Method::Bdf2 => i::Bdf2::new(newton).map(|x| Box::new(x) as _),
            Method::Static => i::StaticSolver::new(statics).map(|x| Box::new(x) as _),
        };
        built.map_err(|e| scene_error(py, None, e.to_string()))
    }

    /// The implicit Euler integrator with default settings.
    pub fn default_euler() -> Self {
        let d = splinerod::NewtonParams::default();
        Self {
            method: Method::ImplicitEuler,
            max_iterations: d.max_iterations,
            tolerance: d.tolerance,
            line_search: d.line_search,
        }
    }
}

#[pymethods]
impl Integrator {
    fn __repr__(&self) -> String {
        format!(
            "{:?}(max_iterations={}, tolerance={:e})",
            self.method, self.max_iterations, self.tolerance
        )
    }
}

/// Makes the Python class `$name` for integrator `$method`.
macro_rules! integrator_class {
    ($(#[$doc:meta])* $name:ident, $method:expr, $defaults:expr) => {
        $(#[$doc])*
        #[pyclass(module = "splinerod", extends = Integrator, frozen)]
        pub struct $name;

        #[pymethods]
        impl $name {
            #[new]
            #[pyo3(signature = (max_iterations = None, tolerance = None, line_search = None))]
            fn new(
                py: Python<'_>,
                max_iterations: Option<usize>,
                tolerance: Option<Real>,
                line_search: Option<bool>,
            ) -> PyResult<PyClassInitializer<Self>> {
                let (iterations, tol, search) = $defaults;
                let tolerance = positive(py, "tolerance", tolerance.unwrap_or(tol))?;
                let integrator = Integrator {
                    method: $method,
                    max_iterations: max_iterations.unwrap_or(iterations),
                    tolerance,
                    line_search: line_search.unwrap_or(search),
                };
                integrator.build(py)?;
                Ok(PyClassInitializer::from(integrator).add_subclass(Self))
            }
        }
    };
}

/// Newton defaults of the time integrators.
fn newton_defaults() -> (usize, Real, bool) {
    let d = splinerod::NewtonParams::default();
    (d.max_iterations, d.tolerance, d.line_search)
}

/// Newton defaults of the static solver.
fn static_defaults() -> (usize, Real, bool) {
    let d = splinerod::StaticParams::default();
    (d.max_iterations, d.tolerance, true)
}

integrator_class!(
    /// Implicit (backward) Euler: L-stable, first order, damps high frequencies.
    ImplicitEuler,
    Method::ImplicitEuler,
    newton_defaults()
);
integrator_class!(
    /// The implicit midpoint rule: second order, conserves energy (no numerical damping).
    ImplicitMidpoint,
    Method::ImplicitMidpoint,
    newton_defaults()
);
integrator_class!(
    /// BDF2: second order, L-stable.
    Bdf2,
    Method::Bdf2,
    newton_defaults()
);
integrator_class!(
    /// The static solver: the equilibrium (one `step` solves it).
    StaticSolver,
    Method::Static,
    static_defaults()
);
