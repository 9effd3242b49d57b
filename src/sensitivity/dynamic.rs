//! Forward sensitivities of a run (issue #48, item 1, the dynamic part): for a scene
//! stepped by implicit Euler or BDF2 at a fixed `dt`, the derivatives
//! \\(S_q = \mathrm{d}q/\mathrm{d}p\\), \\(S_v = \mathrm{d}v/\mathrm{d}p\\) of the state by
//! each parameter are carried through every step: after the step converged, its
//! residual \\(r(x; \hat q, \hat v, p) = G^T\mu\\) is differentiated and
//!
//! \\[ A z = (1 + \beta\alpha) M \hat q' - \beta\Big[ M'\big((1 + \beta\alpha) x -
//!     \hat v\big) - M \hat v' + \beta\alpha' M x + \beta\,\partial_p\nabla E\Big]
//!     + G^T(\beta\dot\mu) \\]
//!
//! is solved for \\(z = \mathrm{d}q_e/\mathrm{d}p\\) with the step's own Newton matrix
//! \\(A = (1 + \beta\alpha) M + \beta^2 K\\), refactorised at the step's solution (one
//! factorisation per step, one solve per parameter); then \\(S_q, S_v\\) follow from the
//! scheme's update ([`splinerod_integrators::forward`] states every case, BDF2's
//! two-step base and its implicit-midpoint start included). The start does not depend on
//! the parameters, \\(S_q = S_v = 0\\) at `t = 0`, except on a rest length it follows.
//!
//! **The terms per parameter.** `rod.stretch_stiffness`, `rod.bending_stiffness`,
//! `rod.twist_stiffness`, `world.gravity[c]`: \\(\partial_p \nabla E\\) from the energies'
//! [`Parameters`](splinerod_energies::Parameters). `rod.linear_density`: the weight's
//! derivative and \\(M' = M/\mu\\) (the mass matrix is linear in μ). `rod.damping` (α):
//! \\(\alpha' = 1\\), the term \\(\beta M x\\). `loads[i].force[c]`: \\(-b(s_i)\, e_c\\).
//! A grab's target starts where its point is at its start time, so after a start
//! `t₀ > 0` it moves with the parameters: \\(\dot p_g = (1 - f(t))\, b(s_g) S_q(t_0)\\)
//! enters through the spring's gradient, \\(-k\, b(s_g)\, \dot p_g\\). A default contact
//! barrier's stiffness follows the loads: its rate enters as in the static case.
//! `pins[i].position[c]`: no residual term; the pin's target moves,
//! \\(\dot c = e_c\\) on the entry's pin (and an exact clamp's tangent pin) in every
//! step's constraint \\(Gz = G\hat q' + \tfrac{\beta}{\rho}(\dot c - G\hat q')\\) — the
//! rod starts where it does (\\(S_q(0) = 0\\)), so the first step carries the pinned
//! point to its moved target. `contact.friction` (μ): the friction potential of the
//! step's lags is linear in μ, \\(\partial_\mu\nabla D = \nabla D/\mu\\).
//! `rod.rest_length` (`L`, `sensitivity/rest_length.rs`): every energy's
//! \\(\partial_L\nabla E\\), a penalty clamp's derived stiffness, \\(M' = M/L\\), and
//! where the rod's start follows `L` (no `rod.end`) \\(S_q(0) = (q_0 - x_{start})/L\\)
//! and the pins' targets' rates.
//!
//! **What a step freezes at its start.** Friction's lags depend on the state \\(q_n\\)
//! the step starts from: the anchors \\(q^{start}\\) the slip is measured from, and the
//! bound \\(\mu\lambda(g(q_n))\\) from the normal force there. Both are differentiated
//! for every parameter through \\(S_{q,n}\\) (the energies'
//! `Lifecycle::add_start_rate`, here through [`ParameterRates::add_start_rate`]); held
//! fixed: the contact normal of each lag (exact on planes and the floor, not on curved
//! obstacles or between strands), ε, which contacts exist, and the contact barrier's
//! stiffness where it adapts at every step's start to the smallest gap.
//!
//! **Exact and approximated.** Every step's derivative is exact for the discrete run
//! (to its Newton tolerance): the exact Hessian (a step whose solution needed the
//! definite stand-in is refused), every residual term, friction's lags as above (a
//! cable sliding on a plane with a fixed contact stiffness: 1e-10 … 1e-5 against
//! differences at a relative step 1e-5; without the start rates the density's
//! derivative was 2.6 off). The adapting barrier is not followed: a cable swinging onto
//! a plane with the default barrier is within 1e-5 … 4e-5 on the samples, up to 4e-4 on
//! the pin forces (`tests/sensitivities_dynamic.rs`; the adaptation is the likely cause,
//! not fully diagnosed).
//!
//! **Refused** (an error naming the field): another integrator, adaptivity, cuts,
//! ensembles, time error control, a step that needed sub-steps (a failed Newton solve
//! halved it: a shorter `dt` avoids it), unconverged or single-iteration steps, the
//! inextensible rod (its multiplier updates between steps), and the density or damping
//! of one of several `[[rods]]`.

