//! The `[[obstacles]]` scene tables (documented in `scenes/README.md`): rigid planes,
//! spheres and capsules, static or translated along a keyframed `path`, the rod stays out of, with `[contact]`'s penalty
//! stiffness and friction ([`Obstacle`]).

use crate::scene::{finite_vec, non_negative, positive, Scene};
use crate::world::path::Interpolation;
use crate::Error;
use nalgebra::Vector3;
use serde::Deserialize;
use splinerod_energies::Obstacle;

/// One `[[obstacles]]` entry, by `kind`.
#[derive(Debug, Clone, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase", deny_unknown_fields)]
pub enum ObstacleSpec {
    /// The half-space on the `normal` side of the plane through `point`.
    Plane {
        /// A point of the plane, m.
        point: [f64; 3],
        /// Normal towards the rod's side (normalised; not zero).
        normal: [f64; 3],
        /// Keyframed translation `[t, dx, dy, dz]` (s, m). Default: static.
        path: Option<Vec<[f64; 4]>>,
        /// How the path moves between keyframes.
        #[serde(default)]
        interpolation: Interpolation,
        /// Friction coefficient of its surface (≥ 0). Default `[contact] friction`.
        friction: Option<f64>,
    },
    /// A ball.
    Sphere {
        /// Centre, m.
        centre: [f64; 3],
        /// Radius, m (> 0).
        radius: f64,
        /// Keyframed translation `[t, dx, dy, dz]` (s, m). Default: static.
        path: Option<Vec<[f64; 4]>>,
        /// How the path moves between keyframes.
        #[serde(default)]
        interpolation: Interpolation,
        /// Friction coefficient of its surface (≥ 0). Default `[contact] friction`.
        friction: Option<f64>,
    },
    /// A cylinder of `radius` around the segment `a`–`b`, with rounded ends.
    Capsule {
        /// One end of the axis, m.
        a: [f64; 3],
        /// The other end, m.
        b: [f64; 3],
        /// Radius, m (> 0).
        radius: f64,
        /// Keyframed translation `[t, dx, dy, dz]` (s, m). Default: static.
        path: Option<Vec<[f64; 4]>>,
        /// How the path moves between keyframes.
        #[serde(default)]
        interpolation: Interpolation,
        /// Friction coefficient of its surface (≥ 0). Default `[contact] friction`.
        friction: Option<f64>,
    },
}

impl ObstacleSpec {
    /// Range checks; errors name `obstacles[i].<field>`.
    fn validate(&self, i: usize) -> Result<(), Error> {
        let field = |name: &str| format!("obstacles[{i}].{name}");
        if let Some(mu) = self.friction() {
            non_negative(&field("friction"), mu)?;
        }
        match self {
            ObstacleSpec::Plane { point, normal, .. } => {
                finite_vec(&field("point"), *point)?;
                finite_vec(&field("normal"), *normal)?;
                if Vector3::from(*normal).norm() == 0.0 {
                    let reason = "must not be zero";
                    return Err(Error::field(field("normal"), format!("{normal:?}"), reason));
                }
            }
            ObstacleSpec::Sphere { centre, radius, .. } => {
                finite_vec(&field("centre"), *centre)?;
                positive(&field("radius"), *radius)?;
            }
            ObstacleSpec::Capsule { a, b, radius, .. } => {
                finite_vec(&field("a"), *a)?;
                finite_vec(&field("b"), *b)?;
                if a == b {
                    let reason = "the axis ends a and b must differ";
                    return Err(Error::field(field("b"), format!("{b:?}"), reason));
                }
                positive(&field("radius"), *radius)?;
            }
        }
        if let (Some(keyframes), interpolation) = self.motion() {
            crate::world::path::Path::new(keyframes, interpolation, &field("path"))?;
        }
        Ok(())
    }

    /// The keyframed translation, if any, and its interpolation.
    pub fn motion(&self) -> (Option<&Vec<[f64; 4]>>, Interpolation) {
        match self {
            ObstacleSpec::Plane {
                path,
                interpolation,
                ..
            }
            | ObstacleSpec::Sphere {
                path,
                interpolation,
                ..
            }
            | ObstacleSpec::Capsule {
                path,
                interpolation,
                ..
            } => (path.as_ref(), *interpolation),
        }
    }

    /// Its friction coefficient, if it has its own.
    pub fn friction(&self) -> Option<f64> {
        match self {
            ObstacleSpec::Plane { friction, .. }
            | ObstacleSpec::Sphere { friction, .. }
            | ObstacleSpec::Capsule { friction, .. } => *friction,
        }
    }

    /// The obstacle.
    pub fn obstacle(&self) -> Obstacle {
        match *self {
            ObstacleSpec::Plane { point, normal, .. } => Obstacle::Plane {
                point: point.into(),
                normal: Vector3::from(normal).normalize(),
            },
            ObstacleSpec::Sphere { centre, radius, .. } => Obstacle::Sphere {
                centre: centre.into(),
                radius,
            },
            ObstacleSpec::Capsule { a, b, radius, .. } => Obstacle::Capsule {
                a: a.into(),
                b: b.into(),
                radius,
            },
        }
    }
}

impl Scene {
    /// Checks every `[[obstacles]]` entry, and that `[contact]` gives them a stiffness.
    pub(crate) fn validate_obstacles(&self) -> Result<(), Error> {
        let contact = self.contact.as_ref().is_some_and(|c| c.enabled);
        if !self.obstacles.is_empty() && !contact {
            let reason =
                "obstacles need an enabled [contact] table (penalty stiffness) and rod.radius";
            return Err(Error::field("obstacles[0].kind", "present", reason));
        }
        for (i, o) in self.obstacles.iter().enumerate() {
            o.validate(i)?;
        }
        Ok(())
    }
}
