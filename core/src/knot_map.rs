//! [`KnotMap`]: the sparse, local linear map that a knot insertion or removal applies to
//! every coefficient field of a curve (positions, velocities, ...).
//!
//! New coefficients `first_new .. first_new + rows` are combinations of old coefficients
//! `first_old .. first_old + cols`; the others are copies, shifted by one after the
//! window. Insertion (Boehm, paper eq. 6): `rows = d`, `cols = d + 1`, weights
//! \\(\alpha_i, 1-\alpha_i\\). Removal: `rows = d - 1`, `cols = d + 2`: the
//! least-squares inverse of the insertion, which is exact whenever the knot is removable
//! (paper eq. 7 for the cubic case).
//!
//! On a periodic space ([`crate::PeriodicBSplineSpace`]) the last `d` coefficients repeat
//! the first `d`. A change next to the seam then also rewrites the copies of the window's
//! rows on the other side: the map's *ties*, each a new index that takes the same
//! combination as one window row ([`KnotMap::tied_new`]).

use crate::basis::MAX_ORDER;
use crate::Real;
use nalgebra::Vector3;
use num_traits::Zero;
use std::ops::{Add, Mul};

/// Anything a knot map can transform: a vector space over [`Real`] (e.g. `f64`, `Vector3`).
pub trait Coefficient: Copy + Zero + Add<Output = Self> + Mul<Real, Output = Self> {}
impl<T: Copy + Zero + Add<Output = T> + Mul<Real, Output = T>> Coefficient for T {}

/// Whether a map inserts or removes a knot.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum KnotOperation {
    /// One knot inserted: one coefficient more.
    Insert,
    /// One knot removed: one coefficient less.
    Remove,
}

const MAX_COLS: usize = MAX_ORDER + 1;

/// The old→new coefficient map of one knot insertion or removal. See the module docs.
#[derive(Debug, Clone, PartialEq)]
pub struct KnotMap {
    operation: KnotOperation,
    degree: usize,
    value: Real,
    knot_index: usize,
    old_count: usize,
    first_old: usize,
    first_new: usize,
    rows: usize,
    cols: usize,
    weights: [[Real; MAX_COLS]; MAX_ORDER],
    /// Insertion coefficients α of the refined side (used to measure a removal's error).
    alphas: [Real; MAX_ORDER],
    /// Periodic ties: (new index, window row) pairs; the first `tie_count` are live.
    ties: [(usize, usize); MAX_ORDER],
    tie_count: usize,
}

impl KnotMap {
    /// Map of inserting `value` into span `k` of a degree-`degree` space with `old_count`
    /// coefficients; `alphas[e]` is \\(\alpha_{k-d+1+e}\\).
    pub(crate) fn insertion(
        degree: usize,
        old_count: usize,
        k: usize,
        value: Real,
        alphas: &[Real; MAX_ORDER],
    ) -> Self {
        let mut weights = [[0.0; MAX_COLS]; MAX_ORDER];
        for (r, row) in weights.iter_mut().enumerate().take(degree) {
            row[r] = 1.0 - alphas[r];
            row[r + 1] = alphas[r];
        }
        Self {
            operation: KnotOperation::Insert,
            degree,
            value,
            knot_index: k + 1,
            old_count,
            first_old: k - degree,
            first_new: k - degree + 1,
            rows: degree,
            cols: degree + 1,
            weights,
            alphas: *alphas,
            ties: [(0, 0); MAX_ORDER],
            tie_count: 0,
        }
    }

