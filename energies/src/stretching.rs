//! Continuous Green–Lagrange stretching (paper eq. 11–12).
//!
//! With rest arclength `s` (\\(\partial l_0/\partial s = 1\\)) and \\(\gamma^2 = |C'|^2\\):
//!
//! \\[ E = \frac{EA}{8} \int_0^L (\gamma^2 - 1)^2\, ds, \qquad
//! \frac{\partial E}{\partial q_i} = \frac{EA}{2} \int_0^L (\gamma^2 - 1)\, b_i'\, C'\, ds, \\]
//!
//! \\[ \frac{\partial^2 E}{\partial q_i \partial q_j} = \int_0^L b_i' b_j'\, H(C')\, ds,
//! \qquad H = \frac{EA}{2}\left[(\gamma^2 - 1) I + 2\, C' C'^T\right]. \\]
//!
//! No square root is needed. The 3×3 density Hessian `H` has eigenvalue
//! \\(\tfrac{EA}{2}(3\gamma^2 - 1)\\) along the tangent and \\(\tfrac{EA}{2}(\gamma^2 - 1)\\)
//! across it, so it is indefinite in compression. [`HessianKind::Definite`] clamps both
//! eigenvalues at zero (the nearest positive semi-definite matrix); forces stay exact.
//! The integrands are polynomials of degree `4(d − 1)`, integrated exactly by the rod's
//! quadrature table.

use crate::Energy;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, CoreError, HessianKind, QuadPoint, Real, Rod};

/// Green–Lagrange stretching with axial stiffness `EA = Y·r` (N).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stretching {
    /// Axial stiffness `EA`, N.
    pub stiffness: Real,
}

impl Stretching {
    /// Stretching energy with stiffness `EA > 0`.
    pub fn new(stiffness: Real) -> Result<Self, CoreError> {
        splinerod_core::rod::positive("stretch_stiffness", stiffness)?;
        Ok(Self { stiffness })
    }

    /// Tension \\(T(\gamma) = \tfrac{EA}{2}\gamma(\gamma^2 - 1)\\) at stretch `γ`.
    pub fn tension(&self, gamma: Real) -> Real {
        0.5 * self.stiffness * gamma * (gamma * gamma - 1.0)
    }

    /// The 3×3 density Hessian `H(C')`, clamped to PSD for [`HessianKind::Definite`].
    fn density_hessian(&self, c1: &Vector3<Real>, kind: HessianKind) -> Matrix3<Real> {
        let ea = self.stiffness;
        let g2 = c1.norm_squared();
        // H = across·I + β C'C'ᵀ with across = EA(γ²−1)/2 and β = (along − across)/γ² = EA.
        let (across, beta) = match kind {
            HessianKind::Exact => (0.5 * ea * (g2 - 1.0), ea),
            _ if g2 >= 1.0 => (0.5 * ea * (g2 - 1.0), ea),
            // Compression: the transverse eigenvalue is clamped to 0, the axial one too
            // below γ² = 1/3.
            _ if 3.0 * g2 > 1.0 => (0.0, 0.5 * ea * (3.0 * g2 - 1.0) / g2),
            _ => (0.0, 0.0),
        };
        let mut h = c1 * c1.transpose() * beta;
        for k in 0..3 {
            h[(k, k)] += across;
        }
        h
    }
}

/// \\(C'(s)\\) at a quadrature point.
#[inline]
fn tangent(qp: &QuadPoint<'_>, positions: &[Vector3<Real>]) -> Vector3<Real> {
    qp.d1
        .iter()
        .enumerate()
        .fold(Vector3::zeros(), |acc, (a, &w)| {
            acc + positions[qp.first + a] * w
        })
}

impl Energy for Stretching {
    fn name(&self) -> &str {
        "stretch"
    }

    fn energy(&self, rod: &Rod) -> Real {
        let k = self.stiffness / 8.0;
        rod.quadrature()
            .points()
            .map(|qp| {
                let e = tangent(&qp, &rod.positions).norm_squared() - 1.0;
                qp.weight * k * e * e
            })
            .sum()
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let half = 0.5 * self.stiffness;
        for qp in rod.quadrature().points() {
            let c1 = tangent(&qp, &rod.positions);
            let f = c1 * (qp.weight * half * (c1.norm_squared() - 1.0));
            for (a, &da) in qp.d1.iter().enumerate() {
                gradient[qp.first + a] += f * da;
            }
        }
    }

    fn add_hessian(&self, rod: &Rod, kind: HessianKind, hessian: &mut BlockBanded) {
        for qp in rod.quadrature().points() {
            let c1 = tangent(&qp, &rod.positions);
            let h = self.density_hessian(&c1, kind) * qp.weight;
            for (a, &da) in qp.d1.iter().enumerate() {
                for (b, &db) in qp.d1.iter().enumerate().skip(a) {
                    hessian.add_block(qp.first + a, qp.first + b, &(h * (da * db)));
                }
            }
        }
    }
}
