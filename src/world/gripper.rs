//! 6-DOF clamps: a [`Gripper`] holds an exact clamp (an end pin and the tangent pin on
//! the control point next to it, [`splinerod_core::Pin::tangent_at`]) and moves it with
//! a pose — a translation `x` of the clamp point and a rotation `R` of the gripper, both
//! against its start — keyframed in the scene (`[[pins]] pose`, [`PosePath`]) or set
//! between steps (Python's `set_clamp_pose`, [`crate::RodSystem::set_gripper_pose`]).
//!
//! With \\(p_0\\) the clamp point, \\(a_0\\) the held tangent and \\(h\\) the distance
//! to the next control point at the start, a pose holds
//!
//! \\[ C(s_c) = p_0 + x, \qquad
//!     q_{next} \in \{\,p_0 + x + R a_0 (h + \lambda) : \lambda \in \mathbb{R}\,\}, \\]
//!
//! the end pin at \\(p_0 + x\\) and the tangent pin sliding along \\(R a_0\\) (its target
//! \\(p_0 + x + h R a_0\\) on that line, so the work a turning gripper does enters the
//! midpoint rule's energy guard). The rotation acts about the clamp point.
//!
//! **Twist.** The gripper's rotation splits into a swing `M` taking \\(a_0\\) to
//! \\(R a_0\\) by parallel transport and a roll φ about \\(R a_0\\)
//! ([`splinerod_energies::twisting::grip`]):
//! \\(R = \mathrm{Rot}(R a_0, \varphi)\,M\\), \\(\varphi = \angle_{R a_0}(M d_0, R d_0)\\)
//! mod 2π. The twisting energy measures against the swung frame \\((R a_0, M d_0)\\), and
//! the roll adds to the clamp's turn: \\(\mathrm{Tw} = \psi - \psi_0 + \Phi\\) with
//! \\(\Phi = \Phi_{turn} + \varphi_{end} - \varphi_{start}\\). A rotation vector
//! \\(r\\) (a scene pose) puts φ on the branch nearest \\(r \cdot a_0\\) — exact for a
//! roll about the tangent, \\(r = \theta a_0\\) gives φ = θ, any number of turns —; a
//! rotation given as a matrix or quaternion (Python) on the branch nearest the previous
//! roll, so between two calls the roll must change by less than π.

use crate::world::path::{check_keyframes, Interpolation};
use crate::Error;
use nalgebra::{Matrix3, Rotation3, Vector3, Vector6};
use splinerod_core::{Keyframes, Pin, Real};
use splinerod_energies::twisting::grip::{nearest_branch, roll};
use splinerod_energies::Energy;

/// A gripper's pose against its start.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Translation of the clamp point, m.
    pub translation: Vector3<Real>,
    /// Rotation of the gripper (orthonormal, determinant 1).
    pub rotation: Matrix3<Real>,
    /// Roll about the carried tangent, rad, on a continuous branch (module docs).
    pub roll: Real,
}

impl Pose {
    /// The pose of translation `x` and rotation vector `r` (rad) for a clamp along the
    /// unit `axis`: the roll on the branch nearest \\(r \cdot a_0\\) (module docs).
    pub fn from_rotation_vector(x: Vector3<Real>, r: Vector3<Real>, axis: &Vector3<Real>) -> Self {
        let rotation = Rotation3::new(r).into_inner();
        let phi = roll(axis, &rotation).unwrap_or(Real::NAN);
        Self {
            translation: x,
            rotation,
            roll: nearest_branch(phi, r.dot(axis)),
        }
    }
}

/// Pose keyframes `[t, x, y, z, rx, ry, rz]` (s, m, rad): translation and rotation vector
/// against the start, interpolated component-wise like a pin's `path`
/// ([`crate::world::path`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PosePath(Keyframes<Vector6<Real>>);