use super::{add_barrier_rate, barrier_rate, energy_rate, target, target_value, Target};
use super::{by_name, largest, points_at, rest_length, sample_rows, shared_json, StepView};
use crate::scene::Method;
use crate::{Error, RodSystem, Scene, Simulation};
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};
use splinerod_integrators::{ForwardState, IntegratorError, ParameterRates, System};

/// The derivatives of a run's recorded samples at one output time.
#[derive(Debug, Clone, serde::Serialize)]
pub struct TimeSensitivities {
    /// The time, s.
    pub t: Real,
    /// Per parameter, the derivative of each sample's position, m per unit.
    pub positions: Vec<Vec<[Real; 3]>>,
    /// The samples' positions, m.
    pub at: Vec<[Real; 3]>,
}

/// The sensitivities of a run, at its end and at every recorded time.
#[derive(Debug, Clone, serde::Serialize)]
pub struct DynamicSensitivities {
    /// The parameters, by scene path, with their values.
    pub parameters: Vec<(String, Real)>,
    /// The output samples' material coordinates (fractions of the first rod's length).
    pub s: Vec<Real>,
    /// Per parameter, the derivative of each sample's final position, m per unit.
    pub positions: Vec<Vec<[Real; 3]>>,
    /// The final positions of the samples, m.
    pub at: Vec<[Real; 3]>,
    /// Per parameter, the derivative of the rod's force on each `[[pins]]` entry's
    /// support in the last step, N per unit (as the run's `pin_forces`).
    pub pin_forces: Vec<Vec<[Real; 3]>>,
    /// The rod's force on each `[[pins]]` entry's support in the last step, N.
    pub forces: Vec<[Real; 3]>,
    /// Per recorded time (every step), the samples' derivatives.
    pub times: Vec<TimeSensitivities>,
    /// Per parameter, the final derivative of every control point.
    #[serde(skip)]
    pub control_points: Vec<Vec<Vector3<Real>>>,
    /// Per parameter, the final derivative of every control point's velocity.
    #[serde(skip)]
    pub velocities: Vec<Vec<Vector3<Real>>>,
    /// The rod at the end.
    #[serde(skip)]
    pub rod: Rod,
}

impl DynamicSensitivities {
    /// The JSON of `splinerod sensitivities` for a run: the static one's keys
    /// (`parameters`, `s`, `positions`, `pin_forces`, `at`: at the end) and `times`, a
    /// list of `{t, positions: {name: [[dx, dy, dz], …]}, at}`.
    pub fn json(&self) -> serde_json::Value {
        let by_name = |d: &[Vec<[Real; 3]>]| by_name(&self.parameters, d);
        let times: Vec<serde_json::Value> = self
            .times
            .iter()
            .map(
                |t| serde_json::json!({ "t": t.t, "positions": by_name(&t.positions), "at": t.at }),
            )
            .collect();
        let derivatives = (&self.positions[..], &self.pin_forces[..]);
        let mut json = shared_json(&self.parameters, &self.s, derivatives, &self.at);
        json["times"] = serde_json::Value::Array(times);
        json
    }

    /// One line per parameter: its value and the largest derivative of a final sample.
    pub fn summary(&self) -> Vec<String> {
        let lines = self.parameters.iter().zip(&self.positions);
        lines
            .map(|((name, value), d)| {
                format!(
                    "{name} = {value}: at t = {:.6} s samples move by up to {:.3e} m per unit",
                    self.times.last().map_or(0.0, |t| t.t),
                    largest(d)
                )
            })
            .collect()
    }
}

/// The run of the dynamic `scene` and its forward sensitivities to the parameters
/// `paths` (see the module docs).
pub fn dynamic_sensitivities(scene: &Scene, paths: &[&str]) -> Result<DynamicSensitivities, Error> {
    observed_sensitivities(scene, paths, &mut |_| Ok(()))
}

