//! Least-squares fit of a B-spline to the knot's target curve and its Levenberg–Marquardt
//! relaxation on the energy `E` of the module docs of [`crate::knot`]; curve sampling and
//! arclength.

use super::shape::OverhandSpec;
use crate::Error;
use nalgebra::{DMatrix, DVector, Vector3};
use splinerod_core::basis::spans;
use splinerod_core::{BSplineSpace, BasisSpace, BasisValues, Cancel, GaussLegendre, Real};

/// Fit samples per control point (at least `MIN_FIT_SAMPLES` in all).
const FIT_SAMPLES_PER_POINT: usize = 40;
/// Smallest number of fit samples.
const MIN_FIT_SAMPLES: usize = 400;
/// Samples of the repulsion term.
const REPULSION_SAMPLES: usize = 150;
/// Levenberg–Marquardt iterations of the relaxation.
const RELAX_ITERATIONS: usize = 60;
/// Weight `μ` of the closeness to the target.
const ANCHOR_WEIGHT: Real = 0.3;
/// Weight `κ` of the repulsion.
const REPULSION_WEIGHT: Real = 30.0;
/// Distance `D` below which strands repel, as a fraction of `size`.
const REPULSION_DISTANCE: Real = 0.35;
/// Neighbourhood `ℓ`, as a fraction of `size`: points closer in `s` are one strand.
const NEIGHBOURHOOD: Real = 0.9;

/// Control points of the B-spline fitted to `target` and relaxed (module docs), with its
/// arclength.
///
/// Polls `cancel` before every iteration ([`Cancel::requested`]: the fit is setup, with
/// no step to finish) and returns [`Error::Interrupted`] when a stop is asked.
pub(super) fn relaxed_fit(
    target: &Target,
    spec: &OverhandSpec,
    cancel: &Cancel,
) -> Result<(Vec<Vector3<Real>>, Real), Error> {
    let stopped = || Error::Interrupted("during the scene's setup (the overhand knot's fit)");
    let mut fit = Fit::new(target, spec)?;
    let mut q = fit.least_squares()?;
    let mut lambda = 1e-3;
    for _ in 0..RELAX_ITERATIONS {
        if cancel.requested() {
            return Err(stopped());
        }
        fit.project(&q)?;
        q = fit.relax_step(q, &mut lambda, cancel)?;
    }
    if cancel.requested() {
        return Err(stopped());
    }
    let rest_length = arclength(&q, &fit.space)?;
    Ok((q, rest_length))
}

/// A polyline parametrised by its arclength.
pub(super) struct Target {
    points: Vec<Vector3<Real>>,
    arclength: Vec<Real>,
}

impl Target {
    pub(super) fn new(points: Vec<Vector3<Real>>) -> Self {
        let mut arclength = vec![0.0];
        for w in points.windows(2) {
            arclength.push(arclength[arclength.len() - 1] + (w[1] - w[0]).norm());
        }
        Self { points, arclength }
    }

    pub(super) fn length(&self) -> Real {
        self.arclength[self.arclength.len() - 1]
    }

    /// `P(σ)`, linear between the polyline's points.
    fn at(&self, sigma: Real) -> Vector3<Real> {
        let last = self.points.len() - 1;
        let i = self
            .arclength
            .partition_point(|&x| x <= sigma)
            .clamp(1, last);
        let (s0, s1) = (self.arclength[i - 1], self.arclength[i]);
        let w = if s1 > s0 {
            (sigma - s0) / (s1 - s0)
        } else {
            0.0
        };
        self.points[i - 1].lerp(&self.points[i], w.clamp(0.0, 1.0))
    }

    /// Arclength of the polyline point closest to `p` within `window` of `guess`.
    fn closest(&self, p: &Vector3<Real>, guess: Real, window: Real) -> Real {
        let lo = self.arclength.partition_point(|&x| x < guess - window);
        let hi = self.arclength.partition_point(|&x| x <= guess + window);
        (lo..hi)
            .map(|k| ((self.points[k] - p).norm_squared(), self.arclength[k]))
            .fold(
                (Real::INFINITY, guess),
                |a, b| if b.0 < a.0 { b } else { a },
            )
            .1
    }
}

/// The fitting problem: residuals of the energy `E` (module docs) at samples `s_j`, the
/// unknowns being the interior control points (the ends interpolate the target's).
struct Fit<'a> {
    target: &'a Target,
    space: BSplineSpace,
    s: Vec<Real>,
    sigma: Vec<Real>,
    size: Real,
}

/// Gauss–Newton normal equations `JᵀJ`, `Jᵀr` and the cost `|r|²`, row by row.
struct Normal {
    matrix: DMatrix<Real>,
    gradient: DVector<Real>,
    cost: Real,
}

