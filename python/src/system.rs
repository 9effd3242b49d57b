//! Energies and the `RodSystem` for rods built in code (integrators: `integrator.rs`).
//!
//! An energy or integrator object holds its parameters; the Rust object is made when a
//! `Simulation` is built (an energy may need the rod: the inextensible rod's constraint
//! space, a rest shape), so the same Python object can serve many simulations.

use crate::arrays::vector_from;
use crate::errors::{scene_error, IntoPyResult};
use crate::model::{Pin, Rod};
use nalgebra::Vector3;
use pyo3::prelude::*;
use splinerod::{Energy as RustEnergy, Real};

/// What an energy object makes.
#[derive(Clone, Debug)]
pub enum EnergySpec {
    /// Green–Lagrange stretching.
    Stretching {
        /// EA, N; `None`: inextensible.
        stiffness: Option<Real>,
        /// Strain formulation; `None`: `"auto"` (the scene's default, resolved when
        /// the system is built, [`RodSystem::build`]).
        formulation: Option<splinerod::StretchFormulation>,
        /// At rest in the rod's initial shape instead of arclength.
        rest_initial: bool,
    },
    /// Bending, EI (N·m²).
    Bending(Real),
    /// Gravity, m/s².
    Gravity(Vector3<Real>),
    /// A spring pulling material point `at` (m) to `target`.
    PointSpring(Real, Vector3<Real>, Real),
    /// A force on material point `at` (m).
    PointForce(Real, Vector3<Real>),
    /// A clamp's penalty at `at` along `direction`.
    Clamp(Real, Vector3<Real>, Real),
}

impl EnergySpec {
    /// The Rust energy for `rod`, `auto` the form `"auto"` stretching takes.
    fn build(
        &self,
        rod: &splinerod::Rod,
        auto: splinerod::StretchFormulation,
    ) -> Result<Box<dyn RustEnergy>, splinerod::core::CoreError> {
        use splinerod::energies as e;
        Ok(match *self {
            Self::Stretching {
                stiffness: None, ..
            } => Box::new(e::Stretching::inextensible(rod)),
            Self::Stretching {
                stiffness: Some(k),
                formulation,
                rest_initial,
            } => {
                let mut s = match rest_initial {
                    true => e::Stretching::with_rest_shape(k, rod)?,
                    false => e::Stretching::new(k)?,
                };
                s.formulation = formulation.unwrap_or(auto);
                Box::new(s)
            }
            Self::Bending(k) => Box::new(e::Bending::new(k)?),
            Self::Gravity(g) => Box::new(e::Gravity::new(g)?),
            Self::PointSpring(at, target, k) => Box::new(e::PointSpring::new(at, target, k)?),
            Self::PointForce(at, force) => Box::new(e::PointForce::new(at, force)?),
            Self::Clamp(at, direction, k) => Box::new(e::Clamp::new(at, direction, k)?),
        })
    }
}

/// An energy term of a rod built in code (base class of `Stretching`, `Bending`, ...).
#[pyclass(module = "splinerod", subclass, frozen)]
pub struct Energy {
    spec: EnergySpec,
}

#[pymethods]
impl Energy {
    fn __repr__(&self) -> String {
        format!("{:?}", self.spec)
    }
}

/// Makes the Python class `$name` for an energy spec.
macro_rules! energy_class {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[pyclass(module = "splinerod", extends = Energy, frozen)]
        pub struct $name;
    };
}

energy_class!(
    /// Green–Lagrange stretching, EA in N (`Stretching.inextensible()`: an exactly
    /// inextensible rod). `formulation`: "auto" (default: chosen from the strain the
    /// system puts on the rod, as a scene's `rod.stretch_formulation = "auto"`),
    /// "mixed", "mixed-consistent", "pointwise"; `rest="initial"`: at rest in the rod's
    /// initial shape.
    Stretching
);
energy_class!(
    /// Bending, EI in N·m².
    Bending
);
energy_class!(
    /// Gravity, acceleration in m/s² (default (0, -9.81, 0)).
    Gravity
);
energy_class!(
    /// A spring of `stiffness` (N/m) pulling material point `at` (m) to `target`.
    PointSpring
);
energy_class!(
    /// A constant force (N) on material point `at` (m).
    PointForce
);
energy_class!(
    /// A clamp's penalty holding the tangent at `at` (m) along `direction`.
    Clamp
);

