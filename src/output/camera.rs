//! Cameras and framing for the pictures: a [`Camera`] projects 3-D points (orthographic
//! `xy`, `xz`, `yz`, or an `oblique` view with depth), and a [`View`] fixes where they
//! land on the picture, chosen once at the first frame (see the rules in
//! [`crate::output::picture`]). Also the densely sampled [`centreline`].

use super::plot::{HEIGHT, WIDTH};
use crate::run::observe::Frame;
use crate::Error;
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};
use splinerod_energies::Obstacle;

/// Centreline samples per knot span.
const SAMPLES_PER_SPAN: usize = 40;
/// Blank border around the drawing, px.
pub(crate) const MARGIN: f64 = 20.0;
/// Height of the caption strip at the bottom, px.
pub(crate) const CAPTION: f64 = 34.0;
/// Lengths are stretched by this factor when computing the reach.
const STRETCH: Real = 1.1;

/// How the 3-D rod is projected onto the picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Camera {
    /// x right, y up (seen from +z).
    Xy,
    /// x right, z up (seen from −y).
    Xz,
    /// y right, z up (seen from +x).
    Yz,
    /// y up, turned 30° about y and tilted 20° down; farther is lighter and thinner.
    Oblique,
}

/// The cameras by name.
const CAMERAS: [(&str, Camera); 4] = [
    ("xy", Camera::Xy),
    ("xz", Camera::Xz),
    ("yz", Camera::Yz),
    ("oblique", Camera::Oblique),
];

impl Camera {
    /// Parses `xy`, `xz`, `yz` or `oblique`; the error names the `--camera` option.
    pub fn from_name(name: &str) -> Result<Self, Error> {
        let found = CAMERAS.iter().find(|c| c.0 == name).map(|c| c.1);
        found.ok_or_else(|| {
            let reason = "must be one of xy, xz, yz, oblique";
            Error::field("--camera", format!("{name:?}"), reason)
        })
    }

    /// The name [`from_name`](Self::from_name) accepts.
    pub fn name(self) -> &'static str {
        CAMERAS.iter().find(|c| c.1 == self).map_or("", |c| c.0)
    }

    /// View coordinates `[right, up, toward the viewer]` of a world point, m.
    pub fn project(self, p: &Vector3<Real>) -> [Real; 3] {
        match self {
            Self::Xy => [p.x, p.y, p.z],
            Self::Xz => [p.x, p.z, -p.y],
            Self::Yz => [p.y, p.z, p.x],
            Self::Oblique => {
                let (sa, ca) = 30f64.to_radians().sin_cos();
                let (se, ce) = 20f64.to_radians().sin_cos();
                let (x1, z1) = (p.x * ca + p.z * sa, -p.x * sa + p.z * ca);
                [x1, p.y * ce - z1 * se, p.y * se + z1 * ce]
            }
        }
    }
}

/// A camera with a fixed framing: where world points land on the picture.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct View {
    /// The projection.
    pub camera: Camera,
    centre: [Real; 2],
    /// Pixels per metre.
    scale: Real,
    /// Range of the toward-viewer coordinate (oblique shading).
    depth: (Real, Real),
}

impl View {
    /// The framing that shows all `points` (at least one) with equal scales, leaving a
    /// margin and the caption strip free.
    pub fn fit(camera: Camera, points: &[Vector3<Real>]) -> Self {
        let mut lo = [Real::INFINITY; 3];
        let mut hi = [Real::NEG_INFINITY; 3];
        for p in points {
            let v = camera.project(p);
            for k in 0..3 {
                lo[k] = lo[k].min(v[k]);
                hi[k] = hi[k].max(v[k]);
            }
        }
        if !(lo[0] <= hi[0] && lo[1] <= hi[1]) {
            (lo, hi) = ([-1.0; 3], [1.0; 3]);
        }
        let span = ((hi[0] - lo[0]).max(hi[1] - lo[1]) * 1e-3).max(1e-9);
        let (w, h) = (hi[0] - lo[0] + span, hi[1] - lo[1] + span);
        let (aw, ah) = plot_area();
        Self {
            camera,
            centre: [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])],
            scale: (aw / w).min(ah / h),
            depth: (lo[2], hi[2]),
        }
    }

    /// Picture coordinates of a world point, px (x right, y down, origin top left).
    pub fn pixel(&self, p: &Vector3<Real>) -> (f64, f64) {
        let v = self.camera.project(p);
        self.view_pixel(v[0], v[1])
    }

    /// Metres per pixel.
    pub fn metres_per_pixel(&self) -> Real {
        1.0 / self.scale
    }

    /// How far back `p` is, 0 (nearest) to 1 (farthest); 0 in orthographic views.
    pub fn farness(&self, p: &Vector3<Real>) -> Real {
        let (near, far) = (self.depth.1, self.depth.0);
        if self.camera != Camera::Oblique || near - far <= 0.0 {
            return 0.0;
        }
        ((near - self.camera.project(p)[2]) / (near - far)).clamp(0.0, 1.0)
    }

    /// Picture coordinates (px) of the view coordinates `right`, `up` (m).
    pub(crate) fn view_pixel(&self, right: Real, up: Real) -> (f64, f64) {
        let (_, ah) = plot_area();
        let x = 0.5 * f64::from(WIDTH) + (right - self.centre[0]) * self.scale;
        let y = MARGIN + 0.5 * ah - (up - self.centre[1]) * self.scale;
        (x, y)
    }

    /// The box of view coordinates `[right, up, toward]` (m) the picture shows: the
    /// whole picture above the caption across, and the depth of the framed points.
    pub(crate) fn view_box(&self) -> ([Real; 3], [Real; 3]) {
        let (_, ah) = plot_area();
        let half_w = 0.5 * f64::from(WIDTH) / self.scale;
        let (top, bottom) = (
            MARGIN + 0.5 * ah,
            f64::from(HEIGHT) - CAPTION - MARGIN - 0.5 * ah,
        );
        let lo = [
            self.centre[0] - half_w,
            self.centre[1] - bottom / self.scale,
            self.depth.0,
        ];
        let hi = [
            self.centre[0] + half_w,
            self.centre[1] + top / self.scale,
            self.depth.1,
        ];
        (lo, hi)
    }

    pub(crate) fn px(&self, p: &Vector3<Real>) -> (i32, i32) {
        let (x, y) = self.pixel(p);
        (x.round() as i32, y.round() as i32)
    }
}

