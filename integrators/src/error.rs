//! Errors of the integrators crate.

use splinerod_core::{CoreError, Real, Requirement};

/// What can go wrong while stepping or solving. The system state is left as it was.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum IntegratorError {
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
    /// The Newton matrix is not positive definite (a non-positive pivot in Cholesky).
    #[error("the Newton matrix is not positive definite ({context})")]
    NotPositiveDefinite {
        /// Where it happened.
        context: &'static str,
    },
    /// The pins constrain the same degrees of freedom twice (e.g. two pins at one point).
    #[error("pins are redundant or conflicting: their constraint rows are linearly dependent")]
    RedundantPins,
    /// A value became NaN or infinite; the step was rolled back.
    #[error("the step produced non-finite {what}; state rolled back")]
    NonFinite {
        /// Which quantity.
        what: &'static str,
    },
    /// A Newton step was absurdly large: the iteration is diverging.
    #[error("a Newton step moved a point by {step:e} m (limit {limit:e} m): the solve is diverging; state rolled back")]
    Diverged {
        /// Largest point displacement of the step, m.
        step: Real,
        /// The limit, m.
        limit: Real,
    },
    /// Newton did not reach the tolerance.
    #[error("Newton did not converge in {iterations} iterations (residual {residual:e}); state rolled back")]
    NotConverged {
        /// Iterations done.
        iterations: usize,
        /// Final residual norm.
        residual: Real,
    },
    /// Multiplier updates of a constrained equilibrium (the inextensible rod) did not
    /// bring the constraint violation below the tolerance.
    #[error("a constraint violation (mean strain) of {violation:.3e} remains after {updates} multiplier updates (tolerance {tolerance:e})")]
    ConstraintNotMet {
        /// Violation after the last update.
        violation: Real,
        /// Updates made.
        updates: usize,
        /// Violation allowed.
        tolerance: Real,
    },
    /// A solve was asked of the linear solver before a successful factorisation, or with
    /// a right-hand side of the wrong length.
    #[error("linear solver misuse: {0}")]
    SolverState(&'static str),
    /// A dense analysis was asked of a system too large for it.
    #[error("{what} needs a dense matrix: {dofs} degrees of freedom exceed the limit {limit}")]
    TooLarge {
        /// Which analysis.
        what: &'static str,
        /// Degrees of freedom.
        dofs: usize,
        /// Limit.
        limit: usize,
    },
    /// The solve was abandoned because a stop was asked from outside
    /// ([`crate::System::interrupted`]: a signal, a stop request); the state is rolled
    /// back as for any error. Not recoverable: nothing is retried.
    #[error("interrupted: the solve was abandoned on request (a signal or a stop request); state rolled back")]
    Interrupted,
    /// An error from the core (a pin outside the rod, ...).
    #[error(transparent)]
    Core(#[from] CoreError),
}

impl IntegratorError {
    /// Whether the failure belongs to the solve, not to the input: Newton stopped at its
    /// limit or diverged, a value became non-finite, or the Newton matrix was indefinite.
    /// A shorter time step (or, for a static solve, continuation) may cure it.
    pub fn is_recoverable(&self) -> bool {
        matches!(
            self,
            Self::NotConverged { .. }
                | Self::Diverged { .. }
                | Self::NonFinite { .. }
                | Self::NotPositiveDefinite { .. }
        )
    }
}

/// Error unless `value` is finite and positive.
pub(crate) fn positive(name: &'static str, value: Real) -> Result<(), IntegratorError> {
    Requirement::Positive
        .check(value)
        .map_err(|reason| IntegratorError::InvalidParameter {
            name,
            value,
            reason,
        })
}
