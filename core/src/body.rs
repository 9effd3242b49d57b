//! [`RigidBody`]: a rigid body the rods hold through pins ([`Attachment`]), integrated in
//! the same Newton solve as the rods (the integrators' bordered Schur complement).
//!
//! A body's state is its centre of mass `x`, its orientation `R` (a unit quaternion),
//! its velocity `v` and its angular velocity `ω` (world frame); its inertia `I_b` is a
//! symmetric positive definite tensor about the centre of mass in the body frame, so
//! that in the world frame \\(I_w = R I_b R^T\\). An attachment holds a rod's pin at the
//! body-fixed point `r` (body frame, from the centre of mass): the pin's target is
//! \\(x + R r\\). A welded end (an exact clamp) attaches both of the clamp's pins, the
//! tangent pin sliding along the body-fixed axis \\(R a_b\\).
//!
//! Rotations are updated by the exponential map, \\(R^+ = \exp(\[\beta w\]_\times) \hat R\\);
//! its differential is the left Jacobian of SO(3) ([`left_jacobian`]):
//! \\(\exp([\phi + \delta\phi]_\times) = \exp([T(\phi)\,\delta\phi]_\times)\exp([\phi]_\times)
//! + O(\delta\phi^2)\\).

use crate::{CoreError, Real};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};

/// A rigid body: mass properties and state. All fields are public state.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidBody {
    /// Mass, kg (> 0).
    pub mass: Real,
    /// Inertia tensor about the centre of mass in the body frame, kg m² (symmetric
    /// positive definite).
    pub inertia: Matrix3<Real>,
    /// Centre of mass, m.
    pub position: Vector3<Real>,
    /// Orientation: body frame to world frame.
    pub orientation: UnitQuaternion<Real>,
    /// Velocity of the centre of mass, m/s.
    pub velocity: Vector3<Real>,
    /// Angular velocity in the world frame, rad/s.
    pub angular_velocity: Vector3<Real>,
    /// External force at the centre of mass for the next step (gravity, loads), N.
    pub force: Vector3<Real>,
    /// External torque about the centre of mass for the next step, N m.
    pub torque: Vector3<Real>,
}

impl RigidBody {
    /// A body at rest at `position` with `orientation`; checks the mass (finite, > 0),
    /// the inertia (finite, symmetric, positive definite and physical: each principal
    /// moment at most the sum of the other two) and the pose (finite).
    pub fn at_rest(
        mass: Real,
        inertia: Matrix3<Real>,
        position: Vector3<Real>,
        orientation: UnitQuaternion<Real>,
    ) -> Result<Self, CoreError> {
        let body = Self {
            mass,
            inertia,
            position,
            orientation,
            velocity: Vector3::zeros(),
            angular_velocity: Vector3::zeros(),
            force: Vector3::zeros(),
            torque: Vector3::zeros(),
        };
        body.check()?;
        Ok(body)
    }

    /// An error naming the first field out of range: mass, inertia, or a non-finite
    /// part of the state.
    pub fn check(&self) -> Result<(), CoreError> {
        crate::check::Requirement::Positive.require("mass", self.mass)?;
        check_inertia(&self.inertia)?;
        let state = [
            ("position", self.position),
            ("velocity", self.velocity),
            ("angular_velocity", self.angular_velocity),
            ("force", self.force),
            ("torque", self.torque),
        ];
        for (what, v) in state {
            if !v.iter().all(|c| c.is_finite()) {
                return Err(CoreError::NonFiniteState { what, index: 0 });
            }
        }
        if !self.orientation.coords.iter().all(|c| c.is_finite()) {
            return Err(CoreError::NonFiniteState {
                what: "orientation",
                index: 0,
            });
        }
        Ok(())
    }

    /// The inertia tensor in the world frame, \\(R I_b R^T\\).
    pub fn world_inertia(&self) -> Matrix3<Real> {
        let r = self.orientation.to_rotation_matrix();
        r.matrix() * self.inertia * r.matrix().transpose()
    }

    /// Where the body-fixed point `r` (body frame, from the centre of mass) is.
    pub fn point(&self, r: &Vector3<Real>) -> Vector3<Real> {
        self.position + self.orientation * r
    }

    /// The body-fixed point (body frame) that is at `world` now.
    pub fn local_point(&self, world: &Vector3<Real>) -> Vector3<Real> {
        self.orientation.inverse() * (world - self.position)
    }

