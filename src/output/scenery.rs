//! What a picture shows besides the rod: the floor and the `[[obstacles]]` where they
//! are at the frame's time, and the names of the rods of a `[[rods]]` scene.
//!
//! Every camera is orthographic (the oblique one is a rotation), so with view
//! coordinates \\(v = R x\\) (right, up, toward the viewer;
//! [`Camera::project`](super::camera::Camera::project)):
//! * a **plane** through `p` with normal `n` (the floor: `p = (0, floor, 0)`,
//!   `n = (0, 1, 0)`) is drawn as its solid side \\(\\{v : R n \cdot (v - R p) \le 0\\}\\)
//!   clipped to the view's box (the whole picture across, as deep as the framed points)
//!   and projected: a shaded band below a line when the plane is seen edge-on, a shaded
//!   strip of ground in the oblique view, outlined where the plane cuts the box. A plane
//!   seen nearly face-on (\\(|(R n)_z| > 0.9\\)) would cover the whole picture and is
//!   not drawn;
//! * a **sphere** of radius `r` projects to the disc of radius `r` around its projected
//!   centre;
//! * a **capsule** (radius `r` around the segment `a`–`b`) projects to the projected
//!   segment swept by that disc: two half circles joined by two lines.
//!
//! A rod's name is written beside the point of its centreline farthest (in the
//! picture) from the other rods and the names already placed.

use super::camera::View;
use crate::run::observe::Frame;
use crate::world::path::Path;
use crate::Error;
use nalgebra::Vector3;
use splinerod_core::Real;
use splinerod_energies::Obstacle;

/// A plane seen with `|n_z|` above this (nearly face-on) is not drawn.
const FACE_ON: Real = 0.9;
/// Points of a half circle of a capsule's outline.
const ARC_POINTS: usize = 24;
/// Material points of a rod tried as the anchor of its name.
const LABEL_CANDIDATES: usize = 21;

/// A rigid surface in picture coordinates, px.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Shape {
    /// A plane's solid side inside the view (a convex polygon) and the line where the
    /// plane cuts the view's box (two points when seen edge-on).
    Solid {
        /// The shaded region.
        fill: Vec<(i32, i32)>,
        /// Its outline on the plane, closed.
        edge: Vec<(i32, i32)>,
    },
    /// A disc or a capsule's outline: a closed polyline.
    Outline(Vec<(i32, i32)>),
}

/// The floor and obstacles of `frame` as seen through `view`, in scene order (the
/// floor first).
pub(crate) fn shapes(frame: &Frame<'_>, view: &View) -> Result<Vec<Shape>, Error> {
    let mut out = Vec::new();
    let contact = frame.scene.contact.as_ref().filter(|c| c.enabled);
    if let Some(floor) = contact.and_then(|c| c.floor) {
        let (p, n) = (Vector3::new(0.0, floor, 0.0), Vector3::y());
        out.extend(plane(view, &p, &n));
    }
    for obstacle in obstacles_at(frame)? {
        out.extend(obstacle_shape(view, &obstacle));
    }
    Ok(out)
}

/// The `[[obstacles]]` where they are at the frame's time.
pub(crate) fn obstacles_at(frame: &Frame<'_>) -> Result<Vec<Obstacle>, Error> {
    let mut out = Vec::with_capacity(frame.scene.obstacles.len());
    for (i, spec) in frame.scene.obstacles.iter().enumerate() {
        let mut obstacle = spec.obstacle();
        if let (Some(keyframes), interpolation) = spec.motion() {
            let field = format!("obstacles[{i}].path");
            let path = Path::new(keyframes, interpolation, &field)?;
            obstacle = obstacle.translated(&path.at(frame.time));
        }
        out.push(obstacle);
    }
    Ok(out)
}

/// One obstacle's shape (`None` for a plane seen face-on).
fn obstacle_shape(view: &View, obstacle: &Obstacle) -> Option<Shape> {
    match *obstacle {
        Obstacle::Plane { point, normal } => plane(view, &point, &normal),
        Obstacle::Sphere { centre, radius } => Some(capsule(view, &centre, &centre, radius)),
        Obstacle::Capsule { a, b, radius } => Some(capsule(view, &a, &b, radius)),
    }
}

