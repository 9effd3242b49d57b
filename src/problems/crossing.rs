//! Two pinned ropes crossing at right angles, both with bending, the upper resting on
//! the lower (`scenes/ropes_crossing_pinned.toml`, a static solve). The quantity is the
//! **lift**: the share of the upper rope's weight the lower rope carries, read from the
//! forces of the upper rope's pins. It depends on both ropes' stiffness and sag, and
//! its error on how well the contact region is resolved; a uniform run with 256 control
//! points per rope is the reference (tests/tolerance.rs, the report's crossing).

use crate::{bundled, Error, Real, RunResult, Scene};

/// The bundled scene's name.
pub const SCENE: &str = "ropes_crossing_pinned";

/// Control points per rope of the reference run.
pub const REFERENCE_POINTS: usize = 256;

/// Bending stiffnesses (N m²) and radii (m) of the two ropes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Variant {
    /// Bending stiffness of the lower rope.
    pub ei_lower: Real,
    /// Bending stiffness of the upper rope.
    pub ei_upper: Real,
    /// Radius of the lower rope.
    pub r_lower: Real,
    /// Radius of the upper rope.
    pub r_upper: Real,
}

/// How the ropes are resolved.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Resolution {
    /// `n` uniform control points per rope, no adaptivity.
    Uniform(usize),
    /// From `start` control points per rope, adaptive with the scene's `[adaptivity]`
    /// table, its tolerance (m) replaced when given.
    Adaptive {
        /// Control points per rope at the start.
        start: usize,
        /// Tolerance, m; `None`: the scene's.
        tolerance: Option<Real>,
    },
}

/// The crossing at `resolution`, with the ropes of `variant` (`None`: the bundled ones).
pub fn scene(resolution: Resolution, variant: Option<Variant>) -> Result<Scene, Error> {
    let mut scene = bundled::scene(SCENE)?;
    let n = match resolution {
        Resolution::Uniform(n) => {
            scene.adaptivity = None;
            n
        }
        Resolution::Adaptive { start, tolerance } => {
            let table = scene.adaptivity.as_mut().ok_or_else(|| {
                Error::study("crossing", "the bundled scene lost its [adaptivity] table")
            })?;
            table.tolerance = tolerance.or(table.tolerance);
            start
        }
    };
    for rod in &mut scene.rods {
        rod.control_points = n;
    }
    if let Some(v) = variant {
        for (rod, ei, r) in [(0, v.ei_lower, v.r_lower), (1, v.ei_upper, v.r_upper)] {
            scene.rods[rod].bending_stiffness = Some(ei);
            scene.rods[rod].radius = Some(r);
        }
    }
    Ok(scene)
}

/// The lift of a run of a crossing [`scene`]: the share of the upper rope's weight
/// (`linear_density · rest_length · |g|`) that its pins (those of the rod named
/// `upper`) do not carry.
pub fn lift(scene: &Scene, run: &RunResult) -> Result<Real, Error> {
    let missing = || Error::study("crossing", "no rod named \"upper\"");
    let upper = scene
        .rods
        .iter()
        .find(|r| r.name.as_deref() == Some("upper"))
        .ok_or_else(missing)?;
    let g = scene.world.gravity;
    let g_norm = g.iter().map(|x| x * x).sum::<Real>().sqrt();
    let weight = upper.linear_density * upper.rest_length * g_norm;
    // What the upper rod hangs on its pins, along gravity (`pin_forces`: the rod's
    // forces on them).
    let held: Real = scene
        .pins
        .iter()
        .zip(&run.pin_forces)
        .filter(|(p, _)| p.rod.as_deref() == Some("upper"))
        .map(|(_, f)| (0..3).map(|k| f[k] * g[k]).sum::<Real>() / g_norm)
        .sum();
    Ok((weight - held) / weight)
}

/// Runs the crossing at `resolution` with `variant`: its lift and the run.
pub fn run(resolution: Resolution, variant: Option<Variant>) -> Result<(Real, RunResult), Error> {
    let scene = scene(resolution, variant)?;
    let run = crate::run(&scene)?;
    Ok((lift(&scene, &run)?, run))
}
