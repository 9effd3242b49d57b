//! The rigid bodies (`[[bodies]]`) as transformed USD primitives: an `Xform` per body
//! under `/World/Bodies` (the body's name made an identifier) whose `double3
//! xformOp:translate` (the centre of mass) and `quatd xformOp:orient` (body frame to
//! world frame) are time-sampled at every recorded time code, so that its local frame
//! is the body's. It carries the body exactly: `custom string splinerod:kind = "body"`,
//! `splinerod:name`, `custom double splinerod:mass` and `custom matrix3d
//! splinerod:inertia` (about the centre of mass, body frame).
//!
//! A child prim `shape` shows it: the `Cube` of size 1 scaled (`xformOp:scale`) to the
//! homogeneous box of the body's mass whose principal moments are the body's, turned
//! (`xformOp:orient`, only for a tensor that is not diagonal) onto its principal axes;
//! the box with sides `a, b, c` has `I₁ = M(b² + c²)/12`, …, so
//! `a² = 6(I₂ + I₃ − I₁)/M`, …. An inertia no box has (a side not positive: a plate or
//! a rod's, at the limit a physical tensor allows) is shown as the `Sphere` of the
//! homogeneous ball with the mean principal moment, `r = √(5 Ī / (2M))`. Either way
//! `custom string splinerod:kind` says which (`inertiaBox`, `inertiaSphere`).
//!
//! The body's contact shapes (`spheres`, `capsules`) follow as children `contact_<j>`,
//! in the scene's order (spheres first): a `Sphere` of the shape's radius translated to
//! its centre, or a `Capsule` (axis `Z`, `height` the axis's length) translated to the
//! axis's midpoint and turned from z onto it; `splinerod:kind` `contactSphere` or
//! `contactCapsule`. They are what meets the floor and the obstacles.

use super::text::{quoted, tuple, Num, ATTRIBUTE, SAMPLE};
use crate::world::body_contact::BodyShape;
use crate::RodSystem;
use nalgebra::{Matrix3, Rotation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use splinerod_core::{Real, RigidBody};
use std::collections::BTreeSet;
use std::fmt::{self, Write};

/// What the child prim shows of a body's mass distribution.
#[derive(Debug, Clone, PartialEq)]
enum Shown {
    /// The box of these sides along the principal axes, turned by `axes` from the body
    /// frame (identity for a diagonal tensor).
    Box {
        sides: Vector3<Real>,
        axes: UnitQuaternion<Real>,
    },
    /// The ball of this radius.
    Ball { radius: Real },
}

/// One body's prim: its name, mass properties and what shows it.
#[derive(Debug, Clone)]
pub(super) struct BodyStyle {
    /// Its prim name.
    prim: String,
    /// The body's name (`[[bodies]] name`).
    name: String,
    /// Mass, kg.
    mass: Real,
    /// Inertia about the centre of mass in the body frame, kg m².
    inertia: Matrix3<Real>,
    /// The child prim.
    shown: Shown,
    /// Its contact shapes.
    contacts: Vec<BodyShape>,
}

/// One body's samples so far: its translate's and its orient's lines.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub(super) struct BodyStreams {
    /// `xformOp:translate` samples.
    translate: String,
    /// `xformOp:orient` samples.
    orient: String,
}

/// The style of every body of `system` (prim names unique).
pub(super) fn styles(system: &RodSystem) -> Vec<BodyStyle> {
    let mut taken = BTreeSet::new();
    let bodies = system.bodies.bodies.iter().zip(&system.bodies.names);
    bodies
        .enumerate()
        .map(|(k, (body, name))| BodyStyle {
            prim: super::unique(
                &mut taken,
                super::text::prim_name(name, &format!("body_{k}")),
            ),
            name: name.clone(),
            mass: body.mass,
            inertia: body.inertia,
            shown: shown(body.mass, &body.inertia),
            contacts: contact_shapes(system, k),
        })
        .collect()
}

/// Body `k`'s contact shapes, spheres first (the scene's order).
fn contact_shapes(system: &RodSystem, k: usize) -> Vec<BodyShape> {
    let mine = system.bodies.contact.shapes.iter().filter(|s| s.body == k);
    let (spheres, capsules): (Vec<BodyShape>, Vec<BodyShape>) = mine.partition(|s| s.a == s.b);
    spheres.into_iter().chain(capsules).collect()
}

