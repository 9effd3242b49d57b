//! `Simulation`: a scene's run (every member of an `[ensemble]`) or a rod built in
//! code, stepped from Python with the GIL released, its state read as numpy arrays.
//!
//! A scene's simulation drives [`splinerod::SceneRun`], the CLI's own run loop one stage
//! at a time, so `sim.run()` followed by `sim.to_json()` reports what `splinerod run
//! --json` writes, bit for bit but the wall-clock fields. Properties (`control_points`,
//! `velocities`, ...) describe member 0; methods take `member=`; `stacked_*` methods
//! return one array over all members.

use crate::adaptivity::Adaptivity;
use crate::arrays::{
    points_array, points_at, points_from, stacked_points, values_array, values_from,
};
use crate::driver::Driver;
use crate::errors::{guard, scene_error, shield, IntoPyResult, SplinerodError};
use crate::integrator::Integrator;
use crate::system::RodSystem;
use nalgebra::Vector3;
use numpy::{PyArray1, PyArray2, PyArray3};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict};
use splinerod::integrators::Role;
use splinerod::{Real, SceneRun};

/// A simulation: `Scene.simulation()` or `Simulation(system, integrator, dt)`.
#[pyclass(module = "splinerod")]
pub struct Simulation {
    pub(crate) driver: Driver,
    pub(crate) poisoned: bool,
}

impl Simulation {
    /// The simulation of a scene's run.
    pub fn from_scene(run: SceneRun) -> Self {
        Self {
            driver: Driver::Scene(Box::new(run)),
            poisoned: false,
        }
    }

    /// Member `index`, or `SceneError` naming `member`.
    fn member(&self, py: Python<'_>, index: usize) -> PyResult<&splinerod::Simulation> {
        let count = self.driver.sims().len();
        self.driver
            .sims()
            .get(index)
            .ok_or_else(|| no_member(py, index, count))
    }

    /// The members `member` selects: one, or all for `None`.
    fn selected(&self, py: Python<'_>, member: Option<usize>) -> PyResult<std::ops::Range<usize>> {
        let count = self.driver.sims().len();
        match member {
            None => Ok(0..count),
            Some(i) if i < count => Ok(i..i + 1),
            Some(i) => Err(no_member(py, i, count)),
        }
    }
}

/// `SceneError`: there is no member `index` of `count`.
fn no_member(py: Python<'_>, index: usize, count: usize) -> PyErr {
    let message = format!("`member` = {index}: the simulation has {count} member(s)");
    scene_error(py, Some("member"), message)
}

#[pymethods]
impl Simulation {
    /// A simulation of `system` advanced by `integrator` (default `ImplicitEuler()`) in
    /// steps of `dt` seconds (not needed by the static solver); with `adaptivity`
    /// (an `Adaptivity`), the resolution adapts after every step; `error_estimate=True`
    /// estimates the error of a fixed resolution (`estimated_error`).
    #[new]
    #[pyo3(signature = (system, integrator = None, dt = None, adaptivity = None, error_estimate = false))]
    fn new(
        py: Python<'_>,
        system: &RodSystem,
        integrator: Option<PyRef<'_, Integrator>>,
        dt: Option<Real>,
        adaptivity: Option<PyRef<'_, Adaptivity>>,
        error_estimate: bool,
    ) -> PyResult<Self> {
        shield(|| {
            let integrator = match integrator {
                Some(i) => i.build(py)?,
                None => Integrator::default_euler().build(py)?,
            };
            let statics = integrator.role() == Role::Equilibrium;
            let dt = match (dt, statics) {
                (Some(dt), _) if dt.is_finite() && dt > 0.0 => dt,
                (None, true) => 0.0,
                (dt, _) => {
                    let message =
                        format!("`dt` = {dt:?}: a time integrator needs a finite, positive step");
                    return Err(scene_error(py, Some("dt"), message));
                }
            };
            let (length, initial) = (system.rest_length(), system.control_points());
            let adapter = match &adaptivity {
                Some(a) => a.adapter(py, length, initial)?,
                None => None,
            };
            let (cap, aimed) = match (&adaptivity, &adapter) {
                (Some(a), Some(_)) => a.auto_inputs(length),
                _ => (initial, 0.0),
            };
            let mut sim = splinerod::Simulation::new(system.build(py, cap, aimed)?, integrator);
            if let Some(adapter) = adapter {
                sim = sim.with_adapter(adapter);
            }
            if error_estimate {
                sim = sim.estimate_errors();
            }
            Ok(Self {
                driver: Driver::Code {
                    sim: Box::new(sim),
                    dt,
                    calls: 0,
                },
                poisoned: false,
            })
        })
    }

