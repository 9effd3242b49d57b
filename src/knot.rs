//! Knot tying (Lenoir et al. 2005, §5.2): a loose overhand knot as the initial shape of
//! a clamped B-spline rod, the crossings of a rod's projection, and how tight a knot is.
//!
//! ```
//! use nalgebra::Vector3;
//! use splinerod::knot::{is_trefoil_diagram, overhand_knot, projection_crossings, tightness};
//!
//! // The paper's fixed-resolution run: 11 cubic control points, a 0.1 m knot.
//! let rod = overhand_knot(&Default::default())?.rod(0.01)?;
//! let crossings = projection_crossings(&rod, Vector3::y(), 400)?; // seen from above
//! assert!(is_trefoil_diagram(&crossings));
//! let knot = tightness(&rod, Vector3::y(), 400)?.expect("knotted");
//! assert!(knot.knot_length < rod.material().rest_length);
//! # Ok::<(), splinerod::Error>(())
//! ```
//!
//! # The overhand knot ([`overhand_knot`])
//!
//! In knot units the target curve starts from the trefoil
//! \\[ T(t) = (a, b, h) = (\sin t + 2\sin 2t,\; \cos t - 2\cos 2t,\; -H \sin 3t), \\]
//! whose projection on the `(a, b)` plane has three crossings at radius 1.5 and three
//! lobes reaching radius 3, the strands at a crossing being at heights \\(\pm 0.73 H\\)
//! (`H` = 1.25). The bottom lobe, tip \\(T(\pi) = (0, -3)\\), is opened: the arc
//! \\(|t - \pi| < t_c\\) is removed, where its strands are vertical (\\(da/dt = 0\\),
//! \\(\cos(\pi - t_c) = (-1-\sqrt{129})/16\\), \\(t_c \approx 0.689\\)), just below the two
//! crossings that bound the lobe. Each cut end continues into a quarter circle of radius
//! 2 turning it outwards into a straight tail along `±a`, its height easing to 0 (cubic
//! Hermite matching the cut's height and slope). The curve runs from the `−a` tail through
//! the trefoil (`t` from \\(3\pi - t_c\\) down to \\(\pi + t_c\\)) to the `+a` tail, so it
//! keeps the trefoil's three crossings, alternating over and under. World coordinates are
//! \\((x, y, z) = k\,(a,\ h,\ b_\text{tail} - b)\\), \\(k = \text{size}/6\\) (`size` is the
//! outer diameter of the knot's projection): the knot lies flat, perpendicular to gravity
//! `−y`, three crossings are seen from above (`+y`), and the ends are `(±span/2, 0, 0)`.
//!
//! That target `P(σ)`, `σ` its arclength in `[0, Λ]`, is first fitted by least squares on
//! `m` uniform parameters (\\(C(s_j) \approx P(\sigma_j)\\), clamped uniform knots on
//! `[0, Λ]`, ends interpolated). With few control points such a fit cuts corners: it is
//! slower than 1 there and brings strands together. So it is then relaxed by
//! Levenberg–Marquardt on
//! \\[ E(q) = \int (|C'|^2 - 1)^2 ds
//!     + \mu \int \frac{|C(s) - P(\sigma(s))|^2}{\text{size}^2} ds
//!     + \frac{\kappa}{\text{size}} \iint_{|s - s'| > \ell}
//!       \Big(1 - \frac{|C(s) - C(s')|}{D}\Big)_+^2 ds\, ds' \\]
//!
//! (unit speed; near the target, \\(\sigma(s)\\) being the closest target point, updated
//! every iteration so the curve may slide along it; strands at least `D` apart), with
//! `μ = 0.3`, `κ = 30`, `D = 0.35 size`, `ℓ = 0.9 size`. Finally the knots are scaled to
//! `[0, L]`, `L` the B-spline's own arclength, so the mean of \\(|C'(s)|\\) is exactly 1,
//! and the curve is checked to be knotted (a trefoil diagram seen along `+y`, see
//! [`is_trefoil_diagram`]).
//!
//! # Crossings ([`projection_crossings`])
//!
//! The rod is sampled as a polyline of `samples` points uniform in `s` and projected on
//! the plane normal to the unit direction `d`. Every pair of non-adjacent segments that
//! meet in projection is a [`Crossing`]; the strand with the larger coordinate along
//! `d` is over (the viewer sits at \\(+\infty\, d\\)). The crossing's sign is
//! \\(\operatorname{sign}((t_\text{over} \times t_\text{under}) \cdot d)\\), `+1` for a
//! right-handed crossing; it does not depend on the side the rod is seen from. All
//! pairs are tested, O(samples²): fine for a few hundred samples. These are the crossings
//! of the sampled polyline: the samples must be finer than the rod's sharpest bends
//! (chords across a near-corner of a degree-1 rod can cross each other).
//!
//! # Tightness ([`tightness`])
//!
//! The knot's extent is the material interval \\([s_\min, s_\max]\\) holding every
//! crossing coordinate; its length is the rest arclength inside the knot. As an overhand
//! knot tightens its loop contracts and the strands wrap closer round each other, so less
//! material lies between the first and the last crossing: the excess slides out through
//! the crossings into the tails, and the knot length decreases, as does the radius of the
//! ball holding the knot section.

