//! Narrow phase of the proximity queries: [`closest_points`] between two spans.
//!
//! For spans `A` (parameter `s`) and `B` (parameter `t`) it minimises
//!
//! \\[ f(s, t) = \tfrac12 |r|^2, \qquad r = C(s) - C(t), \\]
//!
//! over the box \\(s \in A, t \in B\\). Gradient and Hessian are
//!
//! \\[ g = \begin{pmatrix} r \cdot C'(s) \\\\ -r \cdot C'(t) \end{pmatrix}, \qquad
//! H = \begin{pmatrix} C'(s)\cdot C'(s) + r \cdot C''(s) & -C'(s)\cdot C'(t) \\\\
//! -C'(s)\cdot C'(t) & C'(t)\cdot C'(t) - r \cdot C''(t) \end{pmatrix}. \\]
//!
//! The iteration starts from the best point of a 4 × 4 grid (ends included) and takes
//! projected Newton steps: a parameter at a bound whose gradient pushes it outwards is
//! held fixed (active) and the step minimises over the other one alone; the step is then
//! clamped to the box and halved until `f` does not increase. Where `H` is not positive
//! definite (far from the minimum, or parallel tangents, where the minimiser is not
//! unique) the step uses the Gauss–Newton matrix \\(J^T J\\), \\(J = [C'(s), -C'(t)]\\),
//! with a Levenberg shift of `1e-10` of its trace. It stops when both parameters move by
//! less than `1e-12` of their span lengths, when the model's predicted decrease
//! \\(-\tfrac12 g \cdot \Delta\\) falls below `1e-14 f` (the distance is then converged to
//! about `1e-14` relative: in the flat valley of parallel spans the parameters never
//! settle to `1e-12`, but the distance does), when no step decreases `f`, or after 50
//! steps. Convergence is quadratic near a non-degenerate minimum: the tests take 1 step
//! (corners) to 6. The minimum found is the global one when `f` has one local minimum
//! on the box, which holds for spans that are short compared with their radii of curvature.
//!
//! The curve is discontinuous at a cut and its derivatives at other knots, so a span is
//! evaluated on `[start, end⁻]`, `end⁻` being the largest float below `end`: the basis
//! of the span itself, never of the next one.

use crate::basis::{BasisValues, Span};
use crate::{CoreError, Real, Rod};
use nalgebra::Vector3;

/// Closest points between two spans, found by [`closest_points`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// Material coordinate on the first span, in `[start, end⁻]`.
    pub s: Real,
    /// Material coordinate on the second span, in `[start, end⁻]`.
    pub t: Real,
    /// Distance \\(|C(s) - C(t)|\\), m.
    pub distance: Real,
    /// Unit vector from \\(C(t)\\) to \\(C(s)\\). When the curves touch (`distance == 0`):
    /// the normalised \\(C'(s) \times C'(t)\\), or if that vanishes any unit vector normal
    /// to \\(C'(s)\\), or zero if the curve is degenerate there.
    pub normal: Vector3<Real>,
}

/// Most projected Newton steps [`closest_points`] takes.
const MAX_STEPS: usize = 50;
/// Points per span of the starting grid (ends included).
const GRID: usize = 4;
/// Relative step size (of the span lengths) at which the iteration stops.
const STEP_TOLERANCE: Real = 1e-12;
/// Predicted relative decrease of `f` at which the iteration stops: the distance is then
/// within about `1e-14` (relative) of the minimum, near the round-off floor.
const DECREASE_TOLERANCE: Real = 1e-14;
/// Most step halvings of the line search.
const MAX_HALVINGS: usize = 30;

/// Closest points \\(C(s), C(t)\\) between the curve pieces of `span_a` and `span_b`
/// (spans of `rod`'s basis, as listed by [`spans`](crate::basis::spans) or
/// [`SpanBoxes::spans`](super::SpanBoxes::spans)), by projected Newton from a grid
/// start (module docs). Errors if a span is not a non-empty knot span of the rod.
pub fn closest_points(rod: &Rod, span_a: &Span, span_b: &Span) -> Result<Closest, CoreError> {
    Ok(closest_points_counted(rod, span_a, span_b)?.0)
}

/// Closest points between the curve pieces on the parameter ranges `range_a` and
/// `range_b` (each `[lo, hi]` inside the domain, any number of knot spans): the same
/// iteration as [`closest_points`], with the curve evaluated through the basis at each
/// parameter. Across a knot of reduced continuity the derivatives are one-sided, which
/// at worst slows the iteration down. Errors if a range is empty, not finite or leaves
/// the domain.
pub fn closest_points_between(
    rod: &Rod,
    range_a: [Real; 2],
    range_b: [Real; 2],
) -> Result<Closest, CoreError> {
    let a = SpanCurve::range(rod, range_a)?;
    let b = SpanCurve::range(rod, range_b)?;
    Ok(solve(&a, &b)?.0)
}

