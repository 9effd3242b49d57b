//! The pointwise gradient \\(\sum_p f_p\, b_a'(s_p)\\) and Hessian
//! \\(\sum_p w_p H(C'(s_p))\, b_a'(s_p)\, b_b'(s_p)\\) added a few quadrature points at a
//! time: the points of one knot span share their control points, so each gradient
//! entry `first + a` and each block `(first + a, first + b)` is loaded once per batch,
//! receives every point's term in point order, and is stored once, instead of being
//! loaded and stored once per point. Each entry receives the same additions in the
//! same order as point by point, so the sums are the same to the bit.

use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, QuadPoint, Real, MAX_DEGREE};

/// Points kept before their terms are added.
const BATCH: usize = 8;

/// Basis functions non-zero at a point, at most.
const MAX_ORDER: usize = MAX_DEGREE + 1;

/// Where the batched terms go: the Hessian's band and, if asked, the gradient.
pub(super) struct Sums<'a> {
    /// Hessian (upper band).
    pub hessian: &'a mut BlockBanded,
    /// Gradient, or `None` for the Hessian alone.
    pub gradient: Option<&'a mut [Vector3<Real>]>,
}

/// Quadrature points of one span waiting to be added.
#[derive(Debug, Clone)]
pub(super) struct PointBatch {
    first: usize,
    order: usize,
    len: usize,
    d1: [[Real; MAX_ORDER]; BATCH],
    h: [Matrix3<Real>; BATCH],
    f: [Vector3<Real>; BATCH],
}

impl Default for PointBatch {
    fn default() -> Self {
        Self {
            first: 0,
            order: 0,
            len: 0,
            d1: [[0.0; MAX_ORDER]; BATCH],
            h: [Matrix3::zeros(); BATCH],
            f: [Vector3::zeros(); BATCH],
        }
    }
}

impl PointBatch {
    /// Keeps point `qp`'s terms: `f b_a'` for the gradient and `h b_a' b_b'` for the
    /// Hessian (`h` its weighted density Hessian), adding the points kept so far first
    /// when `qp` touches other control points.
    #[inline]
    pub(super) fn push(
        &mut self,
        qp: &QuadPoint<'_>,
        (h, f): (Matrix3<Real>, Vector3<Real>),
        sums: &mut Sums<'_>,
    ) {
        let order = qp.d1.len();
        if self.len == BATCH || (self.len > 0 && (qp.first, order) != (self.first, self.order)) {
            self.flush(sums);
        }
        if order > MAX_ORDER {
            // Wider than any basis the batch is sized for: added on its own.
            add_terms(sums, (qp.first, order), &[qp.d1], (&[h], &[f]));
            return;
        }
        (self.first, self.order) = (qp.first, order);
        self.d1[self.len][..order].copy_from_slice(qp.d1);
        (self.h[self.len], self.f[self.len]) = (h, f);
        self.len += 1;
    }

    /// Adds the points kept so far.
    #[inline]
    pub(super) fn flush(&mut self, sums: &mut Sums<'_>) {
        let n = self.len;
        let terms = (&self.h[..n], &self.f[..n]);
        add_terms(sums, (self.first, self.order), &self.d1[..n], terms);
        self.len = 0;
    }
}

