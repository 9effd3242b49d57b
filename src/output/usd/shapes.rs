//! The floor and the `[[obstacles]]` as transformed USD primitives: every prim's first
//! op `xformOp:translate` (double3) is the obstacle's reference point where the
//! simulation has it (a plane's `point`, a sphere's `centre`, a capsule's end `a`),
//! time-sampled for an obstacle with a `path` (at every recorded time code) and a
//! plain value otherwise; `xformOp:orient` (quatd) turns the local axis onto the
//! plane's normal or the capsule's axis.
//!
//! * sphere → `Sphere` (`radius`);
//! * capsule → `Capsule` (`axis = "Z"`, `height = |b − a|`, `radius`), shifted by
//!   `xformOp:translate:centre = (0, 0, height/2)` so that its end `a` is at the origin
//!   of the first translate;
//! * plane and floor → `Mesh`: one square (`doubleSided`), side
//!   [`PLANE_SPAN`] × the rods' total rest length plus twice the distance from the plane's
//!   point to their centre of mass at the start, in the local `y = 0` plane (normal `+y`).
//!
//! Each also carries `custom string splinerod:kind` (`floor`, `plane`, `sphere`,
//! `capsule`) and its scene geometry exactly (`splinerod:normal`, `splinerod:b` at the
//! start).
//!
//! Rigid bodies are written next to these, under `/World/Bodies`, with the same two ops
//! time-sampled (their centre of mass and orientation; see `super::bodies`).

use super::text::{quoted, tuple, Num, ATTRIBUTE, SAMPLE};
use crate::Scene;
use nalgebra::{UnitQuaternion, Vector3};
use splinerod_core::Real;
use splinerod_energies::Obstacle;
use std::fmt::{self, Write};

/// A plane's square is this many times the rods' total rest length across (plus the
/// distance to them).
pub(super) const PLANE_SPAN: Real = 4.0;

/// One floor or obstacle prim: what it is and where it has been.
#[derive(Debug, Clone)]
pub(super) struct Shape {
    /// Its prim name.
    pub prim: String,
    /// `floor`, `plane`, `sphere` or `capsule`.
    pub kind: &'static str,
    /// The obstacle as the scene gives it (before any `path`).
    pub start: Obstacle,
    /// Whether it moves (has a `path`).
    pub moving: bool,
}

/// The floor (first, when `[contact]` has one) and every `[[obstacles]]` entry.
pub(super) fn of_scene(scene: &Scene) -> Vec<Shape> {
    let floor = (scene.contact.as_ref().filter(|c| c.enabled)).and_then(|c| c.floor);
    let floor = floor.map(|h| Shape {
        prim: "floor".into(),
        kind: "floor",
        start: Obstacle::Plane {
            point: Vector3::new(0.0, h, 0.0),
            normal: Vector3::y(),
        },
        moving: false,
    });
    let obstacles = scene.obstacles.iter().enumerate().map(|(i, spec)| {
        let start = spec.obstacle();
        let kind = match start {
            Obstacle::Plane { .. } => "plane",
            Obstacle::Sphere { .. } => "sphere",
            Obstacle::Capsule { .. } => "capsule",
        };
        let moving = spec.motion().0.is_some();
        let prim = format!("obstacle_{i}");
        Shape {
            prim,
            kind,
            start,
            moving,
        }
    });
    floor.into_iter().chain(obstacles).collect()
}

impl Shape {
    /// Half the side of a plane's square: [`PLANE_SPAN`] / 2 × the rods' `total` rest
    /// length plus the distance from its point to their `centre` of mass.
    pub(super) fn half_side(&self, total: Real, centre: &Vector3<Real>) -> Real {
        0.5 * PLANE_SPAN * total + (Self::anchor(&self.start) - centre).norm()
    }

    /// The obstacle's reference point (the first translate).
    pub(super) fn anchor(obstacle: &Obstacle) -> Vector3<Real> {
        match *obstacle {
            Obstacle::Plane { point, .. } => point,
            Obstacle::Sphere { centre, .. } => centre,
            Obstacle::Capsule { a, .. } => a,
        }
    }

    /// Appends the time sample of the first translate at `code`.
    pub(super) fn record(samples: &mut String, obstacle: &Obstacle, code: i64) -> fmt::Result {
        write!(samples, "{SAMPLE}{code}: ")?;
        tuple(samples, &Self::anchor(obstacle), Num)?;
        samples.push_str(",\n");
        Ok(())
    }

