//! A static scene as a [`Model`] for identification: at parameters `p` (by scene path,
//! [`crate::sensitivity::set_parameter`]), the equilibrium and its sensitivities
//! ([`crate::sensitivity::static_sensitivities`]) give every marker's residual
//! \\(r = (x_{obs} - C(s; p))/\sigma\\) and its exact derivative
//! \\(-\sum_i b_i(s)\, \mathrm{d}q_i/\mathrm{d}p / \sigma\\): one static solve per
//! evaluation.
//!
//! Observed now, in a static scene: markers (`t,s,x,y,z`) and pin forces
//! (`t,pin,fx,fy,fz`: the force the rod puts on `[[pins]]` entry `pin`'s support, as the
//! run's `pin_forces`; residual \\((F_{obs} - F(p))/\sigma\\) with the multipliers'
//! derivative), and unlabelled points (`t,x,y,z`: residual the distance to the curve's
//! nearest point over σ, [`crate::fit::closest`]). A run observed along its trajectory
//! is fitted by [`crate::fit::run_fit`].

use crate::fit::closest::closest_point;
use crate::fit::gradient_free::{nelder_mead, GradientFreeFit};
use crate::fit::least_squares::{fit, FitReport, Model, ParameterSpace};
use crate::fit::observations::{ObservationFile, ObservationKind};
use crate::sensitivity::{parameter_value, rest_length, set_parameter, static_sensitivities};
use crate::{Error, Scene};
use nalgebra::Vector3;
use splinerod_core::Real;

/// Model evaluations a fit may use, per parameter.
pub const SIMULATIONS_PER_PARAMETER: usize = 40;

/// The values of the parameters `paths` in `scene` (where a fit starts), and how each
/// is fitted: stiffnesses, densities, the rest length and a positive damping in log
/// space, the others as they are.
pub fn start_and_spaces(
    scene: &Scene,
    paths: &[&str],
) -> Result<(Vec<Real>, Vec<ParameterSpace>), Error> {
    let start = paths
        .iter()
        .map(|p| parameter_value(scene, p))
        .collect::<Result<Vec<_>, _>>()?;
    let spaces = paths
        .iter()
        .zip(&start)
        .map(|(p, &v)| ParameterSpace {
            log: v > 0.0
                && (p.ends_with("stiffness")
                    || p.ends_with("linear_density")
                    || p.ends_with("rest_length")
                    || p.ends_with("damping")),
            bounds: None,
        })
        .collect();
    Ok((start, spaces))
}

/// A static scene observed by markers.
pub struct SceneFit<'a> {
    /// The scene as given: every fit starts from its values.
    origin: Scene,
    /// The scene at the parameters of the latest evaluation.
    scene: Scene,
    paths: Vec<&'a str>,
    /// Per marker: material coordinate (m), observed position, σ.
    markers: Vec<(Real, Vector3<Real>, Real)>,
    /// Per measured pin force: the `[[pins]]` entry, the force, σ.
    forces: Vec<(usize, Vector3<Real>, Real)>,
    /// Per unlabelled point: the point, σ.
    points: Vec<(Vector3<Real>, Real)>,
}

