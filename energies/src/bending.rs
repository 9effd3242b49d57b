//! Continuous bending of an isotropic rod (no twist): with rest arclength `s`,
//! \\(a = C'(s)\\) and \\(b = C''(s)\\), the exact curvature of the deformed centreline is
//!
//! \\[ \kappa^2 = \frac{|a \times b|^2}{|a|^6}, \qquad
//! E_b = \frac{EI}{2} \int_0^L \kappa^2\, ds. \\]
//!
//! **Guard.** \\(|a| \to 0\\) (a collapsed centreline) would divide by zero, so the energy
//! actually implemented is \\(\kappa^2 = N / g(|a|^2)^3\\) with \\(N = |a \times b|^2\\) and
//! the metric [`metric`]: \\(g(u) = u + \delta\\), \\(\delta =\\) [`STRETCH_FLOOR`]
//! \\(= 10^{-10}\\) (a relative change of at most \\(3\delta\\) near the rest stretch
//! \\(|a| = 1\\)), and below \\(u = 2f\\), \\(f =\\) [`FOLD_FLOOR`] (a centreline squeezed
//! below a tenth of its rest speed), a cubic that meets it there with two derivatives
//! and stays above \\(2f/3\\). Without that floor a rod squeezed to a point (a
//! Green–Lagrange rod compressed past a stretch of \\(1/\sqrt3\\) collapses along its axis)
//! had curvature stiffnesses of order \\(|a|^{-6} \sim 10^{30}\\) and no Newton solve
//! converged there, at any step (issue #44: rods with bending released compressed by
//! 50–90 %); with it every step does, and nothing changes above \\(|a| = 0.1\\).
//! Gradient and Hessian are the exact derivatives of this guarded energy (with
//! \\(h_a = -6 g^{-4} g' a\\) and \\(h_{aa} = -6 g^{-4} g' I + (48 g^{-5} g'^2 - 12 g^{-4}
//! g'') a a^T\\); \\(g' = 1, g'' = 0\\) above the floor).
//!
//! **Derivatives.** With \\(g = |a|^2 + \delta\\), \\(h = g^{-3}\\) and
//! \\(N = |a|^2 |b|^2 - (a\cdot b)^2\\):
//! \\(N_a = 2|b|^2 a - 2(a\cdot b) b\\), \\(N_b = 2|a|^2 b - 2(a\cdot b) a\\),
//! \\(N_{aa} = 2(|b|^2 I - b b^T)\\), \\(N_{bb} = 2(|a|^2 I - a a^T)\\),
//! \\(N_{ab} = 4 a b^T - 2 b a^T - 2(a\cdot b) I\\), \\(h_a = -6 g^{-4} a\\),
//! \\(h_{aa} = -6 g^{-4} I + 48 g^{-5} a a^T\\); then for \\(f = N h\\):
//! \\(f_a = N_a h + N h_a\\), \\(f_b = N_b h\\),
//! \\(f_{aa} = N_{aa} h + N_a h_a^T + h_a N_a^T + N h_{aa}\\),
//! \\(f_{ab} = N_{ab} h + h_a N_b^T\\), \\(f_{bb} = N_{bb} h\\).
//! Since \\(a = \sum_i b_i' q_i\\) and \\(b = \sum_i b_i'' q_i\\), the gradient is
//! \\(\partial E/\partial q_i = \tfrac{EI}{2}\int (b_i' f_a + b_i'' f_b)\\) and the Hessian
//! block \\((i, j)\\) is \\(\tfrac{EI}{2}\int [b_i' b_j' f_{aa} + b_i' b_j'' f_{ab} +
//! b_i'' b_j' f_{ab}^T + b_i'' b_j'' f_{bb}]\\).
//!
//! **Definite Hessian.** [`HessianKind::Definite`] replaces the 6×6 density Hessian
//! \\(\begin{pmatrix} f_{aa} & f_{ab} \\ f_{ab}^T & f_{bb}\end{pmatrix}\\) at each
//! quadrature point by its eigen-clamped projection (negative eigenvalues set to zero),
//! as [`crate::Stretching`] does with its 3×3 density; the assembled matrix
//! \\(\sum_p w_p L_p^T H_p^+ L_p\\) is then positive semi-definite, and equals the exact
//! Hessian wherever every density Hessian is (e.g. on a straight rod, where
//! \\(f_{aa} = f_{ab} = 0\\) and \\(f_{bb} = 2|a|^{-6}(|a|^2 I - a a^T) \succeq 0\\)).
//! Forces stay exact, so Newton still converges to the right solution.
//!
//! **Degree.** A degree-1 spline has \\(C''\\) equal to Dirac masses at the knots: κ² is
//! not integrable, and the quadrature would silently return zero. [`Bending::check`]
//! (called by [`Bending::for_rod`]) rejects degree < 2; the [`Energy`] methods themselves
//! cannot return errors.
//!
//! **Assembly.** Gradient and Hessian come from one pass over the quadrature points
//! (\\(C'\\), \\(C''\\) evaluated once per point), the density Hessian's blocks written
//! out entry by entry ([`density_blocks`]) and the points' terms added a span at a time
//! ([`span_batch`]): the same operations in the same order as the matrix expressions
//! above summed point by point, so the same bits (tested against that form).
//!
//! **Quadrature.** κ² is rational in `s`; the rod's table (`max(d+1, 2d−1)` Gauss points
//! per span) does not integrate it exactly, so unlike the polynomial stretching energy,
//! bending changes slightly under knot insertion (the new spans move the quadrature
//! points). The change is the quadrature error, measured by the conformance harness.