/// The class and base for `spec`.
fn energy(spec: EnergySpec) -> PyClassInitializer<Energy> {
    PyClassInitializer::from(Energy { spec })
}

/// `SceneError` naming `field` unless `v` is finite and positive.
pub(crate) fn positive(py: Python<'_>, field: &str, v: Real) -> PyResult<Real> {
    match v.is_finite() && v > 0.0 {
        true => Ok(v),
        false => Err(scene_error(
            py,
            Some(field),
            format!("`{field}` = {v}: must be finite and positive"),
        )),
    }
}

#[pymethods]
impl Stretching {
    #[new]
    #[pyo3(signature = (stiffness, formulation = "auto", rest = "arclength"))]
    fn new(
        py: Python<'_>,
        stiffness: Real,
        formulation: &str,
        rest: &str,
    ) -> PyResult<PyClassInitializer<Self>> {
        use splinerod::StretchFormulation as F;
        let formulation = match formulation {
            "auto" => None,
            "mixed" => Some(F::Mixed),
            "mixed-consistent" => Some(F::MixedConsistent),
            "pointwise" => Some(F::Pointwise),
            other => {
                let message = format!("`formulation` = {other:?}: expected \"auto\", \"mixed\", \"mixed-consistent\" or \"pointwise\"");
                return Err(scene_error(py, Some("formulation"), message));
            }
        };
        let rest_initial = match rest {
            "arclength" => false,
            "initial" => true,
            other => {
                let message = format!("`rest` = {other:?}: expected \"arclength\" or \"initial\"");
                return Err(scene_error(py, Some("rest"), message));
            }
        };
        let stiffness = Some(positive(py, "stiffness", stiffness)?);
        let spec = EnergySpec::Stretching {
            stiffness,
            formulation,
            rest_initial,
        };
        Ok(energy(spec).add_subclass(Self))
    }

    /// An exactly inextensible rod (mixed constraints held by an augmented Lagrangian).
    #[staticmethod]
    fn inextensible(py: Python<'_>) -> PyResult<Py<Self>> {
        let spec = EnergySpec::Stretching {
            stiffness: None,
            formulation: Some(splinerod::StretchFormulation::Mixed),
            rest_initial: false,
        };
        Py::new(py, energy(spec).add_subclass(Self))
    }
}

#[pymethods]
impl Bending {
    #[new]
    fn new(py: Python<'_>, stiffness: Real) -> PyResult<PyClassInitializer<Self>> {
        let k = positive(py, "stiffness", stiffness)?;
        Ok(energy(EnergySpec::Bending(k)).add_subclass(Self))
    }
}

#[pymethods]
impl Gravity {
    #[new]
    #[pyo3(signature = (g = None))]
    fn new(g: Option<&Bound<'_, PyAny>>) -> PyResult<PyClassInitializer<Self>> {
        let g = match g {
            Some(g) => vector_from(g, "g")?,
            None => Vector3::new(0.0, -9.81, 0.0),
        };
        Ok(energy(EnergySpec::Gravity(g)).add_subclass(Self))
    }
}

#[pymethods]
impl PointSpring {
    #[new]
    fn new(
        at: Real,
        target: &Bound<'_, PyAny>,
        stiffness: Real,
    ) -> PyResult<PyClassInitializer<Self>> {
        let py = target.py();
        let at = crate::arrays::finite(py, "at", at)?;
        let target = vector_from(target, "target")?;
        let k = positive(py, "stiffness", stiffness)?;
        Ok(energy(EnergySpec::PointSpring(at, target, k)).add_subclass(Self))
    }
}

#[pymethods]
impl PointForce {
    #[new]
    fn new(at: Real, force: &Bound<'_, PyAny>) -> PyResult<PyClassInitializer<Self>> {
        let at = crate::arrays::finite(force.py(), "at", at)?;
        let force = vector_from(force, "force")?;
        Ok(energy(EnergySpec::PointForce(at, force)).add_subclass(Self))
    }
}

#[pymethods]
impl Clamp {
    #[new]
    fn new(
        at: Real,
        direction: &Bound<'_, PyAny>,
        stiffness: Real,
    ) -> PyResult<PyClassInitializer<Self>> {
        let py = direction.py();
        let at = crate::arrays::finite(py, "at", at)?;
        let direction = vector_from(direction, "direction")?;
        let k = positive(py, "stiffness", stiffness)?;
        Ok(energy(EnergySpec::Clamp(at, direction, k)).add_subclass(Self))
    }
}

