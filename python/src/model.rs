//! Building a rod in code, mirroring the Rust API: `Material`, `BSplineSpace`, `Rod`,
//! `Pin`. Each wraps its Rust value; passing one to another constructor copies it, so a
//! Python object can be reused (two rods from one basis, say).

use crate::arrays::{points_array, points_from, values_array, vector_from};
use crate::errors::{scene_error, shield, IntoPyResult};
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
        let inner = shield(|| splinerod::BSplineSpace::new(degree, knots).py_err(py))?;
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
        check_count(py, control_points)?;
        let inner = shield(|| {
            splinerod::BSplineSpace::clamped_uniform(degree, control_points, length).py_err(py)
        })?;
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

/// A periodic B-spline basis for closed rods: `count` distinct functions around a loop
/// of `period` (the rod's rest length), no seam.
#[pyclass(module = "splinerod", frozen)]
#[derive(Clone)]
pub struct PeriodicBSplineSpace {
    /// The Rust basis.
    pub inner: splinerod::PeriodicBSplineSpace,
}

#[pymethods]
impl PeriodicBSplineSpace {
    /// A basis of `degree` with the breakpoints of one period (`breaks[0] = 0`, then
    /// non-decreasing values below `period`): one control point per breakpoint.
    #[new]
    fn new(py: Python<'_>, degree: usize, breaks: Vec<Real>, period: Real) -> PyResult<Self> {
        let inner =
            shield(|| splinerod::PeriodicBSplineSpace::new(degree, breaks, period).py_err(py))?;
        Ok(Self { inner })
    }

    /// `control_points` functions of `degree` on evenly spaced breakpoints around a loop
    /// of `period`.
    #[staticmethod]
    fn uniform(
        py: Python<'_>,
        degree: usize,
        control_points: usize,
        period: Real,
    ) -> PyResult<Self> {
        check_count(py, control_points)?;
        let inner = shield(|| {
            splinerod::PeriodicBSplineSpace::uniform(degree, control_points, period).py_err(py)
        })?;
        Ok(Self { inner })
    }

    /// The degree.
    #[getter]
    fn degree(&self) -> usize {
        self.inner.degree()
    }

    /// The number of distinct control points.
    #[getter]
    fn count(&self) -> usize {
        self.inner.breaks().len()
    }

    /// The period (the rest length of a closed rod on this basis), m.
    #[getter]
    fn period(&self) -> Real {
        self.inner.period()
    }

    /// The breakpoints of one period, m.
    #[getter]
    fn breaks<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Real>> {
        values_array(py, self.inner.breaks().to_vec())
    }

    fn __repr__(&self) -> String {
        format!(
            "PeriodicBSplineSpace(degree={}, control_points={}, period={})",
            self.inner.degree(),
            self.inner.breaks().len(),
            self.inner.period()
        )
    }
}