/// What sees a run after each of its steps ([`StepView`]: the time, the rod, per
/// parameter the forward state, the pins' forces and their derivatives). An error stops
/// the run.
pub type StepObserver<'a> = dyn FnMut(&StepView<'_>) -> Result<(), Error> + 'a;

/// [`dynamic_sensitivities`], calling `observe` after every step (a fit reads its
/// observations there, at any material coordinate).
pub fn observed_sensitivities(
    scene: &Scene,
    paths: &[&str],
    observe: &mut StepObserver<'_>,
) -> Result<DynamicSensitivities, Error> {
    refuse(scene)?;
    let targets: Vec<Target> = paths
        .iter()
        .map(|p| dynamic_target(scene, p))
        .collect::<Result<_, _>>()?;
    let mut sim = scene.build()?;
    let mut cuts = crate::run::tally::CutSchedule::new(scene)?;
    crate::run::state::prepare(scene, &mut sim, &mut cuts)?;
    let mut rates = Rates::new(scene, &sim.system, paths, targets)?;
    let n = sim.system.rod.len();
    let mut states = vec![ForwardState::new(n); paths.len()];
    for (state, t) in states.iter_mut().zip(&rates.targets) {
        if matches!(*t, Target::Energy(name, None) if rest_length::is_rest_length(name)) {
            let start = rest_length::initial_rate(scene, &sim.system.rod);
            state.positions = start.unwrap_or_else(|| vec![Vector3::zeros(); n]);
        }
    }
    let (s, rows) = sample_rows(scene, &sim.system.rod)?;
    let dt = scene.solver.dt.unwrap_or_default();
    let mut times = Vec::with_capacity(scene.step_count());
    for step in 0..scene.step_count() {
        one_step(&mut sim, dt, step, &mut rates, &mut states)?;
        observe(&StepView::new(scene, &sim, &states))?;
        times.push(TimeSensitivities {
            t: sim.time,
            positions: states
                .iter()
                .map(|d| points_at(&rows, &d.positions))
                .collect(),
            at: points_at(&rows, &sim.system.rod.positions),
        });
    }
    let pin_forces = states
        .iter()
        .map(|d| crate::run::pins::fold_pin_forces(scene, &sim, d.pin_forces.clone()))
        .collect();
    Ok(DynamicSensitivities {
        parameters: paths
            .iter()
            .map(|p| p.to_string())
            .zip(rates.values)
            .collect(),
        s,
        positions: states
            .iter()
            .map(|d| points_at(&rows, &d.positions))
            .collect(),
        at: points_at(&rows, &sim.system.rod.positions),
        pin_forces,
        forces: crate::run::pins::scene_pin_forces(scene, &sim),
        times,
        velocities: states.iter().map(|d| d.velocities.clone()).collect(),
        control_points: states.into_iter().map(|d| d.positions).collect(),
        rod: sim.system.rod.clone(),
    })
}

/// Step `step` of the run and the states' propagation through it.
fn one_step(
    sim: &mut Simulation,
    dt: Real,
    step: usize,
    rates: &mut Rates,
    states: &mut [ForwardState],
) -> Result<(), Error> {
    let epoch = sim.system.rod.topology_epoch();
    rates.waiting.clear();
    let waiting = sim.system.grabs.iter().map(|g| g.from.is_none());
    rates.waiting.extend(waiting);
    let report = sim.step(dt)?;
    let substeps = report.substeps;
    if substeps.substeps != 1 || substeps.rejected != 0 {
        let reason = format!(
            "step {step} needed {} sub-steps ({} rejected): sensitivities through \
             sub-steps are not built; a shorter dt avoids them",
            substeps.substeps, substeps.rejected
        );
        return Err(Error::field("solver.dt", dt, reason));
    }
    if sim.system.rod.topology_epoch() != epoch {
        let reason = "the knots changed during the run: sensitivities need a fixed basis";
        return Err(Error::field("adaptivity", "knot change", reason));
    }
    if states.is_empty() {
        return Ok(());
    }
    rates.grabs_started(&sim.system, states)?;
    let forward = sim.integrator.forward().ok_or_else(|| {
        let reason = "this integrator has no forward sensitivities";
        Error::field("solver.method", "", reason)
    })?;
    let result = forward.propagate(&mut sim.system, rates, states);
    if let Some(e) = rates.error.take() {
        return Err(e);
    }
    result?;
    Ok(())
}

