//! BDF2 for rigid bodies ([`crate::Bdf2`]): the history of the bodies' motion and the
//! two-step base a step starts from.
//!
//! With \\(a = (1+\omega)^2/(1+2\omega)\\), \\(b = \omega^2/(1+2\omega)\\) (`a − b = 1`) as for
//! the rods, a body's step starts from
//!
//! \\[ \hat x = a x_n - b x_{n-1}, \quad \hat v = a v_n - b v_{n-1}, \quad
//!     \hat\omega = a \omega_n - b \omega_{n-1}, \quad
//!     \hat R = \exp\big(b \log(R_n R_{n-1}^T)\big) R_n, \\]
//!
//! the rotation's blend taken on the group (for a constant spin \\(\hat R\\) is
//! \\(\exp(b h \omega) R_n\\), and the step's \\(R_{n+1} = \exp(\beta\omega) \hat R\\) with
//! \\(\beta = (1 + \omega) h/(1 + 2\omega)\\) turns it by exactly \\(h\omega\\)), and the
//! coupling solves implicit Euler's body equations from that base with β
//! ([`crate::newton`]'s body coupling), the gyroscopic term taken at \\(\hat\omega\\) in
//! the world inertia of \\(\hat R\\) (first order in it: exact for bodies without one).
//! The history is the bodies' motion one step back and the motion the last step left
//! (compared bit for bit, as the rod's, before the history is used).

use nalgebra::{Quaternion, UnitQuaternion, Vector3, Vector4};
use splinerod_core::{CoreError, Real, RigidBody, SavedState, StateReader};

/// Reals of one body's motion: position, orientation (quaternion i, j, k, w), velocity,
/// angular velocity.
const PER_BODY: usize = 13;

/// The bodies' motion one step back and the motion the last step left.
#[derive(Debug, Default)]
pub(crate) struct BodyHistory {
    previous: Vec<Real>,
    left: Vec<Real>,
}

/// Appends `body`'s motion to `out` ([`PER_BODY`] reals).
fn push_motion(body: &RigidBody, out: &mut Vec<Real>) {
    out.extend_from_slice(body.position.as_slice());
    out.extend_from_slice(body.orientation.coords.as_slice());
    out.extend_from_slice(body.velocity.as_slice());
    out.extend_from_slice(body.angular_velocity.as_slice());
}

/// The motion stored at `m` (one body's [`PER_BODY`] reals).
fn motion(
    m: &[Real],
) -> (
    Vector3<Real>,
    UnitQuaternion<Real>,
    Vector3<Real>,
    Vector3<Real>,
) {
    let v = |i: usize| Vector3::new(m[i], m[i + 1], m[i + 2]);
    let q = Quaternion::from(Vector4::new(m[3], m[4], m[5], m[6]));
    (v(0), UnitQuaternion::new_unchecked(q), v(7), v(10))
}

impl BodyHistory {
    /// Whether `bodies` move exactly as the last step left them.
    pub fn matches(&self, bodies: &[RigidBody]) -> bool {
        self.left.len() == PER_BODY * bodies.len()
            && self.left.chunks_exact(PER_BODY).zip(bodies).all(|(m, b)| {
                let (x, r, v, w) = motion(m);
                x == b.position
                    && r.coords == b.orientation.coords
                    && v == b.velocity
                    && w == b.angular_velocity
            })
    }

    /// Records a step from the bodies `start` to `now`.
    pub fn record(&mut self, start: &[RigidBody], now: &[RigidBody]) {
        self.previous.clear();
        start
            .iter()
            .for_each(|b| push_motion(b, &mut self.previous));
        self.left.clear();
        now.iter().for_each(|b| push_motion(b, &mut self.left));
    }

    /// Writes into `base` the bodies `now` (the step's start, which the history
    /// [`Self::matches`]) with their motion blended with the one a step back (module
    /// docs), `a` and `b` the scheme's weights.
    pub fn blend(&self, now: &[RigidBody], (a, b): (Real, Real), base: &mut Vec<RigidBody>) {
        base.clear();
        base.extend_from_slice(now);
        for (body, m) in base.iter_mut().zip(self.previous.chunks_exact(PER_BODY)) {
            let (x, r, v, w) = motion(m);
            let turn = (body.orientation * r.inverse()).scaled_axis();
            body.orientation = UnitQuaternion::from_scaled_axis(turn * b) * body.orientation;
            body.position = body.position * a - x * b;
            body.velocity = body.velocity * a - v * b;
            body.angular_velocity = body.angular_velocity * a - w * b;
        }
    }

    /// Appends the history to `out`.
    pub fn save(&self, out: &mut SavedState) {
        out.reals(&self.previous);
        out.reals(&self.left);
    }

    /// Reads the history [`Self::save`] wrote.
    pub fn load(&mut self, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        input.reals_into(&mut self.previous)?;
        input.reals_into(&mut self.left)?;
        if self.previous.len() != self.left.len() || self.left.len() % PER_BODY != 0 {
            return Err(CoreError::InvalidParameter {
                name: "bdf2 body history",
                value: self.left.len() as Real,
                reason: "is not the motion of whole bodies, one step back and now",
            });
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spinning(t: Real) -> RigidBody {
        let w = Vector3::new(0.3, -1.2, 0.7);
        let inertia = nalgebra::Matrix3::identity();
        let start = UnitQuaternion::identity();
        let mut body = RigidBody::at_rest(2.0, inertia, Vector3::zeros(), start).expect("body");
        body.position = Vector3::new(1.0, 2.0, 3.0) + Vector3::new(0.5, 0.0, -0.25) * t;
        body.orientation = UnitQuaternion::from_scaled_axis(w * t);
        body.velocity = Vector3::new(0.5, 0.0, -0.25);
        body.angular_velocity = w;
        body
    }

    #[test]
    fn a_uniform_motion_blends_to_where_the_step_continues_it() {
        // Constant step (ω = 1): a = 4/3, b = 1/3, β = 2h/3; the base turned by β more
        // is the motion one step on.
        let h = 0.05;
        let mut history = BodyHistory::default();
        history.record(&[spinning(0.0)], &[spinning(h)]);
        assert!(history.matches(&[spinning(h)]));
        assert!(!history.matches(&[spinning(0.0)]));
        let mut base = Vec::new();
        history.blend(&[spinning(h)], (4.0 / 3.0, 1.0 / 3.0), &mut base);
        let beta = 2.0 * h / 3.0;
        let next = spinning(2.0 * h);
        let b = &base[0];
        let turned = UnitQuaternion::from_scaled_axis(b.angular_velocity * beta) * b.orientation;
        assert!(turned.angle_to(&next.orientation) < 1e-14);
        assert!((b.position + b.velocity * beta - next.position).norm() < 1e-14);
        assert!((b.angular_velocity - next.angular_velocity).norm() < 1e-14);
    }

    #[test]
    fn the_history_saves_and_loads() {
        let mut history = BodyHistory::default();
        history.record(&[spinning(0.0)], &[spinning(0.1)]);
        let mut out = SavedState::default();
        history.save(&mut out);
        let mut loaded = BodyHistory::default();
        loaded.load(&mut out.reader()).expect("load");
        assert!(loaded.matches(&[spinning(0.1)]));
        assert_eq!(loaded.previous, history.previous);
    }
}