    /// Map of removing knot `knot_index` (value `value`), whose insertion into span `k`
    /// of the coarse space has coefficients `alphas`.
    pub(crate) fn removal(
        degree: usize,
        old_count: usize,
        k: usize,
        knot_index: usize,
        value: Real,
        alphas: &[Real; MAX_ORDER],
    ) -> Self {
        let unknowns = degree - 1;
        let mut weights = [[0.0; MAX_COLS]; MAX_ORDER];
        for c in 0..degree + 2 {
            let x = least_squares_column(degree, alphas, c);
            for (j, row) in weights.iter_mut().enumerate().take(unknowns) {
                row[c] = x[j];
            }
        }
        Self {
            operation: KnotOperation::Remove,
            degree,
            value,
            knot_index,
            old_count,
            first_old: k - degree,
            first_new: k - degree + 1,
            rows: unknowns,
            cols: degree + 2,
            weights,
            alphas: *alphas,
            ties: [(0, 0); MAX_ORDER],
            tie_count: 0,
        }
    }

    /// This map on a periodic space with `distinct` different coefficients after the map
    /// (coefficient `i + distinct` repeats `i`): every window row whose index has a copy
    /// on the other side of the seam gains a tie that writes the same combination there.
    pub(crate) fn with_ties(mut self, distinct: usize) -> Self {
        let total = self.new_count();
        for r in 0..self.rows {
            let i = self.first_new + r;
            let partner = if i + distinct < total {
                Some(i + distinct)
            } else {
                i.checked_sub(distinct)
            };
            if let Some(j) = partner {
                self.ties[self.tie_count] = (j, r);
                self.tie_count += 1;
            }
        }
        self
    }

    /// Whether the map rewrites coefficients on both sides of a periodic seam (it has
    /// ties): then its change is not one contiguous window.
    pub fn wraps(&self) -> bool {
        self.tie_count > 0
    }

    /// New indices outside [`changed_new`](Self::changed_new) that the map rewrites (the
    /// periodic copies of window rows), each with the window index it copies.
    pub fn tied_new(&self) -> impl Iterator<Item = (usize, usize)> + '_ {
        self.ties[..self.tie_count]
            .iter()
            .map(|&(j, r)| (j, self.first_new + r))
    }

    /// Insertion or removal.
    pub fn operation(&self) -> KnotOperation {
        self.operation
    }
    /// The knot value inserted or removed.
    pub fn value(&self) -> Real {
        self.value
    }
    /// Position of the knot in the refined knot vector (after an insertion, before a removal).
    pub fn knot_index(&self) -> usize {
        self.knot_index
    }
    /// Number of coefficients before the map.
    pub fn old_count(&self) -> usize {
        self.old_count
    }
    /// Number of coefficients after the map.
    pub fn new_count(&self) -> usize {
        match self.operation {
            KnotOperation::Insert => self.old_count + 1,
            KnotOperation::Remove => self.old_count - 1,
        }
    }
    /// New coefficient indices that are not plain copies of an old one.
    pub fn changed_new(&self) -> std::ops::Range<usize> {
        self.first_new..self.first_new + self.rows
    }
    /// Old coefficient indices the changed ones are built from.
    pub fn source_old(&self) -> std::ops::Range<usize> {
        self.first_old..self.first_old + self.cols
    }

    /// Weight of old coefficient `old` in new coefficient `new` (the matrix β of eq. 5).
    pub fn weight(&self, new: usize, old: usize) -> Real {
        let new = self
            .tied_new()
            .find(|&(j, _)| j == new)
            .map_or(new, |(_, w)| w);
        if self.changed_new().contains(&new) {
            return match self.source_old().contains(&old) {
                true => self.weights[new - self.first_new][old - self.first_old],
                false => 0.0,
            };
        }
        let shift = new >= self.first_new + self.rows;
        let source = match (shift, self.operation) {
            (false, _) => new,
            (true, KnotOperation::Insert) => new - 1,
            (true, KnotOperation::Remove) => new + 1,
        };
        if source == old {
            1.0
        } else {
            0.0
        }
    }

    /// Applies the map to one coefficient field in place (the vector grows or shrinks by
    /// one; no allocation when its capacity allows).
    #[track_caller]
    pub fn apply_in_place<T: Coefficient>(&self, field: &mut Vec<T>) {
        assert_eq!(
            field.len(),
            self.old_count,
            "field length must match the map"
        );
        let window = self.window(field);
        match self.operation {
            KnotOperation::Insert => field.insert(self.first_new, T::zero()),
            KnotOperation::Remove => {
                field.remove(self.first_new);
            }
        }
        field[self.changed_new()].copy_from_slice(&window[..self.rows]);
        for &(j, r) in &self.ties[..self.tie_count] {
            field[j] = window[r];
        }
    }

    /// Bound on how far removing the knot moves the curve with control points `points`:
    /// the largest distance between `points` and the re-refined result. Because B-splines
    /// are non-negative and sum to one, no curve point moves farther. Zero for insertions.
    #[track_caller]
    pub fn shape_error(&self, points: &[Vector3<Real>]) -> Real {
        assert_eq!(
            points.len(),
            self.old_count,
            "points length must match the map"
        );
        if self.operation == KnotOperation::Insert {
            return 0.0;
        }
        let window = self.window(points);
        let coarse = |j: usize| match j {
            0 => points[self.first_old],
            j if j == self.degree => points[self.first_old + self.degree + 1],
            j => window[j - 1],
        };
        (0..self.degree)
            .map(|e| {
                let a = self.alphas[e];
                let refined = coarse(e + 1) * a + coarse(e) * (1.0 - a);
                (refined - points[self.first_old + 1 + e]).norm()
            })
            .fold(0.0, Real::max)
    }

    fn window<T: Coefficient>(&self, field: &[T]) -> [T; MAX_ORDER] {
        let mut out = [T::zero(); MAX_ORDER];
        let source = &field[self.source_old()];
        for (r, slot) in out.iter_mut().enumerate().take(self.rows) {
            let w = &self.weights[r];
            *slot = source
                .iter()
                .zip(w)
                .fold(T::zero(), |acc, (&c, &wc)| acc + c * wc);
        }
        out
    }
}