    /// Makes `n` time steps (a static simulation: `n` equilibrium solves), every member
    /// of an ensemble. A failing step raises `SplinerodError`; its member keeps the state
    /// before that step. Ctrl-C raises `KeyboardInterrupt` within about a second, every
    /// member left as after the last completed step.
    #[pyo3(signature = (n = 1))]
    fn step(&mut self, py: Python<'_>, n: usize) -> PyResult<()> {
        self.advance(py, n)
    }

    /// Steps until time `until` (default: the scene's duration; a static simulation:
    /// its one solve), calling `callback(sim)` every `every` steps; a callback that
    /// returns `False` stops the run. Returns the number of steps made.
    #[pyo3(signature = (until = None, every = 1, callback = None))]
    fn run(
        slf: &Bound<'_, Self>,
        until: Option<Real>,
        every: usize,
        callback: Option<Bound<'_, PyAny>>,
    ) -> PyResult<usize> {
        let py = slf.py();
        if every == 0 {
            return Err(scene_error(
                py,
                Some("every"),
                "`every` = 0: must be at least 1",
            ));
        }
        let total = slf.borrow().steps_until(py, until)?;
        let mut made = 0;
        while made < total {
            let chunk = every.min(total - made);
            slf.borrow_mut().advance(py, chunk)?;
            made += chunk;
            if let Some(f) = &callback {
                let answer = f.call1((slf,))?;
                if answer.is(PyBool::new(py, false)) {
                    break;
                }
            }
        }
        Ok(made)
    }

    /// Simulated time, s.
    #[getter]
    fn time(&self) -> Real {
        self.driver.sims()[0].time
    }

    /// Time steps made.
    #[getter]
    fn steps(&self) -> usize {
        self.driver.sims()[0].steps
    }

    /// The time step, s (0 for a static simulation).
    #[getter]
    fn dt(&self) -> Real {
        match &self.driver {
            Driver::Scene(run) => run.dt(),
            Driver::Code { dt, .. } => *dt,
        }
    }

    /// Member 0's latest error estimate, m (the largest over its spans), or `None` when
    /// no estimate is made (no tolerance-driven adaptivity, no `error_estimate`).
    #[getter]
    fn estimated_error(&self) -> Option<Real> {
        let estimate = self.driver.sims()[0].error_estimate();
        // Before the first estimate the estimator holds an empty one.
        estimate.filter(|e| e.control_points > 0).map(|e| e.max())
    }

    /// Member 0's number of control points.
    #[getter]
    fn control_point_count(&self) -> usize {
        self.driver.sims()[0].system.rod.len()
    }

    /// Number of members (an `[ensemble]`'s count, else 1).
    #[getter]
    fn members(&self) -> usize {
        self.driver.sims().len()
    }