impl<'a> SceneFit<'a> {
    /// The fit of the parameters `paths` of the static `scene` to `files`; an error names
    /// a file that cannot be used yet or does not fit the scene.
    pub fn new(scene: &Scene, paths: &[&'a str], files: &[ObservationFile]) -> Result<Self, Error> {
        let length = scene.rod_spec(0).rest_length;
        let (mut markers, mut forces, mut points) = (Vec::new(), Vec::new(), Vec::new());
        for file in files {
            file.check(scene.pins.len(), length, None)?;
            for row in &file.rows {
                let value = Vector3::from(row.value);
                match (file.kind, row.s, row.pin) {
                    (ObservationKind::Marker, Some(s), _) => {
                        let s = scene.material_coordinate(s / length);
                        markers.push((s, value, row.sigma));
                    }
                    (ObservationKind::PinForce, _, Some(pin)) => {
                        forces.push((pin, value, row.sigma))
                    }
                    (ObservationKind::Point, _, _) => points.push((value, row.sigma)),
                    _ => {
                        let reason = "a row that is neither a marker, a pin force nor a point";
                        return Err(Error::field("observations", &file.path, reason));
                    }
                }
            }
        }
        Ok(Self {
            origin: scene.clone(),
            scene: scene.clone(),
            paths: paths.to_vec(),
            markers,
            forces,
            points,
        })
    }

    /// Fits from the scene's own values: stiffnesses and densities in log space, the
    /// other parameters as they are.
    pub fn fit(&mut self) -> Result<FitReport, Error> {
        let (start, spaces) = start_and_spaces(&self.origin, &self.paths)?;
        let budget = SIMULATIONS_PER_PARAMETER * self.paths.len();
        fit(self, &start, &spaces, budget)
    }

    /// The gradient-free baseline ([`crate::fit::gradient_free`]) from the same start
    /// in the same variables as [`Self::fit`], until the residuals' root mean square is
    /// at most `target_rms` or `max_simulations` are spent.
    pub fn nelder_mead(
        &mut self,
        target_rms: Real,
        max_simulations: usize,
    ) -> Result<GradientFreeFit, Error> {
        let (start, spaces) = start_and_spaces(&self.origin, &self.paths)?;
        nelder_mead(self, &start, &spaces, target_rms, max_simulations)
    }
}

impl Model for SceneFit<'_> {
    fn residual_count(&self) -> usize {
        3 * (self.markers.len() + self.forces.len()) + self.points.len()
    }

    fn evaluate(
        &mut self,
        p: &[Real],
        r: &mut [Real],
        j: Option<&mut [Real]>,
    ) -> Result<(), Error> {
        for (path, &v) in self.paths.iter().zip(p) {
            set_parameter(&mut self.scene, path, v)?;
        }
        if rest_length::index_in(&self.paths).is_some() {
            let farthest = self.markers.iter().map(|m| m.0).reduce(Real::max);
            rest_length::check_markers(&self.scene, farthest)?;
        }
        let found = static_sensitivities(&self.scene, &self.paths)?;
        let n = p.len();
        let rest = rest_length::index_in(&self.paths);
        let mut j = j;
        for (m, (s, observed, sigma)) in self.markers.iter().enumerate() {
            let row = found.rod.basis_at(*s)?;
            let at = |q: &[Vector3<Real>]| -> Vector3<Real> {
                (0..row.order)
                    .map(|k| q[row.first + k] * row.value[k])
                    .sum()
            };
            let model = at(&found.rod.positions);
            for c in 0..3 {
                r[3 * m + c] = (observed[c] - model[c]) / sigma;
            }
            if let Some(j) = j.as_deref_mut() {
                for (k, dq) in found.control_points.iter().enumerate() {
                    let mut d = at(dq);
                    if Some(k) == rest {
                        // A marker's `s` is in metres: it slides along the rod with `L`.
                        rest_length::add_metric_shift(&found.rod, *s, &mut d)?;
                    }
                    for c in 0..3 {
                        j[(3 * m + c) * n + k] = -d[c] / sigma;
                    }
                }
            }
        }
        let first = self.markers.len();
        for (f, (pin, observed, sigma)) in self.forces.iter().enumerate() {
            let model = found.forces[*pin];
            for c in 0..3 {
                r[3 * (first + f) + c] = (observed[c] - model[c]) / sigma;
            }
            if let Some(j) = j.as_deref_mut() {
                for (k, d) in found.pin_forces.iter().enumerate() {
                    for c in 0..3 {
                        j[(3 * (first + f) + c) * n + k] = -d[*pin][c] / sigma;
                    }
                }
            }
        }
        let first = 3 * (self.markers.len() + self.forces.len());
        for (i, (observed, sigma)) in self.points.iter().enumerate() {
            let (s, model) = closest_point(&found.rod, observed)?;
            let gap = observed - model;
            let d = gap.norm();
            r[first + i] = d / sigma;
            if let Some(j) = j.as_deref_mut() {
                let row = found.rod.basis_at(s)?;
                let normal = if d > 0.0 { gap / d } else { Vector3::zeros() };
                for (k, dq) in found.control_points.iter().enumerate() {
                    let dc: Vector3<Real> = (0..row.order)
                        .map(|a| dq[row.first + a] * row.value[a])
                        .sum();
                    j[(first + i) * n + k] = -normal.dot(&dc) / sigma;
                }
            }
        }
        Ok(())
    }
}
