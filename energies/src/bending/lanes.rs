//! The bending energy of [`LANES`] rods at once (the lane form of [`crate::lanes`]): at
//! each quadrature point the formulas of [`super`] (κ², its gradient and its exact
//! 6×6 density Hessian in the blocks \\(f_{aa}, f_{ab}, f_{bb}\\)) over the lanes, then
//! the gradient \\(\sum_p b_i' f_a + b_i'' f_b\\) and the Hessian blocks
//! \\(b_i' b_j' f_{aa} + b_i' b_j'' f_{ab} + b_i'' b_j' f_{ab}^T + b_i'' b_j'' f_{bb}\\),
//! weighted by \\(w_p\, EI/2\\). The rods share their knots, so their quadrature tables
//! are equal (checked: [`BendingTerm::same_shape`]) and one of them serves all lanes;
//! each lane has its own `EI`. Each lane's result equals [`Bending`]'s own evaluation up
//! to round-off (tested in [`crate::lanes`]).

use super::{metric, Bending};
use crate::lanes::{LaneField, LaneTerm};
use splinerod_core::lanes::{fma, ZERO};
use splinerod_core::{Derivatives, LaneBand, Lanes, QuadPoint, QuadratureTable, Real, Rod, LANES};

/// A lane 3-vector: component `c` of every lane.
type V3 = [Lanes; 3];

/// One rod's bending as a lane term: its quadrature table and `EI`.
#[derive(Debug, Clone, Copy)]
pub struct BendingTerm<'a> {
    table: &'a QuadratureTable,
    /// The knots the table was made for.
    knots: &'a [Real],
    stiffness: Real,
}

impl BendingTerm<'_> {
    /// Whether the table's points touch control points below `n` only, with second
    /// derivatives and within block bandwidth `bw`.
    pub(crate) fn fits(&self, n: usize, bw: usize) -> bool {
        let t = self.table;
        let last = t
            .len()
            .checked_sub(1)
            .map_or(0, |p| t.first_function(p) + t.order());
        t.has_second_derivatives() && t.order() <= bw + 1 && last <= n
    }

    /// Whether both rods have the same quadrature table, the one the lanes share: the
    /// same knots (bit for bit) and the same rule (points per span, order, second
    /// derivatives), of which the table is a function (up to round-off where it was
    /// updated span by span after knot changes, which the lanes' contract allows).
    pub(crate) fn same_shape(&self, other: &BendingTerm<'_>) -> bool {
        let (a, b) = (self.table, other.table);
        let rule = |t: &QuadratureTable| {
            let last = t.len().checked_sub(1).map(|p| t.first_function(p));
            (
                t.len(),
                t.points_per_span(),
                t.order(),
                t.has_second_derivatives(),
                last,
            )
        };
        let knots = self.knots.len() == other.knots.len()
            && self
                .knots
                .iter()
                .zip(other.knots)
                .all(|(x, y)| x.to_bits() == y.to_bits());
        rule(a) == rule(b) && knots
    }
}

impl Bending {
    /// The lane term of this energy on `rod` (an open rod of degree ≥ 2 whose table has
    /// second derivatives); `None` otherwise.
    pub(super) fn bending_term<'a>(&'a self, rod: &'a Rod) -> Option<LaneTerm<'a>> {
        let table = rod.quadrature();
        let usable = table.has_second_derivatives() && rod.basis().degree() >= 2;
        (usable && !rod.is_closed()).then_some(LaneTerm::Bending(BendingTerm {
            table,
            knots: rod.basis().knots(),
            stiffness: self.stiffness,
        }))
    }
}

