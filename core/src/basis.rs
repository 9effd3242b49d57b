//! The [`BasisSpace`] trait: a space of piecewise-polynomial basis functions on a knot
//! vector, evaluated into caller buffers and refined or coarsened by exact knot maps.
//!
//! A curve in the space is \\(C(s) = \sum_i q_i\, b_i(s)\\) (paper eq. 1). Only `d + 1`
//! functions are non-zero at any parameter, so evaluation returns the index of the first
//! one and their values and first two derivatives in a fixed-size [`BasisValues`].

use crate::{CoreError, KnotMap, Real};
use std::fmt;

/// Largest polynomial degree a basis space supports. Fixed so that evaluation needs no
/// heap allocation; degree 9 is far beyond what rods need (cubic is the default).
pub const MAX_DEGREE: usize = 9;

/// Largest number of basis functions non-zero at one parameter (`MAX_DEGREE + 1`).
pub const MAX_ORDER: usize = MAX_DEGREE + 1;

/// Most basis functions (control points) a space may have, 2^24: checked before its
/// knots are allocated, so that an absurd count is an error, not an allocation failure.
/// A rod this fine needs gigabytes; the scene limits stop far below it.
pub const MAX_BASIS_FUNCTIONS: usize = 1 << 24;

/// Error unless `count` basis functions are at most [`MAX_BASIS_FUNCTIONS`].
pub(crate) fn check_count(count: usize) -> Result<(), CoreError> {
    if count > MAX_BASIS_FUNCTIONS {
        return Err(CoreError::InvalidParameter {
            name: "control_points",
            value: count as Real,
            reason: "more than the 16777216 (2^24) basis functions a space may have",
        });
    }
    Ok(())
}

/// Values and derivatives of the basis functions that are non-zero at one parameter.
///
/// Function `first + k` has value `value[k]`, first derivative `d1[k]` and second
/// derivative `d2[k]`, for `k < order`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BasisValues {
    /// Index of the first non-zero basis function.
    pub first: usize,
    /// Number of non-zero functions (`degree + 1`).
    pub order: usize,
    /// Values \\(b_{first+k}(s)\\).
    pub value: [Real; MAX_ORDER],
    /// First derivatives \\(b'_{first+k}(s)\\).
    pub d1: [Real; MAX_ORDER],
    /// Second derivatives \\(b''_{first+k}(s)\\).
    pub d2: [Real; MAX_ORDER],
}

impl Default for BasisValues {
    fn default() -> Self {
        Self {
            first: 0,
            order: 0,
            value: [0.0; MAX_ORDER],
            d1: [0.0; MAX_ORDER],
            d2: [0.0; MAX_ORDER],
        }
    }
}

impl BasisValues {
    /// Combines per-control-point coefficients with the values: \\(\sum_k b_{first+k}\, c_{first+k}\\).
    #[inline]
    pub fn combine<T>(&self, weights: &[Real; MAX_ORDER], coefficients: &[T]) -> T
    where
        T: Copy + std::ops::Add<Output = T> + std::ops::Mul<Real, Output = T> + Default,
    {
        let mut sum = T::default();
        for (k, w) in weights.iter().enumerate().take(self.order) {
            sum = sum + coefficients[self.first + k] * *w;
        }
        sum
    }
}

