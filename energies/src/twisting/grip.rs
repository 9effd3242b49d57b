//! A clamp frame carried by a gripper (a 6-DOF clamp): the gripper's rotation `R`
//! against its start splits into a *swing*, the minimal rotation `M` (the parallel
//! transport of [`transport`]) taking the start axis \\(a_0\\) to \\(a = R a_0\\), and a
//! *roll* φ about `a` after it:
//!
//! \\[ R = \mathrm{Rot}(a, \varphi)\, M(a_0 \to R a_0), \qquad
//!     \varphi = \angle_a\!\big(M d_0,\; R d_0\big) \in (-\pi, \pi], \\]
//!
//! with \\(d_0\\) any director across \\(a_0\\) (\\(M^{-1}R\\) turns about \\(a_0\\),
//! so φ does not depend on which) and \\(\angle_a(u, w)\\) the signed angle from `u` to
//! `w` about `a`. The carried frame is \\((a, M d_0)\\), free of roll, and φ adds to the
//! clamp's turn ([`super::Twisting::grip`]); a rotation by an angle in the scene (a
//! rotation vector) or a continuous sequence of rotations (Python) fixes φ's branch
//! mod 2π, which the caller chooses ([`nearest_branch`]). At a swing by π (`a = −a₀`)
//! `M` is not defined: the frame is then \\((a, R d_0)\\) with φ = 0.

use super::holonomy::{signed_angle, transport};
use super::Frame;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{CoreError, Real};

/// Below this `1 + a₀·a` the swing counts as a half turn (module docs).
const HALF_TURN: Real = 1e-12;

/// `base` carried by the gripper rotation `rotation` (module docs): the rolled-free frame
/// \\((R a_0, M d_0)\\) and the roll φ ∈ (−π, π]. An error if the rotation is not finite.
pub fn carried(base: &Frame, rotation: &Matrix3<Real>) -> Result<(Frame, Real), CoreError> {
    let axis = rotation * base.axis;
    let turned = rotation * base.director;
    if 1.0 + base.axis.dot(&axis) <= HALF_TURN {
        return Ok((Frame::new(axis, turned)?, 0.0));
    }
    let swung = transport(&base.axis, &axis, &base.director);
    let frame = Frame::new(axis, swung)?;
    Ok((frame, signed_angle(&frame.director, &turned, &frame.axis)))
}

/// The roll of `rotation` about the carried axis ([`carried`]) for a clamp along `axis`
/// (unit), in (−π, π]; `None` if the rotation or the axis is not finite.
pub fn roll(axis: &Vector3<Real>, rotation: &Matrix3<Real>) -> Option<Real> {
    let base = Frame::along(*axis).ok()?;
    carried(&base, rotation).ok().map(|(_, phi)| phi)
}

/// `angle + 2πk` for the whole `k` that puts it nearest `reference` (rad): a roll known
/// mod 2π on the branch of a continuous one.
pub fn nearest_branch(angle: Real, reference: Real) -> Real {
    let two_pi = 2.0 * std::f64::consts::PI;
    angle + two_pi * ((reference - angle) / two_pi).round()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Rotation3;

    #[test]
    fn a_rotation_splits_into_swing_and_roll() {
        let base = Frame::along(Vector3::new(1.0, 0.0, 0.0)).expect("frame");
        // A pure roll: the axis stays, φ is the angle.
        let r = Rotation3::new(Vector3::new(0.7, 0.0, 0.0));
        let (frame, phi) = carried(&base, r.matrix()).expect("carried");
        assert!((phi - 0.7).abs() < 1e-15 && (frame.axis - base.axis).norm() < 1e-15);
        // A pure swing about a normal: no roll.
        let r = Rotation3::new(Vector3::new(0.0, 0.0, 1.2));
        let (frame, phi) = carried(&base, r.matrix()).expect("carried");
        assert!(phi.abs() < 1e-15, "{phi}");
        assert!((frame.director - r * base.director).norm() < 1e-15);
        // Roll then swing: the roll is recovered.
        let r = Rotation3::new(Vector3::new(0.0, 0.9, 0.0)) * Rotation3::new(Vector3::x() * -2.5);
        let (_, phi) = carried(&base, r.matrix()).expect("carried");
        assert!((phi + 2.5).abs() < 1e-14, "{phi}");
        assert!((nearest_branch(phi, -3.5) + 2.5).abs() < 1e-14);
        assert!((nearest_branch(0.1, 6.2) - (0.1 + 2.0 * std::f64::consts::PI)).abs() < 1e-15);
    }
}
