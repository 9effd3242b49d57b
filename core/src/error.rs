//! Errors of the core crate: everything a user can get wrong about a basis, a knot or a rod.

use crate::Real;

/// What went wrong in `splinerod-core`. Each variant names the offending value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum CoreError {
    /// Saved run state does not fit the object reading it (a checkpoint of another
    /// build or scene); says what did not fit.
    #[error("saved state does not fit: {0}")]
    StateMismatch(&'static str),
    /// The polynomial degree is outside the supported range.
    #[error("degree {degree} is not supported (allowed: 1 to {max})")]
    InvalidDegree {
        /// Requested degree.
        degree: usize,
        /// Largest supported degree.
        max: usize,
    },
    /// Fewer control points than a degree-`degree` spline needs.
    #[error("{count} control points are too few for degree {degree} (need at least {})", degree + 1)]
    TooFewControlPoints {
        /// Requested number of control points.
        count: usize,
        /// Polynomial degree.
        degree: usize,
    },
    /// The knot vector length does not match `count + degree + 1`.
    #[error("knot vector has {found} knots, expected {expected} (control points + degree + 1)")]
    KnotCountMismatch {
        /// Number of knots given.
        found: usize,
        /// Number expected.
        expected: usize,
    },
    /// A knot is NaN or infinite.
    #[error("knot {index} is not finite ({value})")]
    NonFiniteKnot {
        /// Position in the knot vector.
        index: usize,
        /// Its value.
        value: Real,
    },
    /// The knot vector decreases somewhere.
    #[error("knots are not sorted: knot {index} = {value} is below knot {} = {previous}", index - 1)]
    KnotsNotSorted {
        /// Position of the first knot smaller than its predecessor.
        index: usize,
        /// Value of the predecessor.
        previous: Real,
        /// Value of the knot.
        value: Real,
    },
    /// A knot value repeats more often than `degree + 1`.
    #[error("knot {value} has multiplicity {multiplicity}, more than degree + 1 = {max}")]
    MultiplicityTooHigh {
        /// The knot value.
        value: Real,
        /// Its multiplicity (after the operation, for insertions).
        multiplicity: usize,
        /// The largest allowed multiplicity.
        max: usize,
    },
    /// The parameter domain `[t_d, t_n]` has zero or negative length.
    #[error("the parameter domain [{start}, {end}] is empty")]
    EmptyDomain {
        /// Domain start.
        start: Real,
        /// Domain end.
        end: Real,
    },
    /// A parameter lies outside the domain.
    #[error("parameter {s} is outside the domain [{start}, {end}]")]
    OutsideDomain {
        /// The parameter.
        s: Real,
        /// Domain start.
        start: Real,
        /// Domain end.
        end: Real,
    },
    /// A knot operation needs a knot strictly inside the domain.
    #[error("knot {index} (value {value}) is not an interior knot; only knots strictly inside the domain can be removed")]
    NotInteriorKnot {
        /// Position in the knot vector.
        index: usize,
        /// Its value.
        value: Real,
    },
    /// Removing a knot would move the curve more than allowed.
    #[error("removing knot {index} would move the curve by up to {error:e}, above the tolerance {tolerance:e}")]
    RemovalNotWithinTolerance {
        /// Position in the knot vector.
        index: usize,
        /// Bound on the shape change (max control-point deviation in the refined space).
        error: Real,
        /// Tolerance asked for.
        tolerance: Real,
    },
    /// A physical or numerical parameter is out of its range.
    #[error("{name} = {value} is invalid: {reason}")]
    InvalidParameter {
        /// Name of the parameter.
        name: &'static str,
        /// The value given.
        value: Real,
        /// What it must satisfy.
        reason: &'static str,
    },
    /// A list of per-control-point values has the wrong length.
    #[error("{what}: expected {expected} values (one per control point), found {found}")]
    CountMismatch {
        /// Which list.
        what: &'static str,
        /// Expected length.
        expected: usize,
        /// Actual length.
        found: usize,
    },
    /// A state value (position, velocity, ...) is NaN or infinite.
    #[error("{what} {index} is not finite")]
    NonFiniteState {
        /// Which quantity.
        what: &'static str,
        /// Index of the first non-finite entry.
        index: usize,
    },
    /// The basis domain does not match the rod's rest length.
    #[error("the basis domain [{start}, {end}] must be [0, rest_length = {rest_length}]: knots are rest arclength")]
    DomainMismatch {
        /// Domain start.
        start: Real,
        /// Domain end.
        end: Real,
        /// Rest length of the rod.
        rest_length: Real,
    },
}
