//! Gauss–Legendre quadrature per knot span, and the [`QuadratureTable`] that caches the
//! basis functions at every quadrature point of a rod.
//!
//! With `m` points per span the rule is exact for polynomials of degree `2m − 1`. The
//! integrands that matter for a degree-`d` spline with constant rest metric are the mass
//! \\(\mu b_i b_j\\) (degree `2d`) and the Green–Lagrange stretching density
//! \\((|C'|^2-1)^2\\) and its derivatives (degree `4(d−1)`), so the default is
//! `m = max(d + 1, 2d − 1)`: exact for both.

use crate::basis::{spans, BasisSpace, BasisValues, MAX_ORDER};
use crate::bspline::bspline_values;
use crate::local_update::ChangedRegion;
use crate::{CoreError, Real};
use std::ops::Range;

/// Gauss–Legendre nodes and weights on `[0, 1]`.
#[derive(Debug, Clone, PartialEq)]
pub struct GaussLegendre {
    /// Nodes in `(0, 1)`, increasing.
    pub nodes: Vec<Real>,
    /// Weights, summing to one.
    pub weights: Vec<Real>,
}

impl GaussLegendre {
    /// The `m`-point rule (`m ≥ 1`), from Newton iteration on the Legendre polynomial.
    #[track_caller]
    pub fn new(m: usize) -> Self {
        assert!(m >= 1, "a quadrature rule needs at least one point");
        let mut nodes = vec![0.0; m];
        let mut weights = vec![0.0; m];
        for i in 0..m {
            // Initial guess for the i-th largest root of P_m on [-1, 1].
            let mut x = (std::f64::consts::PI * (i as Real + 0.75) / (m as Real + 0.5)).cos();
            for _ in 0..100 {
                let (p, d) = legendre(m, x);
                let dx = p / d;
                x -= dx;
                if dx.abs() < 1e-16 {
                    break;
                }
            }
            let (_, d) = legendre(m, x);
            // Map [-1, 1] to [0, 1]; store in ascending order.
            nodes[m - 1 - i] = 0.5 * (x + 1.0);
            weights[m - 1 - i] = 1.0 / ((1.0 - x * x) * d * d);
        }
        Self { nodes, weights }
    }

    /// Points needed to integrate the mass (degree `2d`) and Green–Lagrange stretching
    /// (degree `4(d − 1)`) integrands of a degree-`d` spline exactly: `max(d + 1, 2d − 1)`.
    pub fn points_for_degree(degree: usize) -> usize {
        (degree + 1).max((2 * degree).saturating_sub(1))
    }
}

/// Consecutive rows of `len` entries of `v`, then empty rows for ever (a table's
/// optional columns: none when `v` is empty).
fn rows(v: &[Real], len: usize) -> impl Iterator<Item = &[Real]> + '_ {
    v.chunks(len.max(1)).chain(std::iter::repeat(&v[..0]))
}

/// Legendre polynomial P_m(x) and its derivative, by the three-term recurrence.
fn legendre(m: usize, x: Real) -> (Real, Real) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=m {
        let kf = k as Real;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let p = if m == 0 { 1.0 } else { p1 };
    let d = if m == 0 {
        0.0
    } else {
        m as Real * (x * p - p0) / (x * x - 1.0)
    };
    (p, d)
}

/// One quadrature point: parameter, weight (including the span length) and the basis
/// functions non-zero there.
#[derive(Debug, Clone, Copy)]
pub struct QuadPoint<'a> {
    /// Parameter (rest arclength).
    pub s: Real,
    /// Integration weight `w · (span length)`.
    pub weight: Real,
    /// Index of the first non-zero basis function.
    pub first: usize,
    /// Values of the non-zero basis functions.
    pub value: &'a [Real],
    /// Their first derivatives.
    pub d1: &'a [Real],
    /// Their second derivatives.
    pub d2: &'a [Real],
    /// Values of the `degree` B-splines of degree `degree − 1` on the same knots that
    /// are non-zero here (functions `first + 1 ..= first + degree`): the space the
    /// derivative \(C'\) lives in, used by mixed (assumed-strain) energies.
    pub lower: &'a [Real],
}