/// The solid side of the plane through `p` with normal `n`, clipped to the view's box.
fn plane(view: &View, p: &Vector3<Real>, n: &Vector3<Real>) -> Option<Shape> {
    let camera = view.camera;
    let (pv, nv) = (camera.project(p), camera.project(&n.normalize()));
    if nv[2].abs() > FACE_ON {
        return None;
    }
    let side = |v: &[Real; 3]| (0..3).map(|k| nv[k] * (v[k] - pv[k])).sum::<Real>();
    let (lo, hi) = view.view_box();
    let corner = |i: usize| -> [Real; 3] {
        std::array::from_fn(|k| if i >> k & 1 == 0 { lo[k] } else { hi[k] })
    };
    let (mut solid, mut section) = (Vec::new(), Vec::new());
    for i in 0..8 {
        let c = corner(i);
        if side(&c) <= 0.0 {
            solid.push(c);
        }
        for bit in [1, 2, 4].into_iter().filter(|b| i & b == 0) {
            let d = corner(i | bit);
            let (f, g) = (side(&c), side(&d));
            if (f < 0.0) != (g < 0.0) && f != g {
                let t = f / (f - g);
                let v: [Real; 3] = std::array::from_fn(|k| c[k] + t * (d[k] - c[k]));
                section.push(v);
                solid.push(v);
            }
        }
    }
    if section.is_empty() {
        return None; // the plane misses the picture
    }
    let px = |vs: &[[Real; 3]]| hull(vs.iter().map(|v| view.view_pixel(v[0], v[1])).collect());
    let mut edge = px(&section);
    if edge.len() > 2 {
        edge.push(edge[0]); // a polygon, closed (two points are a line seen edge-on)
    }
    Some(Shape::Solid {
        fill: px(&solid),
        edge,
    })
}

/// The outline of the points within `radius` of the segment `a`–`b` (a disc when
/// `a = b` or when the segment is seen end-on).
fn capsule(view: &View, a: &Vector3<Real>, b: &Vector3<Real>, radius: Real) -> Shape {
    let (pa, pb) = (view.pixel(a), view.pixel(b));
    let r = radius / view.metres_per_pixel();
    let phi = (pb.1 - pa.1).atan2(pb.0 - pa.0); // the axis' direction on the picture
    let half = std::f64::consts::FRAC_PI_2;
    let arc = |c: (f64, f64), from: f64| {
        (0..=ARC_POINTS).map(move |k| {
            let t = from + std::f64::consts::PI * k as f64 / ARC_POINTS as f64;
            (c.0 + r * t.cos(), c.1 + r * t.sin())
        })
    };
    // The half circle around `b` facing away from `a`, then the one around `a` facing
    // away from `b`; the gaps between them are the two straight sides.
    let points: Vec<(f64, f64)> = arc(pb, phi - half).chain(arc(pa, phi + half)).collect();
    let mut outline: Vec<(i32, i32)> = points.iter().map(|p| round(*p)).collect();
    outline.push(outline[0]);
    Shape::Outline(outline)
}

/// A rod's name and the point of the picture it names, px.
pub(crate) type Label = (String, (i32, i32));

/// Where each rod's name goes in a `[[rods]]` scene (none for one rod): beside the
/// point of its centreline farthest from the other rods and the names already placed.
pub(crate) fn labels(frame: &Frame<'_>, view: &View) -> Result<Vec<Label>, Error> {
    let scene = frame.scene;
    if scene.rods.len() < 2 {
        return Ok(Vec::new());
    }
    let rod = &frame.system.rod;
    let fractions: Vec<Real> = (0..LABEL_CANDIDATES)
        .map(|k| (k as Real + 0.5) / LABEL_CANDIDATES as Real)
        .collect();
    let mut candidates = Vec::with_capacity(scene.rods.len());
    for k in 0..scene.rods.len() {
        let points = fractions
            .iter()
            .map(|&f| Ok(view.pixel(&rod.point(scene.coordinate(k, f))?)))
            .collect::<Result<Vec<_>, Error>>()?;
        candidates.push(points);
    }
    let mut placed: Vec<(f64, f64)> = Vec::new();
    let mut out = Vec::new();
    for (k, spec) in scene.rods.iter().enumerate() {
        let others: Vec<(f64, f64)> = candidates
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != k)
            .flat_map(|(_, p)| p.iter().copied())
            .chain(placed.iter().copied())
            .collect();
        let clearance = |p: &(f64, f64)| {
            let d = others.iter().map(|o| (o.0 - p.0).hypot(o.1 - p.1));
            d.fold(f64::INFINITY, f64::min)
        };
        let best = candidates[k]
            .iter()
            .max_by(|a, b| clearance(a).total_cmp(&clearance(b)))
            .copied()
            .unwrap_or_default();
        placed.push(best);
        let name = spec.name.clone().unwrap_or_else(|| format!("rods[{k}]"));
        out.push((name, round(best)));
    }
    Ok(out)
}

/// The nearest pixel.
fn round(p: (f64, f64)) -> (i32, i32) {
    (p.0.round() as i32, p.1.round() as i32)
}