    /// Member 0's control points, `(n, 3)`, m (a closed rod's distinct ones).
    #[getter]
    fn control_points<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        let rod = &self.driver.sims()[0].system.rod;
        points_array(py, distinct(rod, &rod.positions))
    }

    /// Member 0's control-point velocities, `(n, 3)`, m/s; settable.
    #[getter]
    fn velocities<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        let rod = &self.driver.sims()[0].system.rod;
        points_array(py, distinct(rod, &rod.velocities))
    }

    #[setter(velocities)]
    fn set_velocities_property(&mut self, value: &Bound<'_, PyAny>) -> PyResult<()> {
        self.set_velocities(value, Some(0))
    }

    /// Sets the control-point velocities (`(n, 3)`, m/s) of `member` (all members if
    /// `None`).
    #[pyo3(signature = (velocities, member = None))]
    fn set_velocities(
        &mut self,
        velocities: &Bound<'_, PyAny>,
        member: Option<usize>,
    ) -> PyResult<()> {
        let py = velocities.py();
        let members = self.selected(py, member)?;
        // Every member's array checked before any is set: all or nothing.
        let checked = members.clone().map(|i| {
            let rod = &self.driver.sims()[i].system.rod;
            let mut v = points_from(velocities, "velocities", Some(rod.distinct_len()))?;
            // A closed rod's copies across the seam move with what they copy.
            v.extend_from_within(..rod.len() - rod.distinct_len());
            Ok(v)
        });
        let checked = checked.collect::<PyResult<Vec<_>>>()?;
        for (i, v) in members.zip(checked) {
            if let Some(sim) = self.driver.sim_mut(i) {
                sim.system.rod.velocities = v;
            }
        }
        Ok(())
    }

    /// Member 0's knot vector, m.
    #[getter]
    fn knots<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<Real>> {
        let rod = &self.driver.sims()[0].system.rod;
        values_array(py, rod.basis().knots().to_vec())
    }

    /// Where member 0's pins hold the rod, `(k, 3)`, m (a scene's pins first, in order).
    #[getter]
    fn pins<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        let pins = &self.driver.sims()[0].system.pins;
        let points: Vec<Vector3<Real>> = pins.iter().map(|p| p.position).collect();
        points_array(py, &points)
    }

    /// Moves pin `index` to `position` (m) in `member` (all members if `None`), from the
    /// next step on; a clamp's tangent pin moves with it. A pin driven by a `path` is
    /// moved by its path again at the next step.
    #[pyo3(signature = (index, position, member = None))]
    fn set_pin(
        &mut self,
        index: usize,
        position: &Bound<'_, PyAny>,
        member: Option<usize>,
    ) -> PyResult<()> {
        let members = self.selected(position.py(), member)?;
        crate::pins::set_pin(&mut self.driver, index, position, members)
    }

    /// Moves the gripper of clamp `index` (its `[[pins]]` entry: `clamp = true` at an end
    /// of a rod with clamped knots) in `member` (all if `None`), from the next step on:
    /// the clamp point to `position` (absolute, m), the gripper turned by `rotation`
    /// against its start (a `(3, 3)` rotation matrix, or a quaternion `(w, x, y, z)`),
    /// about the clamp point. The roll about the tangent is followed from the last call:
    /// between calls it must change by less than π. A clamp with a scene `pose` is moved
    /// by it again at the next step.
    #[pyo3(signature = (index, position, rotation, member = None))]
    fn set_clamp_pose(
        &mut self,
        index: usize,
        position: &Bound<'_, PyAny>,
        rotation: &Bound<'_, PyAny>,
        member: Option<usize>,
    ) -> PyResult<()> {
        let members = self.selected(position.py(), member)?;
        crate::pins::set_clamp_pose(&mut self.driver, index, position, rotation, members)
    }

    /// Forces member 0's rod puts on its pins' supports (grippers, bodies, fixed points)
    /// in the last step, `(k, 3)`, N (a scene: one per `[[pins]]` entry, as the JSON's
    /// `pin_forces`; the pins' forces on the rod are the negative).
    #[getter]
    fn pin_forces<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<Real>> {
        points_array(py, &crate::pins::pin_forces(&self.driver))
    }

    /// Torques member 0's rod puts on its pins' supports about their points after the
    /// last step, `(k, 3)`, N·m, one per `[[pins]]` entry (as the JSON's `pin_torques`:
    /// a clamp's bending and twisting moment as the gripper feels it, zero for a plain
    /// pin); empty for a simulation built in code.
    #[getter]
    fn pin_torques<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray2<Real>>> {
        Ok(points_array(
            py,
            &crate::pins::pin_torques(py, &self.driver)?,
        ))
    }

    /// Member 0's rigid bodies (`[[bodies]]`) now: a list of dicts with `name`, `mass`,
    /// `inertia`, `position`, `orientation` (rotation vector), `velocity` and
    /// `angular_velocity` (numpy arrays, as the JSON's `bodies[i]` last entries).
    #[getter]
    fn bodies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyList>> {
        crate::bodies::bodies(py, &self.driver.sims()[0])
    }

    /// Material points at coordinates `s` (m, a number or a 1-D array) of `member`:
    /// `(3,)` for a number, `(k, 3)` for an array.
    #[pyo3(signature = (s, member = 0))]
    fn positions<'py>(&self, s: &Bound<'py, PyAny>, member: usize) -> PyResult<Bound<'py, PyAny>> {
        let py = s.py();
        let (values, scalar) = values_from(s, "s")?;
        let points = shield(|| points_at(py, self.member(py, member)?, &values))?;
        let array = points_array(py, &points);
        match scalar {
            true => array.get_item(0),
            false => Ok(array.into_any()),
        }
    }

    /// Axial tension (N) at coordinates `s` (m, 1-D) of `member`.
    #[pyo3(signature = (s, member = 0))]
    fn tension<'py>(
        &self,
        s: &Bound<'py, PyAny>,
        member: usize,
    ) -> PyResult<Bound<'py, PyArray1<Real>>> {
        let py = s.py();
        let (values, _) = values_from(s, "s")?;
        let sim = self.member(py, member)?;
        let tension = shield(|| {
            points_at(py, sim, &values)?;
            Ok(sim.system.tension(&values))
        })?;
        Ok(values_array(py, tension))
    }

    /// Derivatives `(len(params), len(s), 3)` at material coordinates `s` (m) by scene
    /// paths `params`: a static scene's equilibrium, or a run's end, solved anew.
    fn sensitivities<'py>(
        &self,
        params: &Bound<'py, PyAny>,
        s: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray3<Real>>> {
        crate::calibration::sensitivities(&self.driver, params, s)
    }

    /// A run's times `(T,)` and derivatives `(T, len(params), len(s), 3)` at `s` (m).
    fn sensitivity_history<'py>(
        &self,
        params: &Bound<'py, PyAny>,
        s: &Bound<'py, PyAny>,
    ) -> PyResult<crate::calibration::History<'py>> {
        crate::calibration::sensitivity_history(&self.driver, params, s)
    }

    /// Energies of `member`, J: `kinetic` and one entry per energy term.
    #[pyo3(signature = (member = 0))]
    fn energies<'py>(&self, py: Python<'py>, member: usize) -> PyResult<Bound<'py, PyDict>> {
        let sim = self.member(py, member)?;
        let breakdown = shield(|| Ok(sim.system.energy_breakdown()))?;
        let dict = PyDict::new(py);
        dict.set_item("kinetic", sim.system.rod.kinetic_energy())?;
        for (name, value) in breakdown {
            dict.set_item(name, value)?;
        }
        Ok(dict)
    }

    /// Material points at `s` (m) of every member, `(members, k, 3)`.
    fn stacked_positions<'py>(
        &self,
        s: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyArray3<Real>>> {
        let py = s.py();
        let (values, _) = values_from(s, "s")?;
        let sims = self.driver.sims();
        let all: Vec<_> = shield(|| sims.iter().map(|sim| points_at(py, sim, &values)).collect())?;
        Ok(stacked_points(py, &all))
    }

    /// Control points of every member, `(members, n, 3)`; `ValueError` when members
    /// differ in size (adaptivity).
    fn stacked_control_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyArray3<Real>>> {
        let sims = self.driver.sims();
        let all: Vec<_> = sims
            .iter()
            .map(|s| distinct(&s.system.rod, &s.system.rod.positions).to_vec())
            .collect();
        if all.iter().any(|p| p.len() != all[0].len()) {
            let message = "the members have different numbers of control points (adaptivity); read them one by one with member_control_points(i)";
            return Err(pyo3::exceptions::PyValueError::new_err(message));
        }
        Ok(stacked_points(py, &all))
    }

    /// Control points of `member`, `(n, 3)`, m.
    fn member_control_points<'py>(
        &self,
        py: Python<'py>,
        member: usize,
    ) -> PyResult<Bound<'py, PyArray2<Real>>> {
        let rod = &self.member(py, member)?.system.rod;
        Ok(points_array(py, distinct(rod, &rod.positions)))
    }

    /// Energies of every member: a dict of arrays of length `members`, J.
    fn stacked_energies<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let dict = PyDict::new(py);
        let sims = self.driver.sims();
        let kinetic = sims.iter().map(|s| s.system.rod.kinetic_energy()).collect();
        dict.set_item("kinetic", values_array(py, kinetic))?;
        let breakdowns: Vec<_> =
            shield(|| Ok(sims.iter().map(|s| s.system.energy_breakdown()).collect()))?;
        for (k, (name, _)) in breakdowns[0].iter().enumerate() {
            let values = breakdowns
                .iter()
                .map(|b| b.get(k).map_or(Real::NAN, |e| e.1));
            dict.set_item(name, values_array(py, values.collect()))?;
        }
        Ok(dict)
    }

    /// The JSON `splinerod run --json` writes, had the run ended now (scenes only).
    fn to_json(&self, py: Python<'_>) -> PyResult<String> {
        let Driver::Scene(run) = &self.driver else {
            let message =
                "to_json reports a scene's run: build the simulation with Scene(...).simulation()";
            return Err(SplinerodError::new_err(message));
        };
        let result = shield(|| run.result().py_err(py))?;
        serde_json::to_string_pretty(&result).map_err(|e| SplinerodError::new_err(e.to_string()))
    }

    /// `to_json()` as a dict.
    fn result<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let text = self.to_json(py)?;
        py.import("json")?.call_method1("loads", (text,))
    }

    /// Panics inside the guarded region, to test that a panic surfaces as an exception.
    fn _panic_for_tests(&mut self) -> PyResult<()> {
        guard(&mut self.poisoned, || {
            panic!("deliberate panic for the test suite")
        })
    }

    fn __repr__(&self) -> String {
        let sim = &self.driver.sims()[0];
        format!(
            "Simulation(members={}, time={}, steps={}, control_points={})",
            self.driver.sims().len(),
            sim.time,
            sim.steps,
            sim.system.rod.len()
        )
    }
}

/// The entries of a per-control-point field that belong to distinct control points (a
/// closed rod's copies across the seam left out).
fn distinct<'a, T>(rod: &splinerod::Rod, field: &'a [T]) -> &'a [T] {
    &field[..rod.distinct_len()]
}