/// An error naming the first field of `scene` whose run cannot be differentiated.
fn refuse(scene: &Scene) -> Result<(), Error> {
    scene.without_bodies("sensitivities")?;
    let solver = &scene.solver;
    if !matches!(solver.method, Method::ImplicitEuler | Method::Bdf2) {
        let reason = "sensitivities of runs are built for implicit-euler and bdf2 \
                      (and static solves)";
        return Err(Error::field(
            "solver.method",
            format!("{:?}", solver.method),
            reason,
        ));
    }
    let fixed = "sensitivities of runs need a fixed basis";
    let checks: [(bool, &str, &str); 6] = [
        (scene.adaptivity.is_some(), "adaptivity", fixed),
        (!scene.cuts.is_empty(), "cuts", fixed),
        (scene.ensemble.is_some(), "ensemble", "one run at a time"),
        (
            solver.time_tolerance.is_some(),
            "solver.time_tolerance",
            "sub-steps of time error control are not differentiated",
        ),
        (
            solver.accept_unconverged || solver.newton_iterations == Some(1),
            "solver.newton_iterations",
            "every step must converge (the derivative is that of its solution)",
        ),
        (
            (0..scene.rod_count()).any(|k| scene.rod_spec(k).stretch_stiffness.is_infinite()),
            "rod.stretch_stiffness",
            "the inextensible rod's multiplier updates between steps are not differentiated",
        ),
    ];
    for (bad, field, reason) in checks {
        if bad {
            return Err(Error::field(field, "set", reason));
        }
    }
    Ok(())
}

/// The target of `path` for a run: [`target`], without a `[[rods]]` entry's density or
/// damping (the mass matrix and the damping would change on one segment only).
fn dynamic_target(scene: &Scene, path: &str) -> Result<Target, Error> {
    let t = target(scene, path)?;
    match t {
        Target::Energy("linear_density", Some(_)) | Target::Damping(Some(_)) => {
            let reason = "a [[rods]] entry's density or damping has no run sensitivities yet";
            Err(Error::field("params", format!("\"{path}\""), reason))
        }
        t => Ok(t),
    }
}

/// The parameters' rates ([`ParameterRates`]) for the facade's system.
struct Rates {
    targets: Vec<Target>,
    values: Vec<Real>,
    /// Per parameter, the contact barrier's relative stiffness rate.
    barrier: Vec<Option<Real>>,
    /// `1/μ` (the density's mass rate).
    inverse_density: Real,
    /// `1/L` (the rest length's mass rate: \\(M \propto L\\)).
    inverse_length: Real,
    /// Per parameter and grab, the derivative of the grab's start point.
    grab_from: Vec<Vec<Option<Vector3<Real>>>>,
    /// Per grab, whether it had not started before the step.
    waiting: Vec<bool>,
    /// Per parameter, the derivative of each pin's target (`pins[i].position[c]`).
    pin_rates: Vec<Vec<Vector3<Real>>>,
    scratch: Vec<Vector3<Real>>,
    /// A facade error met inside a callback.
    error: Option<Error>,
}

impl Rates {
    /// The rates of `targets` (of `paths`) on `system`, checked: every parameter must
    /// change the run.
    fn new(
        scene: &Scene,
        system: &RodSystem,
        paths: &[&str],
        targets: Vec<Target>,
    ) -> Result<Self, Error> {
        let mut barrier = Vec::with_capacity(targets.len());
        let mut pin_rates = vec![Vec::new(); targets.len()];
        for (t, out) in targets.iter().zip(&mut pin_rates) {
            super::paths::target_rates(scene, &system.pins, t, out);
        }
        let mut probe = vec![Vector3::zeros(); system.rod.len()];
        for (path, t) in paths.iter().zip(&targets) {
            let value = target_value(scene, t);
            barrier.push(barrier_rate(system, scene, t, value)?);
            if let Target::Energy(name, segment) = *t {
                if rest_length::is_rest_length(name) {
                    rest_length::check_energies(system, path)?;
                }
                let found = energy_rate(system, name, segment, &mut probe)?;
                if !found && name != "linear_density" {
                    let reason = "no energy of the scene depends on it (is it set?)";
                    return Err(Error::field("params", format!("\"{path}\""), reason));
                }
            }
        }
        Ok(Self {
            values: targets.iter().map(|t| target_value(scene, t)).collect(),
            grab_from: vec![vec![None; system.grabs.len()]; targets.len()],
            targets,
            barrier,
            inverse_density: 1.0 / system.rod.material().linear_density,
            inverse_length: 1.0 / system.rod.material().rest_length,
            waiting: Vec::with_capacity(system.grabs.len()),
            pin_rates,
            scratch: Vec::with_capacity(system.rod.len()),
            error: None,
        })
    }

