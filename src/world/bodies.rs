//! Rigid bodies held by the rods' pins ([`Bodies`], in [`RodSystem::bodies`]).
//!
//! A body is integrated with the rods in one Newton system (the integrators' body
//! coupling: the pins it holds follow its body-fixed points, and their multipliers act
//! back on it); implicit Euler, BDF2 and the static solver support it. Between steps the held
//! pins are moved to where the bodies put them ([`RodSystem::follow_bodies`]), so that
//! every reader of the pins (outputs, pin torques) sees the solved state.
//!
//! The rod's wrench on a body ([`RodSystem::body_wrench`]) is the negative of the held
//! pins' forces on the rod, applied at the rod's held points:
//! \\(F = -\sum_p f_p\\), \\(\tau = -\sum_p (C_p - x) \times f_p\\) about the centre of
//! mass `x`, with \\(C_p\\) the held point (the control point next to the clamp for a
//! tangent pin).

use crate::world::body_contact::BodyContact;
use crate::world::path::Path;
use crate::RodSystem;
use nalgebra::Vector3;
use splinerod_core::{Attachment, CoreError, Real, RigidBody};

/// The bodies of a system, their names and the pins they hold. All fields are public.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Bodies {
    /// The bodies (state and mass properties).
    pub bodies: Vec<RigidBody>,
    /// Their names, in the same order.
    pub names: Vec<String>,
    /// The pins they hold.
    pub attachments: Vec<Attachment>,
    /// Gravity, m/s² (each body's weight at its centre of mass).
    pub gravity: Vector3<Real>,
    /// Forces at the bodies' centres of mass (`[[loads]] body`).
    pub loads: Vec<BodyLoad>,
    /// The bodies' contact shapes and what they meet
    /// ([`crate::world::body_contact`]).
    pub contact: BodyContact,
}

/// A force on a body at its centre of mass, constant or keyframed.
#[derive(Debug, Clone, PartialEq)]
pub struct BodyLoad {
    /// Index of the body.
    pub body: usize,
    /// The force when constant, N.
    pub force: Vector3<Real>,
    /// Keyframes of the force (`[t, Fx, Fy, Fz]` as positions of a [`Path`]).
    pub path: Option<Path>,
}

impl RodSystem {
    /// Adds a body named `name`; returns its index.
    pub fn add_body(&mut self, name: &str, body: RigidBody) -> Result<usize, CoreError> {
        body.check()?;
        self.bodies.bodies.push(body);
        self.bodies.names.push(name.to_string());
        Ok(self.bodies.bodies.len() - 1)
    }

    /// Lets body `body` hold pin `pin` at the body-fixed point where the pin is now (and,
    /// for an exact clamp's tangent pin, along the body-fixed tangent it slides on).
    pub fn attach(&mut self, pin: usize, body: usize) -> Result<(), CoreError> {
        let bad = |name, value: usize| CoreError::InvalidParameter {
            name,
            value: value as Real,
            reason: "no such index",
        };
        let p = *self.pins.get(pin).ok_or(bad("pin", pin))?;
        let b = self.bodies.bodies.get(body).ok_or(bad("body", body))?;
        let axis = p.tangent.then_some(p.slides_along).flatten();
        self.bodies.attachments.push(Attachment {
            pin,
            body,
            point: b.local_point(&p.position),
            axis: axis.map(|a| b.orientation.inverse() * a),
        });
        Ok(())
    }

    /// Sets each body's external force for a step ending at `t`: its weight plus its
    /// loads at `t`.
    pub fn drive_bodies(&mut self, t: Real) {
        let Bodies {
            bodies,
            gravity,
            loads,
            ..
        } = &mut self.bodies;
        for (k, b) in bodies.iter_mut().enumerate() {
            let on = loads.iter().filter(|l| l.body == k);
            let applied = on.map(|l| l.path.as_ref().map_or(l.force, |p| p.at(t)));
            b.force = *gravity * b.mass + applied.sum::<Vector3<Real>>();
        }
    }

    /// Moves the held pins to the bodies' points (after a step or a state restored).
    pub fn follow_bodies(&mut self) {
        for a in &self.bodies.attachments {
            let (Some(body), Some(pin)) =
                (self.bodies.bodies.get(a.body), self.pins.get_mut(a.pin))
            else {
                continue;
            };
            pin.position = body.point(&a.point);
            if let Some(axis) = a.axis {
                pin.slides_along = Some(body.orientation * axis);
            }
        }
    }

    /// The rod's force (N) and torque about the centre of mass (N m) on body `body`,
    /// from the pins' forces on the rod `pin_forces` (one per pin, as the integrators
    /// report them). Zero for an index out of range.
    pub fn body_wrench(
        &self,
        body: usize,
        pin_forces: &[Vector3<Real>],
    ) -> (Vector3<Real>, Vector3<Real>) {
        let Some(b) = self.bodies.bodies.get(body) else {
            return (Vector3::zeros(), Vector3::zeros());
        };
        let (mut force, mut torque) = (Vector3::zeros(), Vector3::zeros());
        for a in self.bodies.attachments.iter().filter(|a| a.body == body) {
            let (Some(f), Some(pin)) = (pin_forces.get(a.pin), self.pins.get(a.pin)) else {
                continue;
            };
            let held = pin.row(&self.rod).map_or(pin.position, |row| {
                row.combine(&row.value, &self.rod.positions)
            });
            force -= f;
            torque -= (held - b.position).cross(f);
        }
        (force, torque)
    }
}
