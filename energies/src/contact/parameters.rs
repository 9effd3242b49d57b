//! [`Parameters`] of [`Contact`]: the friction coefficient `"friction"`. Every lag of a
//! step bounds its friction force by \\(\mu\lambda\\) and the friction potential
//! \\(D = \sum \mu\lambda f_0(|u|)\\) is linear in μ at fixed lags, so
//! \\(\partial\nabla D/\partial\mu = \nabla D/\mu\\) — exact for the step's lagged
//! potential; how the lags (normal force, normal) follow the state is not part of it
//! (their anchors are: [`crate::Lifecycle::add_start_rate`]). Valid while every contact
//! takes the scene-wide coefficient (the caller checks: no surface with its own).
//!
//! And the rest length `"rest_length"` ([`crate::rest_length`]): at fixed control points
//! the samples stay at their fractions of the rod and only their weights scale with `L`
//! — the obstacles' and floor's sums and the frozen friction forces \\(\propto L\\), the
//! pairs' double sum \\(\propto L^2\\) — so
//! \\(\partial_L\nabla E = (\nabla E + \nabla E_{pairs})/L\\). Held: which samples and
//! pairs exist (their counts are whole numbers of spacings) and the stiffness (a scene's
//! derived barrier stiffness follows `L` through its caller).

use super::Contact;
use crate::rest_length::REST_LENGTH;
use crate::{Energy, Parameters};
use nalgebra::Vector3;
use splinerod_core::{CoreError, Real, Rod};

impl Parameters for Contact {
    fn parameter_names(&self) -> &[&'static str] {
        &["friction", REST_LENGTH]
    }

    fn add_gradient_derivative(
        &self,
        rod: &Rod,
        name: &str,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError> {
        if name == REST_LENGTH {
            return self.add_rest_length_rate(rod, out);
        }
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

impl Contact {
    /// `out += (∇E + ∇E_pairs) / L` (module docs).
    fn add_rest_length_rate(
        &self,
        rod: &Rod,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError> {
        let l = rod.material().rest_length;
        if !(l.is_finite() && l > 0.0) {
            return Err(CoreError::InvalidParameter {
                name: "rest_length",
                value: l,
                reason: "a derivative by the rest length needs it finite and positive",
            });
        }
        let mut gradient = vec![Vector3::zeros(); rod.len()];
        self.add_gradient(rod, &mut gradient);
        self.add_pair_gradient(rod, &mut gradient);
        if gradient.iter().any(|g| !g.iter().all(|x| x.is_finite())) {
            return Err(CoreError::InvalidParameter {
                name: "rest_length",
                value: l,
                reason: "the contact's gradient is not finite at this state",
            });
        }
        for (o, g) in out.iter_mut().zip(&gradient) {
            *o += g / l;
        }
        Ok(true)
    }
}