/// [`crate::lanes::add_lanes`] for the bending terms `terms` (checked compatible).
pub(crate) fn add_bending_lanes(
    terms: [&BendingTerm<'_>; LANES],
    q: &LaneField,
    energy: &mut Lanes,
    derivatives: Option<Derivatives<'_>>,
) {
    #[cfg(target_arch = "x86_64")]
    if splinerod_core::lanes::wide() {
        // SAFETY: the processor has AVX2 and FMA (checked on the line above).
        return unsafe { bending_wide(terms, q, energy, derivatives) };
    }
    bending::<false>(terms, q, energy, derivatives);
}

/// [`bending`] compiled for AVX2 with fused multiply-add.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn bending_wide(
    terms: [&BendingTerm<'_>; LANES],
    q: &LaneField,
    energy: &mut Lanes,
    derivatives: Option<Derivatives<'_>>,
) {
    bending::<true>(terms, q, energy, derivatives);
}

/// Energy, gradient and Hessian, point by point.
#[inline(always)]
fn bending<const FUSED: bool>(
    terms: [&BendingTerm<'_>; LANES],
    q: &LaneField,
    energy: &mut Lanes,
    mut derivatives: Option<Derivatives<'_>>,
) {
    let half: Lanes = std::array::from_fn(|l| 0.5 * terms[l].stiffness);
    for qp in terms[0].table.walk() {
        let (a, b) = tangents::<FUSED>(q, &qp);
        let weight: Lanes = half.map(|k| k * qp.weight);
        let point = Point::new(&a, &b);
        for l in 0..LANES {
            energy[l] += weight[l] * (point.n[l] * point.h[l]);
        }
        let Some(d) = derivatives.as_mut() else {
            continue;
        };
        let (fa, fb) = point.gradient(&a, &b);
        for (i, (&d1, &d2)) in qp.d1.iter().zip(qp.d2).enumerate() {
            for c in 0..3 {
                let slot = &mut d.gradient[3 * (qp.first + i) + c];
                let term: Lanes =
                    std::array::from_fn(|l| weight[l] * (fa[c][l] * d1 + fb[c][l] * d2));
                *slot = std::array::from_fn(|l| slot[l] + term[l]);
            }
        }
        let scale = weight.map(|w| w * d.hessian_scale);
        let blocks = point.hessian_blocks(&a, &b, scale);
        add_point_blocks::<FUSED>(d.hessian, &qp, &blocks);
    }
}

/// \\(C'\\) and \\(C''\\) of every lane at `qp`.
#[inline(always)]
fn tangents<const FUSED: bool>(q: &LaneField, qp: &QuadPoint<'_>) -> (V3, V3) {
    let (mut a, mut b) = ([ZERO; 3], [ZERO; 3]);
    for (k, (&d1, &d2)) in qp.d1.iter().zip(qp.d2).enumerate() {
        for c in 0..3 {
            let x = q[3 * (qp.first + k) + c];
            fma::<FUSED>(&mut a[c], x, [d1; LANES]);
            fma::<FUSED>(&mut b[c], x, [d2; LANES]);
        }
    }
    (a, b)
}

/// The scalars of the density at one point, per lane (notation of [`super`]).
struct Point {
    a2: Lanes,
    b2: Lanes,
    ab: Lanes,
    /// \\(|a \times b|^2\\).
    n: Lanes,
    /// \\(g = |a|^2 + \delta\\) ([`metric`]).
    g: Lanes,
    /// \\(g'\\) and \\(g''\\) with respect to \\(|a|^2\\) (1 and 0 unless the
    /// centreline is squeezed below [`super::FOLD_FLOOR`]).
    g1: Lanes,
    g2: Lanes,
    /// \\(g^{-3}\\).
    h: Lanes,
}

/// The lanes' values of `f(lane)`.
#[inline(always)]
fn lanes(f: impl Fn(usize) -> Real) -> Lanes {
    std::array::from_fn(f)
}

/// `a · b` per lane.
#[inline(always)]
fn dot(a: &V3, b: &V3) -> Lanes {
    std::array::from_fn(|l| a[0][l] * b[0][l] + a[1][l] * b[1][l] + a[2][l] * b[2][l])
}

impl Point {
    #[inline(always)]
    fn new(a: &V3, b: &V3) -> Self {
        let (a2, b2, ab) = (dot(a, a), dot(b, b), dot(a, b));
        let cross: V3 = std::array::from_fn(|c| {
            let (i, j) = ((c + 1) % 3, (c + 2) % 3);
            std::array::from_fn(|l| a[i][l] * b[j][l] - a[j][l] * b[i][l])
        });
        let m = a2.map(metric);
        let g: Lanes = m.map(|m| m.0);
        Self {
            a2,
            b2,
            ab,
            n: dot(&cross, &cross),
            g,
            g1: m.map(|m| m.1),
            g2: m.map(|m| m.2),
            h: g.map(|g| 1.0 / (g * g * g)),
        }
    }

    /// \\(N_a = 2|b|^2 a - 2(a\cdot b) b\\) and \\(h_a = -6 g^{-4} a\\).
    #[inline(always)]
    fn na_ha(&self, a: &V3, b: &V3) -> (V3, V3) {
        let na = std::array::from_fn(|c| {
            std::array::from_fn(|l| a[c][l] * (2.0 * self.b2[l]) - b[c][l] * (2.0 * self.ab[l]))
        });
        let ha = std::array::from_fn(|c| {
            std::array::from_fn(|l| a[c][l] * (-6.0 * self.h[l] * self.g1[l] / self.g[l]))
        });
        (na, ha)
    }

    /// \\(N_b = 2|a|^2 b - 2(a\cdot b) a\\).
    #[inline(always)]
    fn nb(&self, a: &V3, b: &V3) -> V3 {
        std::array::from_fn(|c| {
            std::array::from_fn(|l| b[c][l] * (2.0 * self.a2[l]) - a[c][l] * (2.0 * self.ab[l]))
        })
    }

    /// \\(f_a = N_a h + h_a N\\) and \\(f_b = N_b h\\).
    #[inline(always)]
    fn gradient(&self, a: &V3, b: &V3) -> (V3, V3) {
        let (na, ha) = self.na_ha(a, b);
        let nb = self.nb(a, b);
        let fa = std::array::from_fn(|c| {
            std::array::from_fn(|l| na[c][l] * self.h[l] + ha[c][l] * self.n[l])
        });
        let fb = std::array::from_fn(|c| std::array::from_fn(|l| nb[c][l] * self.h[l]));
        (fa, fb)
    }

    /// \\(f_{aa}, f_{ab}, f_{ab}^T, f_{bb}\\) times `scale`, column-major blocks.
    #[inline(always)]
    fn hessian_blocks(&self, a: &V3, b: &V3, scale: Lanes) -> [[Lanes; 9]; 4] {
        let (na, ha) = self.na_ha(a, b);
        let nb = self.nb(a, b);
        let (h, g, n) = (self.h, self.g, self.n);
        let (g1, g2) = (self.g1, self.g2);
        let haa_id = lanes(|l| -6.0 * h[l] * g1[l] / g[l]);
        let haa_aa =
            lanes(|l| 48.0 * h[l] * g1[l] * g1[l] / (g[l] * g[l]) - 12.0 * h[l] * g2[l] / g[l]);
        let mut out = [[ZERO; 9]; 4];
        for e in 0..9 {
            let (r, c) = (e % 3, e / 3);
            let id: Real = if r == c { 1.0 } else { 0.0 };
            let naa = lanes(|l| (id * self.b2[l] - b[r][l] * b[c][l]) * 2.0);
            let nbb = lanes(|l| (id * self.a2[l] - a[r][l] * a[c][l]) * 2.0);
            let nab = lanes(|l| {
                a[r][l] * b[c][l] * 4.0 - b[r][l] * a[c][l] * 2.0 - id * 2.0 * self.ab[l]
            });
            let haa = lanes(|l| id * haa_id[l] + a[r][l] * a[c][l] * haa_aa[l]);
            out[0][e] = lanes(|l| {
                (naa[l] * h[l] + na[r][l] * ha[c][l] + ha[r][l] * na[c][l] + haa[l] * n[l])
                    * scale[l]
            });
            out[1][e] = lanes(|l| (nab[l] * h[l] + ha[r][l] * nb[c][l]) * scale[l]);
            out[3][e] = lanes(|l| nbb[l] * h[l] * scale[l]);
        }
        out[2] = std::array::from_fn(|e| out[1][3 * (e % 3) + e / 3]);
        out
    }
}

/// Adds one point's blocks `[aa, ab, ba, bb]` at `(first + i, first + j)`, `i ≤ j`.
#[inline(always)]
fn add_point_blocks<const FUSED: bool>(
    hessian: &mut LaneBand,
    qp: &QuadPoint<'_>,
    [aa, ab, ba, bb]: &[[Lanes; 9]; 4],
) {
    let (d1, d2) = (qp.d1, qp.d2);
    for i in 0..d1.len() {
        let row = hessian.row_mut(qp.first + i);
        for (j, block) in (i..d1.len()).zip(row.iter_mut()) {
            let s =
                [d1[i] * d1[j], d1[i] * d2[j], d2[i] * d1[j], d2[i] * d2[j]].map(|x| [x; LANES]);
            let mut sum = *block;
            for (e, entry) in sum.iter_mut().enumerate() {
                fma::<FUSED>(entry, aa[e], s[0]);
                fma::<FUSED>(entry, ab[e], s[1]);
                fma::<FUSED>(entry, ba[e], s[2]);
                fma::<FUSED>(entry, bb[e], s[3]);
            }
            *block = sum;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plain_and_the_fused_kernels_agree_to_round_off() {
        let rod = crate::test_rods::wavy_rod(3, 5, (0.3, 0.2));
        let energy = Bending::for_rod(0.02, &rod).expect("bending");
        let Some(LaneTerm::Bending(term)) = energy.bending_term(&rod) else {
            panic!("lane form");
        };
        let n = rod.len();
        let q: Vec<Lanes> = (0..3 * n)
            .map(|k| {
                std::array::from_fn(|l| rod.positions[k / 3][k % 3] * (1.0 + 0.03 * l as Real))
            })
            .collect();
        let run = |fused: bool| {
            let (mut e, mut g, mut h) = ([0.0; LANES], vec![ZERO; 3 * n], LaneBand::default());
            h.reset(n, 3);
            let d = Derivatives {
                gradient: &mut g,
                hessian: &mut h,
                hessian_scale: 1e-4,
            };
            let terms = [&term; LANES];
            if fused {
                bending::<true>(terms, &q, &mut e, Some(d));
            } else {
                bending::<false>(terms, &q, &mut e, Some(d));
            }
            (e, g, h)
        };
        let (plain, fused) = (run(false), run(true));
        let close = |a: &[Real], b: &[Real]| {
            let scale = b.iter().fold(1e-300, |m: Real, x| m.max(x.abs()));
            a.iter().zip(b).all(|(x, y)| (x - y).abs() <= 1e-12 * scale)
        };
        assert!(close(&plain.0, &fused.0), "energy");
        assert!(
            close(plain.1.as_flattened(), fused.1.as_flattened()),
            "gradient"
        );
        let band = |h: &LaneBand| -> Vec<Real> {
            h.blocks().iter().flatten().flatten().copied().collect()
        };
        assert!(close(&band(&plain.2), &band(&fused.2)), "Hessian");
        assert!(band(&fused.2).iter().any(|x| *x != 0.0));
    }
}