/// The convex hull of `points` (px), counter-clockwise on screen, as whole pixels
/// (Andrew's monotone chain; collinear points give the two ends).
fn hull(mut points: Vec<(f64, f64)>) -> Vec<(i32, i32)> {
    points.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
    points.dedup_by(|a, b| (a.0 - b.0).abs() < 1e-9 && (a.1 - b.1).abs() < 1e-9);
    if points.len() < 3 {
        return points.into_iter().map(round).collect();
    }
    let cross = |o: (f64, f64), a: (f64, f64), b: (f64, f64)| {
        (a.0 - o.0) * (b.1 - o.1) - (a.1 - o.1) * (b.0 - o.0)
    };
    let mut out: Vec<(f64, f64)> = Vec::with_capacity(2 * points.len());
    for pass in [points.clone(), points.into_iter().rev().collect()] {
        let floor = out.len();
        for p in pass {
            while out.len() >= floor + 2 && cross(out[out.len() - 2], out[out.len() - 1], p) <= 1e-9
            {
                out.pop();
            }
            out.push(p);
        }
        out.pop();
    }
    out.into_iter().map(round).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::camera::Camera;

    fn view(camera: Camera) -> View {
        let points = [Vector3::new(-1.0, -1.0, -1.0), Vector3::new(1.0, 1.0, 1.0)];
        View::fit(camera, &points)
    }

    #[test]
    fn hull_of_a_square_and_its_centre_is_the_square() {
        let square = vec![
            (0.0, 0.0),
            (10.0, 0.0),
            (10.0, 10.0),
            (0.0, 10.0),
            (5.0, 5.0),
        ];
        let mut h = hull(square);
        h.sort();
        assert_eq!(h, vec![(0, 0), (0, 10), (10, 0), (10, 10)]);
    }

    #[test]
    fn floor_seen_edge_on_is_a_band_below_a_line_at_its_height() {
        let v = view(Camera::Xy);
        let Some(Shape::Solid { fill, edge }) = plane(&v, &Vector3::zeros(), &Vector3::y()) else {
            panic!("the floor is seen edge-on in the xy view");
        };
        let y0 = v.px(&Vector3::zeros()).1;
        // The edge is a horizontal line at the floor's height (within a pixel).
        assert!(edge.iter().all(|p| (p.1 - y0).abs() <= 1), "{edge:?}");
        // The band lies below it (larger picture y) and reaches the picture's bottom edge.
        assert!(fill.iter().all(|p| p.1 >= y0 - 1), "{fill:?}");
        assert!(
            fill.iter().map(|p| p.1).max().unwrap() > y0 + 10,
            "{fill:?}"
        );
    }

    #[test]
    fn floor_seen_face_on_is_not_drawn() {
        assert_eq!(
            plane(&view(Camera::Xz), &Vector3::zeros(), &Vector3::y()),
            None
        );
    }

    #[test]
    fn sphere_outline_is_a_circle_of_its_radius() {
        let v = view(Camera::Oblique);
        let centre = Vector3::new(0.2, 0.1, -0.3);
        let Shape::Outline(points) = capsule(&v, &centre, &centre, 0.5) else {
            panic!("a sphere is an outline");
        };
        let c = v.pixel(&centre);
        let r = 0.5 / v.metres_per_pixel();
        for p in points {
            let d = (f64::from(p.0) - c.0).hypot(f64::from(p.1) - c.1);
            assert!((d - r).abs() <= 1.0, "{d} vs {r}");
        }
    }

    #[test]
    fn capsule_outline_keeps_its_radius_from_the_axis() {
        let v = view(Camera::Xy);
        let (a, b) = (Vector3::new(-0.5, 0.0, 0.0), Vector3::new(0.5, 0.3, 0.0));
        let Shape::Outline(points) = capsule(&v, &a, &b, 0.2) else {
            panic!("a capsule is an outline");
        };
        let (pa, pb) = (v.pixel(&a), v.pixel(&b));
        let r = 0.2 / v.metres_per_pixel();
        for p in points {
            let p = (f64::from(p.0), f64::from(p.1));
            let d = segment_distance(p, pa, pb);
            assert!((d - r).abs() <= 1.0, "{d} vs {r}");
        }
    }

    fn segment_distance(p: (f64, f64), a: (f64, f64), b: (f64, f64)) -> f64 {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let t = (((p.0 - a.0) * dx + (p.1 - a.1) * dy) / (dx * dx + dy * dy)).clamp(0.0, 1.0);
        (p.0 - a.0 - t * dx).hypot(p.1 - a.1 - t * dy)
    }
}
