//! The `[[loads]]` scene tables (documented in `scenes/README.md`): a force at a
//! material point, constant (`force`) or keyframed (`path` of `[t, Fx, Fy, Fz]`).

use crate::scene::{finite_vec, fraction, Scene};
use crate::world::path::{Interpolation, Path};
use crate::{Error, Load};
use nalgebra::Vector3;
use serde::Deserialize;
use splinerod_energies::PointForce;

/// One `[[loads]]` entry.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// The rod (its `name` in `[[rods]]`) this acts on; needed when the scene has
    /// several rods.
    pub rod: Option<String>,
    /// Material coordinate, fraction of the rest length in `[0, 1]` (required unless
    /// `body` is given).
    pub at: Option<f64>,
    /// A `[[bodies]]` entry the force acts on, at its centre of mass (instead of `at`).
    pub body: Option<String>,
    /// A constant force, N.
    pub force: Option<[f64; 3]>,
    /// Keyframes `[t, Fx, Fy, Fz]` (s, N) of a force changing in time.
    pub path: Option<Vec<[f64; 4]>>,
    /// How the force changes between keyframes. Default linear.
    #[serde(default)]
    pub interpolation: Interpolation,
}

impl Scene {
    /// The loads of `[[loads]]`, validated (errors name `loads[i].<field>`).
    pub fn loads(&self) -> Result<Vec<Load>, Error> {
        let l = self.rod.rest_length;
        let mut loads = Vec::with_capacity(self.loads.len());
        for (i, spec) in self.loads.iter().enumerate() {
            let (force, path) = spec.force_and_path(i)?;
            if spec.body.is_some() {
                continue;
            }
            let field = format!("loads[{i}].at");
            let at = spec.at.ok_or_else(|| {
                let reason = "required: the loaded material point (or `body`)";
                Error::field(&field, "missing", reason)
            })?;
            fraction(&field, at)?;
            let force = PointForce::new(at * l, force)?;
            loads.push(Load { force, path });
        }
        Ok(loads)
    }
}

impl LoadSpec {
    /// The force at t = 0 and the keyframed path, if any (errors name `loads[i]`).
    pub(crate) fn force_and_path(&self, i: usize) -> Result<(Vector3<f64>, Option<Path>), Error> {
        let spec = self;
        {
            let (force, path) = match (&spec.force, &spec.path) {
                (Some(f), None) => {
                    finite_vec(&format!("loads[{i}].force"), *f)?;
                    (Vector3::from(*f), None)
                }
                (None, Some(keyframes)) => {
                    let field = format!("loads[{i}].path");
                    let path = Path::new(keyframes, spec.interpolation, &field)?;
                    (path.at(0.0), Some(path))
                }
                _ => {
                    let reason = "give exactly one of force (constant) and path (keyframed)";
                    return Err(Error::field(format!("loads[{i}].force"), "?", reason));
                }
            };
            Ok((force, path))
        }
    }
}