/// The Rust basis of a Python `BSplineSpace` or `PeriodicBSplineSpace`.
fn basis_from(basis: &Bound<'_, PyAny>) -> PyResult<Box<dyn splinerod::BasisSpace>> {
    if let Ok(b) = basis.cast::<BSplineSpace>() {
        return Ok(Box::new(b.get().inner.clone()));
    }
    if let Ok(b) = basis.cast::<PeriodicBSplineSpace>() {
        return Ok(Box::new(b.get().inner.clone()));
    }
    let message = "`basis` must be a BSplineSpace or a PeriodicBSplineSpace";
    Err(scene_error(basis.py(), Some("basis"), message.to_string()))
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
    /// A rod of `material` on `basis` with the given `(n, 3)` control points; on a
    /// `PeriodicBSplineSpace` a closed rod, with its `basis.count` distinct control
    /// points (the curve wraps from the last back to the first).
    #[new]
    fn new(
        material: &Material,
        basis: &Bound<'_, PyAny>,
        control_points: &Bound<'_, PyAny>,
    ) -> PyResult<Self> {
        let py = control_points.py();
        let basis = basis_from(basis)?;
        let distinct = basis.periodic_count().unwrap_or(basis.count());
        let mut points = points_from(control_points, "control_points", Some(distinct))?;
        // A closed rod stores the first `degree` points again after the last.
        points.extend_from_within(..basis.count() - distinct);
        let rod = shield(|| splinerod::Rod::new(material.rust(), basis, points).py_err(py))?;
        Ok(Self { inner: rod })
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
        let basis = Box::new(basis.inner.clone());
        let rod = shield(|| splinerod::Rod::straight(material.rust(), basis, a, b).py_err(py))?;
        Ok(Self { inner: rod })
    }

    /// A closed rod on `basis` fitted to the circle of `radius` (m) about `center` in
    /// the plane normal to `normal` (at rest when 2π · radius is the rest length).
    #[staticmethod]
    #[pyo3(signature = (material, basis, radius, center=None, normal=None))]
    fn ring(
        py: Python<'_>,
        material: &Material,
        basis: &PeriodicBSplineSpace,
        radius: Real,
        center: Option<&Bound<'_, PyAny>>,
        normal: Option<&Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let center = center.map_or(Ok(nalgebra::Vector3::zeros()), |c| vector_from(c, "center"))?;
        let normal = normal.map_or(Ok(nalgebra::Vector3::z()), |n| vector_from(n, "normal"))?;
        let basis = Box::new(basis.inner.clone());
        let rod = shield(|| {
            splinerod::Rod::ring(material.rust(), basis, center, normal, radius).py_err(py)
        })?;
        Ok(Self { inner: rod })
    }

    /// Whether the rod is closed (on a `PeriodicBSplineSpace`).
    #[getter]
    fn closed(&self) -> bool {
        self.inner.is_closed()
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
            return Err(scene_error(py, Some("damping"), message));
        }
        self.inner.damping = damping;
        Ok(())
    }

    /// The control points, `(n, 3)`, m (a closed rod's distinct ones).
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        points_array(py, &self.inner.positions[..self.inner.distinct_len()])
    }

    /// The knot vector, m.
    #[getter]
    fn knots<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Real>> {
        values_array(py, self.inner.basis().knots().to_vec())
    }

    /// The number of (distinct) control points.
    fn __len__(&self) -> usize {
        self.inner.distinct_len()
    }

    fn __repr__(&self) -> String {
        let m = self.inner.material();
        format!(
            "Rod(control_points={}, degree={}, rest_length={}{})",
            self.inner.distinct_len(),
            self.inner.basis().degree(),
            m.rest_length,
            if self.inner.is_closed() {
                ", closed"
            } else {
                ""
            }
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
        let inner = shield(|| splinerod::Pin::here(&rod.inner, at).py_err(py))?;
        Ok(Self { inner })
    }

    /// Pins the tangent at `at` (m): the control point next to an end, for a clamp.
    #[staticmethod]
    fn tangent_at(py: Python<'_>, rod: &Rod, at: Real) -> PyResult<Self> {
        let inner = shield(|| splinerod::Pin::tangent_at(&rod.inner, at).py_err(py))?;
        Ok(Self { inner })
    }

    /// This pin, free to slide along `axis` (a direction; normalised).
    fn sliding(&self, axis: &Bound<'_, PyAny>) -> PyResult<Self> {
        let py = axis.py();
        let axis = vector_from(axis, "axis")?;
        let inner = shield(|| self.inner.sliding(axis).py_err(py))?;
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

/// `SceneError` naming `control_points` past what a basis may have
/// ([`splinerod::core::MAX_BASIS_FUNCTIONS`]), checked before anything is allocated.
fn check_count(py: Python<'_>, control_points: usize) -> PyResult<()> {
    let max = splinerod::core::MAX_BASIS_FUNCTIONS;
    if control_points <= max {
        return Ok(());
    }
    let message =
        format!("`control_points` = {control_points}: more than the {max} a basis may have");
    Err(scene_error(py, Some("control_points"), message))
}
