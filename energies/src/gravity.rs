//! Uniform gravity: \\(E = -\int_0^L \mu\, g \cdot C(s)\, ds = -\sum_i m_i\, g \cdot q_i\\)
//! with the lumped masses \\(m_i = \int \mu b_i\\) (paper §3.2, \\(B_i = m g \int b_i\\)).

use crate::capabilities::{Capabilities, LaneForm};
use crate::Energy;
use nalgebra::Vector3;
use splinerod_core::{BlockBanded, CoreError, HessianKind, Real, Rod};

/// Uniform gravitational field `g` (m/s²). Linear in the positions: zero Hessian.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Gravity {
    /// Acceleration of gravity, m/s².
    pub g: Vector3<Real>,
}

impl Gravity {
    /// Gravity `g`; every component must be finite.
    pub fn new(g: Vector3<Real>) -> Result<Self, CoreError> {
        match g.iter().position(|x| !x.is_finite()) {
            Some(index) => Err(CoreError::NonFiniteState {
                what: "gravity component",
                index,
            }),
            None => Ok(Self { g }),
        }
    }
}

impl Energy for Gravity {
    fn name(&self) -> &str {
        "gravity"
    }

    fn energy(&self, rod: &Rod) -> Real {
        let m = rod.lumped_masses();
        -m.iter()
            .zip(&rod.positions)
            .map(|(m, q)| m * self.g.dot(q))
            .sum::<Real>()
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        for (g, m) in gradient.iter_mut().zip(rod.lumped_masses()) {
            *g -= self.g * *m;
        }
    }

    fn add_hessian(&self, _rod: &Rod, _kind: HessianKind, _hessian: &mut BlockBanded) {}

    fn capabilities(&self) -> Capabilities<'_> {
        Capabilities {
            lanes: Some(self),
            parameters: Some(self),
            ..Capabilities::default()
        }
    }
}

impl LaneForm for Gravity {
    fn lane_term<'a>(&'a self, rod: &'a Rod) -> Option<crate::LaneTerm<'a>> {
        Some(crate::LaneTerm::Gravity {
            g: self.g,
            masses: rod.lumped_masses(),
        })
    }
}
