//! [`BSplineSpace`]: B-splines of any degree on an arbitrary non-decreasing knot vector.
//!
//! Evaluation is the Cox–de Boor recursion with derivatives (Piegl & Tiller, algorithm
//! A2.3) on stack arrays. Knot insertion is Boehm's algorithm, the one-knot case of the
//! Oslo algorithm (paper eq. 3–6): inserting `u` in span `k` gives new coefficients
//! \\(q^1_i = \alpha_i q^0_i + (1-\alpha_i) q^0_{i-1}\\) with
//! \\(\alpha_i = (u - t_i)/(t_{i+d} - t_i)\\) for \\(k-d < i \le k\\), copies elsewhere.
//! Removal inverts that map in the least-squares sense (exact when the knot is
//! removable; paper eq. 7 is its cubic, exact case) and reports the shape change.

use crate::basis::{BasisSpace, BasisValues, MAX_DEGREE, MAX_ORDER};
use crate::knot_map::KnotMap;
use crate::refine::{bspline_refinement, RefinementOperator};
use crate::{CoreError, Real};

/// B-spline basis functions of degree `d` on a knot vector `t_0 ≤ … ≤ t_{n+d}`.
#[derive(Debug, Clone, PartialEq)]
pub struct BSplineSpace {
    degree: usize,
    knots: Vec<Real>,
}

impl BSplineSpace {
    /// A space on an explicit knot vector; checks degree, length-independent ordering,
    /// finiteness, multiplicities (at most `degree + 1`) and a non-empty domain.
    /// The number of control points is `knots.len() - degree - 1`.
    pub fn new(degree: usize, knots: Vec<Real>) -> Result<Self, CoreError> {
        check_degree(degree)?;
        let count = knots.len().saturating_sub(degree + 1);
        crate::basis::check_count(count)?;
        if count < degree + 1 {
            return Err(CoreError::TooFewControlPoints { count, degree });
        }
        for (index, &value) in knots.iter().enumerate() {
            if !value.is_finite() {
                return Err(CoreError::NonFiniteKnot { index, value });
            }
            if index > 0 && value < knots[index - 1] {
                let previous = knots[index - 1];
                return Err(CoreError::KnotsNotSorted {
                    index,
                    previous,
                    value,
                });
            }
        }
        let space = Self { degree, knots };
        space.check_multiplicities()?;
        let (start, end) = space.domain();
        if end <= start {
            return Err(CoreError::EmptyDomain { start, end });
        }
        Ok(space)
    }

    /// Clamped (open) uniform knots on `[0, length]`: ends repeated `degree + 1` times so
    /// the curve interpolates its end control points.
    pub fn clamped_uniform(degree: usize, count: usize, length: Real) -> Result<Self, CoreError> {
        check_layout(degree, count, length)?;
        let spans = count - degree;
        let knots = (0..count + degree + 1)
            .map(|i| {
                let k = i.saturating_sub(degree).min(spans);
                // The end exactly at `length` (k L / k can round below it).
                if k == spans {
                    length
                } else {
                    length * k as Real / spans as Real
                }
            })
            .collect();
        Self::new(degree, knots)
    }

    /// Uniform knots as in the paper (ends not interpolated): evenly spaced knots whose
    /// domain `[t_d, t_n]` is `[0, length]`.
    pub fn uniform(degree: usize, count: usize, length: Real) -> Result<Self, CoreError> {
        check_layout(degree, count, length)?;
        let h = length / (count - degree) as Real;
        let knots = (0..count + degree + 1)
            .map(|i| match i {
                // The domain's end exactly at `length`.
                i if i == count => length,
                _ => (i as Real - degree as Real) * h,
            })
            .collect();
        Self::new(degree, knots)
    }

    /// Greville abscissa of control point `i` (see [`crate::basis::greville`]).
    #[track_caller]
    pub fn greville(&self, i: usize) -> Real {
        crate::basis::greville(self, i)
    }