use crate::Error;
use nalgebra::{DMatrix, DVector, Vector2, Vector3};
use splinerod_core::basis::spans;
use splinerod_core::{
    BSplineSpace, BasisSpace, BasisValues, GaussLegendre, Material, Real, Rod, MAX_DEGREE,
};
use std::f64::consts::PI;

/// Amplitude `H` of the trefoil's heights, knot units.
const HEIGHT: Real = 1.25;
/// Radius of the quarter circles joining the cut ends to the tails, knot units.
const BEND_RADIUS: Real = 2.0;
/// Outer diameter of the trefoil's projection, knot units (`size` in metres).
const KNOT_DIAMETER: Real = 6.0;
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
/// Most control points [`overhand_knot`] accepts: its fit is dense, O(n³) (refine the
/// rod afterwards by knot insertion instead).
pub const MAX_CONTROL_POINTS: usize = 200;
/// Polyline samples used to check that the B-spline is knotted.
const CHECK_SAMPLES: usize = 600;

/// Parameters of [`overhand_knot`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OverhandSpec {
    /// Outer diameter of the target knot's projection on the `xz` plane, m (the relaxed
    /// B-spline's knot is about as large, not exactly).
    pub size: Real,
    /// Distance between the two ends, m; must exceed [`OverhandSpec::min_span`].
    pub span: Real,
    /// Number of control points (`degree + 1` to [`MAX_CONTROL_POINTS`]).
    pub control_points: usize,
    /// Polynomial degree of the B-spline (1 to `MAX_DEGREE`).
    pub degree: usize,
}

impl Default for OverhandSpec {
    /// The paper's fixed-resolution run: 11 cubic control points (8 spans); a 0.1 m knot
    /// between ends 0.3 m apart.
    fn default() -> Self {
        Self {
            size: 0.1,
            span: 0.3,
            control_points: 11,
            degree: 3,
        }
    }
}

impl OverhandSpec {
    /// The knot's width without tails (≈ 1.11 `size`), m: `span` must exceed it.
    pub fn min_span(&self) -> Real {
        2.0 * (BEND_RADIUS - cut_point().x) * self.size / KNOT_DIAMETER
    }

    /// Error naming the first field out of range.
    pub fn validate(&self) -> Result<(), Error> {
        positive("size", self.size)?;
        positive("span", self.span)?;
        if !(1..=MAX_DEGREE).contains(&self.degree) {
            let reason = format!("must be 1 to {MAX_DEGREE}");
            return Err(Error::field("degree", self.degree, reason));
        }
        if !(self.degree + 1..=MAX_CONTROL_POINTS).contains(&self.control_points) {
            let reason = format!("must be degree + 1 to {MAX_CONTROL_POINTS}");
            return Err(Error::field("control_points", self.control_points, reason));
        }
        let min = self.min_span();
        if self.span <= min {
            let reason = format!("must exceed the knot's width {min:.4} m (≈ 1.11 size)");
            return Err(Error::field("span", self.span, reason));
        }
        Ok(())
    }
}

/// A clamped uniform B-spline rod shape holding a loose overhand knot.
#[derive(Debug, Clone, PartialEq)]
pub struct OverhandKnot {
    /// Control points, m, on `BSplineSpace::clamped_uniform(degree, n, rest_length)`.
    pub control_points: Vec<Vector3<Real>>,
    /// Rest length `L`, m: the B-spline's arclength.
    pub rest_length: Real,
    /// Polynomial degree.
    pub degree: usize,
}

impl OverhandKnot {
    /// The basis: clamped uniform knots on `[0, rest_length]`.
    pub fn basis(&self) -> Result<BSplineSpace, Error> {
        let n = self.control_points.len();
        Ok(BSplineSpace::clamped_uniform(
            self.degree,
            n,
            self.rest_length,
        )?)
    }

