//! [`Parameters`] of [`Contact`]: the friction coefficient `"friction"`. Every lag of a
//! step bounds its friction force by \\(\mu\lambda\\) and the friction potential
//! \\(D = \sum \mu\lambda f_0(|u|)\\) is linear in μ at fixed lags, so
//! \\(\partial\nabla D/\partial\mu = \nabla D/\mu\\) — exact for the step's lagged
//! potential; how the lags (normal force, normal) follow the state is not part of it
//! (their anchors are: [`crate::Lifecycle::add_start_rate`]). Valid while every contact
//! takes the scene-wide coefficient (the caller checks: no surface with its own).

use super::Contact;
use crate::Parameters;
use nalgebra::Vector3;
use splinerod_core::{CoreError, Real, Rod};

impl Parameters for Contact {
    fn parameter_names(&self) -> &[&'static str] {
        &["friction"]
    }

    fn add_gradient_derivative(
        &self,
        rod: &Rod,
        name: &str,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError> {
        if name != "friction" {
            return Ok(false);
        }
        let mu = self.params.friction;
        if !(mu.is_finite() && mu > 0.0) {
            return Err(CoreError::InvalidParameter {
                name: "friction",
                value: mu,
                reason: "a derivative by the friction coefficient needs it positive",
            });
        }
        self.friction_state()
            .add_scaled_gradient(rod, 1.0 / mu, out);
        Ok(true)
    }
}