/// Adds `Σ_p f_p b_a'` at gradient entries `first + a` and `Σ_p h_p b_a' b_b'` at
/// blocks `(first + a, first + b)`, `a ≤ b < order`, for the points `p` of one span
/// (derivatives `d1[p]`), each entry loaded and stored once.
#[inline]
fn add_terms<D: AsRef<[Real]>>(
    sums: &mut Sums<'_>,
    (first, order): (usize, usize),
    d1: &[D],
    (h, f): (&[Matrix3<Real>], &[Vector3<Real>]),
) {
    if let Some(gradient) = sums.gradient.as_deref_mut() {
        for (a, g) in gradient[first..].iter_mut().take(order).enumerate() {
            let mut sum = *g;
            for (d, f) in d1.iter().zip(f) {
                sum += f * d.as_ref()[a];
            }
            *g = sum;
        }
    }
    let hessian = &mut *sums.hessian;
    debug_assert!(hessian.bandwidth() + 1 >= order, "band narrower than d");
    for a in 0..order {
        let row = hessian.band_row_mut(first + a);
        for (b, block) in (a..order).zip(row.iter_mut()) {
            let mut sum = *block;
            for (d, h) in d1.iter().zip(h) {
                let d = d.as_ref();
                sum += h * (d[a] * d[b]);
            }
            *block = sum;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::super::{tangent, StretchFormulation, Stretching};
    use crate::Energy;
    use crate::Lifecycle;
    use nalgebra::Vector3;
    use splinerod_core::{BlockBanded, HessianKind, Real, Rod};

    /// A rod of `degree` with `points` quadrature points per span, bent and stretched
    /// here, compressed there (with the rest shape of the tests, `g0 ≠ 1`).
    fn rod(degree: usize, points: usize) -> Rod {
        crate::test_rods::wavy_rod(degree, points, (0.05, 0.03))
    }

    /// The gradient and Hessian summed point by point, each term added on its own.
    fn point_by_point(
        s: &Stretching,
        rod: &Rod,
        kind: HessianKind,
    ) -> (Vec<Vector3<Real>>, BlockBanded) {
        let n = rod.len();
        let mut g = vec![Vector3::zeros(); n];
        let mut h = BlockBanded::zeros(n, s.bandwidth(rod));
        for (p, qp) in rod.quadrature().points().enumerate() {
            let (c1, (g0, scale)) = (tangent(&qp, &rod.positions), s.metric(p));
            let f = c1 * (qp.weight * 0.5 * s.stiffness * (c1.norm_squared() - g0) * scale);
            for (gi, &da) in g[qp.first..].iter_mut().zip(qp.d1) {
                *gi += f * da;
            }
            let hp = s.density_hessian(&c1, (g0, scale), kind) * qp.weight;
            for (a, &da) in qp.d1.iter().enumerate() {
                let row = h.band_row_mut(qp.first + a);
                for (block, &db) in row.iter_mut().zip(&qp.d1[a..]) {
                    *block += hp * (da * db);
                }
            }
        }
        (g, h)
    }

    #[test]
    fn batched_sums_equal_the_point_by_point_sums_bit_for_bit() {
        // 11 points per span: a span's points fill more than one batch.
        for (degree, points) in [(2, 3), (3, 4), (3, 11), (5, 9)] {
            let mut rest = rod(degree, points);
            rest.positions.iter_mut().for_each(|p| *p *= 1.1);
            let mut s = Stretching::with_rest_shape(60.0, &rest).expect("stretching");
            s.formulation = StretchFormulation::Pointwise;
            let rod = rod(degree, points);
            s.begin_step(&rod, 1e-3).expect("begin");
            for kind in [HessianKind::Exact, HessianKind::Definite] {
                let (g_ref, h_ref) = point_by_point(&s, &rod, kind);
                let n = rod.len();
                let mut g = vec![Vector3::zeros(); n];
                let mut h = BlockBanded::zeros(n, s.bandwidth(&rod));
                s.add_gradient_and_hessian(&rod, kind, &mut g, &mut h);
                assert_eq!(g, g_ref, "gradient, degree {degree}, {points} points");
                assert_eq!(
                    h.band_blocks(),
                    h_ref.band_blocks(),
                    "Hessian, degree {degree}"
                );
                let mut alone = BlockBanded::zeros(n, s.bandwidth(&rod));
                s.add_hessian(&rod, kind, &mut alone);
                assert_eq!(alone.band_blocks(), h_ref.band_blocks(), "Hessian alone");
            }
        }
    }
}
