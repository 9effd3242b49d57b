//! `[[bodies]]`: rigid bodies, and `[[pins]] body = "…"` attaching a rod's point to one
//! (a ball joint; with `clamp = true` a weld: the exact clamp's two pins, so the body
//! holds the rod's end and its tangent). Errors name `bodies[i].<field>` or
//! `pins[i].body`.

use crate::scene::{finite_vec, positive, Scene};
use crate::world::body_contact::BodyShape;
use crate::{Error, RodSystem};
use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use serde::Deserialize;
use splinerod_core::RigidBody;
use splinerod_energies::Obstacle;

/// `[[bodies]]`: one rigid body.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    /// Its name, for `[[pins]] body` and the output.
    pub name: String,
    /// Mass, kg (> 0).
    pub mass: f64,
    /// Inertia about the centre of mass in the body frame, kg m²: principal moments
    /// `[I1, I2, I3]` (about the body's axes) or a symmetric 3×3 tensor.
    pub inertia: InertiaSpec,
    /// Centre of mass at the start, m.
    pub position: [f64; 3],
    /// Orientation at the start: a rotation vector (axis × angle, rad) from the world
    /// frame. Default: none.
    #[serde(default)]
    pub orientation: [f64; 3],
    /// Velocity of the centre of mass at the start, m/s. Default zero.
    #[serde(default)]
    pub velocity: [f64; 3],
    /// Angular velocity at the start (world frame), rad/s. Default zero.
    #[serde(default)]
    pub angular_velocity: [f64; 3],
    /// Contact spheres `[x, y, z, r]` (centre in the body frame from the centre of
    /// mass, radius), resting on the floor and the obstacles. Default none.
    #[serde(default)]
    pub spheres: Vec<[f64; 4]>,
    /// Contact capsules `[ax, ay, az, bx, by, bz, r]` (axis ends in the body frame,
    /// radius). Default none.
    #[serde(default)]
    pub capsules: Vec<[f64; 7]>,
}

/// An inertia: principal moments or a whole tensor.
#[derive(Debug, Clone, Deserialize)]
#[serde(
    untagged,
    expecting = "expected principal moments [I1, I2, I3] or a 3×3 tensor [[…], […], […]] (kg m²)"
)]
pub enum InertiaSpec {
    /// `[I1, I2, I3]` about the body's axes.
    Principal([f64; 3]),
    /// A symmetric tensor, row by row.
    Tensor([[f64; 3]; 3]),
}

impl InertiaSpec {
    /// The tensor.
    pub fn matrix(&self) -> Matrix3<f64> {
        match self {
            Self::Principal(m) => Matrix3::from_diagonal(&Vector3::from(*m)),
            Self::Tensor(rows) => Matrix3::from_fn(|i, j| rows[i][j]),
        }
    }

    /// The values as the scene gives them, for an error message.
    fn shown(&self) -> String {
        match self {
            Self::Principal(m) => format!("{m:?}"),
            Self::Tensor(rows) => format!("{rows:?}"),
        }
    }
}

impl BodySpec {
    /// The body at its start (checked; errors name `bodies[i].<field>`).
    fn body(&self, i: usize, gravity: Vector3<f64>) -> Result<RigidBody, Error> {
        let field = |f: &str| format!("bodies[{i}].{f}");
        positive(&field("mass"), self.mass)?;
        let inertia = self.inertia.matrix();
        splinerod_core::body::check_inertia(&inertia).map_err(|e| {
            let reason = match e {
                splinerod_core::CoreError::InvalidParameter { reason, .. } => reason.to_string(),
                other => other.to_string(),
            };
            Error::field(field("inertia"), self.inertia.shown(), reason)
        })?;
        for (name, v) in [
            ("position", self.position),
            ("orientation", self.orientation),
            ("velocity", self.velocity),
            ("angular_velocity", self.angular_velocity),
        ] {
            finite_vec(&field(name), v)?;
        }
        for (j, s) in self.spheres.iter().enumerate() {
            let name = field(&format!("spheres[{j}]"));
            finite_vec(&name, [s[0], s[1], s[2]])?;
            positive(&format!("{name}[3]"), s[3])?;
        }
        for (j, c) in self.capsules.iter().enumerate() {
            let name = field(&format!("capsules[{j}]"));
            finite_vec(&name, [c[0], c[1], c[2]])?;
            finite_vec(&name, [c[3], c[4], c[5]])?;
            positive(&format!("{name}[6]"), c[6])?;
        }
        let turn = Vector3::from(self.orientation);
        if !turn.norm().is_finite() {
            let reason = "its length, the angle, must be finite";
            return Err(Error::field(
                field("orientation"),
                format!("{:?}", self.orientation),
                reason,
            ));
        }
        let orientation = UnitQuaternion::new(turn);
        let position = Vector3::from(self.position);
        let mut body = RigidBody::at_rest(self.mass, inertia, position, orientation)
            .map_err(|e| Error::field(field("orientation"), format!("{turn:?}"), e.to_string()))?;
        body.velocity = Vector3::from(self.velocity);
        body.angular_velocity = Vector3::from(self.angular_velocity);
        body.force = gravity * self.mass;
        Ok(body)
    }
}