    /// A rod at rest in this shape with mass per unit length `linear_density`, kg/m.
    pub fn rod(&self, linear_density: Real) -> Result<Rod, Error> {
        let material = Material {
            rest_length: self.rest_length,
            linear_density,
        };
        let basis = Box::new(self.basis()?);
        Ok(Rod::new(material, basis, self.control_points.clone())?)
    }
}

/// Builds the overhand knot of `spec` (construction in the module docs). Fails naming
/// the field if `spec` is out of range, or `control_points` if they are too few for the
/// B-spline to stay knotted.
pub fn overhand_knot(spec: &OverhandSpec) -> Result<OverhandKnot, Error> {
    spec.validate()?;
    let target = Target::new(world_polyline(spec));
    if !(target.length().is_finite() && target.length() > 0.0) {
        return Err(Error::field(
            "size",
            spec.size,
            "is out of the representable range",
        ));
    }
    let mut fit = Fit::new(&target, spec)?;
    let mut q = fit.least_squares()?;
    let mut lambda = 1e-3;
    for _ in 0..RELAX_ITERATIONS {
        fit.project(&q)?;
        q = fit.relax_step(q, &mut lambda)?;
    }
    let rest_length = arclength(&q, &fit.space)?;
    let basis = BSplineSpace::clamped_uniform(spec.degree, q.len(), rest_length)?;
    let (s, points) = sample_curve(&basis, &q, CHECK_SAMPLES)?;
    if !is_trefoil_diagram(&polyline_crossings(&points, &s, &Vector3::y())) {
        let reason = "too few to hold the knot at this size and span (the B-spline is unknotted)";
        return Err(Error::field("control_points", q.len(), reason));
    }
    Ok(OverhandKnot {
        control_points: q,
        rest_length,
        degree: spec.degree,
    })
}

/// Error naming `field` unless `value` is finite and positive.
fn positive(field: &str, value: Real) -> Result<(), Error> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(Error::field(field, value, "must be finite and positive"))
    }
}

/// The trefoil `T(t)` in knot units, and `T'(t)`.
fn trefoil(t: Real) -> (Vector3<Real>, Vector3<Real>) {
    let (s1, c1, s2, c2) = (t.sin(), t.cos(), (2.0 * t).sin(), (2.0 * t).cos());
    let p = Vector3::new(s1 + 2.0 * s2, c1 - 2.0 * c2, -HEIGHT * (3.0 * t).sin());
    let v = Vector3::new(
        c1 + 4.0 * c2,
        4.0 * s2 - s1,
        -3.0 * HEIGHT * (3.0 * t).cos(),
    );
    (p, v)
}

/// Half-width `t_c` of the removed arc: `cos(π − t_c) = (−1 − √129)/16`.
fn cut_offset() -> Real {
    PI - ((-1.0 - 129.0_f64.sqrt()) / 16.0).acos()
}

/// The left cut point `T(π − t_c)`, where the curve enters the knot.
fn cut_point() -> Vector3<Real> {
    trefoil(PI - cut_offset()).0
}

/// Quarter circle from the cut point `p` (outward tangent `v`, heading down) to the tail
/// on side `side = ±1`, in outward order, `count + 1` points.
fn bend((p, v): (Vector3<Real>, Vector3<Real>), side: Real, count: usize) -> Vec<Vector3<Real>> {
    let length = 0.5 * PI * BEND_RADIUS;
    let slope = v.z / v.xy().norm();
    (0..=count)
        .map(|i| {
            let tau = i as Real / count as Real;
            let phi = 0.5 * PI * tau;
            let a = p.x + side * BEND_RADIUS * (1.0 - phi.cos());
            let b = p.y - BEND_RADIUS * phi.sin();
            let h00 = (2.0 * tau - 3.0) * tau * tau + 1.0;
            let h10 = ((tau - 2.0) * tau + 1.0) * tau;
            Vector3::new(a, b, p.z * h00 + length * slope * h10)
        })
        .collect()
}

/// Dense polyline of the open knot in knot units, from `a = −half` to `a = +half`.
fn knot_polyline(half: Real) -> Vec<Vector3<Real>> {
    const ARC: usize = 3000;
    const BEND: usize = 200;
    let tc = cut_offset();
    let (left, right) = (trefoil(PI - tc), trefoil(PI + tc));
    let tail_b = left.0.y - BEND_RADIUS;
    let mut points = vec![Vector3::new(-half, tail_b, 0.0)];
    points.extend(bend(left, -1.0, BEND).iter().rev());
    let (t0, t1) = (3.0 * PI - tc, PI + tc);
    points.extend((1..ARC).map(|i| trefoil(t0 + (t1 - t0) * i as Real / ARC as Real).0));
    points.extend(bend((right.0, -right.1), 1.0, BEND));
    points.push(Vector3::new(half, tail_b, 0.0));
    points
}