impl Normal {
    fn new(unknowns: usize) -> Self {
        Self {
            matrix: DMatrix::zeros(unknowns, unknowns),
            gradient: DVector::zeros(unknowns),
            cost: 0.0,
        }
    }

    /// Adds residual `r` with its non-zero derivatives `(unknown, ∂r/∂x)`.
    fn add(&mut self, r: Real, row: &[(usize, Real)]) {
        self.cost += r * r;
        for &(i, a) in row {
            self.gradient[i] += a * r;
            for &(j, b) in row {
                self.matrix[(i, j)] += a * b;
            }
        }
    }

    /// The step `−(JᵀJ + λ diag JᵀJ)⁻¹ Jᵀr`, if the matrix is definite.
    fn step(&self, lambda: Real) -> Option<DVector<Real>> {
        let mut a = self.matrix.clone();
        for i in 0..a.nrows() {
            a[(i, i)] *= 1.0 + lambda;
        }
        a.cholesky().map(|c| -c.solve(&self.gradient))
    }
}

impl<'a> Fit<'a> {
    fn new(target: &'a Target, spec: &OverhandSpec) -> Result<Self, Error> {
        let (d, n, length) = (spec.degree, spec.control_points, target.length());
        let space = BSplineSpace::clamped_uniform(d, n, length)?;
        let m = (FIT_SAMPLES_PER_POINT * n).max(MIN_FIT_SAMPLES);
        let end = space.domain().1;
        let s: Vec<Real> = (0..m)
            .map(|j| (length * j as Real / (m - 1) as Real).min(end))
            .collect();
        let sigma = s.clone();
        let size = spec.size;
        Ok(Self {
            target,
            space,
            s,
            sigma,
            size,
        })
    }

    /// Unknown index of coordinate `c` of control point `i`; `None` for the fixed ends.
    fn unknown(&self, i: usize, c: usize) -> Option<usize> {
        (i > 0 && i + 1 < self.space.count()).then(|| 3 * (i - 1) + c)
    }

    /// `q` moved by the unknowns' step `dx`.
    fn moved(&self, q: &[Vector3<Real>], dx: &DVector<Real>, scale: Real) -> Vec<Vector3<Real>> {
        let mut out = q.to_vec();
        for (i, p) in out.iter_mut().enumerate() {
            for c in 0..3 {
                if let Some(u) = self.unknown(i, c) {
                    p[c] += scale * dx[u];
                }
            }
        }
        out
    }

    /// The least-squares fit (closeness term alone: one exact Gauss–Newton step).
    fn least_squares(&self) -> Result<Vec<Vector3<Real>>, Error> {
        let n = self.space.count();
        let mut q = vec![Vector3::zeros(); n];
        (q[0], q[n - 1]) = (self.target.at(0.0), self.target.at(self.target.length()));
        let mut normal = Normal::new(3 * (n - 2));
        self.add_samples(&q, &mut normal, false)?;
        match normal.step(0.0) {
            Some(dx) => Ok(self.moved(&q, &dx, 1.0)),
            None if n == 2 => Ok(q),
            None => Err(Error::field(
                "control_points",
                n,
                "least-squares fit is singular",
            )),
        }
    }

    /// Moves `σ_j` to the target point closest to `C(s_j)`.
    fn project(&mut self, q: &[Vector3<Real>]) -> Result<(), Error> {
        let mut b = BasisValues::default();
        for (&sj, gj) in self.s.iter().zip(self.sigma.iter_mut()) {
            self.space.evaluate(sj, &mut b)?;
            let c = b.combine(&b.value, q);
            *gj = self.target.closest(&c, *gj, 0.3 * self.size);
        }
        Ok(())
    }

    /// One Levenberg–Marquardt step on `E`, moving no control point more than `size/10`.
    fn relax_step(
        &self,
        q: Vec<Vector3<Real>>,
        lambda: &mut Real,
        cancel: &Cancel,
    ) -> Result<Vec<Vector3<Real>>, Error> {
        let normal = self.energy(&q)?;
        for _ in 0..20 {
            if cancel.requested() {
                // The caller sees the request before its next iteration.
                return Ok(q);
            }
            if let Some(dx) = normal.step(*lambda) {
                let longest = dx
                    .as_slice()
                    .chunks(3)
                    .map(|c| c.iter().map(|x| x * x).sum::<Real>());
                let longest = longest.fold(0.0, Real::max).sqrt();
                let trial = self.moved(&q, &dx, (0.1 * self.size / longest).min(1.0));
                if self.energy(&trial)?.cost < normal.cost {
                    *lambda = (*lambda / 3.0).max(1e-9);
                    return Ok(trial);
                }
            }
            *lambda *= 5.0;
        }
        Ok(q)
    }

