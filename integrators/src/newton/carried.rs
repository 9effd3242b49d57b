//! Tangent solves at an equilibrium whose exact banded matrix is indefinite although the
//! whole exact matrix is definite there (a stable equilibrium): a curved obstacle's
//! surface-curvature term \\(\phi' \nabla n\\) is negative semi-definite, and with the
//! mixed stretching's axial stiffness partly in the non-banded remainder `R`, the banded
//! part alone can lose definiteness. The remainder's conjugate gradients need a definite
//! preconditioner, so the solve factorises the problem's definite matrix `P_d` instead
//! and carries the difference \\(D = P_e - P_d\\) with the remainder:
//! \\(A = P_d + (D + sR)\\), preconditioned by `P_d` — the exact tangent, to the
//! correction's tolerance.

use nalgebra::Vector3;
use splinerod_core::{BlockBanded, Real};

/// The exact and the definite banded matrices of a tangent solve, and scratch (kept in
/// the workspace between solves: no allocation once sized).
#[derive(Debug, Default)]
pub(crate) struct Carried {
    /// Whether the current tangent solve carries the difference.
    pub active: bool,
    /// \\(P_e\\), the exact banded matrix (indefinite).
    pub exact: BlockBanded,
    /// \\(P_d\\), the definite matrix factorised in its place.
    pub definite: BlockBanded,
    a: Vec<Vector3<Real>>,
    b: Vec<Vector3<Real>>,
}

impl Carried {
    /// Adds `sign · (P_e − P_d) v` to `out` if active.
    pub fn add_product(&mut self, v: &[Vector3<Real>], sign: Real, out: &mut [Vector3<Real>]) {
        if !self.active {
            return;
        }
        let n = v.len();
        self.a.resize(n, Vector3::zeros());
        self.b.resize(n, Vector3::zeros());
        self.exact.mul_vec(v, &mut self.a);
        self.definite.mul_vec(v, &mut self.b);
        for ((o, a), b) in out.iter_mut().zip(&self.a).zip(&self.b) {
            *o += (a - b) * sign;
        }
    }
}