impl PosePath {
    /// The path through `keyframes`; `field` names them in errors: finite (the element
    /// named, `field[k][c]`), times strictly increasing (`field[k][0]`), the first at
    /// time 0 with the start pose (all zeros: a gripper never makes the rod jump).
    pub fn new(
        keyframes: &[[Real; 7]],
        interpolation: Interpolation,
        field: &str,
    ) -> Result<Self, Error> {
        for (k, row) in keyframes.iter().enumerate() {
            if let Some(c) = row.iter().position(|v| !v.is_finite()) {
                return Err(Error::field(
                    format!("{field}[{k}][{c}]"),
                    row[c],
                    "must be finite",
                ));
            }
            let parts = [(1, "translation"), (4, "rotation vector")];
            for (first, what) in parts {
                let v = Vector3::new(row[first], row[first + 1], row[first + 2]);
                if !v.norm_squared().is_finite() {
                    let reason = format!("its {what}'s length must be finite");
                    return Err(Error::field(
                        format!("{field}[{k}]"),
                        format!("{row:?}"),
                        reason,
                    ));
                }
            }
        }
        // An out-of-order row is named by its time, `field[k][0]`.
        check_keyframes(keyframes, field).map_err(|e| match e {
            Error::InvalidField {
                field: row,
                value,
                reason,
            } if row != field => Error::InvalidField {
                field: format!("{row}[0]"),
                value,
                reason,
            },
            other => other,
        })?;
        if keyframes[0] != [0.0; 7] {
            let reason = "the first keyframe must be [0, 0, 0, 0, 0, 0, 0]: the gripper as it starts (time 0, no translation, no rotation)";
            return Err(Error::field(
                format!("{field}[0]"),
                format!("{:?}", keyframes[0]),
                reason,
            ));
        }
        let frames = keyframes
            .iter()
            .map(|f| (f[0], Vector6::from_column_slice(&f[1..])));
        Ok(Self(Keyframes::new(frames, interpolation.into())?))
    }

    /// The translation (m) and rotation vector (rad) at time `t`.
    pub fn at(&self, t: Real) -> (Vector3<Real>, Vector3<Real>) {
        let v = self.0.at(t);
        (v.fixed_rows::<3>(0).into(), v.fixed_rows::<3>(3).into())
    }

    /// The last keyframe's time, s.
    pub fn end_time(&self) -> Real {
        self.0.end_time()
    }

    /// How far the gripper turns from time 0 to `t`, rad: the sum of the angles between
    /// its rotations at 64 evenly spaced times and at the keyframes in between.
    pub fn turning(&self, t: Real) -> Real {
        let mut times: Vec<Real> = (0..=64).map(|k| t * k as Real / 64.0).collect();
        times.extend(self.0.times().iter().copied().filter(|&k| k < t));
        times.sort_by(Real::total_cmp);
        let rotation = |time: Real| Rotation3::new(self.at(time).1);
        let pairs = times.windows(2);
        pairs
            .map(|w| rotation(w[0]).angle_to(&rotation(w[1])))
            .sum()
    }
}

/// A gripper holding an exact clamp (module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct Gripper {
    /// Index of the clamp's end pin in [`crate::RodSystem::pins`].
    pub pin: usize,
    /// Index of its tangent pin.
    pub tangent: usize,
    /// Which end of its rod the clamp holds: 0 at `s = 0`, 1 at the rod's end.
    pub end: usize,
    /// The segment of a joined rod it holds (`None`: a one-rod system), for the
    /// energies it turns.
    pub segment: Option<usize>,
    /// The clamp point at the start, m.
    pub origin: Vector3<Real>,
    /// The held tangent at the start (unit).
    pub axis: Vector3<Real>,
    /// Distance from the clamp point to the next control point at the start, m.
    pub lever: Real,
    /// The scene's pose keyframes, if any.
    pub path: Option<PosePath>,
    /// The pose last applied (`None`: never moved).
    pub held: Option<Pose>,
}

impl Gripper {
    /// A gripper still at its start holding end pin `pin` and tangent pin `tangent` of
    /// `pins` at end `end` (0 or 1), the next control point `lever` m from the end.
    pub fn new(pins: &[Pin], pin: usize, tangent: usize, end: usize, lever: Real) -> Option<Self> {
        let (p, t) = (pins.get(pin)?, pins.get(tangent)?);
        Some(Self {
            pin,
            tangent,
            end,
            segment: None,
            origin: p.position,
            axis: t.slides_along?,
            lever,
            path: None,
            held: None,
        })
    }

    /// This gripper following `path` (builder style).
    pub fn with_path(mut self, path: PosePath) -> Self {
        self.path = Some(path);
        self
    }

    /// The pose of its path at time `t` (`None` without a path).
    pub fn scheduled(&self, t: Real) -> Option<Pose> {
        let (x, r) = self.path.as_ref()?.at(t);
        Some(Pose::from_rotation_vector(x, r, &self.axis))
    }

    /// Puts `pose` on the pins (end pin, tangent pin's target and axis) and on the
    /// energies of its segment ([`splinerod_energies::Lifecycle::grip`]), and holds it.
    pub fn apply(&mut self, pose: Pose, pins: &mut [Pin], energies: &mut [Box<dyn Energy>]) {
        let point = self.origin + pose.translation;
        let axis = pose.rotation * self.axis;
        if let Some(p) = pins.get_mut(self.pin) {
            p.position = point;
        }
        if let Some(t) = pins.get_mut(self.tangent) {
            t.position = point + axis * self.lever;
            t.slides_along = Some(axis);
        }
        for e in energies.iter_mut() {
            if e.capabilities().segment != self.segment {
                continue;
            }
            if let Some(l) = e.lifecycle_mut() {
                l.grip(self.end, &pose.rotation, pose.roll);
            }
        }
        self.held = Some(pose);
    }

