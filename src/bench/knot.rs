//! The cost of contact (`bench` key `knot_step_us`): the median step of
//! `scenes/knot_tying_adaptive.toml` over its first 0.5 s — a rod tying itself into an
//! overhand knot under gravity, with self-contact and adaptive resolution (11 to 40
//! control points), implicit Euler at 1 ms.

use crate::{Error, Scene};
use splinerod_core::Real;

/// The bundled scene, embedded.
const KNOT_SCENE: &str = include_str!("../../scenes/knot_tying_adaptive.toml");

/// Simulated time the median is taken over, s.
const DURATION: Real = 0.5;

/// Median wall time of one step of the knot scene over its first `DURATION` s, s.
pub fn knot_step_seconds() -> Result<Real, Error> {
    let mut scene = Scene::from_toml(KNOT_SCENE)?;
    scene.solver.duration = Some(DURATION);
    let result = crate::run(&scene)?;
    Ok(result.median_step_seconds)
}