/// A space of piecewise-polynomial basis functions on a knot vector.
///
/// Required: [`degree`](BasisSpace::degree), [`count`](BasisSpace::count),
/// [`knots`](BasisSpace::knots), [`evaluate`](BasisSpace::evaluate),
/// [`insert_knot`](BasisSpace::insert_knot), [`removal`](BasisSpace::removal),
/// [`remove_knot`](BasisSpace::remove_knot) and [`clone_box`](BasisSpace::clone_box);
/// the rest have defaults (a periodic or refinable space overrides
/// [`periodic_count`](BasisSpace::periodic_count) and
/// [`refined`](BasisSpace::refined)). Implementations must be
/// exact under [`insert_knot`](BasisSpace::insert_knot): the returned [`KnotMap`]
/// expresses every old basis function in the new ones (paper eq. 3), so any curve keeps
/// its shape when its coefficients go through the map.
pub trait BasisSpace: Send + Sync + fmt::Debug {
    /// Polynomial degree `d`.
    fn degree(&self) -> usize;
    /// Number of basis functions (control points).
    fn count(&self) -> usize;
    /// The knot vector, `count + degree + 1` non-decreasing values.
    fn knots(&self) -> &[Real];
    /// Parameter domain `[t_d, t_count]`, where the functions sum to one.
    fn domain(&self) -> (Real, Real) {
        let (t, d) = (self.knots(), self.degree());
        (t[d], t[self.count()])
    }
    /// For a periodic space (closed curves), the number `m` of distinct coefficients:
    /// coefficient `i + m` is a copy of coefficient `i` for every `i < count − m`, and
    /// whoever changes coefficients must keep the copies equal. `None` (the default) for
    /// an ordinary space.
    fn periodic_count(&self) -> Option<usize> {
        None
    }
    /// Writes the non-zero functions at `s` and their first two derivatives into `out`.
    /// Fails if `s` is outside the domain or not finite.
    fn evaluate(&self, s: Real, out: &mut BasisValues) -> Result<(), CoreError>;
    /// Writes the non-zero functions at `s` into `out` (`first`, `order`, `value`; the
    /// derivatives are unspecified), with the same values as
    /// [`evaluate`](BasisSpace::evaluate) bit for bit: for positions alone, where the
    /// derivatives would cost most of an evaluation. The default evaluates them too.
    fn evaluate_values(&self, s: Real, out: &mut BasisValues) -> Result<(), CoreError> {
        self.evaluate(s, out)
    }
    /// Inserts the knot value `s` (strictly inside the domain) and returns the exact
    /// old→new coefficient map.
    fn insert_knot(&mut self, s: Real) -> Result<KnotMap, CoreError>;
    /// The map that removing knot `index` would apply (least-squares inverse of its
    /// insertion), without changing the space. Use [`KnotMap::shape_error`] on it to
    /// decide whether the removal is acceptable.
    fn removal(&self, index: usize) -> Result<KnotMap, CoreError>;
    /// Removes knot `index` (one instance of its value) and returns the map.
    fn remove_knot(&mut self, index: usize) -> Result<KnotMap, CoreError>;
    /// A boxed copy, so rods holding `Box<dyn BasisSpace>` can be cloned.
    fn clone_box(&self) -> Box<dyn BasisSpace>;
    /// This space with every value of `values` (non-decreasing, strictly inside the
    /// domain) inserted at once, and the exact old→new coefficient map in `op` — O(n),
    /// where one insertion at a time is O(n²). Error estimators build finer scratch
    /// copies with it. The default reports that the space does not support it.
    fn refined(
        &self,
        values: &[Real],
        op: &mut crate::refine::RefinementOperator,
    ) -> Result<Box<dyn BasisSpace>, CoreError> {
        let _ = op;
        Err(CoreError::InvalidParameter {
            name: "refinement",
            value: values.len() as Real,
            reason: "this basis space does not support inserting many knots at once",
        })
    }
}

impl Clone for Box<dyn BasisSpace> {
    fn clone(&self) -> Self {
        self.clone_box()
    }
}

/// A non-empty knot span `[start, end)` and the index of the first basis function that
/// is non-zero on it (the others follow consecutively, `degree + 1` in all).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Span {
    /// Span start.
    pub start: Real,
    /// Span end (`> start`).
    pub end: Real,
    /// Index of the first non-zero basis function on the span.
    pub first: usize,
}

/// The non-empty spans of `space` inside its domain, in order. Zero-length spans (repeated
/// knots, cuts) are skipped: they carry no material.
pub fn spans(space: &dyn BasisSpace) -> impl Iterator<Item = Span> + '_ {
    let (t, d, n) = (space.knots(), space.degree(), space.count());
    (d..n).filter(move |&k| t[k + 1] > t[k]).map(move |k| Span {
        start: t[k],
        end: t[k + 1],
        first: k - d,
    })
}

/// Greville abscissa of basis function `i`: the mean of knots `i+1 ..= i+d`. Control
/// points of a straight line placed at these parameters reproduce it exactly.
#[track_caller]
pub fn greville(space: &dyn BasisSpace, i: usize) -> Real {
    let d = space.degree();
    space.knots()[i + 1..=i + d].iter().sum::<Real>() / d as Real
}
