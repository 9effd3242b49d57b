//! Errors of the adaptivity crate.

use splinerod_core::{CoreError, Real, Requirement};

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

/// Error unless `value` is finite and positive.
pub(crate) fn positive(name: &'static str, value: Real) -> Result<(), AdaptError> {
    require(name, value, Requirement::Positive)
}

/// Error unless `value` is in `[0, 1]`.
pub(crate) fn in_unit(name: &'static str, value: Real) -> Result<(), AdaptError> {
    require(name, value, Requirement::UnitInterval)
}

fn require(name: &'static str, value: Real, r: Requirement) -> Result<(), AdaptError> {
    r.check(value)
        .map_err(|reason| AdaptError::InvalidParameter {
            name,
            value,
            reason,
        })
}
