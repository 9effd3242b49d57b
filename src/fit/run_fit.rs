//! A run as a [`Model`] for identification (issue #48): markers `t,s,x,y,z` observed
//! during an implicit Euler or BDF2 run at step times, residual
//! \\(r = (x_{obs} - C(s; t, p))/\sigma\\) and its exact derivative
//! \\(-\sum_i b_i(s)\, S_{q,i}(t) / \sigma\\) from the run's forward sensitivities
//! ([`crate::sensitivity::observed_sensitivities`]): one run per evaluation, each
//! marker read after the step that ends at its time.
//!
//! What the forward sensitivities refuse (adaptivity, cuts, sub-steps, other schemes)
//! is refused here too, naming it. A marker's time must be a step's end (a multiple of
//! `solver.dt`, to 10⁻⁶ of a step), up to the run's duration.

use crate::fit::least_squares::{fit, FitReport, Model};
use crate::fit::observations::{ObservationFile, ObservationKind};
use crate::fit::scene_fit::{start_and_spaces, SIMULATIONS_PER_PARAMETER};
use crate::sensitivity::{observed_sensitivities, set_parameter};
use crate::{Error, Scene};
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};
use splinerod_integrators::ForwardState;

/// How far from a step's end, in steps, a marker's time may be.
const STEP_TIME_TOLERANCE: Real = 1e-6;

/// One observed marker of a run.
#[derive(Debug, Clone, Copy)]
pub struct RunMarker {
    /// The step after which it is observed (1 = the first step's end).
    pub step: usize,
    /// Material coordinate, m.
    pub s: Real,
    /// Observed position, m.
    pub position: Vector3<Real>,
    /// Standard deviation, m.
    pub sigma: Real,
}

/// A dynamic scene observed by markers at step times.
pub struct RunFit<'a> {
    scene: Scene,
    paths: Vec<&'a str>,
    /// Sorted by step.
    markers: Vec<RunMarker>,
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
        let dt = scene.solver.dt.unwrap_or_default();
        let steps = scene.step_count();
        let mut found = Vec::with_capacity(markers.len());
        for &(t, s, position, sigma) in markers {
            let step = (t / dt).round();
            let off = (t / dt - step).abs() > STEP_TIME_TOLERANCE;
            let stepped = dt > 0.0;
            if !stepped || off || step < 1.0 || step as usize > steps {
                let reason = format!(
                    "a run's markers are read at the end of a step: t must be a multiple \
                     of solver.dt = {dt} s in (0, {}] s",
                    steps as Real * dt
                );
                return Err(Error::field("observations.t", t, reason));
            }
            let step = step as usize;
            found.push(RunMarker {
                step,
                s,
                position,
                sigma,
            });
        }
        found.sort_by_key(|m| m.step);
        Ok(Self {
            scene: scene.clone(),
            paths: paths.to_vec(),
            markers: found,
        })
    }
}

impl<'a> RunFit<'a> {
    /// The fit of `paths` of the dynamic `scene` to the observation `files`: markers
    /// with times (points and pin forces of runs are not built: refused, naming the
    /// file).
    pub fn from_files(
        scene: &Scene,
        paths: &[&'a str],
        files: &[ObservationFile],
    ) -> Result<Self, Error> {
        let length = scene.rod_spec(0).rest_length;
        // The last step's end (at or just past the duration), and its round-off.
        let dt = scene.solver.dt.unwrap_or_default();
        let end = Some(scene.step_count() as Real * dt * (1.0 + 1e-9));
        let mut markers = Vec::new();
        for file in files {
            file.check(scene.pins.len(), length, end)?;
            if file.kind != ObservationKind::Marker {
                let reason = "a run is fitted to markers (t,s,x,y,z) yet: points and pin \
                              forces of runs are not built";
                return Err(Error::field("observations", &file.path, reason));
            }
            for row in &file.rows {
                let (t, s) = (row.t.unwrap_or_default(), row.s.unwrap_or_default());
                markers.push((t, s, Vector3::from(row.value), row.sigma));
            }
        }
        Self::new(scene, paths, &markers)
    }

    /// Fits from the scene's own values ([`start_and_spaces`]).
    pub fn fit(&mut self) -> Result<FitReport, Error> {
        let (start, spaces) = start_and_spaces(&self.scene, &self.paths)?;
        let budget = SIMULATIONS_PER_PARAMETER * self.paths.len();
        fit(self, &start, &spaces, budget)
    }
}

impl Model for RunFit<'_> {
    fn residual_count(&self) -> usize {
        3 * self.markers.len()
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
        let (scene, markers, n) = (&self.scene, &self.markers, p.len());
        let paths = if j.is_some() { &self.paths[..] } else { &[] };
        let length = scene.rod_spec(0).rest_length;
        let (mut step, mut next) = (0, 0);
        let mut observe = |_: Real, rod: &Rod, states: &[ForwardState]| -> Result<(), Error> {
            step += 1;
            while let Some(m) = markers.get(next).filter(|m| m.step == step) {
                let row = rod.basis_at(scene.material_coordinate(m.s / length))?;
                let model = row.combine(&row.value, &rod.positions);
                for c in 0..3 {
                    r[3 * next + c] = (m.position[c] - model[c]) / m.sigma;
                }
                if let Some(j) = j.as_deref_mut() {
                    for (k, state) in states.iter().enumerate() {
                        let d = row.combine(&row.value, &state.positions);
                        for c in 0..3 {
                            j[(3 * next + c) * n + k] = -d[c] / m.sigma;
                        }
                    }
                }
                next += 1;
            }
            Ok(())
        };
        observed_sensitivities(scene, paths, &mut observe)?;
        Ok(())
    }
}
