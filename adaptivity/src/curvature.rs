//! The curvature criterion (paper eq. 13) read as a disturbance measure on the control
//! polygon: at interior control point `i`, with φ_i the turning angle between the edges
//! \\(P_{i-1}P_i\\) and \\(P_iP_{i+1}\\),
//!
//! \\[ c_i = \tfrac12 (1 - \cos\varphi_i) = \sin^2(\varphi_i / 2) \in [0, 1], \\]
//!
//! 0 where the polygon is straight, 1 where it folds back. A span between control points
//! `i` and `i + 1` is refined at the parameter midway between their Greville abscissae
//! when both `c_i` and `c_{i+1}` exceed `insert_threshold`; an interior knot is proposed
//! for removal when every control point it influences has `c < remove_threshold` (the
//! adapt step then removes it only if the shape moves by at most its tolerance).
//! Control-polygon edges shorter than `1e-12 · L` count as straight.

use crate::{AdaptError, Refinement, RefinementCriterion};
use splinerod_core::basis::greville;
use splinerod_core::{Real, Rod};

/// Refines where the control polygon turns, coarsens where it is straight.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurvatureCriterion {
    /// Insert when `c_i` and `c_{i+1}` exceed this (default 0.05, a turn of about 26°).
    pub insert_threshold: Real,
    /// Propose removal when all influenced `c` are below this (default 0.005, about 8°).
    pub remove_threshold: Real,
}

impl Default for CurvatureCriterion {
    fn default() -> Self {
        Self {
            insert_threshold: 0.05,
            remove_threshold: 0.005,
        }
    }
}

impl CurvatureCriterion {
    /// A criterion with the given thresholds: `0 ≤ remove ≤ insert ≤ 1`.
    pub fn new(insert_threshold: Real, remove_threshold: Real) -> Result<Self, AdaptError> {
        crate::error::in_unit("insert_threshold", insert_threshold)?;
        crate::error::in_unit("remove_threshold", remove_threshold)?;
        if remove_threshold > insert_threshold {
            return Err(AdaptError::InvalidParameter {
                name: "remove_threshold",
                value: remove_threshold,
                reason: "must not exceed insert_threshold",
            });
        }
        Ok(Self {
            insert_threshold,
            remove_threshold,
        })
    }
}

/// The disturbance `c_i` at interior control point `i` (0 at the ends).
pub fn disturbance(rod: &Rod, i: usize) -> Real {
    let q = &rod.positions;
    if i == 0 || i + 1 >= q.len() {
        return 0.0;
    }
    let (e1, e2) = (q[i] - q[i - 1], q[i + 1] - q[i]);
    let (l1, l2) = (e1.norm(), e2.norm());
    let tiny = 1e-12 * rod.material().rest_length;
    if l1 <= tiny || l2 <= tiny {
        return 0.0;
    }
    (0.5 * (1.0 - e1.dot(&e2) / (l1 * l2))).clamp(0.0, 1.0)
}

impl RefinementCriterion for CurvatureCriterion {
    fn name(&self) -> &str {
        "curvature"
    }

    fn mark(&self, rod: &Rod, _interactions: &[Real], out: &mut Vec<Refinement>) {
        let n = rod.len();
        let basis = rod.basis();
        let mut previous = disturbance(rod, 0);
        for i in 0..n.saturating_sub(1) {
            let next = disturbance(rod, i + 1);
            if previous > self.insert_threshold && next > self.insert_threshold {
                let at = 0.5 * (greville(basis, i) + greville(basis, i + 1));
                out.push(Refinement::Insert { at });
            }
            previous = next;
        }
        let d = basis.degree();
        let (start, end) = basis.domain();
        for (k, &t) in basis.knots().iter().enumerate() {
            // Knot k lies in the support of basis functions k-d-1 ..= k.
            if t <= start || t >= end {
                continue;
            }
            let calm = (k.saturating_sub(d + 1)..(k + 1).min(n))
                .all(|i| disturbance(rod, i) < self.remove_threshold);
            if calm {
                out.push(Refinement::Remove { knot: k });
            }
        }
    }
}