    /// Kinetic energy \\(\tfrac12 M|v|^2 + \tfrac12 \omega^T I_w \omega\\), J.
    pub fn kinetic_energy(&self) -> Real {
        let w = self.angular_velocity;
        0.5 * self.mass * self.velocity.norm_squared() + 0.5 * w.dot(&(self.world_inertia() * w))
    }
}

/// Checks an inertia tensor: finite, symmetric (to 1e-12 of its largest entry),
/// positive definite, and each principal moment at most the sum of the other two (a
/// mass distribution can have it; 1e-12 of slack for round-off).
pub fn check_inertia(inertia: &Matrix3<Real>) -> Result<(), CoreError> {
    let bad = |reason| CoreError::InvalidParameter {
        name: "inertia",
        value: inertia.amax(),
        reason,
    };
    if !inertia.iter().all(|c| c.is_finite()) {
        return Err(bad("must be finite"));
    }
    let scale = inertia.amax();
    if (inertia - inertia.transpose()).amax() > 1e-12 * scale {
        return Err(bad("must be symmetric"));
    }
    let moments = inertia.symmetric_eigenvalues();
    let least = moments.min();
    if least.is_nan() || least <= 0.0 {
        return Err(bad(
            "must be positive definite (every principal moment > 0)",
        ));
    }
    let sum = moments.sum();
    if moments.iter().any(|&m| m > sum - m + 1e-12 * sum) {
        return Err(bad(
            "no principal moment may exceed the sum of the other two (triangle inequality)",
        ));
    }
    Ok(())
}

/// A rod's pin held by a body: pin `pin` of the system follows the body-fixed point
/// `point` (body frame, from the centre of mass); a tangent pin (an exact clamp's second
/// pin) also slides along the body-fixed `axis`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Attachment {
    /// Index of the pin in the system's pins.
    pub pin: usize,
    /// Index of the body.
    pub body: usize,
    /// The held point in the body frame, m.
    pub point: Vector3<Real>,
    /// For a tangent pin: the held tangent in the body frame (unit).
    pub axis: Option<Vector3<Real>>,
}

/// The cross-product matrix \\(\[a\]_\times\\): \\(\[a\]_\times b = a \times b\\).
pub fn skew(a: &Vector3<Real>) -> Matrix3<Real> {
    Matrix3::new(0.0, -a.z, a.y, a.z, 0.0, -a.x, -a.y, a.x, 0.0)
}

/// The left Jacobian of SO(3) at the rotation vector φ (θ = |φ|):
/// \\(T(\phi) = I + \frac{1 - \cos\theta}{\theta^2}[\phi]_\times +
/// \frac{\theta - \sin\theta}{\theta^3}[\phi]_\times^2\\) (Taylor series below θ = 1e-4).
pub fn left_jacobian(phi: &Vector3<Real>) -> Matrix3<Real> {
    let t2 = phi.norm_squared();
    let k = skew(phi);
    let (a, b) = if t2 < 1e-8 {
        (0.5 - t2 / 24.0, 1.0 / 6.0 - t2 / 120.0)
    } else {
        let t = t2.sqrt();
        ((1.0 - t.cos()) / t2, (t - t.sin()) / (t2 * t))
    };
    Matrix3::identity() + k * a + k * k * b
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn left_jacobian_is_the_differential_of_the_exponential() {
        for phi in [Vector3::new(0.3, -1.2, 0.7), Vector3::new(1e-6, 2e-6, 0.0)] {
            let d = Vector3::new(0.2, 0.5, -0.4);
            let eps = 1e-6;
            let exp = |p: Vector3<Real>| UnitQuaternion::new(p).to_rotation_matrix().into_inner();
            let diff = (exp(phi + d * eps) - exp(phi - d * eps)) / (2.0 * eps);
            let exact = skew(&(left_jacobian(&phi) * d)) * exp(phi);
            assert!((diff - exact).amax() < 1e-9, "{}", (diff - exact).amax());
        }
    }

    #[test]
    fn inertia_checks_name_what_is_wrong() {
        let ok = Matrix3::from_diagonal(&Vector3::new(1.0, 2.0, 2.5));
        assert!(check_inertia(&ok).is_ok());
        for bad in [
            Matrix3::from_diagonal(&Vector3::new(1.0, 0.0, 1.0)),
            Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, 3.0)),
            Matrix3::new(1.0, 0.5, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0),
            Matrix3::from_diagonal(&Vector3::new(1.0, Real::NAN, 1.0)),
        ] {
            assert!(matches!(
                check_inertia(&bad),
                Err(CoreError::InvalidParameter {
                    name: "inertia",
                    ..
                })
            ));
        }
    }
}