/// Least-squares removal weights for old window column `c`: solves the normal equations
/// of \\(\alpha_e x_e + (1-\alpha_e) x_{e-1} = Q_e\\) (boundary points fixed) for a unit
/// coefficient in column `c`, by the Thomas algorithm on the tridiagonal normal matrix.
fn least_squares_column(degree: usize, alphas: &[Real; MAX_ORDER], c: usize) -> [Real; MAX_ORDER] {
    let m = degree - 1;
    let mut x = [0.0; MAX_ORDER];
    if m == 0 {
        return x;
    }
    // Right-hand side of equation e (0..degree) for a unit value in old column c.
    let mut rhs = [0.0; MAX_ORDER];
    for (e, r) in rhs.iter_mut().enumerate().take(degree) {
        let a = alphas[e];
        *r = if c == e + 1 { 1.0 } else { 0.0 };
        if e == 0 && c == 0 {
            *r -= 1.0 - a;
        }
        if e == m && c == degree + 1 {
            *r -= a;
        }
    }
    // Equation e: a_e x_e [e < m] + b_e x_{e-1} [e ≥ 1], a_e = α_e, b_e = 1 - α_e.
    let (a, b) = (|e: usize| alphas[e], |e: usize| 1.0 - alphas[e]);
    let mut diag = [0.0; MAX_ORDER];
    let mut upper = [0.0; MAX_ORDER];
    for j in 0..m {
        diag[j] = a(j) * a(j) + b(j + 1) * b(j + 1);
        upper[j] = b(j + 1) * a(j + 1);
        x[j] = a(j) * rhs[j] + b(j + 1) * rhs[j + 1];
    }
    for j in 1..m {
        let f = upper[j - 1] / diag[j - 1];
        diag[j] -= f * upper[j - 1];
        x[j] -= f * x[j - 1];
    }
    x[m - 1] /= diag[m - 1];
    for j in (0..m - 1).rev() {
        x[j] = (x[j] - upper[j] * x[j + 1]) / diag[j];
    }
    x
}