    /// The pose putting the clamp point at `position` (absolute, m) with the gripper
    /// turned by `rotation` against its start (checked: finite, orthonormal to 1e-9,
    /// determinant +1), its roll on the branch nearest the last one (module docs).
    /// Errors name `position` or `rotation`.
    pub fn pose_at(&self, position: Vector3<Real>, rotation: Matrix3<Real>) -> Result<Pose, Error> {
        if !position.iter().all(|x| x.is_finite()) {
            let value = format!("{:?}", position.as_slice());
            return Err(Error::field("position", value, "must be finite"));
        }
        check_rotation(&rotation)?;
        let phi = roll(&self.axis, &rotation).unwrap_or(Real::NAN);
        let last = self.held.map_or(0.0, |p| p.roll);
        Ok(Pose {
            translation: position - self.origin,
            rotation,
            roll: nearest_branch(phi, last),
        })
    }
}

/// An error naming `rotation` unless it is a finite proper rotation matrix (orthonormal
/// to 1e-9, determinant +1).
pub fn check_rotation(rotation: &Matrix3<Real>) -> Result<(), Error> {
    let value = || format!("{:?}", rotation.transpose().as_slice());
    if !rotation.iter().all(|x| x.is_finite()) {
        return Err(Error::field("rotation", value(), "must be finite"));
    }
    let off = (rotation.transpose() * rotation - Matrix3::identity()).amax();
    if off > 1e-9 || rotation.determinant() < 0.0 {
        let reason = format!(
            "must be a rotation (orthonormal, determinant +1): RᵀR − I is {off:.1e} off, det {:.6}",
            rotation.determinant()
        );
        return Err(Error::field("rotation", value(), reason));
    }
    Ok(())
}

/// The rotation of the unit quaternion `(w, x, y, z)` (normalised; an error naming
/// `rotation` if it is zero or not finite).
pub fn quaternion_rotation(q: [Real; 4]) -> Result<Matrix3<Real>, Error> {
    let norm = q.iter().map(|c| c * c).sum::<Real>().sqrt();
    if !(norm.is_finite() && norm > 0.0) {
        let reason = "a quaternion (w, x, y, z) must be finite and non-zero";
        return Err(Error::field("rotation", format!("{q:?}"), reason));
    }
    let [w, x, y, z] = q;
    let quaternion = nalgebra::Quaternion::new(w, x, y, z) / norm;
    let unit = nalgebra::UnitQuaternion::new_unchecked(quaternion);
    Ok(unit.to_rotation_matrix().into_inner())
}

impl crate::RodSystem {
    /// Whether a gripper follows a pose path.
    pub fn has_posed_grippers(&self) -> bool {
        self.grippers.iter().any(|g| g.path.is_some())
    }

    /// Puts gripper `k` in `pose` (its pins and the energies measured against its
    /// clamp frame), from the next step on; a gripper with a pose path is moved by it
    /// again at the next step. An error naming `index` if there is no gripper `k`, and
    /// `pins[i].body` if a rigid body holds its clamp (the body moves it).
    pub fn set_gripper_pose(&mut self, k: usize, pose: Pose) -> Result<(), Error> {
        let count = self.grippers.len();
        let Some(gripper) = self.grippers.get_mut(k) else {
            let reason = format!("the system has {count} gripper(s)");
            return Err(Error::field("index", k, reason));
        };
        let held =
            |a: &&splinerod_core::Attachment| a.pin == gripper.pin || a.pin == gripper.tangent;
        if let Some(a) = self.bodies.attachments.iter().find(held) {
            let name = self.bodies.names.get(a.body).map_or("?", String::as_str);
            let reason =
                "a rigid body holds this clamp: its pose follows the body, it cannot be set";
            return Err(Error::field(
                format!("pins[{}].body", gripper.pin),
                name,
                reason,
            ));
        }
        gripper.apply(pose, &mut self.pins, &mut self.energies);
        Ok(())
    }

    /// Moves every gripper with a pose path to its pose at time `t`.
    pub fn drive_grippers(&mut self, t: Real) {
        let Self {
            grippers,
            pins,
            energies,
            ..
        } = self;
        for g in grippers.iter_mut() {
            if let Some(pose) = g.scheduled(t) {
                g.apply(pose, pins, energies);
            }
        }
    }
}