    /// Records the start points' derivatives of the grabs that started in the step just
    /// taken, from the states at its start.
    fn grabs_started(&mut self, system: &RodSystem, states: &[ForwardState]) -> Result<(), Error> {
        for (g, grab) in system.grabs.iter().enumerate() {
            if !(self.waiting[g] && grab.from.is_some()) {
                continue;
            }
            let row = system.rod.basis_at(grab.spring.at)?;
            for (k, state) in states.iter().enumerate() {
                self.grab_from[k][g] = Some(row.combine(&row.value, &state.positions));
            }
        }
        Ok(())
    }

    /// `out = ∂∇E/∂p_k` on `system` (see the module docs).
    fn rate(
        &mut self,
        system: &RodSystem,
        k: usize,
        out: &mut [Vector3<Real>],
    ) -> Result<(), Error> {
        out.iter_mut().for_each(|o| *o = Vector3::zeros());
        match self.targets[k] {
            Target::Energy(name, segment) => {
                energy_rate(system, name, segment, out)?;
                if rest_length::is_rest_length(name) {
                    rest_length::add_derived(system, out);
                }
            }
            Target::Load(i, c) => {
                let row = system.rod.basis_at(system.loads[i].force.at)?;
                for j in 0..row.order {
                    out[row.first + j][c] -= row.value[j];
                }
            }
            Target::Friction => {
                energy_rate(system, "friction", None, out)?;
            }
            Target::Damping(_) | Target::Pin { .. } => {}
        }
        if let Some(ratio) = self.barrier[k] {
            add_barrier_rate(system, ratio, out, &mut self.scratch);
        }
        for (grab, from) in system.grabs.iter().zip(&self.grab_from[k]) {
            let Some(from) = from.filter(|_| grab.active(system.time)) else {
                continue;
            };
            let span = grab.end_time - grab.start_time;
            let f = if span > 0.0 {
                ((system.time - grab.start_time) / span).clamp(0.0, 1.0)
            } else {
                1.0
            };
            let row = system.rod.basis_at(grab.spring.at)?;
            let target_rate = from * (1.0 - f);
            for j in 0..row.order {
                out[row.first + j] -= target_rate * (grab.spring.stiffness * row.value[j]);
            }
        }
        Ok(())
    }
}

impl ParameterRates for Rates {
    fn gradient_rate(
        &mut self,
        system: &dyn System,
        k: usize,
        out: &mut [Vector3<Real>],
    ) -> Result<(), IntegratorError> {
        let facade = "forward sensitivities need the facade's system";
        let Some(system) = system.as_any().and_then(|a| a.downcast_ref::<RodSystem>()) else {
            return Err(IntegratorError::SolverState(facade));
        };
        self.rate(system, k, out).map_err(|e| {
            self.error = Some(e);
            IntegratorError::SolverState("a parameter's rate")
        })
    }

    fn mass_rate(&self, k: usize) -> Real {
        match self.targets[k] {
            Target::Energy("linear_density", None) => self.inverse_density,
            Target::Energy(name, None) if rest_length::is_rest_length(name) => self.inverse_length,
            _ => 0.0,
        }
    }

    fn damping_rate(&self, k: usize) -> Real {
        match self.targets[k] {
            Target::Damping(None) => 1.0,
            _ => 0.0,
        }
    }

    fn add_start_rate(
        &mut self,
        system: &dyn System,
        start_rate: &[Vector3<Real>],
        out: &mut [Vector3<Real>],
    ) -> Result<(), IntegratorError> {
        let Some(system) = system.as_any().and_then(|a| a.downcast_ref::<RodSystem>()) else {
            return Err(IntegratorError::SolverState(
                "forward sensitivities need the facade's system",
            ));
        };
        for energy in system.acting() {
            if let Some(lifecycle) = energy.capabilities().lifecycle {
                lifecycle.add_start_rate(&system.rod, start_rate, out);
            }
        }
        Ok(())
    }

    fn target_rate(&self, k: usize, pin: usize) -> Vector3<Real> {
        self.pin_rates[k].get(pin).copied().unwrap_or_default()
    }
}
