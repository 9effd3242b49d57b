//! Building a rod in code, mirroring the Rust API: `Material`, `BSplineSpace`, `Rod`,
//! `Pin`. Each wraps its Rust value; passing one to another constructor copies it, so a
//! Python object can be reused (two rods from one basis, say).

use crate::arrays::{points_array, points_from, values_array, vector_from};
use crate::errors::IntoPyResult;
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use splinerod::core::BasisSpace as _;
use splinerod::Real;

/// Rest length (m) and mass per unit rest length (kg/m) of a rod.
#[pyclass(module = "splinerod", get_all, set_all)]
#[derive(Clone, Copy)]
pub struct Material {
    /// Rest length, m.
    pub rest_length: Real,
    /// Mass per unit rest length, kg/m.
    pub linear_density: Real,
}

#[pymethods]
impl Material {
    #[new]
    #[pyo3(signature = (rest_length, linear_density))]
    fn new(rest_length: Real, linear_density: Real) -> Self {
        Self {
            rest_length,
            linear_density,
        }
    }

    fn __repr__(&self) -> String {
        format!(
            "Material(rest_length={}, linear_density={})",
            self.rest_length, self.linear_density
        )
    }
}

impl Material {
    /// The Rust material.
    pub fn rust(&self) -> splinerod::Material {
        splinerod::Material {
            rest_length: self.rest_length,
            linear_density: self.linear_density,
        }
    }
}

/// A B-spline basis of any degree on `[0, rest_length]` (knots are rest arclength, m).
#[pyclass(module = "splinerod", frozen)]
#[derive(Clone)]
pub struct BSplineSpace {
    /// The Rust basis.
    pub inner: splinerod::BSplineSpace,
}

#[pymethods]
impl BSplineSpace {
    /// A basis of `degree` with the full knot vector `knots` (control points + degree +
    /// 1 values, non-decreasing).
    #[new]
    fn new(py: Python<'_>, degree: usize, knots: Vec<Real>) -> PyResult<Self> {
        let inner = splinerod::BSplineSpace::new(degree, knots).py_err(py)?;
        Ok(Self { inner })
    }

    /// `control_points` functions of `degree` on `[0, length]`, uniform interior knots,
    /// end knots repeated degree + 1 times (the curve starts and ends at its end control
    /// points).
    #[staticmethod]
    fn clamped_uniform(
        py: Python<'_>,
        degree: usize,
        control_points: usize,
        length: Real,
    ) -> PyResult<Self> {
        let inner =
            splinerod::BSplineSpace::clamped_uniform(degree, control_points, length).py_err(py)?;
        Ok(Self { inner })
    }

    /// The degree.
    #[getter]
    fn degree(&self) -> usize {
        self.inner.degree()
    }

    /// The number of basis functions (control points).
    #[getter]
    fn count(&self) -> usize {
        self.inner.count()
    }

    /// The knot vector, m.
    #[getter]
    fn knots<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Real>> {
        values_array(py, self.inner.knots().to_vec())
    }

    fn __repr__(&self) -> String {
        format!(
            "BSplineSpace(degree={}, control_points={})",
            self.inner.degree(),
            self.inner.count()
        )
    }
}

/// A rod: a B-spline curve whose control points are the degrees of freedom, with its
/// material and (mass-proportional) damping.
#[pyclass(module = "splinerod")]
#[derive(Clone)]
pub struct Rod {
    /// The Rust rod.
    pub inner: splinerod::Rod,
}

#[pymethods]
impl Rod {
    /// A rod of `material` on `basis` with the given `(n, 3)` control points.
    #[new]
    fn new(
        material: &Material,
        basis: &BSplineSpace,
        control_points: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let py = control_points.py();
        let n = basis.inner.count();
        let points = points_from(control_points, "control_points", Some(n))?;
        let rod = splinerod::Rod::new(material.rust(), Box::new(basis.inner.clone()), points);
        Ok(Self {
            inner: rod.py_err(py)?,
        })
    }

    /// A straight rod at rest from `start` to `end` (control points at the Greville
    /// abscissae).
    #[staticmethod]
    fn straight(
        material: &Material,
        basis: &BSplineSpace,
        start: &Bound<'_, PyAny>,
        end: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let py = start.py();
        let (a, b) = (vector_from(start, "start")?, vector_from(end, "end")?);
        let rod = splinerod::Rod::straight(material.rust(), Box::new(basis.inner.clone()), a, b);
        Ok(Self {
            inner: rod.py_err(py)?,
        })
    }

    /// Mass-proportional damping, 1/s.
    #[getter]
    fn damping(&self) -> Real {
        self.inner.damping
    }

    #[setter]
    fn set_damping(&mut self, py: Python<'_>, damping: Real) -> PyResult<()> {
        if !(damping.is_finite() && damping >= 0.0) {
            let message = format!("`damping` = {damping}: must be finite and non-negative");
            return Err(crate::errors::scene_error(py, Some("damping"), message));
        }
        self.inner.damping = damping;
        Ok(())
    }

    /// The control points, `(n, 3)`, m.
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        points_array(py, &self.inner.positions)
    }

    /// The knot vector, m.
    #[getter]
    fn knots<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Real>> {
        values_array(py, self.inner.basis().knots().to_vec())
    }

    /// The number of control points.
    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        let m = self.inner.material();
        format!(
            "Rod(control_points={}, degree={}, rest_length={})",
            self.inner.len(),
            self.inner.basis().degree(),
            m.rest_length
        )
    }
}

/// A point of the rod (material coordinate `at`, m) held at a position; with
/// `sliding(axis)`, free to slide along an axis.
#[pyclass(module = "splinerod", frozen)]
#[derive(Clone, Copy)]
pub struct Pin {
    /// The Rust pin.
    pub inner: splinerod::Pin,
}

#[pymethods]
impl Pin {
    /// Pins the material point `at` (m) of `rod` where it is now.
    #[staticmethod]
    fn here(py: Python<'_>, rod: &Rod, at: Real) -> PyResult<Self> {
        let inner = splinerod::Pin::here(&rod.inner, at).py_err(py)?;
        Ok(Self { inner })
    }

    /// Pins the tangent at `at` (m): the control point next to an end, for a clamp.
    #[staticmethod]
    fn tangent_at(py: Python<'_>, rod: &Rod, at: Real) -> PyResult<Self> {
        let inner = splinerod::Pin::tangent_at(&rod.inner, at).py_err(py)?;
        Ok(Self { inner })
    }

    /// This pin, free to slide along `axis` (a direction; normalised).
    fn sliding(&self, axis: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = axis.py();
        let axis = vector_from(axis, "axis")?;
        let inner = self.inner.sliding(axis).py_err(py)?;
        Ok(Self { inner })
    }

    /// Material coordinate of the pinned point, m.
    #[getter]
    fn at(&self) -> Real {
        self.inner.at
    }

    /// Where the point is held, m.
    #[getter]
    fn position<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Real>> {
        values_array(py, self.inner.position.iter().copied().collect())
    }

    fn __repr__(&self) -> String {
        let p = self.inner.position;
        format!(
            "Pin(at={}, position=[{}, {}, {}])",
            self.inner.at, p.x, p.y, p.z
        )
    }
}
