//! The projection guard: on request ([`Stretching::guard`]; scenes with contact ask for
//! it), the mixed forms of the stretching stiffen where the strain varies inside one
//! knot span by more than [`GUARD_DEVIATION`] (10 %) from the span's mean — the
//! variation their tension space cannot see.
//!
//! On a span with quadrature points `p` (weights \\(\omega_p = w_p\sqrt{g_{0,p}} / \sum_q
//! w_q \sqrt{g_{0,q}}\\)), with \\(\bar\varepsilon = \sum_q \omega_q \varepsilon_q\\) and the
//! deviation \\(\delta_p = \varepsilon_p - \bar\varepsilon\\),
//!
//! \\[ E_g = \frac{EA}{2} \sum_p w_p \sqrt{g_{0,p}}\, \psi(\delta_p), \qquad
//! \psi(\delta) = \frac{(|\delta| - \delta_c)^3}{3 \delta_c} \quad (|\delta| > \delta_c),
//! \quad 0 \text{ otherwise}, \\]
//!
//! with \\(\delta_c =\\) [`GUARD_DEVIATION`]: zero with two derivatives at the threshold,
//! its stiffness \\(\tfrac{EA}{2}\psi''\\) rising linearly to `EA` at twice it. With
//! \\(J_{p,a} = b_a'(s_p)\, C'_p / g_{0,p}\\) (\\(= \partial\varepsilon_p/\partial q_a\\)) and
//! \\(K_{p,a} = J_{p,a} - \sum_q \omega_q J_{q,a}\\) (\\(= \partial\delta_p/\partial q_a\\)),
//! the gradient is \\(\sum_p W_p \psi'(\delta_p) K_{p,a}\\), \\(W_p = \tfrac{EA}{2} w_p
//! \sqrt{g_{0,p}}\\), and the Hessian block \\((a, c)\\)
//! \\(\sum_p W_p [\psi''(\delta_p) K_{p,a} K_{p,c}^T + \psi'(\delta_p)\,(L_{p,ac} -
//! \sum_q \omega_q L_{q,ac})\, I]\\) with \\(L_{p,ac} = b_a' b_c' / g_{0,p}\\)
//! ([`HessianKind::Definite`] keeps the first, positive semi-definite, term only). A span
//! couples its own `d + 1` control points: the band is the degree's.
//!
//! **Why.** The mixed forms see the strain only through its projection on the tension
//! space (mean strains over `d` spans), so a rod can vary its strain inside a span —
//! bunch its material at one point, stretch it at another — at no cost. Measured (issue
//! #44): the lumped form's shortest axial waves (a zig-zag of the control points, whose
//! strain alternates inside the spans) keep an eighth of the pointwise stiffness, so a
//! rod compressed by more than about 12 % grows a spurious zig-zag; and a knot pulled
//! tight bunches a string into corners with \\(|C'| \approx 0.45\\), whose points then
//! come closer than the rod's diameter along the curve (contact clearance 0.76–0.91 of
//! `2r` with the mixed forms against 0.98 pointwise). A uniform strain, however large,
//! has no deviation, and a smooth strain field's deviation is \\(O(h\,
//! \varepsilon')\\): the guard leaves converged and tension-dominated states (catenaries,
//! strings, stiff cables) exactly as they were, and vanishes as the rod is refined. The
//!
//! **Why only with contact.** Contact forces are what push material into such corners;
//! without contact the guard did more harm than good: from a cable squeezed straight
//! to a fifth of its length, the static solver's stiffness continuation passes through
//! soft stages whose folds the guard made stable (EA = 1e9 N, 16 points: a folded
//! equilibrium 0.26 m from the catenary), and a rod compressed uniformly needs no guard
//! (the lumped form's zig-zag there is avoided by `"auto"` taking the consistent form).
//!
//! The pointwise form sees every point and has no guard (and keeps its exact invariance under
//! knot insertion: the guard's integrand is not a polynomial, so in the mixed forms an
//! insertion changes it by its quadrature error where it acts). An inextensible rod
//! (held by multipliers) has none either.

use super::{tangent, Stretching};
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, HessianKind, QuadPoint, Real, Rod, MAX_DEGREE};
use std::cell::RefCell;

/// The strain deviation from its span's mean beyond which the guard acts.
pub const GUARD_DEVIATION: Real = 0.1;

/// Basis functions non-zero on a span, at most.
const MAX_ORDER: usize = MAX_DEGREE + 1;

/// \\(\psi, \psi', \psi''\\) at deviation `d` (zeros within the threshold).
#[inline]
fn psi(d: Real) -> (Real, Real, Real) {
    let x = d.abs() - GUARD_DEVIATION;
    if x <= 0.0 {
        return (0.0, 0.0, 0.0);
    }
    let c = 1.0 / GUARD_DEVIATION;
    (x * x * x * c / 3.0, d.signum() * x * x * c, 2.0 * x * c)
}

/// One quadrature point of a span: its weight times \\(\sqrt{g_0}\\), \\(g_0\\), strain,
/// tangent, first basis function and derivatives.
#[derive(Debug, Clone, Copy)]
struct Point {
    weight: Real,
    g0: Real,
    strain: Real,
    c1: Vector3<Real>,
    first: usize,
    order: usize,
    d1: [Real; MAX_ORDER],
}

thread_local! {
    /// The points of the span being summed (scratch, reused).
    static SPAN: RefCell<Vec<Point>> = const { RefCell::new(Vec::new()) };
}

/// Where the guard's derivatives go.
pub(super) struct GuardSums<'a> {
    /// Hessian of this kind, if asked for.
    pub hessian: Option<(HessianKind, &'a mut BlockBanded)>,
    /// Gradient, if asked for.
    pub gradient: Option<&'a mut [Vector3<Real>]>,
}

