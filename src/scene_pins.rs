//! The `[[pins]]` and `[world]` scene tables (documented in `scenes/README.md`): held
//! and driven material points, and gravity.

use crate::path::{Interpolation, Path};
use crate::scene::{finite_vec, fraction, Scene};
use crate::Error;
use serde::Deserialize;

/// `[[pins]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PinSpec {
    /// Material coordinate, fraction of the rest length in `[0, 1]`.
    pub at: f64,
    /// Held position, m. Default: where the point starts; if given it must agree with the
    /// initial shape (a pin never makes the rod jump).
    pub position: Option<[f64; 3]>,
    /// Also hold the tangent direction there (a clamp; needs `rod.bending_stiffness`).
    #[serde(default)]
    pub clamp: bool,
    /// Keyframes `[t, x, y, z]` (s, m) the pin follows: the first at time 0 where the
    /// point starts, times increasing ([`crate::path`]).
    pub path: Option<Vec<[f64; 4]>>,
    /// How the path moves between keyframes. Default linear.
    #[serde(default)]
    pub interpolation: Interpolation,
}

/// `[world]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldSpec {
    /// Gravity, m/s². Default `[0, -9.81, 0]`.
    #[serde(default = "default_gravity")]
    pub gravity: [f64; 3],
}

fn default_gravity() -> [f64; 3] {
    [0.0, -9.81, 0.0]
}

impl Default for WorldSpec {
    fn default() -> Self {
        Self {
            gravity: default_gravity(),
        }
    }
}

impl Scene {
    /// Range checks of `[[pins]]` (the agreement of positions and paths with the initial
    /// shape is checked when the rod is built); errors name `pins[i].<field>`.
    pub(crate) fn validate_pins(&self) -> Result<(), Error> {
        for (i, pin) in self.pins.iter().enumerate() {
            fraction(&format!("pins[{i}].at"), pin.at)?;
            if let Some(p) = pin.position {
                finite_vec(&format!("pins[{i}].position"), p)?;
            }
            if pin.clamp && self.rod.bending_stiffness.is_none() {
                let reason = "a clamp holds the tangent against bending: set rod.bending_stiffness";
                return Err(Error::field(format!("pins[{i}].clamp"), true, reason));
            }
            if let Some(keyframes) = &pin.path {
                let field = format!("pins[{i}].path");
                let path = Path::new(keyframes, pin.interpolation, &field)?;
                if path.start().0 != 0.0 {
                    let reason = "the first keyframe must be at time 0 (where the point starts)";
                    return Err(Error::field(format!("{field}[0]"), path.start().0, reason));
                }
            }
        }
        Ok(())
    }
}
