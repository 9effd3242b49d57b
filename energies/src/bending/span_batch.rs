//! The bending gradient \\(\sum_p b_i'(s_p) f_a + b_i''(s_p) f_b\\) and Hessian blocks
//! \\(\sum_p b_i' b_j' H_{aa} + b_i' b_j'' H_{ab} + b_i'' b_j' H_{ab}^T + b_i'' b_j'' H_{bb}\\)
//! (each point's weighted density derivatives, see [`super`]) added a span at a time:
//! the quadrature points of one knot span share their control points, so each gradient
//! entry and each band block is loaded once per batch, receives every point's term in
//! point order and is stored once, instead of once per point. Each entry receives the
//! same additions in the same order as point by point (each term the same products,
//! summed alike), so the sums are the same to the bit.

use nalgebra::{Matrix3, Matrix6, Vector3};
use splinerod_core::{BlockBanded, QuadPoint, Real, MAX_DEGREE};

/// Points kept before their terms are added.
const BATCH: usize = 8;

/// Basis functions non-zero at a point, at most.
const MAX_ORDER: usize = MAX_DEGREE + 1;

/// A 3×3 block's entries, column-major (`(r, c)` at `3c + r`).
pub(super) type Entries = [Real; 9];

/// Where the terms go: the gradient and the Hessian's band, each if asked.
pub(super) struct Sums<'a> {
    /// Gradient, or `None`.
    pub gradient: Option<&'a mut [Vector3<Real>]>,
    /// Hessian (upper band), or `None`.
    pub hessian: Option<&'a mut BlockBanded>,
}

/// One point's weighted terms.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct PointTerms {
    /// \\(w f_a\\) and \\(w f_b\\) (`w` the weight times `EI/2`).
    pub f: [Vector3<Real>; 2],
    /// \\(w H_{aa}\\), \\(w H_{ab}\\), \\((w H_{ab})^T\\) and \\(w H_{bb}\\).
    pub h: [Entries; 4],
}

impl PointTerms {
    /// The Hessian terms from the point's 6×6 density Hessian `h6` and weight `scale`:
    /// its upper blocks scaled, and the transpose of the scaled upper right block.
    pub fn hessian(h6: &Matrix6<Real>, scale: Real) -> [Entries; 4] {
        let block = |r0: usize, c0: usize| -> Entries {
            std::array::from_fn(|e| h6[(r0 + e % 3, c0 + e / 3)])
        };
        Self::scaled([block(0, 0), block(0, 3), block(3, 3)], scale)
    }

    /// The Hessian terms from the density Hessian's blocks `[aa, ab, bb]` and `scale`.
    pub fn scaled(blocks: [Entries; 3], scale: Real) -> [Entries; 4] {
        let [aa, ab, bb] = blocks.map(|b| b.map(|x| x * scale));
        let ba = std::array::from_fn(|e| ab[3 * (e % 3) + e / 3]);
        [aa, ab, ba, bb]
    }
}

/// Quadrature points of one span waiting to be added.
#[derive(Debug, Clone)]
pub(super) struct SpanBatch {
    first: usize,
    order: usize,
    len: usize,
    d1: [[Real; MAX_ORDER]; BATCH],
    d2: [[Real; MAX_ORDER]; BATCH],
    terms: [PointTerms; BATCH],
}

impl Default for SpanBatch {
    fn default() -> Self {
        Self {
            first: 0,
            order: 0,
            len: 0,
            d1: [[0.0; MAX_ORDER]; BATCH],
            d2: [[0.0; MAX_ORDER]; BATCH],
            terms: [PointTerms::default(); BATCH],
        }
    }
}

impl SpanBatch {
    /// Keeps point `qp`'s terms, adding the points kept so far first when `qp` touches
    /// other control points.
    #[inline]
    pub fn push(&mut self, qp: &QuadPoint<'_>, terms: PointTerms, sums: &mut Sums<'_>) {
        let order = qp.d1.len();
        if self.len == BATCH || (self.len > 0 && (qp.first, order) != (self.first, self.order)) {
            self.flush(sums);
        }
        if order > MAX_ORDER {
            // Wider than any basis the batch is sized for: added on its own.
            add_terms(sums, (qp.first, order), (&[qp.d1], &[qp.d2]), &[terms]);
            return;
        }
        (self.first, self.order) = (qp.first, order);
        self.d1[self.len][..order].copy_from_slice(qp.d1);
        self.d2[self.len][..order].copy_from_slice(qp.d2);
        self.terms[self.len] = terms;
        self.len += 1;
    }

    /// Adds the points kept so far.
    #[inline]
    pub fn flush(&mut self, sums: &mut Sums<'_>) {
        let n = self.len;
        let derivatives = (&self.d1[..n], &self.d2[..n]);
        add_terms(
            sums,
            (self.first, self.order),
            derivatives,
            &self.terms[..n],
        );
        self.len = 0;
    }
}