/// The knot polyline in metres: `(x, y, z) = k (a, h, b_tail − b)`, `k = size / 6`.
fn world_polyline(spec: &OverhandSpec) -> Vec<Vector3<Real>> {
    let k = spec.size / KNOT_DIAMETER;
    let tail_b = cut_point().y - BEND_RADIUS;
    knot_polyline(0.5 * spec.span / k)
        .iter()
        .map(|p| Vector3::new(p.x, p.z, tail_b - p.y) * k)
        .collect()
}

/// A polyline parametrised by its arclength.
struct Target {
    points: Vec<Vector3<Real>>,
    arclength: Vec<Real>,
}

impl Target {
    fn new(points: Vec<Vector3<Real>>) -> Self {
        let mut arclength = vec![0.0];
        for w in points.windows(2) {
            arclength.push(arclength[arclength.len() - 1] + (w[1] - w[0]).norm());
        }
        Self { points, arclength }
    }

    fn length(&self) -> Real {
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
    ) -> Result<Vec<Vector3<Real>>, Error> {
        let normal = self.energy(&q)?;
        for _ in 0..20 {
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
fn sample_curve(
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

/// One crossing of a projected rod.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Crossing {
    /// Material coordinate of the strand on top (larger coordinate along the direction).
    pub s_over: Real,
    /// Material coordinate of the strand below.
    pub s_under: Real,
    /// Sign of the oriented crossing, \\(\operatorname{sign}((t_o \times t_u)\cdot d)\\).
    pub sign: i8,
    /// Height of the over strand above the under strand along the direction, m.
    pub gap: Real,
}

/// The crossings of `rod` seen along `direction` (module docs), ordered by the smaller of
/// their two coordinates. Fails if `samples < 2` or `direction` is zero or not finite.
pub fn projection_crossings(
    rod: &Rod,
    direction: Vector3<Real>,
    samples: usize,
) -> Result<Vec<Crossing>, Error> {
    let d = unit_direction(direction)?;
    let (s, points) = sample_rod(rod, samples)?;
    Ok(polyline_crossings(&points, &s, &d))
}

/// Error naming `direction` unless it is finite and non-zero; else its unit vector.
fn unit_direction(direction: Vector3<Real>) -> Result<Vector3<Real>, Error> {
    let norm = direction.norm();
    if norm.is_finite() && norm > 0.0 {
        Ok(direction / norm)
    } else {
        let value = format!("({}, {}, {})", direction.x, direction.y, direction.z);
        Err(Error::field(
            "direction",
            value,
            "must be finite and non-zero",
        ))
    }
}

/// `samples` points of the rod uniform in `s`, with their `s`.
fn sample_rod(rod: &Rod, samples: usize) -> Result<(Vec<Real>, Vec<Vector3<Real>>), Error> {
    if samples < 2 {
        return Err(Error::field("samples", samples, "must be at least 2"));
    }
    sample_curve(rod.basis(), &rod.positions, samples)
}

/// Crossings of the polyline `points` (at coordinates `s`) seen along unit `d`.
fn polyline_crossings(points: &[Vector3<Real>], s: &[Real], d: &Vector3<Real>) -> Vec<Crossing> {
    let helper = if d.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = d.cross(&helper).normalize();
    let e2 = d.cross(&e1);
    let flat: Vec<Vector2<Real>> = points
        .iter()
        .map(|p| Vector2::new(p.dot(&e1), p.dot(&e2)))
        .collect();
    let mut out = Vec::new();
    for i in 0..points.len().saturating_sub(1) {
        for j in i + 2..points.len() - 1 {
            if let Some((u, v)) = segment_intersection(&flat, i, j) {
                out.push(crossing(points, s, d, (i, u), (j, v)));
            }
        }
    }
    out
}

/// Parameters `(u, v) ∈ [0, 1)²` where projected segments `i` and `j` meet, if they do.
fn segment_intersection(flat: &[Vector2<Real>], i: usize, j: usize) -> Option<(Real, Real)> {
    let cross = |a: Vector2<Real>, b: Vector2<Real>| a.x * b.y - a.y * b.x;
    let (r, w) = (flat[i + 1] - flat[i], flat[j + 1] - flat[j]);
    let denom = cross(r, w);
    if denom == 0.0 {
        return None;
    }
    let c = flat[j] - flat[i];
    let (u, v) = (cross(c, w) / denom, cross(c, r) / denom);
    ((0.0..1.0).contains(&u) && (0.0..1.0).contains(&v)).then_some((u, v))
}

/// The crossing of segment `a.0` at fraction `a.1` with segment `b.0` at `b.1`.
fn crossing(
    points: &[Vector3<Real>],
    s: &[Real],
    d: &Vector3<Real>,
    a: (usize, Real),
    b: (usize, Real),
) -> Crossing {
    let at = |(k, u): (usize, Real)| {
        let p = points[k].lerp(&points[k + 1], u);
        (
            s[k] + (s[k + 1] - s[k]) * u,
            p.dot(d),
            points[k + 1] - points[k],
        )
    };
    let (mut over, mut under) = (at(a), at(b));
    if under.1 > over.1 {
        std::mem::swap(&mut over, &mut under);
    }
    let sign = if over.2.cross(&under.2).dot(d) >= 0.0 {
        1
    } else {
        -1
    };
    Crossing {
        s_over: over.0,
        s_under: under.0,
        sign,
        gap: over.1 - under.1,
    }
}

/// Whether the over/under events, sorted along `s`, alternate (over, under, over, …).
pub fn is_alternating(crossings: &[Crossing]) -> bool {
    let mut events: Vec<(Real, bool)> = crossings
        .iter()
        .flat_map(|c| [(c.s_over, true), (c.s_under, false)])
        .collect();
    events.sort_by(|a, b| a.0.total_cmp(&b.0));
    events.windows(2).all(|w| w[0].1 != w[1].1)
}

/// Whether `crossings` form the minimal diagram of an open trefoil (overhand knot):
/// three crossings of equal sign, alternating, and pairwise interleaved along `s` (the
/// Gauss code `1 2 3 1 2 3`; kinks would nest or separate instead).
pub fn is_trefoil_diagram(crossings: &[Crossing]) -> bool {
    let interval = |c: &Crossing| (c.s_over.min(c.s_under), c.s_over.max(c.s_under));
    let interleaved = |a: &Crossing, b: &Crossing| {
        let ((a0, a1), (b0, b1)) = (interval(a), interval(b));
        (a0 < b0 && b0 < a1) != (a0 < b1 && b1 < a1)
    };
    crossings.len() == 3
        && crossings.iter().all(|c| c.sign == crossings[0].sign)
        && is_alternating(crossings)
        && (0..3).all(|i| interleaved(&crossings[i], &crossings[(i + 1) % 3]))
}

/// The material interval `[s_min, s_max]` holding every crossing coordinate; `None`
/// without crossings.
pub fn knot_extent(crossings: &[Crossing]) -> Option<(Real, Real)> {
    crossings
        .iter()
        .flat_map(|c| [c.s_over, c.s_under])
        .fold(None, |acc, s| match acc {
            None => Some((s, s)),
            Some((lo, hi)) => Some((lo.min(s), hi.max(s))),
        })
}

/// How tight a knot is (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tightness {
    /// `s_max − s_min`: rest arclength inside the knot, m.
    pub knot_length: Real,
    /// Largest distance from the centroid of the knot section's samples to one of them, m.
    pub radius: Real,
    /// Number of crossings in the projection.
    pub crossings: usize,
}

/// Tightness of the knot seen along `direction` with a `samples`-point polyline; `None`
/// when the projection has no crossing (no knot). Fails like [`projection_crossings`].
pub fn tightness(
    rod: &Rod,
    direction: Vector3<Real>,
    samples: usize,
) -> Result<Option<Tightness>, Error> {
    let d = unit_direction(direction)?;
    let (s, points) = sample_rod(rod, samples)?;
    let crossings = polyline_crossings(&points, &s, &d);
    let Some((lo, hi)) = knot_extent(&crossings) else {
        return Ok(None);
    };
    let mut section = vec![rod.point(lo)?, rod.point(hi)?];
    section.extend(
        s.iter()
            .zip(&points)
            .filter(|(&si, _)| lo < si && si < hi)
            .map(|(_, p)| *p),
    );
    let centroid = section.iter().sum::<Vector3<Real>>() / section.len() as Real;
    let radius = section
        .iter()
        .map(|p| (p - centroid).norm())
        .fold(0.0, Real::max);
    Ok(Some(Tightness {
        knot_length: hi - lo,
        radius,
        crossings: crossings.len(),
    }))
}