/// Basis functions tabulated at the Gauss points of every non-empty span.
///
/// Every energy and the mass matrix integrate over the rod through this table, so the
/// basis is evaluated once per change of knots, not once per step.
#[derive(Debug, Clone, Default)]
pub struct QuadratureTable {
    order: usize,
    s: Vec<Real>,
    weight: Vec<Real>,
    /// First non-zero basis function per point (32 bits: rods of up to 4·10⁹ points).
    first: Vec<u32>,
    value: Vec<Real>,
    d1: Vec<Real>,
    d2: Vec<Real>,
    lower: Vec<Real>,
    points_per_span: usize,
    /// Whether the second derivatives are left out ([`Self::without_second_derivatives`]).
    lean: bool,
}

impl QuadratureTable {
    /// Tabulates `space` with `points_per_span` Gauss points on each non-empty span.
    pub fn new(space: &dyn BasisSpace, points_per_span: usize) -> Result<Self, CoreError> {
        Self::tabulate(space, points_per_span, true)
    }

    /// [`Self::new`], with the second derivatives only if `second`.
    pub fn tabulate(
        space: &dyn BasisSpace,
        points_per_span: usize,
        second: bool,
    ) -> Result<Self, CoreError> {
        let rule = GaussLegendre::new(points_per_span.max(1));
        let mut table = Self {
            order: space.degree() + 1,
            points_per_span: rule.nodes.len(),
            lean: !second,
            ..Self::default()
        };
        table.reserve(spans(space).count() * table.points_per_span);
        let mut b = BasisValues::default();
        for span in spans(space) {
            let h = span.end - span.start;
            for (x, w) in rule.nodes.iter().zip(&rule.weights) {
                let s = span.start + h * x;
                space.evaluate(s, &mut b)?;
                table.push(s, w * h, &b, space.knots());
            }
        }
        Ok(table)
    }

    /// This table without the second derivatives of the basis (only bending reads them):
    /// 128 bytes less per span for a cubic rod at 4 points per span. Every later
    /// re-tabulation of its spans leaves them out too; [`QuadPoint::d2`] is then empty.
    pub fn without_second_derivatives(mut self) -> Self {
        self.lean = true;
        self.d2 = Vec::new();
        self
    }

    /// Whether the points carry the second derivatives ([`QuadPoint::d2`]).
    pub fn has_second_derivatives(&self) -> bool {
        !self.lean
    }

    /// Reserves room for exactly `points` more points (a table of 10⁵ spans would
    /// otherwise keep up to twice its size in capacity).
    fn reserve(&mut self, points: usize) {
        let o = self.order.min(MAX_ORDER);
        for v in [&mut self.s, &mut self.weight] {
            v.reserve_exact(points);
        }
        self.first.reserve_exact(points);
        for v in [&mut self.value, &mut self.d1] {
            v.reserve_exact(points * o);
        }
        if !self.lean {
            self.d2.reserve_exact(points * o);
        }
        self.lower.reserve_exact(points * o.saturating_sub(1));
    }

    fn push(&mut self, s: Real, weight: Real, b: &BasisValues, knots: &[Real]) {
        let o = self.order.min(MAX_ORDER);
        let d = o - 1;
        let lower = bspline_values(knots, d.saturating_sub(1), b.first + d, s);
        self.lower.extend_from_slice(&lower[..d]);
        self.s.push(s);
        self.weight.push(weight);
        self.first.push(b.first as u32);
        self.value.extend_from_slice(&b.value[..o]);
        self.d1.extend_from_slice(&b.d1[..o]);
        if !self.lean {
            self.d2.extend_from_slice(&b.d2[..o]);
        }
    }

    /// Number of quadrature points.
    pub fn len(&self) -> usize {
        self.s.len()
    }

    /// Whether the table has no points.
    pub fn is_empty(&self) -> bool {
        self.s.is_empty()
    }

    /// Gauss points per non-empty span.
    pub fn points_per_span(&self) -> usize {
        self.points_per_span
    }

    /// Number of basis functions non-zero at each point (`degree + 1`).
    pub fn order(&self) -> usize {
        self.order
    }