/// Adds the terms of the points `terms` of one span (basis derivatives `d1[p]`,
/// `d2[p]` of the functions `first ..` `first + order`): to each gradient entry and
/// each upper band block, loaded and stored once. Under the wide kernel set
/// ([`splinerod_core::lanes::wide`]) the same operations run four entries per
/// instruction (AVX) instead of two (the same IEEE operations, so the same bits in
/// either set).
fn add_terms<D: AsRef<[Real]>>(
    sums: &mut Sums<'_>,
    shape: (usize, usize),
    derivatives: (&[D], &[D]),
    terms: &[PointTerms],
) {
    #[cfg(target_arch = "x86_64")]
    if splinerod_core::lanes::wide() {
        // SAFETY: the wide set runs only where the processor has AVX2 (so AVX).
        return unsafe { add_terms_avx(sums, shape, derivatives, terms) };
    }
    add_terms_plain(sums, shape, derivatives, terms);
}

/// [`add_terms_plain`] compiled for AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn add_terms_avx<D: AsRef<[Real]>>(
    sums: &mut Sums<'_>,
    shape: (usize, usize),
    derivatives: (&[D], &[D]),
    terms: &[PointTerms],
) {
    add_terms_plain(sums, shape, derivatives, terms);
}

/// The body of [`add_terms`].
#[inline(always)]
fn add_terms_plain<D: AsRef<[Real]>>(
    sums: &mut Sums<'_>,
    (first, order): (usize, usize),
    (d1, d2): (&[D], &[D]),
    terms: &[PointTerms],
) {
    if let Some(gradient) = sums.gradient.as_deref_mut() {
        for (i, g) in gradient[first..].iter_mut().take(order).enumerate() {
            let mut sum = *g;
            for ((a, b), t) in d1.iter().zip(d2).zip(terms) {
                sum += t.f[0] * a.as_ref()[i] + t.f[1] * b.as_ref()[i];
            }
            *g = sum;
        }
    }
    let Some(hessian) = sums.hessian.as_deref_mut() else {
        return;
    };
    debug_assert!(hessian.bandwidth() >= order - 1, "band narrower than d");
    for i in 0..order {
        let row = hessian.band_row_mut(first + i);
        for (j, block) in (i..order).zip(row.iter_mut()) {
            let mut sum = entries(block);
            for ((a, b), t) in d1.iter().zip(d2).zip(terms) {
                let (a, b) = (a.as_ref(), b.as_ref());
                let s = [a[i] * a[j], a[i] * b[j], b[i] * a[j], b[i] * b[j]];
                let [aa, ab, ba, bb] = &t.h;
                for e in 0..9 {
                    sum[e] += ((aa[e] * s[0] + ab[e] * s[1]) + ba[e] * s[2]) + bb[e] * s[3];
                }
            }
            *block = Matrix3::from_column_slice(&sum);
        }
    }
}

/// The entries of `m`.
#[inline(always)]
fn entries(m: &Matrix3<Real>) -> Entries {
    let s = m.as_slice();
    std::array::from_fn(|e| s[e])
}

#[cfg(test)]
mod tests {
    use super::super::{
        clamp_psd, density, density_hessian, derivatives, metric, symmetric6, Bending,
    };
    use crate::Energy;
    use nalgebra::{Matrix3, Matrix6, Vector3};
    use splinerod_core::{BlockBanded, HessianKind, Real, Rod};

    /// A bent and unevenly stretched rod of `degree` with `points` quadrature points
    /// per span.
    fn rod(degree: usize, points: usize) -> Rod {
        crate::test_rods::wavy_rod(degree, points, (0.3, 0.2))
    }

    /// The gradient and Hessian added point by point and block by block (the sums
    /// before the span batches), on top of `g` and `h`.
    fn point_by_point(
        e: &Bending,
        rod: &Rod,
        kind: HessianKind,
        g: &mut [Vector3<Real>],
        h: &mut BlockBanded,
    ) {
        let k = 0.5 * e.stiffness;
        for qp in rod.quadrature().points() {
            let (a, b) = derivatives(&qp, &rod.positions);
            let d = density(&a, &b);
            let (fa, fb) = (d.fa * (qp.weight * k), d.fb * (qp.weight * k));
            for (i, (&d1, &d2)) in qp.d1.iter().zip(qp.d2).enumerate() {
                g[qp.first + i] += fa * d1 + fb * d2;
            }
            let exact = density_hessian_reference(&a, &b);
            let h6 = match kind {
                HessianKind::Exact => exact,
                HessianKind::Definite => clamp_psd(&exact),
            };
            let scale = qp.weight * k;
            let haa: Matrix3<Real> = h6.fixed_view::<3, 3>(0, 0).into_owned() * scale;
            let hab: Matrix3<Real> = h6.fixed_view::<3, 3>(0, 3).into_owned() * scale;
            let hbb: Matrix3<Real> = h6.fixed_view::<3, 3>(3, 3).into_owned() * scale;
            let hba = hab.transpose();
            for i in 0..qp.d1.len() {
                let (ai, bi) = (qp.d1[i], qp.d2[i]);
                for j in i..qp.d1.len() {
                    let (aj, bj) = (qp.d1[j], qp.d2[j]);
                    let block =
                        haa * (ai * aj) + hab * (ai * bj) + hba * (bi * aj) + hbb * (bi * bj);
                    h.add_block(qp.first + i, qp.first + j, &block);
                }
            }
        }
    }