impl Scene {
    /// Checks `[[bodies]]` and the pins that name them: unique non-empty names, known
    /// names, what a held pin cannot also have, and the scene features bodies do not
    /// take part in yet.
    pub(crate) fn validate_bodies(&self) -> Result<(), Error> {
        for (i, spec) in self.bodies.iter().enumerate() {
            if spec.name.is_empty() || self.bodies[..i].iter().any(|b| b.name == spec.name) {
                let reason = "must be a non-empty name no other body has";
                return Err(Error::field(
                    format!("bodies[{i}].name"),
                    format!("{:?}", spec.name),
                    reason,
                ));
            }
            spec.body(i, Vector3::zeros())?;
        }
        for (i, pin) in self.pins.iter().enumerate() {
            let Some(name) = &pin.body else { continue };
            let field = format!("pins[{i}].body");
            if !self.bodies.iter().any(|b| &b.name == name) {
                let known: Vec<_> = self.bodies.iter().map(|b| b.name.as_str()).collect();
                let reason = format!("names no body of [[bodies]] (they are {known:?})");
                return Err(Error::field(field, format!("{name:?}"), reason));
            }
            let driven = [
                ("path", pin.path.is_some()),
                ("pose", pin.pose.is_some()),
                ("turn", pin.turn.is_some()),
                ("slides_along", pin.slides_along.is_some()),
            ];
            if let Some((what, _)) = driven.iter().find(|(_, given)| *given) {
                let reason =
                    format!("a pin a body holds follows the body: it cannot have `{what}` too");
                return Err(Error::field(field, format!("{name:?}"), reason));
            }
            if pin.clamp && self.rod.twist_stiffness.is_some() {
                let reason = "a body welded to a rod with twist_stiffness is not supported yet (the twist's clamp frame does not follow the body)";
                return Err(Error::field(field, format!("{name:?}"), reason));
            }
        }
        for (i, load) in self.loads.iter().enumerate() {
            let Some(name) = &load.body else { continue };
            let field = format!("loads[{i}].body");
            if !self.bodies.iter().any(|b| &b.name == name) {
                let reason = "names no body of [[bodies]]";
                return Err(Error::field(field, format!("{name:?}"), reason));
            }
            if load.at.is_some() || load.rod.is_some() {
                let reason = "a body's load acts at its centre of mass: give no `at` or `rod`";
                return Err(Error::field(field, format!("{name:?}"), reason));
            }
        }
        if self.bodies.is_empty() {
            return Ok(());
        }
        let method = self.solver.method.name();
        if !matches!(method, "implicit-euler" | "bdf2" | "static") {
            let reason =
                "scenes with [[bodies]] are solved by \"implicit-euler\", \"bdf2\" or \"static\"";
            return Err(Error::field("solver.method", format!("{method:?}"), reason));
        }
        let unsupported = [
            ("ensemble", self.ensemble.is_some()),
            ("adaptivity", self.adaptivity.is_some()),
            ("cuts", !self.cuts.is_empty()),
        ];
        if let Some((what, _)) = unsupported.iter().find(|(_, given)| *given) {
            let reason = "is not supported with [[bodies]] yet";
            return Err(Error::field(*what, "given", reason));
        }
        Ok(())
    }