/// [`closest_points`] and the number of Newton steps it took.
pub(crate) fn closest_points_counted(
    rod: &Rod,
    span_a: &Span,
    span_b: &Span,
) -> Result<(Closest, usize), CoreError> {
    let a = SpanCurve::new(rod, span_a)?;
    let b = SpanCurve::new(rod, span_b)?;
    solve(&a, &b)
}

/// The closest points of two span curves and the Newton steps taken.
fn solve(a: &SpanCurve, b: &SpanCurve) -> Result<(Closest, usize), CoreError> {
    let mut x = grid_start(a, b)?;
    for step in 1..=MAX_STEPS {
        let (next, converged) = newton_step(a, b, &x)?;
        x = next;
        if converged {
            return Ok((x.closest(), step));
        }
    }
    Ok((x.closest(), MAX_STEPS))
}

/// One span of a rod, evaluated on `[lo, hi]` with `hi = end⁻`.
struct SpanCurve<'a> {
    rod: &'a Rod,
    lo: Real,
    hi: Real,
}

/// Position and first two derivatives of the curve at one parameter.
#[derive(Clone, Copy)]
struct Jet {
    p: Vector3<Real>,
    d1: Vector3<Real>,
    d2: Vector3<Real>,
}

impl<'a> SpanCurve<'a> {
    fn new(rod: &'a Rod, span: &Span) -> Result<Self, CoreError> {
        let hi = f64::from_bits(span.end.to_bits().saturating_sub(1)).max(span.start);
        let k = span.first + rod.basis().degree();
        let knots = rod.basis().knots().get(k..=k + 1);
        let non_empty = span.end > span.start;
        if !non_empty || knots != Some(&[span.start, span.end][..]) {
            return Err(CoreError::InvalidParameter {
                name: "span.start",
                value: span.start,
                reason: "not a non-empty knot span of the rod's basis",
            });
        }
        Ok(Self {
            rod,
            lo: span.start,
            hi,
        })
    }

    /// The curve on `[lo, hi]`, which must lie in the domain.
    fn range(rod: &'a Rod, [lo, hi]: [Real; 2]) -> Result<Self, CoreError> {
        let (start, end) = rod.basis().domain();
        if !(start <= lo && lo <= hi && hi <= end) {
            return Err(CoreError::InvalidParameter {
                name: "range",
                value: lo,
                reason: "must be a finite non-empty interval inside the domain",
            });
        }
        Ok(Self { rod, lo, hi })
    }

    fn length(&self) -> Real {
        self.hi - self.lo
    }

    fn clamp(&self, s: Real) -> Real {
        s.clamp(self.lo, self.hi)
    }

    /// The curve's point at `s` (the `p` of [`Self::jet`], bit for bit).
    fn point(&self, s: Real) -> Result<Vector3<Real>, CoreError> {
        let mut b = BasisValues::default();
        self.rod.basis().evaluate_values(self.clamp(s), &mut b)?;
        Ok(b.combine(&b.value, &self.rod.positions))
    }

    fn jet(&self, s: Real) -> Result<Jet, CoreError> {
        let mut b = BasisValues::default();
        self.rod.basis().evaluate(self.clamp(s), &mut b)?;
        let q = &self.rod.positions;
        Ok(Jet {
            p: b.combine(&b.value, q),
            d1: b.combine(&b.d1, q),
            d2: b.combine(&b.d2, q),
        })
    }

    /// Where `s` sits in the box: -1 at `lo`, 1 at `hi`, 0 inside.
    fn side(&self, s: Real) -> i8 {
        if s <= self.lo {
            -1
        } else if s >= self.hi {
            1
        } else {
            0
        }
    }
}

/// An iterate: parameters and the jets there.
#[derive(Clone, Copy)]
struct Iterate {
    s: Real,
    t: Real,
    a: Jet,
    b: Jet,
}

impl Iterate {
    fn at(a: &SpanCurve, b: &SpanCurve, s: Real, t: Real) -> Result<Self, CoreError> {
        let (s, t) = (a.clamp(s), b.clamp(t));
        Ok(Self {
            s,
            t,
            a: a.jet(s)?,
            b: b.jet(t)?,
        })
    }

    fn r(&self) -> Vector3<Real> {
        self.a.p - self.b.p
    }

    fn f(&self) -> Real {
        0.5 * self.r().norm_squared()
    }

    fn closest(&self) -> Closest {
        let r = self.r();
        let distance = r.norm();
        let normal = if distance > 0.0 {
            r / distance
        } else {
            contact_normal(&self.a.d1, &self.b.d1)
        };
        Closest {
            s: self.s,
            t: self.t,
            distance,
            normal,
        }
    }
}

/// Normal for touching curves: normalised `ta × tb`, else any unit normal of `ta`.
fn contact_normal(ta: &Vector3<Real>, tb: &Vector3<Real>) -> Vector3<Real> {
    let cross = ta.cross(tb);
    if let Some(n) = cross.try_normalize(0.0) {
        return n;
    }
    let helper = Vector3::ith(ta.iamin(), 1.0);
    ta.cross(&helper).try_normalize(0.0).unwrap_or_default()
}