/// The box whose principal moments are `inertia`'s for `mass`, or the ball.
fn shown(mass: Real, inertia: &Matrix3<Real>) -> Shown {
    let diagonal = (0..3).all(|i| (0..3).all(|j| i == j || inertia[(i, j)] == 0.0));
    let (moments, axes) = if diagonal {
        (inertia.diagonal(), UnitQuaternion::identity())
    } else {
        let eigen = inertia.symmetric_eigen();
        let mut v = eigen.eigenvectors;
        if v.determinant() < 0.0 {
            v.column_mut(2).neg_mut();
        }
        let turn = Rotation3::from_matrix(&v);
        (
            eigen.eigenvalues,
            UnitQuaternion::from_rotation_matrix(&turn),
        )
    };
    let sum = moments.sum();
    let squares = moments.map(|m| 6.0 * (sum - 2.0 * m) / mass);
    if squares.iter().all(|&s| s > 1e-12 * squares.amax()) {
        Shown::Box {
            sides: squares.map(Real::sqrt),
            axes,
        }
    } else {
        Shown::Ball {
            radius: (5.0 * sum / 3.0 / (2.0 * mass)).sqrt(),
        }
    }
}

impl BodyStreams {
    /// Appends `body`'s pose at `code`.
    pub(super) fn record(&mut self, body: &RigidBody, code: i64) -> fmt::Result {
        write!(self.translate, "{SAMPLE}{code}: ")?;
        tuple(&mut self.translate, &body.position, Num)?;
        self.translate.push_str(",\n");
        write!(self.orient, "{SAMPLE}{code}: ")?;
        quaternion(&mut self.orient, &body.orientation)?;
        self.orient.push_str(",\n");
        Ok(())
    }
}

/// `(w, x, y, z)`, USD's order for a `quatd`.
fn quaternion(out: &mut String, q: &UnitQuaternion<Real>) -> fmt::Result {
    let (w, x, y, z) = (Num(q.w), Num(q.i), Num(q.j), Num(q.k));
    write!(out, "({w}, {x}, {y}, {z})")
}

impl BodyStyle {
    /// The body's `Xform` with its samples `s` and its child.
    pub(super) fn write(&self, out: &mut String, s: &BodyStreams) -> fmt::Result {
        let a = ATTRIBUTE;
        writeln!(out, "        def Xform \"{}\"\n        {{", self.prim)?;
        super::text::time_samples(out, "double3 xformOp:translate", &s.translate)?;
        super::text::time_samples(out, "quatd xformOp:orient", &s.orient)?;
        writeln!(
            out,
            "{a}uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:orient\"]"
        )?;
        writeln!(out, "{a}custom string splinerod:kind = \"body\"")?;
        writeln!(
            out,
            "{a}custom string splinerod:name = {}",
            quoted(&self.name)
        )?;
        writeln!(out, "{a}custom double splinerod:mass = {}", Num(self.mass))?;
        write!(out, "{a}custom matrix3d splinerod:inertia = (")?;
        for i in 0..3 {
            if i > 0 {
                out.push_str(", ");
            }
            tuple(out, &self.inertia.row(i).transpose(), Num)?;
        }
        writeln!(out, ")")?;
        self.write_shape(out)?;
        for (j, shape) in self.contacts.iter().enumerate() {
            write_contact(out, j, shape)?;
        }
        writeln!(out, "        }}")
    }

    /// The child prim `shape` (module docs).
    fn write_shape(&self, out: &mut String) -> fmt::Result {
        let a = format!("{ATTRIBUTE}    ");
        let (kind, order) = match &self.shown {
            Shown::Box { sides, axes } => {
                writeln!(out, "{ATTRIBUTE}def Cube \"shape\"\n{ATTRIBUTE}{{")?;
                writeln!(out, "{a}double size = 1")?;
                writeln!(
                    out,
                    "{a}float3[] extent = [(-0.5, -0.5, -0.5), (0.5, 0.5, 0.5)]"
                )?;
                let mut order = Vec::new();
                if *axes != UnitQuaternion::identity() {
                    write!(out, "{a}quatd xformOp:orient = ")?;
                    quaternion(out, axes)?;
                    out.push('\n');
                    order.push("\"xformOp:orient\"");
                }
                write!(out, "{a}double3 xformOp:scale = ")?;
                tuple(out, sides, Num)?;
                out.push('\n');
                order.push("\"xformOp:scale\"");
                ("inertiaBox", order)
            }
            Shown::Ball { radius } => {
                writeln!(out, "{ATTRIBUTE}def Sphere \"shape\"\n{ATTRIBUTE}{{")?;
                writeln!(out, "{a}double radius = {}", Num(*radius))?;
                let (m, p) = (Num(-radius), Num(*radius));
                writeln!(
                    out,
                    "{a}float3[] extent = [({m}, {m}, {m}), ({p}, {p}, {p})]"
                )?;
                ("inertiaSphere", Vec::new())
            }
        };
        if !order.is_empty() {
            writeln!(
                out,
                "{a}uniform token[] xformOpOrder = [{}]",
                order.join(", ")
            )?;
        }
        writeln!(out, "{a}custom string splinerod:kind = {}", quoted(kind))?;
        writeln!(out, "{ATTRIBUTE}}}")
    }
}