mod lanes;
mod span_batch;

pub(crate) use lanes::add_bending_lanes;
pub use lanes::BendingTerm;

use crate::capabilities::{Capabilities, LaneForm, Lifecycle};
use crate::Energy;
use nalgebra::{Matrix3, Matrix6, Vector3};
use span_batch::{Entries, PointTerms, SpanBatch, Sums};
use splinerod_core::{BlockBanded, CoreError, HessianKind, QuadPoint, Real, Rod};

/// Regularisation δ of \\(|C'|^2\\) in the curvature's denominator (dimensionless).
pub const STRETCH_FLOOR: Real = 1e-10;

/// Below \\(|C'|^2 = 2 f\\) (a centreline squeezed below a tenth of its rest speed),
/// the curvature's denominator uses a floored metric (see [`metric`]), `f` this value.
pub const FOLD_FLOOR: Real = 5e-3;

/// The guarded metric \\(g(u)\\) of \\(u = |C'|^2\\) and its first two derivatives:
/// \\(u + \delta\\) for \\(u \ge 2f\\), and below it the cubic
/// \\(p(u) = \tfrac{2f}{3} + \tfrac{u^2}{2f} - \tfrac{u^3}{12 f^2} + \delta\\), which
/// meets \\(u + \delta\\) at \\(2f\\) with equal first and second derivatives, rises
/// monotonically from \\(2f/3\\) and is flat at \\(u = 0\\).
#[inline]
pub(crate) fn metric(u: Real) -> (Real, Real, Real) {
    let f = FOLD_FLOOR;
    if u >= 2.0 * f {
        return (u + STRETCH_FLOOR, 1.0, 0.0);
    }
    let g = 2.0 * f / 3.0 + u * u / (2.0 * f) - u * u * u / (12.0 * f * f) + STRETCH_FLOOR;
    let g1 = u / f - u * u / (4.0 * f * f);
    let g2 = 1.0 / f - u / (2.0 * f * f);
    (g, g1, g2)
}

/// Bending energy with bending stiffness `EI` (N·m²), exact nonlinear curvature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bending {
    /// Bending stiffness `EI`, N·m².
    pub stiffness: Real,
}

/// First derivatives of the density κ² at one point (without the factor `EI/2`).
struct Density {
    fa: Vector3<Real>,
    fb: Vector3<Real>,
}

impl Bending {
    /// Bending energy with stiffness `EI > 0`. Use [`Bending::for_rod`] (or call
    /// [`Bending::check`]) to also reject rods of degree < 2.
    pub fn new(stiffness: Real) -> Result<Self, CoreError> {
        splinerod_core::rod::positive("bending_stiffness", stiffness)?;
        Ok(Self { stiffness })
    }

    /// Bending energy for `rod`: checks `EI > 0` and the rod's degree (≥ 2).
    pub fn for_rod(stiffness: Real, rod: &Rod) -> Result<Self, CoreError> {
        let bending = Self::new(stiffness)?;
        bending.check(rod)?;
        Ok(bending)
    }

    /// Error unless `rod`'s degree is at least 2 (a degree-1 rod's curvature is a sum of
    /// Dirac masses at the knots, not square-integrable).
    pub fn check(&self, rod: &Rod) -> Result<(), CoreError> {
        degree_at_least_two(
            rod,
            "bending needs degree >= 2: the curvature of a degree-1 spline is not square-integrable",
        )
    }