/// Width and height available for the drawing, px.
fn plot_area() -> (f64, f64) {
    let w = f64::from(WIDTH) - 2.0 * MARGIN;
    let h = f64::from(HEIGHT) - 2.0 * MARGIN - CAPTION;
    (w, h)
}

/// The centreline sampled span by span: one polyline per non-empty knot span. The last
/// sample of a span ending at a cut is taken just before it (the left piece's end).
pub fn centreline(rod: &Rod) -> Result<Vec<Vec<Vector3<Real>>>, Error> {
    let cuts = rod.cuts();
    splinerod_core::basis::spans(rod.basis())
        .map(|span| {
            let len = span.end - span.start;
            (0..=SAMPLES_PER_SPAN)
                .map(|k| {
                    let mut s = span.start + len * k as Real / SAMPLES_PER_SPAN as Real;
                    if k == SAMPLES_PER_SPAN && cuts.contains(&span.end) {
                        s = span.end - 1e-9 * len;
                    }
                    Ok(rod.point(s)?)
                })
                .collect()
        })
        .collect()
}

/// The points the framing must cover (see the module docs).
pub(crate) fn framing_points(frame: &Frame<'_>) -> Result<Vec<Vector3<Real>>, Error> {
    let system = frame.system;
    let mut points: Vec<_> = centreline(&system.rod)?.concat();
    points.extend(system.rod.positions.iter().copied());
    let mut anchors: Vec<(Real, Vector3<Real>)> =
        system.pins.iter().map(|p| (p.at, p.position)).collect();
    anchors.extend(system.grabs.iter().map(|g| (g.spring.at, g.to)));
    anchors.sort_by(|a, b| a.0.total_cmp(&b.0));
    points.extend(anchors.iter().map(|a| a.1));
    let length = system.rod.material().rest_length;
    let mut reach = Vec::new();
    if let (Some(first), Some(last)) = (anchors.first(), anchors.last()) {
        reach.extend(region(first.1, first.1, first.0 * STRETCH));
        reach.extend(region(last.1, last.1, (length - last.0) * STRETCH));
    }
    for pair in anchors.windows(2) {
        let half = 0.5 * (pair[1].0 - pair[0].0) * STRETCH;
        reach.extend(region(pair[0].1, pair[1].1, half));
    }
    let g = Vector3::from(frame.scene.world.gravity);
    if g.norm() > 0.0 {
        let up = -g.normalize();
        let top = points.iter().map(|p| up.dot(p)).fold(Real::MIN, Real::max);
        for p in &mut reach {
            *p -= up * (up.dot(p) - top).max(0.0);
        }
    }
    points.extend(reach);
    // A rod that can fall onto the floor (y = floor) lands in the picture.
    if let Some(floor) = frame.scene.contact.as_ref().and_then(|c| c.floor) {
        let shadows: Vec<_> = points
            .iter()
            .map(|p| Vector3::new(p.x, floor, p.z))
            .collect();
        points.extend(shadows);
    }
    // The spheres and capsules, where they are now.
    for obstacle in super::scenery::obstacles_at(frame)? {
        let mut ball = |c: Vector3<Real>, r: Real| {
            for k in 0..3 {
                let e = Vector3::ith(k, r);
                points.extend([c + e, c - e]);
            }
        };
        match obstacle {
            Obstacle::Plane { .. } => {}
            Obstacle::Sphere { centre, radius } => ball(centre, radius),
            Obstacle::Capsule { a, b, radius } => {
                ball(a, radius);
                ball(b, radius);
            }
        }
    }
    Ok(points)
}

/// Points on the surface of the ellipsoid with foci `f1`, `f2` and semi-major axis `a`
/// (a ball of radius `a` when the foci coincide).
fn region(f1: Vector3<Real>, f2: Vector3<Real>, a: Real) -> Vec<Vector3<Real>> {
    let d = f2 - f1;
    let a = a.max(0.5 * d.norm());
    let b = (a * a - 0.25 * d.norm_squared()).max(0.0).sqrt();
    let e = d.try_normalize(1e-12).unwrap_or(Vector3::x());
    let n1 = e.cross(&Vector3::y()).try_normalize(1e-6);
    let n1 = n1.unwrap_or_else(|| e.cross(&Vector3::z()).normalize());
    let n2 = e.cross(&n1);
    let centre = 0.5 * (f1 + f2);
    let (rings, around) = (12, 24);
    let mut out = Vec::with_capacity((rings + 1) * around);
    for i in 0..=rings {
        let (st, ct) = (std::f64::consts::PI * i as Real / rings as Real).sin_cos();
        for j in 0..around {
            let (sp, cp) = (std::f64::consts::TAU * j as Real / around as Real).sin_cos();
            out.push(centre + e * (a * ct) + (n1 * cp + n2 * sp) * (b * st));
        }
    }
    out
}