/// Best pair of a `GRID × GRID` grid of parameters, ends included.
fn grid_start<'a>(a: &SpanCurve<'a>, b: &SpanCurve<'a>) -> Result<Iterate, CoreError> {
    let at = |c: &SpanCurve, k: usize| c.lo + c.length() * k as Real / (GRID - 1) as Real;
    let mut pb = [Vector3::zeros(); GRID];
    for (k, p) in pb.iter_mut().enumerate() {
        *p = b.point(at(b, k))?;
    }
    let (mut best, mut best_d) = ((0, 0), Real::INFINITY);
    for i in 0..GRID {
        let pa = a.point(at(a, i))?;
        for (j, p) in pb.iter().enumerate() {
            let d = (pa - p).norm_squared();
            if d < best_d {
                (best, best_d) = ((i, j), d);
            }
        }
    }
    Iterate::at(a, b, at(a, best.0), at(b, best.1))
}

/// One projected Newton step with backtracking: the new iterate and whether the
/// iteration has converged (both parameters held at a corner, a step below
/// [`STEP_TOLERANCE`], a predicted decrease below [`DECREASE_TOLERANCE`], or no
/// decrease at all).
fn newton_step(a: &SpanCurve, b: &SpanCurve, x: &Iterate) -> Result<(Iterate, bool), CoreError> {
    let r = x.r();
    let (ta, tb) = (x.a.d1, x.b.d1);
    let g = [r.dot(&ta), -r.dot(&tb)];
    let cross = -ta.dot(&tb);
    let gn = [[ta.norm_squared(), cross], [cross, tb.norm_squared()]];
    let h = [
        [gn[0][0] + r.dot(&x.a.d2), cross],
        [cross, gn[1][1] - r.dot(&x.b.d2)],
    ];
    // Held: at a bound with the gradient pointing outwards (descent leaves the box).
    let held = [held(a.side(x.s), g[0]), held(b.side(x.t), g[1])];
    if held[0] && held[1] {
        return Ok((*x, true));
    }
    let step = direction(h, gn, g, held);
    let f0 = x.f();
    // Decrease of the quadratic model, -g·Δ/2 = f - f* for an exact model.
    let negligible = -0.5 * (g[0] * step[0] + g[1] * step[1]) <= DECREASE_TOLERANCE * f0;
    let mut scale = 1.0;
    for _ in 0..MAX_HALVINGS {
        let next = Iterate::at(a, b, x.s + scale * step[0], x.t + scale * step[1])?;
        if next.f() <= f0 {
            let small = (next.s - x.s).abs() <= STEP_TOLERANCE * a.length()
                && (next.t - x.t).abs() <= STEP_TOLERANCE * b.length();
            return Ok((next, small || negligible));
        }
        if negligible {
            break;
        }
        scale *= 0.5;
    }
    Ok((*x, true))
}

/// Whether a parameter at `side` of its box with gradient `g` stays on its bound.
fn held(side: i8, g: Real) -> bool {
    (side < 0 && g > 0.0) || (side > 0 && g < 0.0)
}

/// Newton direction on the free parameters: `H` if positive definite on them, else the
/// Gauss–Newton matrix `gn` with a Levenberg shift. Held parameters do not move.
fn direction(h: [[Real; 2]; 2], gn: [[Real; 2]; 2], g: [Real; 2], held: [bool; 2]) -> [Real; 2] {
    let restrict = |m: [[Real; 2]; 2]| {
        let mut m = m;
        for k in 0..2 {
            if held[k] {
                m[k] = [0.0, 0.0];
                m[0][k] = 0.0;
                m[1][k] = 0.0;
                m[k][k] = 1.0;
            }
        }
        m
    };
    let g = [
        if held[0] { 0.0 } else { g[0] },
        if held[1] { 0.0 } else { g[1] },
    ];
    let h = restrict(h);
    if let Some(step) = solve_spd(h, g) {
        return step;
    }
    let mut m = restrict(gn);
    let shift = 1e-10 * (m[0][0] + m[1][1]) + Real::MIN_POSITIVE;
    m[0][0] += shift;
    m[1][1] += shift;
    solve_spd(m, g).unwrap_or([0.0, 0.0])
}

/// Solves `m x = -g` if `m` is (safely) symmetric positive definite.
fn solve_spd(m: [[Real; 2]; 2], g: [Real; 2]) -> Option<[Real; 2]> {
    let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
    let safe = m[0][0] > 0.0 && m[1][1] > 0.0 && det > 1e-12 * m[0][0] * m[1][1];
    safe.then(|| {
        [
            -(m[1][1] * g[0] - m[0][1] * g[1]) / det,
            -(m[0][0] * g[1] - m[1][0] * g[0]) / det,
        ]
    })
}
