//! A run as a [`Model`] for identification (issue #48): observations at step times of
//! an implicit Euler or BDF2 run, each read after the step that ends at its time, with
//! exact derivatives from the run's forward sensitivities
//! ([`crate::sensitivity::observed_sensitivities`]): one run per evaluation.
//!
//! - markers `t,s,x,y,z`: \\(r = (x_{obs} - C(s; t, p))/\sigma\\), derivative
//!   \\(-\sum_i b_i(s)\, S_{q,i}(t) / \sigma\\);
//! - unlabelled points `t,x,y,z`: \\(r = \lVert x_{obs} - C(s^*)\rVert/\sigma\\) at the
//!   curve's nearest point ([`crate::fit::closest`]), derivative
//!   \\(-n \cdot \sum_i b_i(s^*)\, S_{q,i}(t)/\sigma\\) (no derivative of `s*`, as for
//!   a static scene);
//! - pin forces `t,pin,fx,fy,fz`: \\(r = (F_{obs} - F_j(t; p))/\sigma\\) with the force
//!   the rod puts on `[[pins]]` entry `j`'s support during the step ending at `t` (the
//!   run's `pin_forces`), derivative \\(-\mathrm{d}F_j/\mathrm{d}p/\sigma\\) from the step's
//!   tangent solve ([`crate::sensitivity::StepView`]).
//!
//! What the forward sensitivities refuse (adaptivity, cuts, sub-steps, other schemes)
//! is refused here too, naming it. An observation's time must be a step's end (a
//! multiple of `solver.dt`, to 10⁻⁶ of a step), up to the run's duration.

use crate::fit::closest::closest_point;
use crate::fit::least_squares::{fit, FitReport, Model};
use crate::fit::observations::{ObservationFile, ObservationKind};
use crate::fit::scene_fit::{start_and_spaces, SIMULATIONS_PER_PARAMETER};
use crate::sensitivity::{observed_sensitivities, set_parameter, StepView};
use crate::{Error, Scene};
use nalgebra::Vector3;
use splinerod_core::Real;

/// How far from a step's end, in steps, an observation's time may be.
const STEP_TIME_TOLERANCE: Real = 1e-6;

/// What an observation of a run sees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Observed {
    /// A marker at a material coordinate, m.
    Marker(Real),
    /// The force the rod puts on a `[[pins]]` entry's support.
    PinForce(usize),
    /// An unlabelled point: compared with the curve's nearest point.
    Point,
}

impl Observed {
    /// Its residuals: three, one for a point (a distance).
    fn rows(self) -> usize {
        match self {
            Observed::Point => 1,
            _ => 3,
        }
    }
}

/// One observation of a run.
#[derive(Debug, Clone, Copy)]
pub struct RunObservation {
    /// The step after which it is observed (1 = the first step's end).
    pub step: usize,
    /// What it sees.
    pub what: Observed,
    /// The observed position (m) or force (N).
    pub value: Vector3<Real>,
    /// Standard deviation, m or N.
    pub sigma: Real,
    /// Its first residual's row.
    first: usize,
}

/// A dynamic scene observed at step times.
pub struct RunFit<'a> {
    scene: Scene,
    paths: Vec<&'a str>,
    /// Sorted by step.
    observations: Vec<RunObservation>,
    /// The residuals of all observations.
    rows: usize,
}

