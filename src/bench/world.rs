//! The cost of several rods in one system (`bench` key `world_overhead_8`): the median
//! step of 8 independent hanging cables joined in one system (`[[rods]]`), over 8 times
//! the median step of one such cable alone. Each cable: 16 control points, stretching,
//! gravity, both ends pinned, implicit Euler with the default Newton settings.

use crate::bench::median_step_seconds;
use crate::{Error, Scene};
use splinerod_core::Real;

/// One cable's table fields, starting at height `y`.
fn cable(y: Real) -> String {
    format!(
        "rest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 100.0\ndamping = 1.0\n\
         control_points = 16\nstart = [0.0, {y}, 0.0]\nend = [0.8, {y}, 0.0]\n"
    )
}

const SOLVER: &str = "[solver]\nmethod = \"implicit-euler\"\ndt = 0.001\nduration = 1.0\n";

/// The scene of `rods` cables (`[rod]` for one, `[[rods]]` otherwise).
fn scene(rods: usize) -> Result<Scene, Error> {
    let mut text = String::new();
    for k in 0..rods {
        let pins = if rods == 1 {
            text.push_str(&format!("[rod]\n{}", cable(0.0)));
            String::new()
        } else {
            text.push_str(&format!("[[rods]]\nname = \"c{k}\"\n{}", cable(k as Real)));
            format!("rod = \"c{k}\"\n")
        };
        for at in [0.0, 1.0] {
            text.push_str(&format!("[[pins]]\n{pins}at = {at}\n"));
        }
    }
    text.push_str(SOLVER);
    Scene::from_toml(&text)
}

/// Median step of `rods` cables in one system over `rods` times one cable's, with
/// `reps` timed steps each.
pub fn world_overhead(rods: usize, reps: usize) -> Result<Real, Error> {
    let one = median_step_seconds(scene(1)?.build()?, reps)?;
    let many = median_step_seconds(scene(rods)?.build()?, reps)?;
    Ok(many / (rods as Real * one))
}