    /// Quadrature point `p`.
    #[inline]
    pub fn point(&self, p: usize) -> QuadPoint<'_> {
        let o = self.order;
        let range = p * o..(p + 1) * o;
        QuadPoint {
            s: self.s[p],
            weight: self.weight[p],
            first: self.first[p] as usize,
            value: &self.value[range.clone()],
            d1: &self.d1[range.clone()],
            d2: if self.lean { &[] } else { &self.d2[range] },
            lower: &self.lower[p * (o - 1)..(p + 1) * (o - 1)],
        }
    }

    /// Index of the first non-zero basis function at point `p` (its knot span minus the
    /// degree).
    #[inline]
    pub fn first_function(&self, p: usize) -> usize {
        self.first[p] as usize
    }

    /// Indices of the points with parameter in `[a, b)` (points are sorted by parameter).
    pub fn points_in(&self, (a, b): (Real, Real)) -> Range<usize> {
        self.s.partition_point(|&s| s < a)..self.s.partition_point(|&s| s < b)
    }

    /// Re-tabulates the spans of `region` on the new basis `space`, replacing the old
    /// points in the region's interval and shifting the first-function index of the
    /// points after it by the change in function count.
    pub fn replace_spans(
        &mut self,
        space: &dyn BasisSpace,
        region: &ChangedRegion,
    ) -> Result<(), CoreError> {
        let old = self.points_in(region.interval);
        let mut fresh = Self {
            order: self.order,
            points_per_span: self.points_per_span,
            lean: self.lean,
            ..Self::default()
        };
        let rule = GaussLegendre::new(self.points_per_span.max(1));
        let (t, d) = (space.knots(), space.degree());
        let mut b = BasisValues::default();
        for k in region.new_spans.clone().filter(|&k| t[k + 1] > t[k]) {
            let h = t[k + 1] - t[k];
            for (x, w) in rule.nodes.iter().zip(&rule.weights) {
                let s = t[k] + h * x;
                space.evaluate(s, &mut b)?;
                debug_assert_eq!(b.first, k - d);
                fresh.push(s, w * h, &b, t);
            }
        }
        let shift = region.new_functions.len() as isize - region.old_functions.len() as isize;
        for f in &mut self.first[old.end..] {
            *f = f.wrapping_add_signed(shift as i32);
        }
        let o = self.order;
        self.s.splice(old.clone(), fresh.s);
        self.weight.splice(old.clone(), fresh.weight);
        self.first.splice(old.clone(), fresh.first);
        let flat = old.start * o..old.end * o;
        self.value.splice(flat.clone(), fresh.value);
        self.d1.splice(flat.clone(), fresh.d1);
        if !self.lean {
            self.d2.splice(flat, fresh.d2);
        }
        let d = o - 1;
        self.lower.splice(old.start * d..old.end * d, fresh.lower);
        Ok(())
    }

    /// All points, in increasing parameter order.
    pub fn points(&self) -> impl Iterator<Item = QuadPoint<'_>> + '_ {
        (0..self.len()).map(|p| self.point(p))
    }

    /// The points of [`Self::points`], the table's rows walked in step (no index
    /// arithmetic or bounds check per point): for the hot loops of energies evaluated
    /// point by point.
    pub fn walk(&self) -> impl Iterator<Item = QuadPoint<'_>> + '_ {
        let o = self.order;
        // Chunks of at least one entry (`lower` has `degree` per point, `d2` none when
        // lean), so that every row has one; empty rows are cut from the full slices.
        let d2 = if self.lean {
            &self.d2[..0]
        } else {
            &self.d2[..]
        };
        let lower = rows(&self.lower, o - 1).map(move |r| &r[..r.len().min(o - 1)]);
        self.s
            .iter()
            .zip(&self.weight)
            .zip(&self.first)
            .zip(self.value.chunks_exact(o))
            .zip(self.d1.chunks_exact(o))
            .zip(rows(d2, o))
            .zip(lower)
            .map(
                |((((((&s, &weight), &first), value), d1), d2), lower)| QuadPoint {
                    s,
                    weight,
                    first: first as usize,
                    value,
                    d1,
                    d2,
                    lower,
                },
            )
    }
}