    /// Squared curvature \\(\kappa^2\\) (guarded) of the rod at material point `s`.
    pub fn curvature_squared(rod: &Rod, s: Real) -> Result<Real, CoreError> {
        let b = rod.basis_at(s)?;
        let (c1, c2) = (
            b.combine(&b.d1, &rod.positions),
            b.combine(&b.d2, &rod.positions),
        );
        Ok(kappa_squared(&c1, &c2))
    }

    /// Adds the gradient and (of `kind`) the Hessian, each if `sums` asks for it, point
    /// by point and a span at a time ([`span_batch`]).
    fn accumulate(&self, rod: &Rod, kind: HessianKind, mut sums: Sums<'_>) {
        let k = 0.5 * self.stiffness;
        let mut batch = SpanBatch::default();
        for qp in rod.quadrature().points() {
            let (a, b) = derivatives(&qp, &rod.positions);
            let scale = qp.weight * k;
            let mut terms = PointTerms::default();
            if sums.gradient.is_some() {
                let d = density(&a, &b);
                terms.f = [d.fa * scale, d.fb * scale];
            }
            if sums.hessian.is_some() {
                terms.h = match kind {
                    HessianKind::Exact => PointTerms::scaled(density_blocks(&a, &b), scale),
                    HessianKind::Definite => {
                        PointTerms::hessian(&clamp_psd(&density_hessian(&a, &b)), scale)
                    }
                };
            }
            batch.push(&qp, terms, &mut sums);
        }
        batch.flush(&mut sums);
    }
}

/// Error `reason` (naming `degree`) unless `rod`'s degree is at least 2.
pub(crate) fn degree_at_least_two(rod: &Rod, reason: &'static str) -> Result<(), CoreError> {
    let degree = rod.basis().degree();
    if degree >= 2 {
        return Ok(());
    }
    Err(CoreError::InvalidParameter {
        name: "degree",
        value: degree as Real,
        reason,
    })
}

/// \\(C'\\) and \\(C''\\) at a quadrature point.
#[inline]
fn derivatives(qp: &QuadPoint<'_>, positions: &[Vector3<Real>]) -> (Vector3<Real>, Vector3<Real>) {
    let mut a = Vector3::zeros();
    let mut b = Vector3::zeros();
    for (k, (&d1, &d2)) in qp.d1.iter().zip(qp.d2).enumerate() {
        a += positions[qp.first + k] * d1;
        b += positions[qp.first + k] * d2;
    }
    (a, b)
}

/// Guarded \\(\kappa^2 = |a \times b|^2 / (|a|^2 + \delta)^3\\).
#[inline]
fn kappa_squared(a: &Vector3<Real>, b: &Vector3<Real>) -> Real {
    let (g, _, _) = metric(a.norm_squared());
    a.cross(b).norm_squared() / (g * g * g)
}

/// κ² and its first derivatives with respect to `a` and `b`.
#[inline]
fn density(a: &Vector3<Real>, b: &Vector3<Real>) -> Density {
    let (g, g1, _) = metric(a.norm_squared());
    let h = 1.0 / (g * g * g);
    let n = a.cross(b).norm_squared();
    let ab = a.dot(b);
    let na = a * (2.0 * b.norm_squared()) - b * (2.0 * ab);
    let nb = b * (2.0 * a.norm_squared()) - a * (2.0 * ab);
    let ha = a * (-6.0 * h * g1 / g);
    Density {
        fa: na * h + ha * n,
        fb: nb * h,
    }
}

/// The blocks \\(f_{aa}, f_{ab}, f_{bb}\\) of the exact Hessian of κ² with respect to
/// `(a, b)` (module docs), entry by entry: each entry is computed by the operations of
/// the matrix expressions of the docs, in their order, without the 3×3 temporaries.
fn density_blocks(a: &Vector3<Real>, b: &Vector3<Real>) -> [Entries; 3] {
    let (g, g1, g2) = metric(a.norm_squared());
    let h = 1.0 / (g * g * g);
    let (a2, b2, ab) = (a.norm_squared(), b.norm_squared(), a.dot(b));
    let n = a.cross(b).norm_squared();
    let na = a * (2.0 * b2) - b * (2.0 * ab);
    let nb = b * (2.0 * a2) - a * (2.0 * ab);
    let ha = a * (-6.0 * h * g1 / g);
    let haa_aa = 48.0 * h * g1 * g1 / (g * g) - 12.0 * h * g2 / g;
    let (haa_id, nab_id) = (-6.0 * h * g1 / g, 2.0 * ab);
    const IDENTITY: Entries = [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0];
    let mut out = [[0.0; 9]; 3];
    for (e, &id) in IDENTITY.iter().enumerate() {
        let (r, c) = (e % 3, e / 3);
        let naa = (id * b2 - b[r] * b[c]) * 2.0;
        let nbb = (id * a2 - a[r] * a[c]) * 2.0;
        let nab = (a[r] * b[c]) * 4.0 - (b[r] * a[c]) * 2.0 - id * nab_id;
        let haa = id * haa_id + (a[r] * a[c]) * haa_aa;
        out[0][e] = ((naa * h + na[r] * ha[c]) + ha[r] * na[c]) + haa * n;
        out[1][e] = nab * h + ha[r] * nb[c];
        out[2][e] = nbb * h;
    }
    out
}

