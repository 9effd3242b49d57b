//! The facade's error: every lower crate's error, plus scene and I/O errors.

use splinerod_adaptivity::AdaptError;
use splinerod_core::CoreError;
use splinerod_integrators::IntegratorError;

/// Anything that can go wrong in splinerod.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A scene value is missing, unknown, malformed or out of range.
    #[error("scene: {0}")]
    Scene(String),
    /// A scene field is out of range; names the field and the value.
    #[error("scene field `{field}` = {value}: {reason}")]
    InvalidField {
        /// Dotted path of the field, e.g. `rod.linear_density` or `pins[1].at`.
        field: String,
        /// The value given, as written.
        value: String,
        /// What it must satisfy.
        reason: String,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// From the core (basis, knots, rod).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// From an integrator or solver.
    #[error(transparent)]
    Integrator(#[from] IntegratorError),
    /// From the adaptivity crate.
    #[error(transparent)]
    Adapt(#[from] AdaptError),
}

impl Error {
    /// An [`Error::InvalidField`].
    pub fn field(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        Self::InvalidField {
            field: field.into(),
            value: value.to_string(),
            reason: reason.into(),
        }
    }
}
