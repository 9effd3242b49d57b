//! Validation of real parameters, shared by every crate: one [`Requirement`] per kind
//! of check, with the reason its error gives. Each crate wraps [`Requirement::check`]
//! into its own error (naming the parameter or the scene field and the value), so the
//! same check reads the same everywhere.

use crate::{CoreError, Real};

/// What a real value must satisfy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Requirement {
    /// Finite and > 0.
    Positive,
    /// Finite and ≥ 0.
    NonNegative,
    /// In `[0, 1]`.
    UnitInterval,
    /// In `[0, 1]`, as a fraction of a rod's rest length.
    Fraction,
    /// Finite.
    Finite,
}

impl Requirement {
    /// Whether `value` satisfies it (NaN never does).
    pub fn holds(self, value: Real) -> bool {
        match self {
            Self::Positive => value.is_finite() && value > 0.0,
            Self::NonNegative => value.is_finite() && value >= 0.0,
            Self::UnitInterval | Self::Fraction => (0.0..=1.0).contains(&value),
            Self::Finite => value.is_finite(),
        }
    }

    /// The reason an error gives when it does not hold.
    pub fn reason(self) -> &'static str {
        match self {
            Self::Positive => "must be finite and positive",
            Self::NonNegative => "must be finite and non-negative",
            Self::UnitInterval => "must be in [0, 1]",
            Self::Fraction => "must be a fraction of the rest length in [0, 1]",
            Self::Finite => "must be finite",
        }
    }

    /// `Ok` if `value` satisfies it, the reason otherwise.
    pub fn check(self, value: Real) -> Result<(), &'static str> {
        if self.holds(value) {
            Ok(())
        } else {
            Err(self.reason())
        }
    }

    /// `Ok` if `value` satisfies it, [`CoreError::InvalidParameter`] naming `name`
    /// otherwise.
    pub fn require(self, name: &'static str, value: Real) -> Result<(), CoreError> {
        self.check(value)
            .map_err(|reason| CoreError::InvalidParameter {
                name,
                value,
                reason,
            })
    }
}

/// Error unless `value` is finite and positive.
pub fn positive(name: &'static str, value: Real) -> Result<(), CoreError> {
    Requirement::Positive.require(name, value)
}

/// Error unless `value` is finite and non-negative.
pub fn non_negative(name: &'static str, value: Real) -> Result<(), CoreError> {
    Requirement::NonNegative.require(name, value)
}

/// `v` normalised, or an error naming `name` if it is zero or not finite.
pub fn unit(
    name: &'static str,
    v: nalgebra::Vector3<Real>,
) -> Result<nalgebra::Vector3<Real>, CoreError> {
    let norm = v.norm();
    if norm.is_finite() && norm > 0.0 {
        Ok(v / norm)
    } else {
        Err(CoreError::InvalidParameter {
            name,
            value: norm,
            reason: "must be a finite, non-zero vector",
        })
    }
}
