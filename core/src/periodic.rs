//! [`PeriodicBSplineSpace`]: periodic B-splines of any degree for closed curves.
//!
//! A closed curve of rest length `L` has breakpoints \\(0 = u_0 \le u_1 \le \dots \le
//! u_{m-1} < L\\), repeated with period `L` into the bi-infinite knot sequence
//! \\(\tau_j = u_{j \bmod m} + L \lfloor j / m \rfloor\\), and `m` distinct control points
//! \\(c_0 \dots c_{m-1}\\): \\(C(s) = \sum_{j \in \mathbb{Z}} c_{j \bmod m} N_{j,d}(s)\\).
//!
//! It is stored as the ordinary (unclamped) B-spline space on the `m + 2d + 1` knots
//! \\(t_i = \tau_{i-d}\\), whose domain \\([t_d, t_{m+d}]\\) is `[0, L]`, with `m + d`
//! coefficients of which the last `d` repeat the first `d` (\\(q_{m+i} = q_i\\)). So
//! evaluation, quadrature, the mass matrix and every energy see an ordinary B-spline and
//! need nothing new; only whoever moves coefficients (integrators, knot maps) keeps the
//! copies equal, which [`BasisSpace::periodic_count`] announces.
//!
//! Knot insertion is Boehm's algorithm on the periodic sequence: the window of `d` new
//! coefficients is the ordinary one, and a window row whose index has a copy across the
//! seam is written there too (the map's ties, [`KnotMap::tied_new`]). Removal is the
//! least-squares inverse with the insertion coefficients of the coarse periodic sequence.
//! Both are exact wherever the seam is: a closed curve has none.

use crate::basis::{BasisSpace, BasisValues, MAX_ORDER};
use crate::bspline::BSplineSpace;
use crate::knot_map::KnotMap;
use crate::refine::{bspline_refinement, RefinementOperator};
use crate::{CoreError, Real};

/// Periodic B-splines of degree `d` with period `L` (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct PeriodicBSplineSpace {
    /// Breakpoints `u_0 = 0 ≤ … ≤ u_{m-1} < L` of one period.
    breaks: Vec<Real>,
    period: Real,
    /// The ordinary space on the extended knots `t_i = τ_{i-d}`.
    extended: BSplineSpace,
}

impl PeriodicBSplineSpace {
    /// A space of period `period` on the breakpoints of one period: `breaks[0] = 0` (the
    /// seam), then non-decreasing values below `period`, each repeated at most
    /// `degree + 1` times (a cut; the seam too). One control point per breakpoint, at
    /// least `degree + 1`.
    pub fn new(degree: usize, breaks: Vec<Real>, period: Real) -> Result<Self, CoreError> {
        crate::check::positive("period", period)?;
        crate::bspline::check_degree(degree)?;
        let m = breaks.len();
        crate::basis::check_count(m)?;
        if m < degree + 1 {
            return Err(CoreError::TooFewControlPoints { count: m, degree });
        }
        for (index, &value) in breaks.iter().enumerate() {
            if !value.is_finite() {
                return Err(CoreError::NonFiniteKnot { index, value });
            }
            if index > 0 && value < breaks[index - 1] {
                let previous = breaks[index - 1];
                return Err(CoreError::KnotsNotSorted {
                    index,
                    previous,
                    value,
                });
            }
        }
        let inside = |u: Real| u >= 0.0 && u < period;
        if let Some(&s) = breaks.iter().find(|&&u| !inside(u)) {
            return Err(CoreError::OutsideDomain {
                s,
                start: 0.0,
                end: period,
            });
        }
        if breaks[0] != 0.0 {
            return Err(CoreError::InvalidParameter {
                name: "periodic breakpoints",
                value: breaks[0],
                reason: "the first must be 0, the seam",
            });
        }
        let extended = BSplineSpace::new(degree, extended_knots(degree, &breaks, period))?;
        Ok(Self {
            breaks,
            period,
            extended,
        })
    }

    /// `count` distinct control points on evenly spaced breakpoints `k L / count`.
    pub fn uniform(degree: usize, count: usize, period: Real) -> Result<Self, CoreError> {
        crate::check::positive("period", period)?;
        crate::basis::check_count(count)?;
        let breaks = (0..count)
            .map(|k| period * k as Real / count as Real)
            .collect();
        Self::new(degree, breaks, period)
    }

    /// The period `L` (the rest length of a closed rod).
    pub fn period(&self) -> Real {
        self.period
    }

    /// The breakpoints of one period, `u_0 = 0 ≤ … < L`.
    pub fn breaks(&self) -> &[Real] {
        &self.breaks
    }

