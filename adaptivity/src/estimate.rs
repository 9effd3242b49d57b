//! A posteriori error estimate, in metres per knot span: how far the curve is from the
//! curve a finer basis would give for the same problem.
//!
//! **Method: hierarchical, one local correction per new basis function.** A scratch copy
//! of the rod is refined at once ([`Rod::refined`], exact) by a knot at every span's
//! midpoint and one more knot at every interaction point whose multiplicity is below
//! the degree. The copy has the same curve; on it the mechanics ([`FineProblem`]) gives
//! the residual `r̂` of the step's equilibrium (forces, inertia and damping of the step
//! included) and the stiffness `K̂`. Each new knot `v` owns one new basis function
//! `b̂_j` (the finer function that peaks at `v`); a Jacobi correction of its coefficient
//! alone,
//!
//! \\[ \delta_j = -\hat K_{jj}^{-1}\, \hat r_j, \qquad
//! \eta_v = \max_s \hat b_j(s)\, |\delta_j| \approx \hat b_j(v)\, |\delta_j|, \\]
//!
//! is how far that function would move the curve. A span's estimate is the largest
//! `η_v` of the new knots on it (ends included). Why this method: it is exact where the
//! rod is resolved (the residual of a converged curve vanishes on the finer basis too),
//! it needs nothing of an energy but its gradient and Hessian — so users' energies are
//! estimated with the built-in ones — and every correction is local: O(n) per estimate.
//! It measures the error *of one refinement*; for a method of order `p` that is
//! `1 − 2^{-p}` of the distance to the converged curve (0.94 for smooth cubic rods,
//! 0.5 at a corner), the effectivity the report measures. At an interaction the extra
//! knot's correction (`corner` estimate) says whether raising the multiplicity there —
//! a kink on a string under a point load — removes the error.
//!
//! For a dynamic step the residual includes the step's inertial force and the stiffness
//! is the potential's alone: the estimate is the spatial error of the equilibrium the
//! step solved with its acceleration as a load (elliptic reconstruction), which is what
//! a finer run would differ by once the motion is resolved in time.

use crate::AdaptError;
use nalgebra::{Matrix3, SymmetricEigen, Vector3};
use splinerod_core::basis::{greville, spans};
use splinerod_core::{BasisValues, BlockBanded, Real, RefinementOperator, Rod};

/// The mechanics on a finer copy of the rod, as the estimator needs it.
pub trait FineProblem {
    /// On `fine` (the rod refined through `op`), writes the residual of the step's
    /// equilibrium (N per coefficient, zero on coefficients held by pins) into `residual`
    /// and adds the potential's Hessian into `stiffness` (sized by the caller's
    /// [`FineProblem::bandwidth`]).
    fn evaluate(
        &mut self,
        fine: &Rod,
        op: &RefinementOperator,
        residual: &mut [Vector3<Real>],
        stiffness: &mut BlockBanded,
    ) -> Result<(), AdaptError>;
    /// Block bandwidth of the Hessian on `fine`.
    fn bandwidth(&self, fine: &Rod) -> usize {
        fine.basis().degree()
    }
    /// Solves `stiffness · x = rhs` in place (`stiffness` may be overwritten), with the
    /// coefficients pins hold kept at zero; false if the matrix is singular (then the
    /// estimate falls back on the local corrections).
    fn solve(
        &mut self,
        stiffness: &mut BlockBanded,
        rhs: &mut [Vector3<Real>],
    ) -> Result<bool, AdaptError>;
}

/// The estimate on one knot span.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpanError {
    /// Span start (material coordinate, m).
    pub start: Real,
    /// Span end.
    pub end: Real,
    /// Estimated error on it, m: the largest of its midpoint's and its corners'.
    pub error: Real,
    /// The part the knot at its midpoint would remove, m.
    pub midpoint: Real,
}

/// The estimate of the whole rod.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ErrorEstimate {
    /// One entry per non-empty knot span, in order.
    pub spans: Vec<SpanError>,
    /// Interaction points whose knot multiplicity can still grow, with the error one
    /// more knot there would remove.
    pub corners: Vec<Corner>,
    /// Control points of the rod estimated.
    pub control_points: usize,
    /// The estimate of the whole curve: the largest displacement of the global
    /// correction, m.
    pub global: Real,
}

/// The estimate at an interaction point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Corner {
    /// Material coordinate, m.
    pub at: Real,
    /// Knot multiplicity there when estimated.
    pub multiplicity: usize,
    /// Error one more knot there would remove, m.
    pub error: Real,
}

impl ErrorEstimate {
    /// The estimated error of the whole curve, m.
    pub fn max(&self) -> Real {
        self.global
    }

    /// The largest estimate of the spans overlapping `[a, b]` (touching counts).
    pub fn on(&self, a: Real, b: Real) -> Real {
        let from = self.spans.partition_point(|e| e.end < a);
        self.spans[from..]
            .iter()
            .take_while(|e| e.start <= b)
            .map(|e| e.error)
            .fold(0.0, Real::max)
    }
}

/// Computes [`ErrorEstimate`]s, keeping its buffers between calls.
#[derive(Debug, Default)]
pub struct Estimator {
    values: Vec<Real>,
    op: RefinementOperator,
    residual: Vec<Vector3<Real>>,
    correction: Vec<Vector3<Real>>,
    stiffness: BlockBanded,
    /// The latest estimate.
    pub estimate: ErrorEstimate,
}