    /// Normal equations of all of `E` at `q`.
    fn energy(&self, q: &[Vector3<Real>]) -> Result<Normal, Error> {
        let mut normal = Normal::new(3 * (self.space.count() - 2));
        let points = self.add_samples(q, &mut normal, true)?;
        self.add_repulsion(&points, &mut normal);
        Ok(normal)
    }

    /// Closeness (and, if `stretch`, unit-speed) residuals; returns the repulsion samples.
    fn add_samples(
        &self,
        q: &[Vector3<Real>],
        normal: &mut Normal,
        stretch: bool,
    ) -> Result<Vec<(Real, Vector3<Real>, BasisValues)>, Error> {
        let w = (self.s[1] - self.s[0]).sqrt();
        let anchor = w * ANCHOR_WEIGHT.sqrt() / self.size;
        let stride = (self.s.len() / REPULSION_SAMPLES).max(1);
        let mut b = BasisValues::default();
        let mut points = Vec::new();
        for (j, (&sj, &gj)) in self.s.iter().zip(&self.sigma).enumerate() {
            self.space.evaluate(sj, &mut b)?;
            let (c, t) = (b.combine(&b.value, q), b.combine(&b.d1, q));
            let p = self.target.at(gj);
            for k in 0..3 {
                let row = self.row(&b, |i, ck| (ck == k).then(|| anchor * b.value[i]));
                normal.add(anchor * (c[k] - p[k]), &row);
            }
            if stretch {
                let row = self.row(&b, |i, ck| Some(2.0 * w * t[ck] * b.d1[i]));
                normal.add(w * (t.norm_squared() - 1.0), &row);
            }
            if j % stride == 0 {
                points.push((sj, c, b));
            }
        }
        Ok(points)
    }

    /// Derivative entries `(unknown, f(k, c))` over the non-zero functions of `b`.
    fn row(&self, b: &BasisValues, f: impl Fn(usize, usize) -> Option<Real>) -> Vec<(usize, Real)> {
        (0..b.order)
            .flat_map(|k| (0..3).map(move |c| (k, c)))
            .filter_map(|(k, c)| Some((self.unknown(b.first + k, c)?, f(k, c)?)))
            .collect()
    }

    /// Repulsion residuals between samples more than `ℓ` apart in `s` and closer than `D`.
    fn add_repulsion(&self, points: &[(Real, Vector3<Real>, BasisValues)], normal: &mut Normal) {
        let h = points[1].0 - points[0].0;
        let weight = h * (REPULSION_WEIGHT / self.size).sqrt();
        let (reach, near) = (REPULSION_DISTANCE * self.size, NEIGHBOURHOOD * self.size);
        for (i, (si, ci, bi)) in points.iter().enumerate() {
            for (sj, cj, bj) in &points[i + 1..] {
                let d = (ci - cj).norm();
                if sj - si <= near || d >= reach || d == 0.0 {
                    continue;
                }
                let g = (ci - cj) * (-weight / (reach * d));
                let mut row = self.row(bi, |k, c| Some(bi.value[k] * g[c]));
                row.extend(self.row(bj, |k, c| Some(-bj.value[k] * g[c])));
                normal.add(weight * (1.0 - d / reach), &row);
            }
        }
    }
}

/// `C'(s)` of the curve with control points `q` on `space`.
fn derivative(
    space: &dyn BasisSpace,
    q: &[Vector3<Real>],
    s: Real,
) -> Result<Vector3<Real>, Error> {
    let mut b = BasisValues::default();
    space.evaluate(s, &mut b)?;
    Ok(b.combine(&b.d1, q))
}

/// Arclength \\(\int |C'(s)|\, ds\\) by 8-point Gauss–Legendre per span.
fn arclength(q: &[Vector3<Real>], space: &BSplineSpace) -> Result<Real, Error> {
    let rule = GaussLegendre::new(8);
    let mut total = 0.0;
    for span in spans(space) {
        let h = span.end - span.start;
        for (x, w) in rule.nodes.iter().zip(&rule.weights) {
            total += w * h * derivative(space, q, span.start + x * h)?.norm();
        }
    }
    Ok(total)
}

/// `count ≥ 2` points of the curve, uniform in `s` over the domain, with their `s`.
pub(super) fn sample_curve(
    space: &dyn BasisSpace,
    q: &[Vector3<Real>],
    count: usize,
) -> Result<(Vec<Real>, Vec<Vector3<Real>>), Error> {
    let (start, end) = space.domain();
    let s: Vec<Real> = (0..count)
        .map(|i| (start + (end - start) * i as Real / (count - 1) as Real).min(end))
        .collect();
    let mut b = BasisValues::default();
    let mut points = Vec::with_capacity(count);
    for &si in &s {
        space.evaluate(si, &mut b)?;
        points.push(b.combine(&b.value, q));
    }
    Ok((s, points))
}