    /// How many times the value `u` occurs in the knot vector.
    pub fn multiplicity(&self, u: Real) -> usize {
        self.knots.iter().filter(|&&t| t == u).count()
    }

    /// Span index `k` with `t_k ≤ s < t_{k+1}` (the last non-empty span at the domain end).
    fn find_span(&self, s: Real) -> Result<usize, CoreError> {
        let (start, end) = self.domain();
        if !(s >= start && s <= end) {
            return Err(CoreError::OutsideDomain { s, start, end });
        }
        let (d, n, t) = (self.degree, self.count(), &self.knots);
        if s >= end {
            return Ok((d..n).rev().find(|&k| t[k + 1] > t[k]).unwrap_or(d));
        }
        Ok(d + t[d + 1..n].partition_point(|&x| x <= s))
    }

    fn check_multiplicities(&self) -> Result<(), CoreError> {
        let max = self.degree + 1;
        let mut run = 1;
        for i in 1..self.knots.len() {
            run = if self.knots[i] == self.knots[i - 1] {
                run + 1
            } else {
                1
            };
            if run > max {
                let value = self.knots[i];
                return Err(CoreError::MultiplicityTooHigh {
                    value,
                    multiplicity: run,
                    max,
                });
            }
        }
        Ok(())
    }

    /// Checks that `u` is finite and strictly inside the domain.
    fn check_interior(&self, u: Real) -> Result<(), CoreError> {
        let (start, end) = self.domain();
        if u > start && u < end {
            Ok(())
        } else {
            Err(CoreError::OutsideDomain { s: u, start, end })
        }
    }

    /// Basis functions non-zero in span `k` and their derivatives (Piegl & Tiller A2.3),
    /// through [`derivatives`] instantiated for the degree (the same operations in the
    /// same order as the run-time degree, so the same bits; about half the instructions).
    fn basis_derivatives(&self, k: usize, s: Real, out: &mut BasisValues) {
        let t = &self.knots;
        match self.degree {
            1 => derivatives::<1>(1, t, k, s, out),
            2 => derivatives::<2>(2, t, k, s, out),
            3 => derivatives::<3>(3, t, k, s, out),
            4 => derivatives::<4>(4, t, k, s, out),
            5 => derivatives::<5>(5, t, k, s, out),
            p => derivatives::<0>(p, t, k, s, out),
        }
    }
}