impl Estimator {
    /// Estimates the error of `rod`'s curve; `interactions` are the material coordinates
    /// where something acts on it.
    pub fn run(
        &mut self,
        rod: &Rod,
        interactions: &[Real],
        problem: &mut dyn FineProblem,
    ) -> Result<&ErrorEstimate, AdaptError> {
        self.new_knots(rod, interactions);
        let fine = rod.refined(&self.values, &mut self.op)?;
        let n = fine.len();
        self.residual.clear();
        self.residual.resize(n, Vector3::zeros());
        self.stiffness.reset(n, problem.bandwidth(&fine));
        problem.evaluate(&fine, &self.op, &mut self.residual, &mut self.stiffness)?;
        self.local_indicators(rod, &fine, interactions)?;
        // The global correction: one Newton step of the finer problem.
        self.correction.clear();
        self.correction.extend(self.residual.iter().map(|r| -r));
        let global = if problem.solve(&mut self.stiffness, &mut self.correction)? {
            self.largest_displacement(&fine)
        } else {
            Real::NAN
        };
        self.calibrate(global);
        Ok(&self.estimate)
    }

    /// The Jacobi corrections of every new knot's function, per span (midpoints) and per
    /// interaction point (corners), uncalibrated.
    fn local_indicators(
        &mut self,
        rod: &Rod,
        fine: &Rod,
        interactions: &[Real],
    ) -> Result<(), AdaptError> {
        let e = &mut self.estimate;
        e.spans.clear();
        e.spans.extend(spans(rod.basis()).map(|s| SpanError {
            start: s.start,
            end: s.end,
            error: 0.0,
            midpoint: 0.0,
        }));
        e.corners.clear();
        e.control_points = rod.len();
        let mut b = BasisValues::default();
        for &v in &self.values {
            let eta = jacobi(fine, &self.residual, &self.stiffness, v, &mut b)?;
            let corner = interactions.contains(&v);
            if corner {
                let multiplicity = rod.knot_multiplicity(v);
                e.corners.push(Corner {
                    at: v,
                    multiplicity,
                    error: eta,
                });
            }
            let from = e.spans.partition_point(|s| s.end < v);
            for span in e.spans[from..].iter_mut().take_while(|s| s.start <= v) {
                span.error = span.error.max(eta);
                if !corner {
                    span.midpoint = span.midpoint.max(eta);
                }
            }
        }
        Ok(())
    }

    /// Largest displacement of the curve by the correction, over the finer rod's
    /// quadrature points.
    fn largest_displacement(&self, fine: &Rod) -> Real {
        let q = &self.correction;
        fine.quadrature()
            .points()
            .map(|p| {
                let v = p.value.iter().enumerate();
                v.map(|(a, &w)| q[p.first + a] * w)
                    .sum::<Vector3<Real>>()
                    .norm()
            })
            .fold(0.0, Real::max)
    }

    /// Scales the local indicators so that the largest equals the global error.
    fn calibrate(&mut self, global: Real) {
        let e = &mut self.estimate;
        e.global = global;
        let top = e.spans.iter().map(|s| s.error).fold(0.0, Real::max);
        if !global.is_finite() {
            e.global = top;
            return;
        }
        let scale = if top > 0.0 { global / top } else { 1.0 };
        for s in &mut e.spans {
            s.error *= scale;
            s.midpoint *= scale;
        }
        e.corners.iter_mut().for_each(|c| c.error *= scale);
    }

    /// The midpoints of every span and the interaction points that can take one more
    /// knot, sorted and without repeats.
    fn new_knots(&mut self, rod: &Rod, interactions: &[Real]) {
        let basis = rod.basis();
        let (start, end) = basis.domain();
        self.values.clear();
        self.values
            .extend(spans(basis).map(|s| 0.5 * (s.start + s.end)));
        let room = |s: Real| rod.knot_multiplicity(s) < basis.degree();
        self.values.extend(
            interactions
                .iter()
                .filter(|&&s| s > start && s < end && room(s)),
        );
        self.values.sort_by(Real::total_cmp);
        self.values.dedup();
    }
}

/// The Jacobi correction of the finer function that peaks at the new knot `v` (the one
/// whose Greville abscissa is nearest), as a displacement: `b̂_j(v) |K̂_jj⁻¹ r̂_j|`.
fn jacobi(
    fine: &Rod,
    residual: &[Vector3<Real>],
    stiffness: &BlockBanded,
    v: Real,
    b: &mut BasisValues,
) -> Result<Real, AdaptError> {
    let basis = fine.basis();
    basis.evaluate(v, b)?;
    let distance = |j: usize| (greville(basis, j) - v).abs();
    let j = (b.first..=b.first + basis.degree())
        .min_by(|&x, &y| distance(x).total_cmp(&distance(y)))
        .unwrap_or(b.first);
    let r = residual[j];
    if r == Vector3::zeros() {
        return Ok(0.0);
    }
    Ok(b.value[j - b.first] * solve_clamped(&stiffness.block(j, j), &r).norm())
}

/// `K⁻¹ r` for a symmetric 3×3 `K` whose eigenvalues are clamped from below at 1e-9 of
/// the largest (a direction nothing resists is not estimated); zero if `K` has no
/// positive eigenvalue.
fn solve_clamped(k: &Matrix3<Real>, r: &Vector3<Real>) -> Vector3<Real> {
    let eig = SymmetricEigen::new(0.5 * (k + k.transpose()));
    let top = eig.eigenvalues.max();
    if !(top > 0.0) || !top.is_finite() {
        return Vector3::zeros();
    }
    let mut x = Vector3::zeros();
    for (i, &lambda) in eig.eigenvalues.iter().enumerate() {
        let u = eig.eigenvectors.column(i);
        x += u * (u.dot(r) / lambda.max(1e-9 * top));
    }
    x
}
