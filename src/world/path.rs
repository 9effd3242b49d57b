//! Keyframed paths for driven points (`[[pins]] path`): positions given at times, and
//! a point that is there at those times and moves between them.
//!
//! With keyframes \\((t_k, p_k)\\), `t` strictly increasing, the path is \\(p_0\\)
//! before \\(t_0\\) and \\(p_{last}\\) after the last time; in between
//!
//! * **linear**: \\(p(t) = p_k + \tfrac{t - t_k}{t_{k+1} - t_k} (p_{k+1} - p_k)\\)
//!   (continuous, the velocity jumps at keyframes);
//! * **smooth**: the cubic Hermite curve through the keyframes with Catmull–Rom
//!   velocities \\(v_k = \tfrac{p_{k+1} - p_{k-1}}{t_{k+1} - t_{k-1}}\\) inside and zero
//!   velocity at the first and last keyframe (continuous velocity; a start and a stop
//!   without a jerk of speed).

use crate::Error;
use nalgebra::Vector3;
use splinerod_core::{Keyframes, Real};

/// How a [`Path`] moves between keyframes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Interpolation {
    /// Straight lines at constant speed (the default).
    #[default]
    Linear,
    /// Cubic Hermite with Catmull–Rom velocities, at rest at both ends.
    Smooth,
}

impl From<Interpolation> for splinerod_core::Interpolation {
    fn from(i: Interpolation) -> Self {
        match i {
            Interpolation::Linear => Self::Linear,
            Interpolation::Smooth => Self::Smooth,
        }
    }
}

/// Positions at increasing times (module docs): [`Keyframes`] of points, checked with
/// errors naming the scene field.
#[derive(Debug, Clone, PartialEq)]
pub struct Path(Keyframes<Vector3<Real>>);

impl Path {
    /// A path through `keyframes` `[t, x, y, z]`; `field` names them in errors: they
    /// must be finite, at least one, with strictly increasing times.
    pub fn new(
        keyframes: &[[Real; 4]],
        interpolation: Interpolation,
        field: &str,
    ) -> Result<Self, Error> {
        check_keyframes(keyframes, field)?;
        let frames = keyframes
            .iter()
            .map(|f| (f[0], Vector3::new(f[1], f[2], f[3])));
        Ok(Self(Keyframes::new(frames, interpolation.into())?))
    }

    /// The first keyframe's time and position.
    pub fn start(&self) -> (Real, Vector3<Real>) {
        self.0.start()
    }

    /// The last keyframe's time.
    pub fn end_time(&self) -> Real {
        self.0.end_time()
    }

    /// The position at time `t`.
    pub fn at(&self, t: Real) -> Vector3<Real> {
        self.0.at(t)
    }

    /// The keyframes behind it.
    pub fn keyframes(&self) -> &Keyframes<Vector3<Real>> {
        &self.0
    }
}

/// Checks keyframes `[t, v…]` of a scene field: at least one, finite, strictly
/// increasing times; errors name `field[k]`.
pub fn check_keyframes<const N: usize>(keyframes: &[[Real; N]], field: &str) -> Result<(), Error> {
    if keyframes.is_empty() {
        return Err(Error::field(
            field,
            "[]",
            "needs at least one keyframe [t, …]",
        ));
    }
    for (k, f) in keyframes.iter().enumerate() {
        if !f.iter().all(|x| x.is_finite()) {
            return Err(Error::field(
                format!("{field}[{k}]"),
                format!("{f:?}"),
                "must be finite",
            ));
        }
        if k > 0 && f[0] <= keyframes[k - 1][0] {
            let reason = format!(
                "times must increase (the one before is {})",
                keyframes[k - 1][0]
            );
            return Err(Error::field(
                format!("{field}[{k}]"),
                format!("{f:?}"),
                reason,
            ));
        }
    }
    Ok(())
}

/// The schedule through `keyframes` `[t, value]` (checked: see [`check_keyframes`]).
pub fn schedule(
    keyframes: &[[Real; 2]],
    interpolation: Interpolation,
    field: &str,
) -> Result<Keyframes<Real>, Error> {
    check_keyframes(keyframes, field)?;
    let frames = keyframes.iter().map(|f| (f[0], f[1]));
    Keyframes::new(frames, interpolation.into()).map_err(Error::from)
}