    /// The bodies' contact shapes, the floor and the obstacles they meet, and their
    /// stiffnesses ([`crate::world::body_contact`]).
    fn add_body_shapes(&self, system: &mut RodSystem) -> Result<(), Error> {
        let contact = &mut system.bodies.contact;
        for (k, spec) in self.bodies.iter().enumerate() {
            for s in &spec.spheres {
                let a = Vector3::new(s[0], s[1], s[2]);
                contact.shapes.push(BodyShape {
                    body: k,
                    a,
                    b: a,
                    radius: s[3],
                });
            }
            for c in &spec.capsules {
                let (a, b) = (
                    Vector3::new(c[0], c[1], c[2]),
                    Vector3::new(c[3], c[4], c[5]),
                );
                contact.shapes.push(BodyShape {
                    body: k,
                    a,
                    b,
                    radius: c[6],
                });
            }
        }
        if contact.shapes.is_empty() {
            return Ok(());
        }
        let spec = self.contact.as_ref().filter(|c| c.enabled);
        let friction = spec.map_or(0.0, |c| c.friction);
        if let Some(slip) = spec.and_then(|c| c.slip_speed) {
            contact.slip_speed = slip;
        }
        if let Some(h) = spec.and_then(|c| c.floor) {
            let plane = Obstacle::Plane {
                point: Vector3::new(0.0, h, 0.0),
                normal: Vector3::y(),
            };
            contact.surfaces.push(plane);
            contact.friction.push(friction);
        }
        for (i, spec) in self.obstacles.iter().enumerate() {
            if spec.motion().0.is_some() {
                let reason = "bodies' contact shapes meet static obstacles only (yet)";
                return Err(Error::field(
                    format!("obstacles[{i}].path"),
                    "given",
                    reason,
                ));
            }
            contact.surfaces.push(spec.obstacle());
            contact.friction.push(spec.friction().unwrap_or(friction));
        }
        let masses: Vec<f64> = system.bodies.bodies.iter().map(|b| b.mass).collect();
        let g = system.bodies.gravity.norm();
        system.bodies.contact.set_stiffness(&masses, g);
        Ok(())
    }

    /// An error naming `bodies` if the scene has any: for what does not carry them yet
    /// (`what`, e.g. the sensitivities).
    pub(crate) fn without_bodies(&self, what: &str) -> Result<(), Error> {
        match self.bodies.first() {
            None => Ok(()),
            Some(b) => {
                let reason = format!("{what} do not carry rigid bodies yet");
                Err(Error::field("bodies[0]", format!("{:?}", b.name), reason))
            }
        }
    }

    /// `system` with the scene's bodies, each holding the pins that name it (a clamp's
    /// tangent pin too); built after the pins (their indices are the file's).
    pub(crate) fn add_bodies(&self, mut system: RodSystem) -> Result<RodSystem, Error> {
        let g = Vector3::from(self.world.gravity);
        for (i, spec) in self.bodies.iter().enumerate() {
            system.add_body(&spec.name, spec.body(i, g)?)?;
        }
        system.bodies.gravity = g;
        for (i, load) in self.loads.iter().enumerate() {
            let Some(name) = &load.body else { continue };
            let body = self.bodies.iter().position(|b| &b.name == name);
            let body =
                body.ok_or_else(|| Error::field(format!("loads[{i}].body"), name, "unknown body"))?;
            let (force, path) = load.force_and_path(i)?;
            let load = crate::world::bodies::BodyLoad { body, force, path };
            system.bodies.loads.push(load);
        }
        system.drive_bodies(0.0);
        self.add_body_shapes(&mut system)?;
        for (i, pin) in self.pins.iter().enumerate() {
            let Some(name) = &pin.body else { continue };
            let body = self.bodies.iter().position(|b| &b.name == name);
            let body =
                body.ok_or_else(|| Error::field(format!("pins[{i}].body"), name, "unknown body"))?;
            system.attach(i, body)?;
            if !(pin.clamp && self.rod.bending_stiffness.is_some()) {
                continue;
            }
            let Some(gripper) = system.grippers.iter().find(|g| g.pin == i) else {
                let reason =
                    "a welded body needs an exact clamp: an end of a rod with clamped knots";
                return Err(Error::field(format!("pins[{i}].body"), name, reason));
            };
            let tangent = gripper.tangent;
            system.attach(tangent, body)?;
        }
        Ok(system)
    }
}