/// The triangular table of Piegl & Tiller A2.3 for degree `P` (`degree` when `P` is 0)
/// in span `k` of the knots `t` at `s`: the basis values in column `p`, the knot
/// differences below the diagonal.
#[inline(always)]
fn value_table<const P: usize>(
    degree: usize,
    t: &[Real],
    k: usize,
    s: Real,
) -> [[Real; MAX_ORDER]; MAX_ORDER] {
    let p = if P == 0 { degree } else { P };
    let mut ndu = [[0.0; MAX_ORDER]; MAX_ORDER];
    let (mut left, mut right) = ([0.0; MAX_ORDER], [0.0; MAX_ORDER]);
    ndu[0][0] = 1.0;
    for j in 1..=p {
        left[j] = s - t[k + 1 - j];
        right[j] = t[k + j] - s;
        let mut saved = 0.0;
        for r in 0..j {
            ndu[j][r] = right[r + 1] + left[j - r];
            let temp = ndu[r][j - 1] / ndu[j][r];
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    ndu
}

/// The non-zero basis functions of degree `P` (`degree` when `P` is 0) in span `k` of
/// the knots `t` alone (the values of [`derivatives`], bit for bit).
#[inline]
fn values<const P: usize>(degree: usize, t: &[Real], k: usize, s: Real, out: &mut BasisValues) {
    let p = if P == 0 { degree } else { P };
    let ndu = value_table::<P>(degree, t, k, s);
    out.first = k - p;
    out.order = p + 1;
    out.value = [0.0; MAX_ORDER];
    for j in 0..=p {
        out.value[j] = ndu[j][p];
    }
}

/// The non-zero basis functions of degree `P` (`degree` when `P` is 0) in span `k` of
/// the knots `t` and their first two derivatives (Piegl & Tiller A2.3).
#[inline]
pub(crate) fn derivatives<const P: usize>(
    degree: usize,
    t: &[Real],
    k: usize,
    s: Real,
    out: &mut BasisValues,
) {
    let p = if P == 0 { degree } else { P };
    let ndu = value_table::<P>(degree, t, k, s);
    out.first = k - p;
    out.order = p + 1;
    out.value = [0.0; MAX_ORDER];
    out.d1 = [0.0; MAX_ORDER];
    out.d2 = [0.0; MAX_ORDER];
    for j in 0..=p {
        out.value[j] = ndu[j][p];
    }
    let top = p.min(2);
    for r in 0..=p {
        let mut a = [[0.0; MAX_ORDER]; 2];
        let (mut s1, mut s2) = (0, 1);
        a[0][0] = 1.0;
        for kk in 1..=top {
            let (rk, pk) = (r as isize - kk as isize, p - kk);
            let mut d = 0.0;
            if rk >= 0 {
                let rk = rk as usize;
                a[s2][0] = a[s1][0] / ndu[pk + 1][rk];
                d = a[s2][0] * ndu[rk][pk];
            }
            let j1 = if rk >= -1 { 1 } else { (-rk) as usize };
            let j2 = if r as isize - 1 <= pk as isize {
                kk - 1
            } else {
                p - r
            };
            for j in j1..=j2 {
                let idx = (rk + j as isize) as usize;
                a[s2][j] = (a[s1][j] - a[s1][j - 1]) / ndu[pk + 1][idx];
                d += a[s2][j] * ndu[idx][pk];
            }
            if r <= pk {
                a[s2][kk] = -a[s1][kk - 1] / ndu[pk + 1][r];
                d += a[s2][kk] * ndu[r][pk];
            }
            if kk == 1 {
                out.d1[r] = d
            } else {
                out.d2[r] = d
            }
            std::mem::swap(&mut s1, &mut s2);
        }
    }
    let pf = p as Real;
    for j in 0..=p {
        out.d1[j] *= pf;
        out.d2[j] *= pf * (pf - 1.0);
    }
}

pub(crate) fn check_degree(degree: usize) -> Result<(), CoreError> {
    if (1..=MAX_DEGREE).contains(&degree) {
        Ok(())
    } else {
        Err(CoreError::InvalidDegree {
            degree,
            max: MAX_DEGREE,
        })
    }
}

fn check_layout(degree: usize, count: usize, length: Real) -> Result<(), CoreError> {
    check_degree(degree)?;
    crate::basis::check_count(count)?;
    if count < degree + 1 {
        return Err(CoreError::TooFewControlPoints { count, degree });
    }
    if !(length.is_finite() && length > 0.0) {
        return Err(CoreError::InvalidParameter {
            name: "length",
            value: length,
            reason: "must be finite and positive",
        });
    }
    Ok(())
}

impl BasisSpace for BSplineSpace {
    fn degree(&self) -> usize {
        self.degree
    }

    fn count(&self) -> usize {
        self.knots.len() - self.degree - 1
    }

    fn knots(&self) -> &[Real] {
        &self.knots
    }

    fn evaluate(&self, s: Real, out: &mut BasisValues) -> Result<(), CoreError> {
        let k = self.find_span(s)?;
        self.basis_derivatives(k, s, out);
        Ok(())
    }

    fn evaluate_values(&self, s: Real, out: &mut BasisValues) -> Result<(), CoreError> {
        let k = self.find_span(s)?;
        let t = &self.knots;
        match self.degree {
            1 => values::<1>(1, t, k, s, out),
            2 => values::<2>(2, t, k, s, out),
            3 => values::<3>(3, t, k, s, out),
            4 => values::<4>(4, t, k, s, out),
            5 => values::<5>(5, t, k, s, out),
            p => values::<0>(p, t, k, s, out),
        }
        Ok(())
    }

    fn insert_knot(&mut self, u: Real) -> Result<KnotMap, CoreError> {
        self.check_interior(u)?;
        let multiplicity = self.multiplicity(u) + 1;
        if multiplicity > self.degree + 1 {
            let max = self.degree + 1;
            return Err(CoreError::MultiplicityTooHigh {
                value: u,
                multiplicity,
                max,
            });
        }
        let (p, k) = (self.degree, self.find_span(u)?);
        let t = &self.knots;
        let mut alphas = [0.0; MAX_ORDER];
        for (e, alpha) in alphas.iter_mut().enumerate().take(p) {
            let i = k - p + 1 + e;
            *alpha = (u - t[i]) / (t[i + p] - t[i]);
        }
        let map = KnotMap::insertion(p, self.count(), k, u, &alphas);
        self.knots.insert(k + 1, u);
        Ok(map)
    }

    fn removal(&self, index: usize) -> Result<KnotMap, CoreError> {
        let value = *self.knots.get(index).ok_or(CoreError::NotInteriorKnot {
            index,
            value: Real::NAN,
        })?;
        self.check_interior(value)
            .map_err(|_| CoreError::NotInteriorKnot { index, value })?;
        let last = index
            + self.knots[index..]
                .iter()
                .take_while(|&&t| t == value)
                .count()
            - 1;
        // Knots of the coarse space: the current ones without position `last`.
        let coarse = |j: usize| self.knots[if j < last { j } else { j + 1 }];
        let (p, k) = (self.degree, last - 1);
        let mut alphas = [0.0; MAX_ORDER];
        for (e, alpha) in alphas.iter_mut().enumerate().take(p) {
            let i = k - p + 1 + e;
            *alpha = (value - coarse(i)) / (coarse(i + p) - coarse(i));
        }
        Ok(KnotMap::removal(p, self.count(), k, last, value, &alphas))
    }

    fn remove_knot(&mut self, index: usize) -> Result<KnotMap, CoreError> {
        let map = self.removal(index)?;
        self.knots.remove(map.knot_index());
        Ok(map)
    }

    fn clone_box(&self) -> Box<dyn BasisSpace> {
        Box::new(self.clone())
    }

    fn refined(
        &self,
        values: &[Real],
        op: &mut RefinementOperator,
    ) -> Result<Box<dyn BasisSpace>, CoreError> {
        let (start, end) = self.domain();
        if let Some(&s) = values.iter().find(|&&s| !(s > start && s < end)) {
            return Err(CoreError::OutsideDomain { s, start, end });
        }
        let mut knots = Vec::with_capacity(self.knots.len() + values.len());
        knots.extend_from_slice(&self.knots);
        knots.extend_from_slice(values);
        knots.sort_by(Real::total_cmp);
        let fine = Self::new(self.degree, knots)?;
        bspline_refinement(self.degree, &self.knots, &fine.knots, op)?;
        Ok(Box::new(fine))
    }
}

/// Values of the `degree + 1` B-splines of degree `degree` on `knots` that are non-zero in
/// span `span` (`knots[span] ≤ s < knots[span + 1]`, a non-empty span), functions
/// `span − degree ..= span` (Piegl & Tiller A2.2). Any knot vector works, also one built
/// for a higher degree: energies use it for the degree-`d − 1` splines on a rod's knots.
pub fn bspline_values(knots: &[Real], degree: usize, span: usize, s: Real) -> [Real; MAX_ORDER] {
    let mut n = [0.0; MAX_ORDER];
    let (mut left, mut right) = ([0.0; MAX_ORDER], [0.0; MAX_ORDER]);
    n[0] = 1.0;
    for j in 1..=degree {
        left[j] = s - knots[span + 1 - j];
        right[j] = knots[span + j] - s;
        let mut saved = 0.0;
        for r in 0..j {
            let temp = n[r] / (right[r + 1] + left[j - r]);
            n[r] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        n[j] = saved;
    }
    n
}
