//! Several rods as one: [`Rod::join`] puts rods of one degree end to end in parameter
//! space, separated by cuts (knots of multiplicity `d + 1`, see [`Rod::cut`]), so
//! that one Newton matrix, one contact detection and one adapt step serve them all
//! while no basis function, mass entry or span-wise energy couples two of them.
//!
//! Rod `k` of lengths \\(L_0, L_1, \dots\\) occupies the parameter interval
//! \\([o_k, o_k + L_k]\\) with \\(o_k = \sum_{j<k} L_j\\); its material point `s`
//! (\\(0 \le s \le L_k\\)) is the joined rod's \\(o_k + s\\). Each keeps its own linear
//! density and damping ([`Segment`]):
//!
//! * mass \\(M_{ij} = \int \mu(s)\, b_i b_j\\) with \\(\mu\\) constant on each segment;
//! * damping \\(-D \dot q\\) with \\(D = \operatorname{diag}(\alpha_i) M\\), \\(\alpha_i\\)
//!   the damping of the segment that holds control point `i`. `M` is block diagonal
//!   over the segments, so `diag(α)` commutes with it and `D` is symmetric: each rod
//!   is damped exactly as it would be alone.
//!
//! Knot changes keep the segments: their end points are cuts, which insertion cannot
//! remove and removal never touches ([`Rod::segment_at`] tells a caller which rod the
//! parameter of a change belongs to).

use crate::{BSplineSpace, CoreError, Material, Real, Rod};
use std::ops::Range;

/// One rod of a joined rod: its parameter interval and the material constants the core
/// needs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Segment {
    /// Parameter where it starts (its material point `s = 0`).
    pub start: Real,
    /// Parameter where it ends (`start` + its rest length).
    pub end: Real,
    /// Mass per unit rest length `μ`, kg/m.
    pub linear_density: Real,
    /// Mass-proportional damping `α`, 1/s.
    pub damping: Real,
}

impl Segment {
    /// Rest length, m.
    pub fn rest_length(&self) -> Real {
        self.end - self.start
    }
}

/// Linear density at parameter values: one value, or one per segment.
#[derive(Debug, Clone, Copy)]
pub struct Density<'a> {
    /// The density without segments, kg/m.
    pub uniform: Real,
    /// The segments, whose densities apply when there are any.
    pub segments: &'a [Segment],
}

impl Density<'_> {
    /// `μ(s)`; for `s` on a junction, the segment that starts there.
    pub fn at(&self, s: Real) -> Real {
        if self.segments.is_empty() {
            return self.uniform;
        }
        self.segments[segment_index(self.segments, s)].linear_density
    }
}

/// The largest float below `x` (`f64::next_down`, for the supported Rust versions).
pub fn just_below(x: Real) -> Real {
    if x.is_nan() || x == Real::NEG_INFINITY {
        x
    } else if x == 0.0 {
        -Real::from_bits(1)
    } else if x > 0.0 {
        Real::from_bits(x.to_bits() - 1)
    } else {
        Real::from_bits(x.to_bits() + 1)
    }
}

/// The joined parameter of material point `s` of a segment on `[start, end]`: `start + s`,
/// or, when another segment `follows` and that reaches the junction, the float just below
/// it ([`Rod::joined_coordinate`]). The one rule for scenes and rods alike.
pub fn on_segment(start: Real, end: Real, s: Real, follows: bool) -> Real {
    let at = start + s;
    if follows && at >= end {
        just_below(end)
    } else {
        at
    }
}

/// Index of the segment holding `s` (the later one on a junction; clamped to the ends).
fn segment_index(segments: &[Segment], s: Real) -> usize {
    segments
        .partition_point(|g| g.end <= s)
        .min(segments.len() - 1)
}

impl Rod {
    /// The rods of `parts`, end to end in parameter space, as one rod whose pieces are
    /// separated by cuts (module docs): positions, velocities, each part's density and
    /// damping carried over exactly. Every part must be a clamped B-spline (first and
    /// last knots of multiplicity `d + 1`) of the same degree and quadrature. One part
    /// gives a rod equal to it with one segment.
    pub fn join(parts: &[Rod]) -> Result<Rod, CoreError> {
        let first = parts.first().ok_or(CoreError::InvalidParameter {
            name: "rods",
            value: 0.0,
            reason: "joining needs at least one rod",
        })?;
        let d = first.basis().degree();
        let mut knots: Vec<Real> = Vec::new();
        let (mut positions, mut velocities) = (Vec::new(), Vec::new());
        let mut segments = Vec::with_capacity(parts.len());
        let mut offset = 0.0;
        for part in parts {
            check_joinable(part, d, first.quadrature().points_per_span())?;
            let own = part.basis().knots();
            let length = part.material().rest_length;
            let (skip, last) = (if knots.is_empty() { 0 } else { d + 1 }, own.len() - d - 1);
            // The clamped ends exactly at the segment's ends (a part's last knots may
            // differ from its rest length by a rounding).
            knots.extend(own.iter().enumerate().skip(skip).map(|(i, t)| match i {
                i if i <= d => offset,
                i if i >= last => offset + length,
                _ => offset + t,
            }));
            positions.extend_from_slice(&part.positions);
            velocities.extend_from_slice(&part.velocities);
            segments.push(Segment {
                start: offset,
                end: offset + length,
                linear_density: part.material().linear_density,
                damping: part.damping,
            });
            offset += length;
        }
        let material = Material {
            rest_length: offset,
            linear_density: first.material().linear_density,
        };
        let basis = BSplineSpace::new(d, knots)?;
        let mut rod = Rod::with_segments(material, Box::new(basis), positions, segments)?;
        rod = rod.with_quadrature_points(first.quadrature().points_per_span())?;
        rod.velocities = velocities;
        rod.damping = first.damping;
        Ok(rod)
    }

