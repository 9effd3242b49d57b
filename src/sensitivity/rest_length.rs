//! `rod.rest_length` as a parameter of sensitivities (issue #48): the rod's parametric
//! domain `[0, L]` scales with it, and with it every material coordinate the scene gives
//! as a fraction of the rod — pins' and grabs' `at`, loads', clamps', the output
//! samples (`output.samples` at fixed fractions) — while the control points stay free
//! unknowns. At fixed control points a point at a fixed fraction does not move
//! (\\(b_i(uL; L) = B_i(u)\\)); what changes:
//!
//! * every energy's gradient, \\(\partial_L\nabla E\\), from its
//!   [`Parameters`](splinerod_energies::Parameters) (`"rest_length"`, derived in
//!   `splinerod_energies::rest_length`); an acting energy that does not give it is an
//!   error naming the energy ([`check_energies`]);
//! * what the scene derives from `L`: a penalty clamp's stiffness \\(10^6 EI/L\\), whose
//!   term is \\((\mathrm{d}k/\mathrm{d}L)/k\,\nabla E_{clamp} = -\nabla E_{clamp}/L\\)
//!   ([`add_derived`]), and the default contact barrier's stiffness (as for every
//!   parameter: `sensitivity::barrier_rate`);
//! * the mass matrix \\(M = \int \mu\, b b^T ds \propto L\\): \\(M' = M/L\\) (runs);
//! * the initial shape, where the scene makes it of `L`: a straight rod without
//!   `rod.end` runs from `start` along `x` for `L`, so every initial point and pinned
//!   target moves by \\((x - x_{start})/L\\) ([`initial_rate`], [`pin_rates`]); with
//!   `rod.end` or `rod.initial_control_points` the start does not depend on `L`.
//!
//! Material coordinates given in metres — markers' `s`, Python's `positions(s)` — are
//! the same material point whatever `L` (a mark painted at 0.3 m): at fraction `s/L`, so
//! their derivative has the extra \\(-(s/L)\, C'(s)\\) ([`add_metric_shift`]); the nearest
//! point of an unlabelled point has none (its fraction is stationary or an end).
//!
//! Refused, naming the field: `rods[k].rest_length` (one segment of a joined rod), a
//! rod whose rest length `rod.overhand` sets, `rod.rest_shape = "initial"` (the rest
//! metric is then the initial curve's), and a pin away from `s = 0` with a given
//! `position` or `path` while the rod's end follows `L` (the file's pin would no longer
//! agree with the start).

use crate::scene::RestShape;
use crate::{Error, RodSystem, Scene};
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};
use splinerod_energies::rest_length::REST_LENGTH;

/// The scene path of the parameter.
pub(crate) const PATH: &str = "rod.rest_length";

/// Checks that `scene`'s rest length can be differentiated (module docs); `path` is how
/// the user named it.
pub(crate) fn check_scene(scene: &Scene, path: &str) -> Result<(), Error> {
    let bad = |reason: String| Error::field("params", format!("\"{path}\""), reason);
    let r = &scene.rod;
    if r.overhand.is_some() {
        let reason = "rod.overhand sets the rest length with the knot's shape: not a free \
                      parameter";
        return Err(bad(reason.into()));
    }
    if r.rest_shape == RestShape::Initial {
        let reason = "with rod.rest_shape = \"initial\" the rest metric is the initial \
                      curve's, not the domain's: the rest length has no derivative of its own";
        return Err(bad(reason.into()));
    }
    if follows_length(scene) {
        let moved = scene
            .pins
            .iter()
            .enumerate()
            .find(|(_, p)| p.at != 0.0 && (p.position.is_some() || p.path.is_some()));
        if let Some((i, p)) = moved {
            let field = if p.path.is_some() { "path" } else { "position" };
            let reason = format!(
                "pins[{i}].{field} is given while the rod's end follows the rest length \
                 (rod.end unset): the pin would no longer agree with the start; set rod.end"
            );
            return Err(bad(reason));
        }
    }
    Ok(())
}