    /// The prim, with `moves` the translate's time samples (`None`: static) and
    /// `half_side` a plane's (see [`Shape::half_side`]).
    pub(super) fn write(
        &self,
        out: &mut String,
        moves: Option<&str>,
        half_side: Real,
    ) -> fmt::Result {
        let a = ATTRIBUTE;
        match self.start {
            Obstacle::Plane { normal, .. } => {
                writeln!(out, "        def Mesh \"{}\"\n        {{", self.prim)?;
                let s = half_side;
                writeln!(out, "{a}int[] faceVertexCounts = [4]")?;
                writeln!(out, "{a}int[] faceVertexIndices = [0, 1, 2, 3]")?;
                let (m, p) = (Num(-s), Num(s));
                writeln!(
                    out,
                    "{a}point3f[] points = [({m}, 0, {m}), ({m}, 0, {p}), ({p}, 0, {p}), ({p}, 0, {m})]"
                )?;
                writeln!(out, "{a}float3[] extent = [({m}, 0, {m}), ({p}, 0, {p})]")?;
                writeln!(out, "{a}uniform bool doubleSided = 1")?;
                self.write_transform(out, moves, &Vector3::y(), &normal)?;
                write!(out, "{a}custom double3 splinerod:normal = ")?;
                tuple(out, &normal, Num)?;
                out.push('\n');
            }
            Obstacle::Sphere { radius, .. } => {
                writeln!(out, "        def Sphere \"{}\"\n        {{", self.prim)?;
                writeln!(out, "{a}double radius = {}", Num(radius))?;
                let (m, p) = (Num(-radius), Num(radius));
                writeln!(
                    out,
                    "{a}float3[] extent = [({m}, {m}, {m}), ({p}, {p}, {p})]"
                )?;
                self.write_transform(out, moves, &Vector3::z(), &Vector3::z())?;
            }
            Obstacle::Capsule {
                a: start,
                b,
                radius,
            } => {
                writeln!(out, "        def Capsule \"{}\"\n        {{", self.prim)?;
                let axis = b - start;
                let h = axis.norm();
                writeln!(out, "{a}uniform token axis = \"Z\"")?;
                writeln!(out, "{a}double height = {}", Num(h))?;
                writeln!(out, "{a}double radius = {}", Num(radius))?;
                let (m, p, z) = (Num(-radius), Num(radius), Num(0.5 * h + radius));
                let mz = Num(-(0.5 * h + radius));
                writeln!(
                    out,
                    "{a}float3[] extent = [({m}, {m}, {mz}), ({p}, {p}, {z})]"
                )?;
                self.write_transform(out, moves, &Vector3::z(), &axis)?;
                write!(out, "{a}custom double3 splinerod:b = ")?;
                tuple(out, &b, Num)?;
                out.push('\n');
            }
        }
        writeln!(
            out,
            "{a}custom string splinerod:kind = {}",
            quoted(self.kind)
        )?;
        writeln!(out, "        }}")
    }

    /// `xformOp:translate` (static or `moves`), `xformOp:orient` turning `local` onto
    /// `direction` unless they agree, a capsule's shift to its centre, and the op order.
    fn write_transform(
        &self,
        out: &mut String,
        moves: Option<&str>,
        local: &Vector3<Real>,
        direction: &Vector3<Real>,
    ) -> fmt::Result {
        let a = ATTRIBUTE;
        match moves {
            Some(samples) => {
                writeln!(out, "{a}double3 xformOp:translate.timeSamples = {{")?;
                out.push_str(samples);
                writeln!(out, "{a}}}")?;
            }
            None => {
                write!(out, "{a}double3 xformOp:translate = ")?;
                tuple(out, &Self::anchor(&self.start), Num)?;
                out.push('\n');
            }
        }
        let mut order = vec!["\"xformOp:translate\""];
        let turn = rotation(local, direction);
        if turn != UnitQuaternion::identity() {
            let q = turn.quaternion();
            let (w, x, y, z) = (Num(q.w), Num(q.i), Num(q.j), Num(q.k));
            writeln!(out, "{a}quatd xformOp:orient = ({w}, {x}, {y}, {z})")?;
            order.push("\"xformOp:orient\"");
        }
        if let Obstacle::Capsule { a: start, b, .. } = self.start {
            let half = Num(0.5 * (b - start).norm());
            writeln!(out, "{a}double3 xformOp:translate:centre = (0, 0, {half})")?;
            order.push("\"xformOp:translate:centre\"");
        }
        writeln!(
            out,
            "{a}uniform token[] xformOpOrder = [{}]",
            order.join(", ")
        )
    }
}

/// The rotation turning `from` onto `to` (a half turn about an axis normal to `from`
/// when they are opposite).
fn rotation(from: &Vector3<Real>, to: &Vector3<Real>) -> UnitQuaternion<Real> {
    let (u, v) = (from.normalize(), to.normalize());
    UnitQuaternion::rotation_between(&u, &v).unwrap_or_else(|| {
        let other = if u.x.abs() < 0.9 {
            Vector3::x()
        } else {
            Vector3::y()
        };
        let axis = nalgebra::Unit::new_normalize(u.cross(&other));
        UnitQuaternion::from_axis_angle(&axis, std::f64::consts::PI)
    })
}
