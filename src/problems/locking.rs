//! The membrane-locking study (issue #12): the static catenary (L = 1 m, pins 0.8 m
//! apart, μ = 0.1 kg/m, cubic, clamped uniform knots) against the exact elastic catenary
//! of the same Green–Lagrange law ([`ElasticCatenary`]), at growing axial stiffness.
//!
//! The solve starts from the exact curve sampled at the Greville abscissae (so every
//! formulation is asked for *its* equilibrium next to the true one, not for a path to
//! it) and the error is the largest distance between material points, at 41 points.
//! `EA = ∞` compares with the inextensible catenary.

use crate::problems::elastic_catenary::ElasticCatenary;
use crate::problems::pinned_cable_with;
use crate::{Error, RodSystem};
use nalgebra::Vector3;
use splinerod_core::basis::greville;
use splinerod_core::Real;
use splinerod_energies::StretchFormulation;
use splinerod_integrators::{StaticParams, StaticSolver};

/// Weight per length of the study's cable, N/m.
pub const WEIGHT: Real = 0.1 * 9.81;

/// The study's cable with `n` control points at stiffness `ea`, placed on the exact curve.
pub fn cable_on_exact_curve(
    n: usize,
    ea: Real,
    formulation: StretchFormulation,
) -> Result<(RodSystem, ElasticCatenary), Error> {
    let exact = ElasticCatenary::new(1.0, 0.8, WEIGHT, ea)?;
    let mut system = pinned_cable_with(n, 0.8, ea.min(1e300), formulation)?;
    for i in 0..system.rod.len() {
        let p = exact.point(greville(system.rod.basis(), i));
        system.rod.positions[i] = Vector3::new(p[0], p[1], 0.0);
    }
    Ok((system, exact))
}

/// Largest material-point distance (m) between `system`'s rod and `exact`, at 41 points.
pub fn distance(system: &RodSystem, exact: &ElasticCatenary) -> Result<Real, Error> {
    let mut worst: Real = 0.0;
    for k in 0..=40 {
        let s = k as Real / 40.0;
        let p = exact.point(s);
        let q = system.rod.point(s)?;
        worst = worst.max((q - Vector3::new(p[0], p[1], 0.0)).norm());
    }
    Ok(worst)
}

/// Static equilibrium error (m) with `n` control points at stiffness `ea`.
pub fn static_error(n: usize, ea: Real, formulation: StretchFormulation) -> Result<Real, Error> {
    let (mut system, exact) = cable_on_exact_curve(n, ea, formulation)?;
    StaticSolver::new(StaticParams::default())?.solve(&mut system)?;
    distance(&system, &exact)
}

/// One row of the study: `EA` and the errors at 16, 32 and 64 control points (`None`
/// where the static solve failed).
#[derive(Debug, Clone, PartialEq)]
pub struct LockingRow {
    /// Axial stiffness, N.
    pub stiffness: Real,
    /// Errors at 16, 32 and 64 control points, m.
    pub errors: [Option<Real>; 3],
}

/// Stiffnesses of the study, N.
pub const STIFFNESSES: [Real; 6] = [1e2, 1e4, 1e6, 1e7, 1e8, 1e9];

/// Resolutions of the study.
pub const RESOLUTIONS: [usize; 3] = [16, 32, 64];

/// The study for one formulation.
pub fn study(formulation: StretchFormulation) -> Vec<LockingRow> {
    STIFFNESSES
        .iter()
        .map(|&ea| LockingRow {
            stiffness: ea,
            errors: RESOLUTIONS.map(|n| static_error(n, ea, formulation).ok()),
        })
        .collect()
}

/// The lumped-chain peers' EA-independent error at `n` degrees of freedom, ≈ 0.14 h²
/// with h = L/(n − 1) (measured in the peer comparison, `splinerod report`).
pub fn peer_error(n: usize) -> Real {
    let h = 1.0 / (n - 1) as Real;
    0.14 * h * h
}