    /// Segment `k` as a rod of its own (domain `[0, end − start]`, knots shifted by
    /// `−start`, the same quadrature, positions, velocities, density and damping): what
    /// energies of one part see ([`Rod::join`] inverted).
    pub fn segment_rod(&self, k: usize) -> Result<Rod, CoreError> {
        let g = self.segments.get(k).ok_or(CoreError::InvalidParameter {
            name: "segment",
            value: k as Real,
            reason: "no such segment",
        })?;
        let range = self.segment_points(k);
        let d = self.basis().degree();
        let knots = &self.basis().knots()[range.start..range.end + d + 1];
        let knots = knots.iter().map(|t| t - g.start).collect();
        let material = Material {
            rest_length: g.rest_length(),
            linear_density: g.linear_density,
        };
        let basis = BSplineSpace::new(d, knots)?;
        let positions = self.positions[range.clone()].to_vec();
        let mut rod = Rod::new(material, Box::new(basis), positions)?
            .with_quadrature_points(self.quadrature().points_per_span())?;
        rod.velocities.copy_from_slice(&self.velocities[range]);
        rod.damping = g.damping;
        Ok(rod)
    }

    /// The joined rod's parameter of material point `s` (m, `0 ≤ s ≤ L_k`) of segment
    /// `k`. A segment's end shares its parameter with the next one's start, where the
    /// curve takes the next segment's value; so the end of every segment but the last
    /// is the largest float below the junction, where every basis function of the
    /// segment equals its end value to round-off (the last control point's weight is 1
    /// to within `ε L/h`). Without segments: `s`.
    pub fn joined_coordinate(&self, k: usize, s: Real) -> Real {
        match self.segments.get(k) {
            None => s,
            Some(g) => on_segment(g.start, g.end, s, k + 1 < self.segments.len()),
        }
    }

    /// Whether `at` is the start (`Some(true)`) or the end (`Some(false)`) of its segment
    /// (of the rod without segments), in the sense of [`Rod::joined_coordinate`].
    pub fn segment_end(&self, at: Real) -> Option<bool> {
        let (start, end) = match self.segments.get(self.segment_at(at)) {
            Some(g) => (g.start, g.end),
            None => self.basis().domain(),
        };
        if at == start {
            Some(true)
        } else if at == end || at == just_below(end) {
            Some(false)
        } else {
            None
        }
    }

    /// The segments (rods of [`Rod::join`]); empty for a rod built on its own.
    pub fn segments(&self) -> &[Segment] {
        &self.segments
    }

    /// Index of the segment holding parameter `s` (0 without segments).
    pub fn segment_at(&self, s: Real) -> usize {
        if self.segments.is_empty() {
            0
        } else {
            segment_index(&self.segments, s)
        }
    }

    /// Control points of segment `k` (all of them without segments): the basis functions
    /// supported on its interval. O(log n).
    pub fn segment_points(&self, k: usize) -> Range<usize> {
        let Some(g) = self.segments.get(k) else {
            return 0..self.len();
        };
        let (knots, d) = (self.basis().knots(), self.basis().degree());
        let first = if k == 0 {
            0
        } else {
            knots.partition_point(|&t| t < g.start)
        };
        let end = if k + 1 == self.segments.len() {
            self.len()
        } else {
            knots.partition_point(|&t| t <= g.end) - d - 1
        };
        first..end
    }

    /// Damping `α` of control point `i`: its segment's, or [`Rod::damping`] without
    /// segments.
    pub fn damping_at(&self, i: usize) -> Real {
        if self.segments.is_empty() {
            self.damping
        } else {
            // The middle of the support: strictly inside one segment (a Greville
            // abscissa sits on the junction for a part's last control point).
            let (knots, d) = (self.basis().knots(), self.basis().degree());
            let middle = 0.5 * (knots[i] + knots[i + d + 1]);
            self.segments[segment_index(&self.segments, middle)].damping
        }
    }

    /// The damping when it is the same for every control point (always without
    /// segments); `None` when segments differ.
    pub fn uniform_damping(&self) -> Option<Real> {
        match self.segments.split_first() {
            None => Some(self.damping),
            Some((g, rest)) => rest
                .iter()
                .all(|h| h.damping == g.damping)
                .then_some(g.damping),
        }
    }
}

/// Errors unless `part` is a clamped rod of degree `d` with `points` quadrature points.
fn check_joinable(part: &Rod, d: usize, points: usize) -> Result<(), CoreError> {
    let degree = part.basis().degree();
    if degree != d {
        return Err(CoreError::InvalidParameter {
            name: "degree",
            value: degree as Real,
            reason: "rods joined in one system must share one degree",
        });
    }
    if part.quadrature().points_per_span() != points {
        return Err(CoreError::InvalidParameter {
            name: "quadrature points per span",
            value: part.quadrature().points_per_span() as Real,
            reason: "rods joined in one system must share one quadrature",
        });
    }
    let knots = part.basis().knots();
    let (start, end) = part.basis().domain();
    let clamped = knots[..=d].iter().all(|&t| t == start)
        && knots[knots.len() - d - 1..].iter().all(|&t| t == end);
    if !clamped || !part.segments.is_empty() {
        return Err(CoreError::InvalidParameter {
            name: "knots",
            value: start,
            reason: "only clamped rods without segments can be joined",
        });
    }
    Ok(())
}
