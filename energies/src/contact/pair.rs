//! The penalty of one sample pair: its weight \\(w_a w_b / (r_a + r_b)^2\\), gap
//! \\(d - (r_a + r_b)\\), Hessian with respect to the difference of its points, and the
//! merged basis weights through which it acts on the control points.

use super::assemble::SymBlock;
use super::detect::{Detector, SamplePair};
use super::Contact;
use splinerod_core::basis::MAX_ORDER;
use splinerod_core::{HessianKind, Real};

impl Contact {
    /// Weight of a sample pair: \\(w_a w_b / (r_a + r_b)^2\\).
    pub(super) fn pair_weight(&self, d: &Detector, pair: &SamplePair) -> Real {
        let w = &d.samples.weight;
        w[pair.a as usize] * w[pair.b as usize] / self.sum_of_radii(d, pair).powi(2)
    }

    /// The Hessian of a sample pair's penalty with respect to the difference of its
    /// points, \\(w\\,[\\phi'' n n^T + \\tfrac{\\phi'}{d}(I - n n^T)]\\): the stiffness along
    /// the normal and, for [`HessianKind::Exact`], the turning of the normal (negative
    /// semi-definite, since \\(\\phi' \\le 0\\); without it Newton's method converges only
    /// linearly, at the ratio of the two terms, about \\(|\\phi'|/(d\\,\\phi'')\\)).
    pub(super) fn pair_hessian(
        &self,
        d: &Detector,
        pair: &SamplePair,
        kind: HessianKind,
    ) -> SymBlock {
        let (weight, gap) = (self.pair_weight(d, pair), self.gap(d, pair));
        let along = weight * self.penalty.curvature(gap);
        let turning = if kind == HessianKind::Exact {
            weight * self.penalty.slope(gap) / pair.distance
        } else {
            0.0
        };
        // along · n nᵀ + turning · (I − n nᵀ), by its six entries.
        let (n, c) = (&pair.normal, along - turning);
        [
            n.x * n.x * c + turning,
            n.y * n.y * c + turning,
            n.z * n.z * c + turning,
            n.x * n.y * c,
            n.x * n.z * c,
            n.y * n.z * c,
        ]
    }

    /// \\(r_a + r_b\\) of a sample pair.
    pub(super) fn sum_of_radii(&self, d: &Detector, pair: &SamplePair) -> Real {
        if self.radii.values.is_empty() {
            return 2.0 * self.params.radius;
        }
        let s = &d.samples.s;
        self.radius_at(s[pair.a as usize]) + self.radius_at(s[pair.b as usize])
    }

    /// The gap \\(d - (r_a + r_b)\\) of a sample pair.
    pub(super) fn gap(&self, d: &Detector, pair: &SamplePair) -> Real {
        pair.distance - self.sum_of_radii(d, pair)
    }
}

/// Merged weights \\(u_i = b_i(s_a) - b_i(s_b)\\) of a sample pair: at most
/// `2 · MAX_ORDER` control points.
pub(super) fn pair_rows(
    d: &Detector,
    pair: &SamplePair,
    out: &mut [(usize, Real); 2 * MAX_ORDER],
) -> usize {
    let mut len = 0;
    let samples = &d.samples;
    for (k, sign) in [(pair.a as usize, 1.0), (pair.b as usize, -1.0)] {
        let first = samples.first[k] as usize;
        for (a, &b) in samples.row(k).iter().enumerate() {
            let (i, w) = (first + a, sign * b);
            match out[..len].iter_mut().find(|(j, _)| *j == i) {
                Some((_, total)) => *total += w,
                None => {
                    out[len] = (i, w);
                    len += 1;
                }
            }
        }
    }
    len
}