impl Stretching {
    /// Whether the guard can act at all (asked for, a mixed form, not an inextensible rod).
    #[inline]
    fn guarded(&self) -> bool {
        self.guard
            && self.multipliers.is_none()
            && self.formulation != super::StretchFormulation::Pointwise
    }

    /// Calls `f` with the points of every span where the guard acts (its weights
    /// normalised to the means' \\(\omega\\) in `f`'s second argument, the mean strain in
    /// the third).
    fn for_each_guarded_span(&self, rod: &Rod, mut f: impl FnMut(&[Point], Real, Real)) {
        if !self.guarded() {
            return;
        }
        SPAN.with(|span| {
            let mut span = span.borrow_mut();
            span.clear();
            let mut flush = |span: &mut Vec<Point>| {
                let total: Real = span.iter().map(|p| p.weight).sum();
                if total > 0.0 {
                    let mean = span.iter().map(|p| p.weight * p.strain).sum::<Real>() / total;
                    if span
                        .iter()
                        .any(|p| (p.strain - mean).abs() > GUARD_DEVIATION)
                    {
                        f(span, total, mean);
                    }
                }
                span.clear();
            };
            for (p, qp) in rod.quadrature().walk().enumerate() {
                if span.last().is_some_and(|s| s.first != qp.first) {
                    flush(&mut span);
                }
                span.push(self.guard_point(rod, p, &qp));
            }
            flush(&mut span);
        });
    }

    /// Point `p` (`qp`) of the guard's sums.
    #[inline]
    fn guard_point(&self, rod: &Rod, p: usize, qp: &QuadPoint<'_>) -> Point {
        let g0 = self.g0(p);
        let c1 = tangent(qp, &rod.positions);
        let order = qp.d1.len().min(MAX_ORDER);
        let mut d1 = [0.0; MAX_ORDER];
        d1[..order].copy_from_slice(&qp.d1[..order]);
        Point {
            weight: qp.weight * g0.sqrt(),
            g0,
            strain: 0.5 * (c1.norm_squared() - g0) / g0,
            c1,
            first: qp.first,
            order,
            d1,
        }
    }

    /// The guard's energy.
    pub(super) fn guard_energy(&self, rod: &Rod) -> Real {
        let half = 0.5 * self.stiffness;
        let mut sum = 0.0;
        self.for_each_guarded_span(rod, |span, _, mean| {
            for p in span {
                sum += half * p.weight * psi(p.strain - mean).0;
            }
        });
        sum
    }

    /// Adds the guard's gradient and Hessian where `sums` asks for them.
    pub(super) fn add_guard_terms(&self, rod: &Rod, mut sums: GuardSums<'_>) {
        let half = 0.5 * self.stiffness;
        self.for_each_guarded_span(rod, |span, total, mean| {
            let (first, order) = (span[0].first, span[0].order);
            // J̄_a = Σ_q ω_q J_{q,a} and L̄_ac = Σ_q ω_q L_{q,ac}.
            let mut jbar = [Vector3::zeros(); MAX_ORDER];
            let mut lbar = [[0.0; MAX_ORDER]; MAX_ORDER];
            for q in span {
                let omega = q.weight / total;
                for a in 0..order {
                    jbar[a] += q.c1 * (omega * q.d1[a] / q.g0);
                    for c in a..order {
                        lbar[a][c] += omega * q.d1[a] * q.d1[c] / q.g0;
                    }
                }
            }
            for p in span {
                let (_, d1, d2) = psi(p.strain - mean);
                if d2 == 0.0 {
                    continue;
                }
                let w = half * p.weight;
                let k: [Vector3<Real>; MAX_ORDER] =
                    std::array::from_fn(|a| p.c1 * (p.d1[a] / p.g0) - jbar[a]);
                if let Some(g) = sums.gradient.as_deref_mut() {
                    for a in 0..order {
                        g[first + a] += k[a] * (w * d1);
                    }
                }
                if let Some((kind, h)) = sums.hessian.as_mut() {
                    for a in 0..order {
                        for c in a..order {
                            let mut block: Matrix3<Real> = k[a] * k[c].transpose() * (w * d2);
                            if *kind == HessianKind::Exact {
                                let l = p.d1[a] * p.d1[c] / p.g0 - lbar[a][c];
                                for i in 0..3 {
                                    block[(i, i)] += w * d1 * l;
                                }
                            }
                            if a == c {
                                block = (block + block.transpose()) * 0.5;
                            }
                            h.add_block(first + a, first + c, &block);
                        }
                    }
                }
            }
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn psi_is_twice_differentiable_at_the_threshold_and_reaches_ea_at_twice_it() {
        for side in [1.0, -1.0] {
            let (e, d1, d2) = psi(side * GUARD_DEVIATION);
            assert_eq!((e, d1, d2), (0.0, 0.0, 0.0));
            let (_, _, d2) = psi(side * 2.0 * GUARD_DEVIATION);
            assert!((0.5 * d2 - 1.0).abs() < 1e-15, "{d2}");
        }
        // Central differences of psi and psi' give psi' and psi''.
        let h = 1e-6;
        for d in [-0.9, -0.3, -0.15, 0.15, 0.3, 0.9] {
            let (_, d1, d2) = psi(d);
            let fd1 = (psi(d + h).0 - psi(d - h).0) / (2.0 * h);
            let fd2 = (psi(d + h).1 - psi(d - h).1) / (2.0 * h);
            assert!((fd1 - d1).abs() < 1e-8 && (fd2 - d2).abs() < 1e-8, "{d}");
        }
    }
}
