//! Local update of a rod's caches after one knot insertion or removal (paper §4.1–4.2).
//!
//! With the knot at index `k` of the refined knot vector and `lo = k − d − 1`, the basis
//! functions whose support has the knot strictly inside are old `lo .. lo + m_old` and
//! new `lo .. lo + m_new` (`m = d + 1` on the coarse side, `d + 2` on the refined side);
//! every other function is unchanged: index `j` stays `j` below `lo`, and becomes
//! `j + Δ` above (Δ = ±1). Their supports cover the parameter interval
//! \\([a, b] = [t'_{lo}, t'_{lo + m_{new} + d}]\\) of the new knots. So only
//!
//! * the quadrature points in `[a, b)` (at most `2d + 2` spans) are re-evaluated,
//! * the mass entries \\(M_{ij} = \int \mu b_i b_j\\) and lumped masses
//!   \\(m_i = \int \mu b_i\\) involving a changed function are recomputed from them,
//!
//! and the rest is moved by one index (a memory move, no arithmetic).

use crate::segments::Density;
use crate::{BasisSpace, CoreError, KnotMap, KnotOperation, QuadratureTable, Real, SymBanded};
use std::ops::Range;

/// What changed: function ranges (old and new indexing) and the parameter interval.
#[derive(Debug, Clone, PartialEq)]
pub struct ChangedRegion {
    /// Changed basis functions before the operation.
    pub old_functions: Range<usize>,
    /// Changed basis functions after the operation.
    pub new_functions: Range<usize>,
    /// Knot-span indices `k` (of the new knot vector) whose spans `[t_k, t_{k+1})` may
    /// carry a changed function.
    pub new_spans: Range<usize>,
    /// Parameter interval covered by those spans.
    pub interval: (Real, Real),
}

impl ChangedRegion {
    /// The region of `map`, applied to give `space` (the new basis).
    pub fn of(map: &KnotMap, space: &dyn BasisSpace) -> Self {
        let d = space.degree();
        let k = map.knot_index();
        let lo = k.saturating_sub(d + 1);
        let (m_old, m_new) = match map.operation() {
            KnotOperation::Insert => (d + 1, d + 2),
            KnotOperation::Remove => (d + 2, d + 1),
        };
        let knots = space.knots();
        let hi = (lo + m_new + d).min(knots.len() - 1);
        Self {
            old_functions: lo..(lo + m_old).min(map.old_count()),
            new_functions: lo..(lo + m_new).min(map.new_count()),
            new_spans: lo.max(d)..hi.min(space.count()),
            interval: (knots[lo], knots[hi]),
        }
    }
}

/// Updates `table`, `mass` and `lumped` (density `mu`, per segment) from the basis before `map` to
/// `space`, the basis after it.
pub fn update_caches(
    map: &KnotMap,
    space: &dyn BasisSpace,
    mu: Density<'_>,
    table: &mut QuadratureTable,
    mass: &mut SymBanded,
    lumped: &mut Vec<Real>,
) -> Result<(), CoreError> {
    let region = ChangedRegion::of(map, space);
    table.replace_spans(space, &region)?;
    mass.reindex(&region.old_functions, region.new_functions.len());
    let (start, end) = (region.old_functions.start, region.old_functions.end);
    lumped.splice(
        start..end,
        std::iter::repeat_n(0.0, region.new_functions.len()),
    );
    accumulate(table, &region, mu, mass, lumped);
    Ok(())
}

/// Adds the mass and lumped-mass contributions of the region's quadrature points for
/// every pair involving a changed function.
fn accumulate(
    table: &QuadratureTable,
    region: &ChangedRegion,
    mu: Density<'_>,
    mass: &mut SymBanded,
    lumped: &mut [Real],
) {
    let changed = &region.new_functions;
    for p in table.points_in(region.interval) {
        let qp = table.point(p);
        let mu = mu.at(qp.s);
        for a in 0..qp.value.len() {
            let i = qp.first + a;
            let wa = mu * qp.weight * qp.value[a];
            if changed.contains(&i) {
                lumped[i] += wa;
            }
            for b in a..qp.value.len() {
                let j = qp.first + b;
                if changed.contains(&i) || changed.contains(&j) {
                    mass.add(i, j, wa * qp.value[b]);
                }
            }
        }
    }
}
