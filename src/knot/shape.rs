//! The overhand knot's target curve (an opened trefoil with two tails, in the module
//! docs of [`crate::knot`]) and [`overhand_knot`], which fits and relaxes a B-spline on it.

use super::diagram::{is_trefoil_diagram, polyline_crossings};
use super::relax::{relaxed_fit, sample_curve, Target};
use crate::Error;
use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, Cancel, Material, Real, Rod, MAX_DEGREE};
use std::f64::consts::PI;

/// Amplitude `H` of the trefoil's heights, knot units.
const HEIGHT: Real = 1.25;
/// Radius of the quarter circles joining the cut ends to the tails, knot units.
const BEND_RADIUS: Real = 2.0;
/// Outer diameter of the trefoil's projection, knot units (`size` in metres).
const KNOT_DIAMETER: Real = 6.0;
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
        crate::scene::plausible::length("size", self.size)?;
        crate::scene::plausible::length("span", self.span)?;
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
    overhand_knot_cancellable(spec, &Cancel::none())
}

/// [`overhand_knot`], polling `cancel` during the fit (a few seconds for a hundred
/// control points): a stop asked returns [`Error::Interrupted`].
pub fn overhand_knot_cancellable(
    spec: &OverhandSpec,
    cancel: &Cancel,
) -> Result<OverhandKnot, Error> {
    spec.validate()?;
    let target = Target::new(world_polyline(spec));
    if !(target.length().is_finite() && target.length() > 0.0) {
        return Err(Error::field(
            "size",
            spec.size,
            "is out of the representable range",
        ));
    }
    let (q, rest_length) = relaxed_fit(&target, spec, cancel)?;
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
