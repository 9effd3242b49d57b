//! Crossings of a rod's projection, the trefoil diagram test, and a knot's tightness
//! (module docs of [`crate::knot`]).

use super::relax::sample_curve;
use crate::Error;
use nalgebra::{Vector2, Vector3};
use splinerod_core::{Real, Rod};

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
pub(super) fn polyline_crossings(
    points: &[Vector3<Real>],
    s: &[Real],
    d: &Vector3<Real>,
) -> Vec<Crossing> {
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

/// A rod seen along a direction: its crossings and, if there are any, how tight the knot
/// is. One sampling and one crossing search serve both.
#[derive(Debug, Clone, PartialEq)]
pub struct KnotDiagram {
    /// The crossings of the projection, as [`projection_crossings`] gives them.
    pub crossings: Vec<Crossing>,
    /// The knot's tightness; `None` without crossings (no knot).
    pub tightness: Option<Tightness>,
}

/// The diagram of `rod` seen along `direction` with a `samples`-point polyline. Fails
/// like [`projection_crossings`].
pub fn knot_diagram(
    rod: &Rod,
    direction: Vector3<Real>,
    samples: usize,
) -> Result<KnotDiagram, Error> {
    let d = unit_direction(direction)?;
    let (s, points) = sample_rod(rod, samples)?;
    let crossings = polyline_crossings(&points, &s, &d);
    let Some((lo, hi)) = knot_extent(&crossings) else {
        return Ok(KnotDiagram {
            crossings,
            tightness: None,
        });
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
    let tightness = Some(Tightness {
        knot_length: hi - lo,
        radius,
        crossings: crossings.len(),
    });
    Ok(KnotDiagram {
        crossings,
        tightness,
    })
}

/// Tightness of the knot seen along `direction` with a `samples`-point polyline; `None`
/// when the projection has no crossing (no knot). Fails like [`projection_crossings`].
pub fn tightness(
    rod: &Rod,
    direction: Vector3<Real>,
    samples: usize,
) -> Result<Option<Tightness>, Error> {
    Ok(knot_diagram(rod, direction, samples)?.tightness)
}

/// The determinant \\(|\Delta(-1)|\\) of the knot whose diagram has `crossings` (3 for a
/// trefoil, 1 for the unknot): a knot invariant, unchanged by any motion that does not
/// pass a strand through another. The open rod is closed far away, which adds no
/// crossing when its ends point outwards (the tails of [`overhand_knot`](super::overhand_knot)
/// leave along ±x, seen from above). Arc `k` runs from the `k`-th under-crossing along
/// `s` to the next (the last joins the first through the closure); each crossing gives
/// the coloring-matrix row 2 at its over arc and −1 at each of its two under arcs, and
/// the determinant is that of any `(n − 1)`-minor. Crossings must come from one generic
/// projection (as [`projection_crossings`] gives).
pub fn knot_determinant(crossings: &[Crossing]) -> i64 {
    let n = crossings.len();
    if n < 2 {
        return 1;
    }
    let mut unders: Vec<Real> = crossings.iter().map(|c| c.s_under).collect();
    unders.sort_by(Real::total_cmp);
    let arc = |s: Real| unders.partition_point(|&u| u < s) % n;
    let mut m = nalgebra::DMatrix::<Real>::zeros(n, n);
    for (k, c) in crossings.iter().enumerate() {
        let incoming = arc(c.s_under);
        m[(k, arc(c.s_over))] += 2.0;
        m[(k, incoming)] -= 1.0;
        m[(k, (incoming + 1) % n)] -= 1.0;
    }
    let minor = m.view((0, 0), (n - 1, n - 1)).into_owned();
    minor.determinant().abs().round() as i64
}