/// The exact 6×6 Hessian of κ² with respect to `(a, b)`.
fn density_hessian(a: &Vector3<Real>, b: &Vector3<Real>) -> Matrix6<Real> {
    let [faa, fab, fbb] = density_blocks(a, b).map(|e| Matrix3::from_column_slice(&e));
    symmetric6(&faa, &fab, &fbb)
}

/// The symmetric 6×6 matrix of blocks `[[aa, ab], [abᵀ, bb]]`.
fn symmetric6(aa: &Matrix3<Real>, ab: &Matrix3<Real>, bb: &Matrix3<Real>) -> Matrix6<Real> {
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(0, 0).copy_from(aa);
    out.fixed_view_mut::<3, 3>(0, 3).copy_from(ab);
    out.fixed_view_mut::<3, 3>(3, 0).copy_from(&ab.transpose());
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(bb);
    out
}

/// Nearest positive semi-definite matrix (negative eigenvalues set to zero).
fn clamp_psd(m: &Matrix6<Real>) -> Matrix6<Real> {
    let sym = (m + m.transpose()) * 0.5;
    let eig = sym.symmetric_eigen();
    if eig.eigenvalues.iter().all(|&l| l >= 0.0) {
        return sym;
    }
    let clamped = eig.eigenvalues.map(|l| l.max(0.0));
    eig.eigenvectors * Matrix6::from_diagonal(&clamped) * eig.eigenvectors.transpose()
}

impl Energy for Bending {
    fn name(&self) -> &str {
        "bending"
    }

    fn energy(&self, rod: &Rod) -> Real {
        let k = 0.5 * self.stiffness;
        rod.quadrature()
            .points()
            .map(|qp| {
                let (a, b) = derivatives(&qp, &rod.positions);
                qp.weight * k * kappa_squared(&a, &b)
            })
            .sum()
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let sums = Sums {
            gradient: Some(gradient),
            hessian: None,
        };
        self.accumulate(rod, HessianKind::Exact, sums);
    }

    fn add_hessian(&self, rod: &Rod, kind: HessianKind, hessian: &mut BlockBanded) {
        let sums = Sums {
            gradient: None,
            hessian: Some(hessian),
        };
        self.accumulate(rod, kind, sums);
    }

    fn add_gradient_and_hessian(
        &self,
        rod: &Rod,
        kind: HessianKind,
        gradient: &mut [Vector3<Real>],
        hessian: &mut BlockBanded,
    ) {
        let sums = Sums {
            gradient: Some(gradient),
            hessian: Some(hessian),
        };
        self.accumulate(rod, kind, sums);
    }

    fn capabilities(&self) -> Capabilities<'_> {
        Capabilities {
            lifecycle: Some(self),
            lanes: Some(self),
            parameters: Some(self),
            ..Capabilities::default()
        }
    }

    fn lifecycle_mut(&mut self) -> Option<&mut dyn Lifecycle> {
        Some(self)
    }
}

impl Lifecycle for Bending {
    fn supports(&self, rod: &Rod) -> Result<(), CoreError> {
        if rod.quadrature().has_second_derivatives() {
            return Ok(());
        }
        Err(CoreError::InvalidParameter {
            name: "bending on a rod without second derivatives",
            value: 0.0,
            reason: "bending reads the basis' second derivatives, which \
                     Rod::without_second_derivatives left out of the quadrature table",
        })
    }

    fn begin_step(&mut self, rod: &Rod, _dt: Real) -> Result<(), CoreError> {
        self.supports(rod)
    }
}

impl LaneForm for Bending {
    fn lane_term<'a>(&'a self, rod: &'a Rod) -> Option<crate::LaneTerm<'a>> {
        self.bending_term(rod)
    }
}
