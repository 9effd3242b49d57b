//! Errors of the adaptivity crate.

use splinerod_core::{CoreError, Real};

/// What can go wrong configuring or running adaptivity.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum AdaptError {
    /// A parameter is out of range.
    #[error("{name} = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// Value given.
        value: Real,
        /// What it must satisfy.
        reason: &'static str,
    },
    /// A knot operation failed.
    #[error(transparent)]
    Core(#[from] CoreError),
}

pub(crate) fn positive(name: &'static str, value: Real) -> Result<(), AdaptError> {
    if value.is_finite() && value > 0.0 {
        return Ok(());
    }
    let reason = "must be finite and positive";
    Err(AdaptError::InvalidParameter {
        name,
        value,
        reason,
    })
}

pub(crate) fn in_unit(name: &'static str, value: Real) -> Result<(), AdaptError> {
    if (0.0..=1.0).contains(&value) {
        return Ok(());
    }
    let reason = "must be in [0, 1]";
    Err(AdaptError::InvalidParameter {
        name,
        value,
        reason,
    })
}