    /// Inserts the seam's value once more (Boehm at `u = 0`, the last of the seam's
    /// knots): raising it to `degree + 1` cuts the loop open there.
    fn insert_at_seam(&mut self) -> Result<KnotMap, CoreError> {
        let d = self.degree();
        let seam = self.breaks.iter().take_while(|&&u| u == 0.0).count();
        if seam > d {
            let max = d + 1;
            let (value, multiplicity) = (0.0, seam + 1);
            return Err(CoreError::MultiplicityTooHigh {
                value,
                multiplicity,
                max,
            });
        }
        let t = self.knots();
        let k = d + seam - 1;
        let mut alphas = [0.0; MAX_ORDER];
        for (e, alpha) in alphas.iter_mut().enumerate().take(d) {
            let i = k - d + 1 + e;
            *alpha = (0.0 - t[i]) / (t[i + d] - t[i]);
        }
        let map = KnotMap::insertion(d, self.count(), k, 0.0, &alphas);
        let mut breaks = self.breaks.clone();
        breaks.insert(0, 0.0);
        *self = self.with_breaks(breaks)?;
        Ok(map.with_ties(self.breaks.len()))
    }

    /// How many times the seam's value occurs (`degree + 1`: the loop is cut there).
    pub fn seam_multiplicity(&self) -> usize {
        self.breaks.iter().take_while(|&&u| u == 0.0).count()
    }

    /// The same period on new breakpoints.
    fn with_breaks(&self, breaks: Vec<Real>) -> Result<Self, CoreError> {
        Self::new(self.extended.degree(), breaks, self.period)
    }
}

/// The extended knots `t_i = τ_{i-d}`, `i = 0 ..= m + 2d`, of breakpoints `breaks`.
fn extended_knots(degree: usize, breaks: &[Real], period: Real) -> Vec<Real> {
    let m = breaks.len() as isize;
    (0..breaks.len() + 2 * degree + 1)
        .map(|i| {
            let j = i as isize - degree as isize;
            let (turns, k) = (j.div_euclid(m), j.rem_euclid(m));
            // The domain's end exactly at the period (u_0 + L).
            match (turns, k) {
                (1, 0) => period,
                _ => breaks[k as usize] + period * turns as Real,
            }
        })
        .collect()
}

impl BasisSpace for PeriodicBSplineSpace {
    fn degree(&self) -> usize {
        self.extended.degree()
    }

    fn count(&self) -> usize {
        self.extended.count()
    }

    fn knots(&self) -> &[Real] {
        self.extended.knots()
    }

    fn periodic_count(&self) -> Option<usize> {
        Some(self.breaks.len())
    }

    fn evaluate(&self, s: Real, out: &mut BasisValues) -> Result<(), CoreError> {
        self.extended.evaluate(s, out)
    }

    fn evaluate_values(&self, s: Real, out: &mut BasisValues) -> Result<(), CoreError> {
        self.extended.evaluate_values(s, out)
    }

    fn insert_knot(&mut self, s: Real) -> Result<KnotMap, CoreError> {
        if s == 0.0 || s == self.period {
            return self.insert_at_seam();
        }
        // The stored knots are the periodic ones around the window, so the ordinary
        // insertion computes the window; the new space rebuilds its copies.
        let mut extended = self.extended.clone();
        let map = extended.insert_knot(s)?;
        let mut breaks = self.breaks.clone();
        breaks.insert(breaks.partition_point(|&u| u <= s), s);
        *self = self.with_breaks(breaks)?;
        Ok(map.with_ties(self.breaks.len()))
    }

    fn removal(&self, index: usize) -> Result<KnotMap, CoreError> {
        let (d, knots) = (self.degree(), self.knots());
        let value = *knots.get(index).ok_or(CoreError::NotInteriorKnot {
            index,
            value: Real::NAN,
        })?;
        if !(value > 0.0 && value < self.period) {
            return Err(CoreError::NotInteriorKnot { index, value });
        }
        let last = index + knots[index..].iter().take_while(|&&t| t == value).count() - 1;
        let mut breaks = self.breaks.clone();
        breaks.remove(last - d);
        let coarse = self.with_breaks(breaks)?;
        let t = coarse.knots();
        let k = last - 1;
        let mut alphas = [0.0; MAX_ORDER];
        for (e, alpha) in alphas.iter_mut().enumerate().take(d) {
            let i = k - d + 1 + e;
            *alpha = (value - t[i]) / (t[i + d] - t[i]);
        }
        let map = KnotMap::removal(d, self.count(), k, last, value, &alphas);
        Ok(map.with_ties(coarse.breaks.len()))
    }

    fn remove_knot(&mut self, index: usize) -> Result<KnotMap, CoreError> {
        let map = self.removal(index)?;
        let mut breaks = self.breaks.clone();
        breaks.remove(map.knot_index() - self.degree());
        *self = self.with_breaks(breaks)?;
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
        if let Some(&s) = values.iter().find(|&&s| !(s > 0.0 && s < self.period)) {
            let end = self.period;
            return Err(CoreError::OutsideDomain { s, start: 0.0, end });
        }
        let mut breaks = Vec::with_capacity(self.breaks.len() + values.len());
        breaks.extend_from_slice(&self.breaks);
        breaks.extend_from_slice(values);
        breaks.sort_by(Real::total_cmp);
        let fine = self.with_breaks(breaks)?;
        // The blossom identity holds on the bi-infinite sequences, which the extended
        // knots of both spaces follow around every window.
        bspline_refinement(self.degree(), self.knots(), fine.knots(), op)?;
        op.tie_periodic(fine.breaks.len());
        Ok(Box::new(fine))
    }
}
