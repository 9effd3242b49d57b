//! `Adaptivity`: adaptive resolution for a rod built in code, with the fields (names,
//! defaults, meaning, checks) of a scene's `[adaptivity]` table.

use crate::errors::{shield, IntoPyResult};
use crate::scene::{toml_value, without_position};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use splinerod::scene::AdaptivitySpec;
use splinerod::Real;

/// Adaptive resolution: `Adaptivity()` is tolerance-driven with the default tolerance
/// (1e-4 × rest length); `Adaptivity(tolerance=1e-5, max_control_points=80)` and the
/// other `[adaptivity]` fields of scenes/README.md as keywords
/// (`insert_threshold`/`remove_threshold` select the paper's curvature criterion).
#[pyclass(module = "splinerod", frozen)]
pub struct Adaptivity {
    spec: AdaptivitySpec,
}

#[pymethods]
impl Adaptivity {
    #[new]
    #[pyo3(signature = (**fields))]
    fn new(py: Python<'_>, fields: Option<&Bound<'_, PyDict>>) -> PyResult<Self> {
        let table = PyDict::new(py);
        table.set_item(
            "adaptivity",
            fields.cloned().unwrap_or_else(|| PyDict::new(py)),
        )?;
        let value = toml_value(table.as_any(), "")?;
        let text = toml::to_string(&value)
            .map_err(|e| crate::errors::scene_error(py, None, e.to_string()))?;
        shield(|| {
            let spec = AdaptivitySpec::from_toml(&text)
                .map_err(without_position)
                .py_err(py)?;
            // The checks that do not depend on the rod now; the others when a
            // simulation gets it.
            let initial = spec.min_control_points.unwrap_or(2);
            spec.validate(initial).py_err(py)?;
            Ok(Self { spec })
        })
    }

    /// The error tolerance, m, for a rod of `rest_length` m.
    fn tolerance_for(&self, rest_length: Real) -> Real {
        self.spec.tolerance_for(rest_length)
    }

    fn __repr__(&self) -> String {
        format!("Adaptivity({:?})", self.spec)
    }
}

impl Adaptivity {
    /// The adapt step for a rod of `rest_length` starting with `initial` control points
    /// (`None` when the table says `enabled = false`); range errors name the field.
    pub fn adapter(
        &self,
        py: Python<'_>,
        rest_length: Real,
        initial: usize,
    ) -> PyResult<Option<splinerod::adaptivity::Adapter>> {
        if !self.spec.enabled {
            return Ok(None);
        }
        self.spec.validate(initial).py_err(py)?;
        self.spec.adapter(rest_length, initial).map(Some).py_err(py)
    }

    /// What `"auto"` stretching reads from the adapter of a rod of `rest_length` m: the
    /// most control points it allows and the error it aims at.
    pub fn auto_inputs(&self, rest_length: Real) -> (usize, Real) {
        (
            self.spec.max_control_points,
            self.spec.aimed_error(rest_length),
        )
    }
}