    /// The density Hessian through nalgebra's 3×3 expressions (the form before
    /// [`super::super::density_blocks`] wrote it out).
    fn density_hessian_reference(a: &Vector3<Real>, b: &Vector3<Real>) -> Matrix6<Real> {
        let (g, g1, g2) = metric(a.norm_squared());
        let h = 1.0 / (g * g * g);
        let (a2, b2, ab) = (a.norm_squared(), b.norm_squared(), a.dot(b));
        let n = a.cross(b).norm_squared();
        let id = Matrix3::identity();
        let na = a * (2.0 * b2) - b * (2.0 * ab);
        let nb = b * (2.0 * a2) - a * (2.0 * ab);
        let naa = (id * b2 - b * b.transpose()) * 2.0;
        let nbb = (id * a2 - a * a.transpose()) * 2.0;
        let nab = a * b.transpose() * 4.0 - b * a.transpose() * 2.0 - id * (2.0 * ab);
        let ha = a * (-6.0 * h * g1 / g);
        let haa = id * (-6.0 * h * g1 / g)
            + a * a.transpose() * (48.0 * h * g1 * g1 / (g * g) - 12.0 * h * g2 / g);
        let faa = naa * h + na * ha.transpose() + ha * na.transpose() + haa * n;
        let fab = nab * h + ha * nb.transpose();
        let fbb = nbb * h;
        symmetric6(&faa, &fab, &fbb)
    }

    #[test]
    fn the_written_out_density_hessian_is_the_matrix_expressions_value_for_value() {
        let mut cases = vec![
            (Vector3::new(1.0, 0.0, 0.0), Vector3::zeros()),
            (Vector3::new(1.0, 0.0, 0.0), Vector3::new(-2.0, 0.0, 0.0)),
            (Vector3::zeros(), Vector3::new(0.0, 3.0, 0.0)),
        ];
        for k in 0..500 {
            let x = |j: usize| ((k * 6 + j) as Real * 0.917).sin() * (1.0 + (k % 7) as Real);
            cases.push((
                Vector3::new(x(0), x(1), x(2)),
                Vector3::new(x(3), -x(4), x(5)),
            ));
        }
        for (a, b) in cases {
            // Equal values (a zero's sign aside, which == ignores).
            assert_eq!(
                density_hessian(&a, &b),
                density_hessian_reference(&a, &b),
                "{a} {b}"
            );
        }
    }

    #[test]
    fn span_batches_equal_the_point_by_point_sums_bit_for_bit() {
        // 11 points per span: a span's points fill more than one batch.
        for (degree, points) in [(2, 3), (3, 5), (3, 11), (5, 9)] {
            let rod = rod(degree, points);
            let e = Bending::for_rod(0.37, &rod).expect("bending");
            let n = rod.len();
            // Something in the band and the gradient already, as other energies leave.
            let start_g: Vec<_> = (0..n).map(|i| Vector3::repeat(0.1 * i as Real)).collect();
            let mut start_h = BlockBanded::zeros(n, e.bandwidth(&rod));
            for i in 0..n {
                start_h.add_block(i, i, &(Matrix3::identity() * (1.0 + i as Real / 3.0)));
            }
            for kind in [HessianKind::Exact, HessianKind::Definite] {
                let (mut g_ref, mut h_ref) = (start_g.clone(), start_h.clone());
                point_by_point(&e, &rod, kind, &mut g_ref, &mut h_ref);
                let (mut g, mut h) = (start_g.clone(), start_h.clone());
                e.add_gradient_and_hessian(&rod, kind, &mut g, &mut h);
                let bits = |v: &[Vector3<Real>]| -> Vec<u64> {
                    v.iter()
                        .flat_map(|p| p.iter().map(|x| x.to_bits()))
                        .collect()
                };
                let band_bits = |m: &BlockBanded| -> Vec<u64> {
                    let blocks = m.band_blocks().iter();
                    blocks.flat_map(|b| b.iter().map(|x| x.to_bits())).collect()
                };
                assert_eq!(bits(&g), bits(&g_ref), "gradient, degree {degree}");
                assert_eq!(band_bits(&h), band_bits(&h_ref), "Hessian, degree {degree}");
                let (mut g_alone, mut h_alone) = (start_g.clone(), start_h.clone());
                e.add_gradient(&rod, &mut g_alone);
                e.add_hessian(&rod, kind, &mut h_alone);
                assert_eq!(bits(&g_alone), bits(&g_ref), "gradient alone");
                assert_eq!(band_bits(&h_alone), band_bits(&h_ref), "Hessian alone");
            }
        }
    }
}
