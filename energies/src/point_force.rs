//! A force applied at one material point (a load): \\(E = -F \cdot C(s)\\), with
//! gradient \\(-F\, b_i(s)\\) and a zero Hessian. The force is a public field: whoever
//! drives the load changes it between steps. If `s` is outside the rod, the energy is
//! NaN (and the step fails cleanly).

use crate::Energy;
use nalgebra::Vector3;
use splinerod_core::{BlockBanded, CoreError, HessianKind, Real, Rod};

/// A force `force` (N) at material point `at` (m of rest arclength).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointForce {
    /// Material coordinate, m of rest arclength.
    pub at: Real,
    /// The force, N.
    pub force: Vector3<Real>,
}

impl PointForce {
    /// A load at `at`; everything finite.
    pub fn new(at: Real, force: Vector3<Real>) -> Result<Self, CoreError> {
        splinerod_core::Requirement::Finite.require("load material coordinate", at)?;
        splinerod_core::rod::check_finite("load force", &[force])?;
        Ok(Self { at, force })
    }
}

impl Energy for PointForce {
    fn name(&self) -> &str {
        "load"
    }

    fn energy(&self, rod: &Rod) -> Real {
        match rod.point(self.at) {
            Ok(p) => -self.force.dot(&p),
            Err(_) => Real::NAN,
        }
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let Ok(row) = rod.basis_at(self.at) else {
            gradient.iter_mut().for_each(|g| g.x = Real::NAN);
            return;
        };
        for k in 0..row.order {
            gradient[row.first + k] -= self.force * row.value[k];
        }
    }

    fn add_hessian(&self, _rod: &Rod, _kind: HessianKind, _hessian: &mut BlockBanded) {}

    fn bandwidth(&self, _rod: &Rod) -> usize {
        0
    }

    /// Its [`Parameters`](crate::Parameters): the rest length.
    fn capabilities(&self) -> crate::capabilities::Capabilities<'_> {
        crate::capabilities::Capabilities {
            parameters: Some(self),
            ..crate::capabilities::Capabilities::default()
        }
    }
}