/// Contact shape `j`'s prim (module docs).
fn write_contact(out: &mut String, j: usize, shape: &BodyShape) -> fmt::Result {
    let a = format!("{ATTRIBUTE}    ");
    let (r, axis) = (shape.radius, shape.b - shape.a);
    let (kind, half) = if axis == Vector3::zeros() {
        writeln!(out, "{ATTRIBUTE}def Sphere \"contact_{j}\"\n{ATTRIBUTE}{{")?;
        ("contactSphere", 0.0)
    } else {
        writeln!(out, "{ATTRIBUTE}def Capsule \"contact_{j}\"\n{ATTRIBUTE}{{")?;
        writeln!(out, "{a}uniform token axis = \"Z\"")?;
        writeln!(out, "{a}double height = {}", Num(axis.norm()))?;
        ("contactCapsule", 0.5 * axis.norm())
    };
    writeln!(out, "{a}double radius = {}", Num(r))?;
    let (m, p, zm, zp) = (Num(-r), Num(r), Num(-r - half), Num(r + half));
    writeln!(
        out,
        "{a}float3[] extent = [({m}, {m}, {zm}), ({p}, {p}, {zp})]"
    )?;
    write!(out, "{a}double3 xformOp:translate = ")?;
    tuple(out, &((shape.a + shape.b) * 0.5), Num)?;
    out.push('\n');
    let mut order = "\"xformOp:translate\"".to_string();
    if half > 0.0 {
        let turn = UnitQuaternion::rotation_between(&Vector3::z(), &axis).unwrap_or_else(|| {
            UnitQuaternion::from_scaled_axis(Vector3::x() * std::f64::consts::PI)
        });
        write!(out, "{a}quatd xformOp:orient = ")?;
        quaternion(out, &turn)?;
        out.push('\n');
        order.push_str(", \"xformOp:orient\"");
    }
    writeln!(out, "{a}uniform token[] xformOpOrder = [{order}]")?;
    writeln!(out, "{a}custom string splinerod:kind = {}", quoted(kind))?;
    writeln!(out, "{ATTRIBUTE}}}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_box_has_the_moments_it_was_made_from() {
        let (m, sides) = (3.0, Vector3::new(0.2, 0.5, 0.7));
        let s2 = sides.map(|s| s * s);
        let moments = Vector3::new(s2.y + s2.z, s2.x + s2.z, s2.x + s2.y) * (m / 12.0);
        let Shown::Box { sides: got, axes } = shown(m, &Matrix3::from_diagonal(&moments)) else {
            panic!("a box's inertia");
        };
        assert!((got - sides).amax() < 1e-15 && axes == UnitQuaternion::identity());
        // Turned: the same box along the principal axes.
        let turn = UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.2, 0.5));
        let r = turn.to_rotation_matrix();
        let tensor = r.matrix() * Matrix3::from_diagonal(&moments) * r.matrix().transpose();
        let Shown::Box { sides: got, axes } = shown(m, &tensor) else {
            panic!("a turned box's inertia");
        };
        let back = axes.inverse().to_rotation_matrix();
        let principal = back.matrix() * tensor * back.matrix().transpose();
        for i in 0..3 {
            let s = got.map(|s| s * s);
            let expected = m / 12.0 * (s.sum() - s[i]);
            assert!((principal[(i, i)] - expected).abs() < 1e-14);
        }
        // A plate (I₃ = I₁ + I₂) has no box: the ball of the mean moment.
        let plate = Matrix3::from_diagonal(&Vector3::new(1.0, 2.0, 3.0));
        let Shown::Ball { radius } = shown(2.0, &plate) else {
            panic!("a plate is shown as a ball");
        };
        assert!((0.4 * 2.0 * radius * radius - 2.0).abs() < 1e-14);
    }
}