/// A rod, its energies and pins: what a `Simulation` built in code advances.
#[pyclass(module = "splinerod")]
pub struct RodSystem {
    rod: splinerod::Rod,
    energies: Vec<EnergySpec>,
    pins: Vec<splinerod::Pin>,
}

#[pymethods]
impl RodSystem {
    /// A system of a copy of `rod` with `energies` and `pins`.
    #[new]
    #[pyo3(signature = (rod, energies = Vec::new(), pins = Vec::new()))]
    fn new(rod: &Rod, energies: Vec<PyRef<'_, Energy>>, pins: Vec<PyRef<'_, Pin>>) -> Self {
        Self {
            rod: rod.inner.clone(),
            energies: energies.iter().map(|e| e.spec.clone()).collect(),
            pins: pins.iter().map(|p| p.inner).collect(),
        }
    }

    /// Adds an energy.
    fn add_energy(&mut self, energy: PyRef<'_, Energy>) {
        self.energies.push(energy.spec.clone());
    }

    /// Adds a pin.
    fn add_pin(&mut self, pin: PyRef<'_, Pin>) {
        self.pins.push(pin.inner);
    }

    fn __repr__(&self) -> String {
        format!(
            "RodSystem(control_points={}, energies={}, pins={})",
            self.rod.len(),
            self.energies.len(),
            self.pins.len()
        )
    }
}

impl RodSystem {
    /// The rod's rest length, m.
    pub fn rest_length(&self) -> Real {
        self.rod.material().rest_length
    }

    /// The rod's number of control points.
    pub fn control_points(&self) -> usize {
        self.rod.len()
    }

    /// The Rust system (energies made for its rod); `"auto"` stretching resolved for
    /// a run of at most `control_points` control points that aims at `aimed_error` m
    /// (an adaptive run's tolerance, else 0).
    pub fn build(
        &self,
        py: Python<'_>,
        control_points: usize,
        aimed_error: Real,
    ) -> PyResult<splinerod::RodSystem> {
        let auto = self
            .auto_formulation(control_points, aimed_error)
            .py_err(py)?;
        let mut system = splinerod::RodSystem::new(self.rod.clone());
        for spec in &self.energies {
            system
                .energies
                .push(spec.build(&self.rod, auto).py_err(py)?);
        }
        system.pins.clone_from(&self.pins);
        Ok(system)
    }

    /// The form `"auto"` stretching takes ([`splinerod::StretchFormulation::auto`]), from
    /// the same strain scale as a scene's: weight, point forces and springs over `EA`,
    /// the stretch between fixed pins and the start's own strain (module docs of the
    /// scene's `auto_form`). The largest `EA` of the system's stretching decides.
    fn auto_formulation(
        &self,
        control_points: usize,
        aimed_error: Real,
    ) -> Result<splinerod::StretchFormulation, splinerod::core::CoreError> {
        use splinerod::energies::AutoInputs;
        let mut ea: Real = 0.0;
        let (mut loads, mut start) = (0.0, (0.0, 0.0));
        let material = self.rod.material();
        for spec in &self.energies {
            match *spec {
                EnergySpec::Stretching {
                    stiffness: Some(k),
                    rest_initial,
                    ..
                } => {
                    ea = ea.max(k);
                    if !rest_initial {
                        start = AutoInputs::start_strains(&self.rod);
                    }
                }
                EnergySpec::Gravity(g) => {
                    loads += material.linear_density * g.norm() * material.rest_length
                }
                EnergySpec::PointForce(_, f) => loads += f.norm(),
                EnergySpec::PointSpring(at, target, k) => {
                    loads += k * (target - self.rod.point(at)?).norm()
                }
                _ => {}
            }
        }
        let mut held: Vec<_> = (self.pins.iter())
            .filter(|p| p.slides_along.is_none() && !p.tangent)
            .map(|p| (p.at, vec![p.position]))
            .collect();
        let loads = if ea > 0.0 { loads / ea } else { 0.0 };
        let strain = start.0.max(loads).max(AutoInputs::held_strain(&mut held));
        Ok(splinerod::StretchFormulation::auto(AutoInputs {
            strain,
            compression: start.1,
            control_points: control_points.max(self.rod.len()),
            length: material.rest_length,
            model_error: aimed_error,
        }))
    }
}