impl<'a> RunFit<'a> {
    /// The fit of the parameters `paths` of the dynamic `scene` to `markers`
    /// (`(t, s, position, σ)`: time s, material coordinate m); an error names a marker
    /// whose time is not a step's end.
    pub fn new(
        scene: &Scene,
        paths: &[&'a str],
        markers: &[(Real, Real, Vector3<Real>, Real)],
    ) -> Result<Self, Error> {
        let seen = markers
            .iter()
            .map(|&(t, s, p, sigma)| (t, Observed::Marker(s), p, sigma));
        Self::observed(scene, paths, seen)
    }

    /// The fit of `paths` of the dynamic `scene` to `observations` (`(t, what, value,
    /// σ)`); an error names one whose time is not a step's end or whose pin the scene
    /// lacks.
    pub fn observed(
        scene: &Scene,
        paths: &[&'a str],
        observations: impl IntoIterator<Item = (Real, Observed, Vector3<Real>, Real)>,
    ) -> Result<Self, Error> {
        let mut found = Vec::new();
        for (t, what, value, sigma) in observations {
            if let Observed::PinForce(pin) = what {
                if pin >= scene.pins.len() {
                    let reason = format!("the scene has {} [[pins]]", scene.pins.len());
                    return Err(Error::field("observations.pin", pin, reason));
                }
            }
            let step = step_of(scene, t)?;
            found.push(RunObservation {
                step,
                what,
                value,
                sigma,
                first: 0,
            });
        }
        found.sort_by_key(|m| m.step);
        let mut rows = 0;
        for o in &mut found {
            o.first = rows;
            rows += o.what.rows();
        }
        Ok(Self {
            scene: scene.clone(),
            paths: paths.to_vec(),
            observations: found,
            rows,
        })
    }

    /// The fit of `paths` of the dynamic `scene` to the observation `files`: markers,
    /// unlabelled points and pin forces, each row with its time (a row without one, of
    /// a static scene, is named with its file).
    pub fn from_files(
        scene: &Scene,
        paths: &[&'a str],
        files: &[ObservationFile],
    ) -> Result<Self, Error> {
        let length = scene.rod_spec(0).rest_length;
        // The last step's end (at or just past the duration), and its round-off.
        let dt = scene.solver.dt.unwrap_or_default();
        let end = Some(scene.step_count() as Real * dt * (1.0 + 1e-9));
        let mut observations = Vec::new();
        for file in files {
            file.check(scene.pins.len(), length, end)?;
            for row in &file.rows {
                let what = match (file.kind, row.s, row.pin) {
                    (ObservationKind::Marker, Some(s), _) => Observed::Marker(s),
                    (ObservationKind::PinForce, _, Some(pin)) => Observed::PinForce(pin),
                    (ObservationKind::Point, _, _) => Observed::Point,
                    _ => {
                        let reason = "a row that is neither a marker, a pin force nor a point";
                        return Err(Error::field("observations", &file.path, reason));
                    }
                };
                let Some(t) = row.t else {
                    let reason = format!("line {}: a run's observation needs its time t", row.line);
                    return Err(Error::field("observations", &file.path, reason));
                };
                observations.push((t, what, Vector3::from(row.value), row.sigma));
            }
        }
        Self::observed(scene, paths, observations)
    }

    /// Fits from the scene's own values ([`start_and_spaces`]).
    pub fn fit(&mut self) -> Result<FitReport, Error> {
        let (start, spaces) = start_and_spaces(&self.scene, &self.paths)?;
        let budget = SIMULATIONS_PER_PARAMETER * self.paths.len();
        fit(self, &start, &spaces, budget)
    }
}

/// The step of `scene` that ends at time `t`, or an error naming `t`.
fn step_of(scene: &Scene, t: Real) -> Result<usize, Error> {
    let dt = scene.solver.dt.unwrap_or_default();
    let steps = scene.step_count();
    let step = (t / dt).round();
    let off = (t / dt - step).abs() > STEP_TIME_TOLERANCE;
    let stepped = dt > 0.0;
    if !stepped || off || step < 1.0 || step as usize > steps {
        let reason = format!(
            "a run's observations are read at the end of a step: t must be a multiple \
             of solver.dt = {dt} s in (0, {}] s",
            steps as Real * dt
        );
        return Err(Error::field("observations.t", t, reason));
    }
    Ok(step as usize)
}

impl Model for RunFit<'_> {
    fn residual_count(&self) -> usize {
        self.rows
    }

    fn evaluate(
        &mut self,
        p: &[Real],
        r: &mut [Real],
        mut j: Option<&mut [Real]>,
    ) -> Result<(), Error> {
        for (path, &v) in self.paths.iter().zip(p) {
            set_parameter(&mut self.scene, path, v)?;
        }
        let (scene, observations) = (&self.scene, &self.observations);
        if crate::sensitivity::rest_length::index_in(&self.paths).is_some() {
            let marks = observations.iter().filter_map(|o| match o.what {
                Observed::Marker(s) => Some(s),
                _ => None,
            });
            crate::sensitivity::rest_length::check_markers(scene, marks.reduce(Real::max))?;
        }
        let paths = if j.is_some() { &self.paths[..] } else { &[] };
        let rest = crate::sensitivity::rest_length::index_in(paths);
        let length = scene.rod_spec(0).rest_length;
        let (mut step, mut next) = (0, 0);
        let mut observe = |view: &StepView<'_>| -> Result<(), Error> {
            step += 1;
            while let Some(o) = observations.get(next).filter(|o| o.step == step) {
                residuals(scene, view, o, (&mut *r, j.as_deref_mut()))?;
                if let (Observed::Marker(s), Some(k), Some(j)) = (o.what, rest, j.as_deref_mut()) {
                    let s = scene.material_coordinate(s / length);
                    marker_rest_length(view.rod, s, o, (k, paths.len()), j)?;
                }
                next += 1;
            }
            Ok(())
        };
        observed_sensitivities(scene, paths, &mut observe)?;
        Ok(())
    }
}

/// Writes the residuals of observation `o` after the step seen in `view` into `r`, and
/// with `j` their derivatives (row-major, one column per parameter).
fn residuals(
    scene: &Scene,
    view: &StepView<'_>,
    o: &RunObservation,
    (r, j): (&mut [Real], Option<&mut [Real]>),
) -> Result<(), Error> {
    match o.what {
        Observed::PinForce(pin) => {
            let force = view.pin_force(pin)?;
            for c in 0..3 {
                r[o.first + c] = (o.value[c] - force[c]) / o.sigma;
            }
            let Some(j) = j else {
                return Ok(());
            };
            let n = view.states.len();
            for k in 0..n {
                let d = view.pin_force_rate(k, pin)?;
                for c in 0..3 {
                    j[(o.first + c) * n + k] = -d[c] / o.sigma;
                }
            }
            Ok(())
        }
        Observed::Marker(s) => {
            let length = scene.rod_spec(0).rest_length;
            let s = scene.material_coordinate(s / length);
            curve_residuals(view, o, (s, None), (r, j))
        }
        Observed::Point => {
            let (s, at) = closest_point(view.rod, &o.value)?;
            let gap = o.value - at;
            let d = gap.norm();
            let normal = if d > 0.0 { gap / d } else { Vector3::zeros() };
            curve_residuals(view, o, (s, Some(normal)), (r, j))
        }
    }
}

/// Adds to a marker's Jacobian column `k` of `j` (`n` columns) what `rod.rest_length`
/// adds: its material coordinate `s` is in metres, so it slides along the rod as `L`
/// changes (\\(-(s/L)\, C'(s)\\) besides the control points',
/// `sensitivity/rest_length.rs`).
fn marker_rest_length(
    rod: &splinerod_core::Rod,
    s: Real,
    o: &RunObservation,
    (k, n): (usize, usize),
    j: &mut [Real],
) -> Result<(), Error> {
    let mut shift = Vector3::zeros();
    crate::sensitivity::rest_length::add_metric_shift(rod, s, &mut shift)?;
    for c in 0..3 {
        j[(o.first + c) * n + k] -= shift[c] / o.sigma;
    }
    Ok(())
}

/// The residuals of `o` against the curve's point at material coordinate `s`: the
/// three components, or with `normal` (an unlabelled point's direction from the curve)
/// the distance; with `j` their derivatives.
fn curve_residuals(
    view: &StepView<'_>,
    o: &RunObservation,
    (s, normal): (Real, Option<Vector3<Real>>),
    (r, j): (&mut [Real], Option<&mut [Real]>),
) -> Result<(), Error> {
    let row = view.rod.basis_at(s)?;
    let curve = row.combine(&row.value, &view.rod.positions);
    match normal {
        None => (0..3).for_each(|c| r[o.first + c] = (o.value[c] - curve[c]) / o.sigma),
        Some(_) => r[o.first] = (o.value - curve).norm() / o.sigma,
    }
    let Some(j) = j else {
        return Ok(());
    };
    let n = view.states.len();
    for (k, state) in view.states.iter().enumerate() {
        let d = row.combine(&row.value, &state.positions);
        match normal {
            None => (0..3).for_each(|c| j[(o.first + c) * n + k] = -d[c] / o.sigma),
            Some(normal) => j[o.first * n + k] = -normal.dot(&d) / o.sigma,
        }
    }
    Ok(())
}
