//! Natural modes of small oscillation about the current configuration: the generalised
//! eigenproblem \\(K v = \omega^2 M v\\) on the subspace the pins leave free
//! (\\(G v = 0\\)), with `K` the exact Hessian of the potential energy.
//!
//! Pins sliding along an axis hold only the directions across it.
//! Dense (O(n³)): an analysis tool for rods of up to [`MAX_DOFS`] degrees of freedom,
//! never part of a time step. Free directions are the null space `Z` of `G`; then
//! \\(M_Z = Z^T M Z = L L^T\\) and the eigenvalues of \\(L^{-1} Z^T K Z L^{-T}\\) are \\(\omega^2\\).

use crate::{IntegratorError, System};
use nalgebra::{DMatrix, Vector3};
use splinerod_core::{add_operator_columns, BlockBanded, HessianKind, Real};

/// Largest number of degrees of freedom (3 per control point) the dense analysis accepts.
pub const MAX_DOFS: usize = 1500;

/// One natural mode.
#[derive(Debug, Clone, PartialEq)]
pub struct Mode {
    /// Angular frequency ω, rad/s (negative ω² — an instability — gives a negative value).
    pub omega: Real,
    /// Frequency ω / 2π, Hz.
    pub frequency: Real,
    /// Control-point displacements of the mode, mass-normalised (\\(v^T M v = 1\\)).
    pub shape: Vec<Vector3<Real>>,
}

/// The `count` lowest modes of `system` about its current positions.
pub fn modes(system: &dyn System, count: usize) -> Result<Vec<Mode>, IntegratorError> {
    let rod = system.rod();
    let (n, dofs) = (rod.len(), 3 * rod.len());
    if dofs > MAX_DOFS {
        return Err(IntegratorError::TooLarge {
            what: "modal analysis",
            dofs,
            limit: MAX_DOFS,
        });
    }
    let mut k = BlockBanded::zeros(n, system.hessian_bandwidth());
    system.add_potential_hessian(HessianKind::Exact, &mut k);
    let mut k = k.to_dense();
    add_remainder_columns(system, &mut k);
    let mut m = BlockBanded::zeros(n, rod.basis().degree());
    m.add_scaled_scalar(1.0, rod.mass_matrix());
    let m = m.to_dense();
    let z = free_directions(system)?;
    let mz = z.transpose() * &m * &z;
    let kz = z.transpose() * &k * &z;
    let chol = mz.cholesky().ok_or(IntegratorError::NotPositiveDefinite {
        context: "mass matrix",
    })?;
    let l = chol.l();
    let linv = l
        .clone()
        .try_inverse()
        .ok_or(IntegratorError::NotPositiveDefinite {
            context: "mass matrix",
        })?;
    let c = &linv * kz * linv.transpose();
    let c = (&c + c.transpose()) * 0.5;
    let eig = c.symmetric_eigen();
    let mut order: Vec<usize> = (0..eig.eigenvalues.len()).collect();
    order.sort_by(|&a, &b| eig.eigenvalues[a].total_cmp(&eig.eigenvalues[b]));
    let back = &z * linv.transpose();
    Ok(order
        .into_iter()
        .take(count)
        .map(|j| {
            let w2 = eig.eigenvalues[j];
            let omega = w2.abs().sqrt().copysign(w2);
            let v = &back * eig.eigenvectors.column(j);
            let shape = (0..n)
                .map(|i| Vector3::new(v[3 * i], v[3 * i + 1], v[3 * i + 2]))
                .collect();
            Mode {
                omega,
                frequency: omega / (2.0 * std::f64::consts::PI),
                shape,
            }
        })
        .collect())
}

/// Orthonormal basis of the null space of the pins' constraint matrix `G`.
fn free_directions(system: &dyn System) -> Result<DMatrix<Real>, IntegratorError> {
    let rod = system.rod();
    let dofs = 3 * rod.len();
    let pins = system.pins();
    if pins.is_empty() {
        return Ok(DMatrix::identity(dofs, dofs));
    }
    let mut g = DMatrix::zeros(3 * pins.len(), dofs);
    for (p, pin) in pins.iter().enumerate() {
        let (b, proj) = (pin.row(rod)?, pin.projector());
        for k in 0..b.order {
            for a in 0..3 {
                for c in 0..3 {
                    g[(3 * p + a, 3 * (b.first + k) + c)] = b.value[k] * proj[(a, c)];
                }
            }
        }
    }
    let gtg = g.transpose() * &g;
    let eig = gtg.symmetric_eigen();
    let scale = eig.eigenvalues.amax();
    let free: Vec<usize> = (0..dofs)
        .filter(|&j| eig.eigenvalues[j] <= 1e-10 * scale)
        .collect();
    let held: usize = pins.iter().map(|p| p.rank()).sum();
    if free.len() + held != dofs {
        return Err(IntegratorError::RedundantPins);
    }
    Ok(DMatrix::from_fn(dofs, free.len(), |i, j| {
        eig.eigenvectors[(i, free[j])]
    }))
}

/// Adds the Hessian's remainder ([`System::add_hessian_remainder`]) to the dense `k`.
fn add_remainder_columns(system: &dyn System, k: &mut DMatrix<Real>) {
    if system.has_hessian_remainder() {
        let n = system.rod().len();
        add_operator_columns(n, k, |v, out| system.add_hessian_remainder(v, 1.0, out));
    }
}
