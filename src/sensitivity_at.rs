//! Static sensitivities at chosen material coordinates: the derivatives of the
//! equilibrium's material points `C(s)` for coordinates `s` (m of rest length, as
//! Python's `positions(s)`) chosen by the caller, not only at the scene's output
//! samples ([`crate::sensitivity`] computes them at those): with the derivatives of
//! the control points `dq/dp` from the same solve,
//! \\(\mathrm{d}C(s)/\mathrm{d}p = \sum_i b_i(s)\, \mathrm{d}q_i/\mathrm{d}p\\).
//! Python's `Simulation.sensitivities(params, s)` is this; for a run (implicit Euler,
//! BDF2), [`run_sensitivities_at`] gives them after every step from the forward
//! sensitivities (`Simulation.sensitivity_history`), the last of them at the end. A
//! coordinate in metres is the same material point whatever the rest length, so
//! `rod.rest_length`'s derivative has the extra \\(-(s/L)\, C'(s)\\) (the point slides
//! along the rescaled domain: `sensitivity/rest_length.rs`).

use crate::sensitivity::{
    observed_sensitivities, points_at, rest_length, static_sensitivities, StaticSensitivities,
    StepView,
};
use crate::{Error, Scene};
use nalgebra::Vector3;
use splinerod_core::Real;

/// The sensitivities of a static scene's equilibrium at chosen material coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct SensitivitiesAt {
    /// The parameters, by scene path, with their values.
    pub parameters: Vec<(String, Real)>,
    /// The material coordinates asked for, m.
    pub s: Vec<Real>,
    /// Per parameter, the derivative of the point at each coordinate, m per unit.
    pub positions: Vec<Vec<[Real; 3]>>,
    /// The equilibrium's point at each coordinate, m.
    pub at: Vec<[Real; 3]>,
}

/// The equilibrium of the static `scene` and the derivatives of its points at the
/// material coordinates `s` (m) with respect to the parameters `paths` (scene paths, as
/// [`static_sensitivities`]). A coordinate that is not finite or lies outside the rod
/// is an error naming `s` (checked before the solve).
pub fn static_sensitivities_at(
    scene: &Scene,
    paths: &[&str],
    s: &[Real],
) -> Result<SensitivitiesAt, Error> {
    let rod = (
        scene.material_coordinate(0.0),
        scene.material_coordinate(1.0),
    );
    check_coordinates(s, rod)?;
    let sensitivities = static_sensitivities(scene, paths)?;
    evaluate_at(&sensitivities, s)
}

/// [`StaticSensitivities`] evaluated at the material coordinates `s` (m) of its rod.
pub fn evaluate_at(
    sensitivities: &StaticSensitivities,
    s: &[Real],
) -> Result<SensitivitiesAt, Error> {
    let rod = &sensitivities.rod;
    check_coordinates(s, rod.basis().domain())?;
    let rows = s
        .iter()
        .map(|&x| rod.basis_at(x))
        .collect::<Result<Vec<_>, _>>()?;
    let point = |q: &[Vector3<Real>]| points_at(&rows, q);
    let mut positions: Vec<Vec<[Real; 3]>> = sensitivities
        .control_points
        .iter()
        .map(|d| point(d))
        .collect();
    if let Some(k) = rest_length::index_in(&names(&sensitivities.parameters)) {
        shift_by_rest_length(rod, s, &mut positions[k])?;
    }
    Ok(SensitivitiesAt {
        parameters: sensitivities.parameters.clone(),
        s: s.to_vec(),
        positions,
        at: point(&rod.positions),
    })
}

/// The sensitivities of a run at chosen material coordinates, after every step.
#[derive(Debug, Clone, PartialEq)]
pub struct RunSensitivitiesAt {
    /// The parameters, by scene path, with their values.
    pub parameters: Vec<(String, Real)>,
    /// The material coordinates asked for, m.
    pub s: Vec<Real>,
    /// The time at the end of each step, s.
    pub times: Vec<Real>,
    /// Per step, per parameter, the derivative of the point at each coordinate.
    pub positions: Vec<Vec<Vec<[Real; 3]>>>,
    /// Per step, the point at each coordinate, m.
    pub at: Vec<Vec<[Real; 3]>>,
}

/// The run of the dynamic `scene` (implicit Euler or BDF2, what
/// [`crate::sensitivity::dynamic_sensitivities`] accepts) and, after every step, the
/// derivatives of its points at the material coordinates `s` (m) with respect to the
/// parameters `paths`.
pub fn run_sensitivities_at(
    scene: &Scene,
    paths: &[&str],
    s: &[Real],
) -> Result<RunSensitivitiesAt, Error> {
    let rod = (
        scene.material_coordinate(0.0),
        scene.material_coordinate(1.0),
    );
    check_coordinates(s, rod)?;
    let (mut times, mut positions, mut at) = (Vec::new(), Vec::new(), Vec::new());
    let rest = rest_length::index_in(paths);
    let mut rows = Vec::new();
    let mut observe = |view: &StepView<'_>| {
        let (t, rod, states) = (view.t, view.rod, view.states);
        if rows.is_empty() {
            // The basis is fixed through a differentiated run: the rows once.
            rows = s
                .iter()
                .map(|&x| rod.basis_at(x))
                .collect::<Result<_, _>>()?;
        }
        let point = |q: &[Vector3<Real>]| points_at(&rows, q);
        times.push(t);
        let mut d: Vec<Vec<[Real; 3]>> = states.iter().map(|d| point(&d.positions)).collect();
        if let Some(k) = rest {
            shift_by_rest_length(rod, s, &mut d[k])?;
        }
        positions.push(d);
        at.push(point(&rod.positions));
        Ok(())
    };
    let found = observed_sensitivities(scene, paths, &mut observe)?;
    Ok(RunSensitivitiesAt {
        parameters: found.parameters,
        s: s.to_vec(),
        times,
        positions,
        at,
    })
}

/// The parameters' names.
fn names(parameters: &[(String, Real)]) -> Vec<&str> {
    parameters.iter().map(|(n, _)| n.as_str()).collect()
}

/// The rest length's derivatives `d` of the points at the coordinates `s` (m), which
/// slide along the rod as `L` changes: each gets \\(-(s/L)\, C'(s)\\)
/// (`sensitivity/rest_length.rs`).
fn shift_by_rest_length(
    rod: &splinerod_core::Rod,
    s: &[Real],
    d: &mut [[Real; 3]],
) -> Result<(), Error> {
    for (x, &s) in d.iter_mut().zip(s) {
        let mut v = Vector3::from(*x);
        rest_length::add_metric_shift(rod, s, &mut v)?;
        *x = v.into();
    }
    Ok(())
}

/// An error naming `s` unless every coordinate is finite and inside `[start, end]`.
fn check_coordinates(s: &[Real], (start, end): (Real, Real)) -> Result<(), Error> {
    match s
        .iter()
        .find(|x| !(x.is_finite() && **x >= start && **x <= end))
    {
        Some(x) => Err(Error::field(
            "s",
            x,
            format!("material coordinates must lie on the rod, in [{start}, {end}] m"),
        )),
        None => Ok(()),
    }
}