/// Whether the initial shape is a straight rod from `start` along `x` of length `L`.
fn follows_length(scene: &Scene) -> bool {
    let r = &scene.rod;
    r.end.is_none() && r.initial_control_points.is_none() && !scene.closed()
}

/// The rod's start (`rod.start`, default the origin).
fn start(scene: &Scene) -> Vector3<Real> {
    Vector3::from(scene.rod.start.unwrap_or([0.0; 3]))
}

/// Where `rod.rest_length` is among the parameter `paths`, if it is.
pub(crate) fn index_in<S: AsRef<str>>(paths: &[S]) -> Option<usize> {
    paths.iter().position(|p| p.as_ref() == PATH)
}

/// Whether `name` (an energy parameter target's) is the rest length.
pub(crate) fn is_rest_length(name: &str) -> bool {
    name == REST_LENGTH
}

/// Every acting energy must give its derivative by the rest length: an error naming the
/// first that does not.
pub(crate) fn check_energies(system: &RodSystem, path: &str) -> Result<(), Error> {
    for energy in system.acting() {
        let gives = energy
            .capabilities()
            .parameters
            .is_some_and(|p| p.parameter_names().contains(&REST_LENGTH));
        if !gives {
            let reason = format!(
                "the energy \"{}\" gives no derivative by the rest length",
                energy.name()
            );
            return Err(Error::field("params", format!("\"{path}\""), reason));
        }
    }
    Ok(())
}

/// Adds the terms of what the scene derives from `L` (module docs): every penalty
/// clamp's stiffness \\(10^6 EI/L\\), \\(-\nabla E_{clamp}/L\\).
pub(crate) fn add_derived(system: &RodSystem, out: &mut [Vector3<Real>]) {
    let l = system.rod.material().rest_length;
    let mut gradient = vec![Vector3::zeros(); system.rod.len()];
    let mut any = false;
    for energy in system.acting().filter(|e| e.name() == "clamp") {
        energy.add_gradient(&system.rod, &mut gradient);
        any = true;
    }
    if any {
        for (o, g) in out.iter_mut().zip(&gradient) {
            *o -= g / l;
        }
    }
}

/// \\(\mathrm{d}q_0/\mathrm{d}L\\) of the initial control points `rod` (as built): where
/// the initial shape follows `L`, \\((q_0 - x_{start})/L\\); else `None` (zero).
pub(crate) fn initial_rate(scene: &Scene, rod: &Rod) -> Option<Vec<Vector3<Real>>> {
    follows_length(scene).then(|| {
        let (start, l) = (start(scene), rod.material().rest_length);
        rod.positions.iter().map(|q| (q - start) / l).collect()
    })
}

/// Per pin of `pins` (the system's, as built), the derivative of its target by `L`
/// (zero unless the initial shape follows `L`), into `out`.
pub(crate) fn pin_rates(scene: &Scene, pins: &[splinerod_core::Pin], out: &mut [Vector3<Real>]) {
    if follows_length(scene) {
        let (start, l) = (start(scene), scene.rod.rest_length);
        for (o, pin) in out.iter_mut().zip(pins) {
            *o = (pin.position - start) / l;
        }
    }
}

/// An error naming `rod.rest_length` if a fit took it below the farthest marker `s`
/// (m): the marker would no longer lie on the rod.
pub(crate) fn check_markers(scene: &Scene, farthest: Option<Real>) -> Result<(), Error> {
    let l = scene.rod.rest_length;
    match farthest.filter(|&s| s > l) {
        Some(s) => Err(Error::field(
            PATH,
            l,
            format!("the fit shortened the rod below its marker at s = {s} m"),
        )),
        None => Ok(()),
    }
}

/// For a material point at `s` m of rest length (a marker, a point of Python's
/// `positions(s)`), `d += −(s/L) C'(s)` on `rod`: the point moves along the rod as `L`
/// changes (module docs).
pub(crate) fn add_metric_shift(rod: &Rod, s: Real, d: &mut Vector3<Real>) -> Result<(), Error> {
    let row = rod.basis_at(s)?;
    let tangent = row.combine(&row.d1, &rod.positions);
    *d -= tangent * (s / rod.material().rest_length);
    Ok(())
}
