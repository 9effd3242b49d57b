//! The `[[pins]]` and `[world]` scene tables (documented in `scenes/README.md`): held
//! and driven material points, and gravity.

use crate::scene::{finite_vec, fraction, Scene};
use crate::world::gripper::PosePath;
use crate::world::path::{Interpolation, Path};
use crate::Error;
use nalgebra::Vector3;
use serde::Deserialize;

/// `[[pins]]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PinSpec {
    /// The rod (its `name` in `[[rods]]`) this acts on; needed when the scene has
    /// several rods.
    pub rod: Option<String>,
    /// Material coordinate, fraction of the rest length in `[0, 1]`.
    pub at: f64,
    /// Held position, m. Default: where the point starts; if given it must agree with the
    /// initial shape (a pin never makes the rod jump).
    pub position: Option<[f64; 3]>,
    /// A translation of the held position, and of the whole `path`, against where the
    /// point starts, m. Never read from a scene file (zero there): set by
    /// [`crate::sensitivity::set_parameter`] for `pins[i].position[c]` (finite
    /// differences, fits). The rod still starts where its shape puts it; the moved
    /// target holds from the first step on (a static solve: at equilibrium), see
    /// `Scene::offset_pins`.
    #[serde(skip)]
    pub offset: [f64; 3],
    /// Also hold the tangent direction there (a clamp; needs `rod.bending_stiffness`).
    #[serde(default)]
    pub clamp: bool,
    /// Keyframes `[t, x, y, z]` (s, m) the pin follows: the first at time 0 where the
    /// point starts, times increasing ([`crate::world::path`]).
    pub path: Option<Vec<[f64; 4]>>,
    /// How the path and the turn move between keyframes. Default linear.
    #[serde(default)]
    pub interpolation: Interpolation,
    /// Axis `[ax, ay, az]` the pinned point slides along (held only across it; no
    /// friction). Default: held in every direction.
    pub slides_along: Option<[f64; 3]>,
    /// Keyframes `[t, angle]` (s, rad) of the clamp's turn about its axis (a clamp at an
    /// end of a rod with `twist_stiffness`). Default: held still.
    pub turn: Option<Vec<[f64; 2]>>,
    /// The tangent `[x, y, z]` a clamp holds (normalised; along increasing `s` at either
    /// end). Default: the rod's tangent as it starts; a rod starting otherwise is bent
    /// into it from the first step (a static solve: in its equilibrium).
    pub direction: Option<[f64; 3]>,
    /// Keyframes `[t, x, y, z, rx, ry, rz]` (s, m, rad) of a clamp's gripper: the
    /// translation of the clamp point and the rotation vector of the gripper (about the
    /// clamp point) against its start, interpolated like `path`
    /// ([`crate::world::gripper`]). The first is `[0, 0, 0, 0, 0, 0, 0]`.
    pub pose: Option<Vec<[f64; 7]>>,
    /// The `[[bodies]]` entry holding this point where it starts (a ball joint; with
    /// `clamp = true` at an end, a weld). Default: none (held in space).
    pub body: Option<String>,
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
            if let Some(axis) = pin.slides_along {
                let field = format!("pins[{i}].slides_along");
                finite_vec(&field, axis)?;
                if axis.iter().all(|a| *a == 0.0) {
                    return Err(Error::field(field, format!("{axis:?}"), "must not be zero"));
                }
            }
            if pin.clamp && self.rod.bending_stiffness.is_none() {
                let reason = "a clamp holds the tangent against bending: set rod.bending_stiffness";
                return Err(Error::field(format!("pins[{i}].clamp"), true, reason));
            }
            if let Some(keyframes) = &pin.turn {
                let field = format!("pins[{i}].turn");
                crate::world::path::schedule(keyframes, pin.interpolation, &field)?;
                let end = pin.at == 0.0 || pin.at == 1.0;
                if !(pin.clamp && end && self.rod.twist_stiffness.is_some()) {
                    let reason = "only a clamp (clamp = true) at an end (at = 0 or 1) of a rod \
                                  with rod.twist_stiffness can turn";
                    return Err(Error::field(field, format!("{keyframes:?}"), reason));
                }
            }
            self.validate_clamp_pose(i, pin)?;
            if let Some(keyframes) = &pin.path {
                let field = format!("pins[{i}].path");
                let path = Path::new(keyframes, pin.interpolation, &field)?;
                if path.start().0 != 0.0 {
                    let reason = "the first keyframe must be at time 0 (where the point starts)";
                    return Err(Error::field(format!("{field}[0]"), path.start().0, reason));
                }
            }
        }
        self.validate_twist()
    }

    /// `direction` and `pose` of pin `i`: on a clamp only; a finite, non-zero direction;
    /// a pose at an end, with finite keyframes in time order starting at rest
    /// ([`PosePath::new`]), not with `path` or `turn` (a gripper's translation and roll
    /// say what they would).
    fn validate_clamp_pose(&self, i: usize, pin: &PinSpec) -> Result<(), Error> {
        let only_clamps = "only a clamp (clamp = true) holds a direction and a pose";
        if let Some(direction) = pin.direction {
            let field = format!("pins[{i}].direction");
            if !pin.clamp {
                return Err(Error::field(field, format!("{direction:?}"), only_clamps));
            }
            finite_vec(&field, direction)?;
            let length = Vector3::from(direction).norm_squared();
            if !(length.is_finite() && length > 0.0) {
                let reason = "must not be zero (the tangent the clamp holds) and its length finite";
                return Err(Error::field(field, format!("{direction:?}"), reason));
            }
        }
        let Some(keyframes) = &pin.pose else {
            return Ok(());
        };
        let field = format!("pins[{i}].pose");
        let value = || format!("{keyframes:?}");
        if !pin.clamp {
            return Err(Error::field(field, value(), only_clamps));
        }
        if !(pin.at == 0.0 || pin.at == 1.0) {
            let reason = "a gripper holds a clamp at an end of a rod (at = 0 or 1)";
            return Err(Error::field(field, value(), reason));
        }
        for (other, given) in [("path", pin.path.is_some()), ("turn", pin.turn.is_some())] {
            if given {
                let reason = format!(
                    "given with pins[{i}].{other}: a pose moves and rolls the clamp itself (its translation and the rotation vector's part along the tangent)"
                );
                return Err(Error::field(field, value(), reason));
            }
        }
        PosePath::new(keyframes, pin.interpolation, &field).map(|_| ())
    }

    /// `rod.twist_stiffness` needs bending and, on an open rod, clamps at both ends;
    /// `rod.twist` a closed rod.
    fn validate_twist(&self) -> Result<(), Error> {
        if let (Some(twist), false) = (self.rod.twist, self.closed()) {
            let reason = "only a closed rod starts twisted; an open one is twisted by turning its clamps (pins[].turn)";
            return Err(Error::field("rod.twist", twist, reason));
        }
        let Some(gj) = self.rod.twist_stiffness else {
            if let Some(twist) = self.rod.twist {
                return Err(Error::field(
                    "rod.twist",
                    twist,
                    "needs rod.twist_stiffness",
                ));
            }
            return Ok(());
        };
        crate::scene::positive("rod.twist_stiffness", gj)?;
        if let Some(twist) = self.rod.twist {
            if !twist.is_finite() {
                return Err(Error::field("rod.twist", twist, "must be finite"));
            }
        }
        if self.closed() {
            return match self.rod.bending_stiffness {
                Some(_) => Ok(()),
                None => Err(Error::field(
                    "rod.twist_stiffness",
                    gj,
                    "a twisted loop needs rod.bending_stiffness",
                )),
            };
        }
        if self.twist_clamps().iter().any(Option::is_none) {
            let reason = "twist needs clamps at both ends ([[pins]] at = 0 and at = 1 with \
                          clamp = true): a rod with a free end carries no twist";
            return Err(Error::field("rod.twist_stiffness", gj, reason));
        }
        Ok(())
    }

    /// Indices of the clamped pins at the start and the end of the rod.
    pub(crate) fn twist_clamps(&self) -> [Option<usize>; 2] {
        let clamp_at = |at: f64| self.pins.iter().position(|p| p.clamp && p.at == at);
        [clamp_at(0.0), clamp_at(1.0)]
    }
}
