//! Pictures of the rod: the [`Pictures`] observer writes PNG frames (and SVG when
//! asked, and an animated GIF) of the centreline as the run unfolds.
//!
//! Each frame shows the centreline drawn thick (at least the rod's diameter, where the
//! scene gives a `radius`) and densely sampled (40 samples per knot
//! span; no line is drawn across a cut), its knot spans coloured alternately blue and
//! orange so the knots are visible (as in Lenoir et al.'s fig. 4), optionally the
//! control polygon and control points (thin, grey), the pins (black squares), the
//! active grabs (red dot at the grabbed material point, red cross at the spring's
//! target), on a rod with twist the material frame as a dark stripe winding around the
//! centreline ([`super::ribbon`]), the floor and `[[obstacles]]` shaded light grey and
//! outlined (`super::scenery`), each rod's name in a `[[rods]]` scene, and a caption
//! with time, step, control points, rods or pieces, and scale.
//!
//! # Camera
//! A [`Camera`] is an orthographic projection (`xy`, `xz`, `yz`) or an `oblique` view
//! (y up, turned 30° about y and tilted 20° down) in which farther parts of the rod are
//! drawn lighter and thinner. The framing ([`View`]) is chosen once, at the first frame,
//! and kept, so motion is seen against a fixed frame. It covers:
//! * the initial centreline and control points, the pins and the grabs' targets;
//! * the reach of the rod hanging from its anchors (pins, and grabs at their final
//!   targets), ordered by material coordinate, with lengths 10 % longer than at rest
//!   to allow for stretching: between two consecutive anchors `p`, `q` the rod piece
//!   of rest length `ℓ` stays inside the ellipsoid `|x − p| + |x − q| ≤ ℓ`; a free end
//!   of rest length `ℓ` beyond an anchor `p` stays inside the ball `|x − p| ≤ ℓ`.
//!   Under gravity only the parts of those regions not higher than the initial
//!   configuration are used (a hanging rod does not rise above where it started);
//! * the floor below all of these, and the spheres and capsules of `[[obstacles]]`.
//!
//! A rod without anchors may fall out of the picture. The framing keeps equal scales
//! on both picture axes.

pub use super::camera::{centreline, Camera, View};
use super::camera::{framing_points, CAPTION, MARGIN};
use super::plot::{write_images, Drawing, GifWriter, FONT, HEIGHT, WIDTH};
use super::scenery::{self, Shape};
use crate::run::observe::{Frame, Observer};
use crate::{Error, RunResult, Scene, StepReport};
use nalgebra::Vector3;
use plotters::coord::Shift;
use plotters::prelude::*;
use splinerod_core::{Real, Rod};
use std::path::{Path, PathBuf};

/// Width of the centreline, px (nearest parts in the oblique view).
const LINE_WIDTH: f64 = 5.0;
/// Colours of alternate knot spans.
const SPAN_COLOURS: [RGBColor; 2] = [RGBColor(31, 119, 180), RGBColor(255, 127, 14)];
/// Control polygon and control points.
const GREY: RGBColor = RGBColor(150, 150, 150);
/// The floor and obstacles.
const SCENERY: RGBColor = RGBColor(228, 228, 228);
/// Font size of the rods' names, px.
const LABEL_FONT: f64 = 18.0;
/// Grabs.
const RED: RGBColor = RGBColor(214, 39, 40);
/// The material frame's stripe (rods with twist), its offset from the centreline (px)
/// and its samples.
const STRIPE: RGBColor = RGBColor(30, 30, 30);
const STRIPE_OFFSET: Real = 4.0;
const STRIPE_SAMPLES: usize = 600;

/// A polyline of one colour and width.
struct Stroke {
    points: Vec<(i32, i32)>,
    colour: RGBColor,
    width: u32,
    farness: Real,
}

/// Everything a frame shows, in picture coordinates.
struct Sketch {
    strokes: Vec<Stroke>,
    /// The control polygon, one polyline per piece (empty unless asked).
    polygon: Vec<Vec<(i32, i32)>>,
    pins: Vec<(i32, i32)>,
    grabs: Vec<((i32, i32), (i32, i32))>,
    caption: String,
    axes: Vec<(&'static str, (i32, i32))>,
    /// The floor and obstacles, drawn under the rod.
    scenery: Vec<Shape>,
    /// Each rod's name and where it goes (`[[rods]]` scenes).
    labels: Vec<scenery::Label>,
}

/// Lightens `c` towards white by `f` in [0, 1].
fn lighten(c: RGBColor, f: Real) -> RGBColor {
    let mix = |v: u8| (f64::from(v) + (255.0 - f64::from(v)) * 0.65 * f).round() as u8;
    RGBColor(mix(c.0), mix(c.1), mix(c.2))
}

/// The rod's cross-section radius at material coordinate `s`, m, where the scene gives
/// one (`rod.radius`, or that of the `[[rods]]` entry holding `s`).
fn radius_at(scene: &Scene, s: Real) -> Option<Real> {
    let mut end = 0.0;
    for rod in &scene.rods {
        end += rod.rest_length;
        if s < end {
            return rod.radius;
        }
    }
    match scene.rods.last() {
        Some(rod) => rod.radius,
        None => scene.rod.radius,
    }
}

/// The centreline as strokes: one per span, or per segment in the oblique view (each
/// shaded by its depth), drawn far to near; as thick as the rod where its diameter
/// (`radius` of the scene) is wider on the picture than the drawn line.
fn strokes(rod: &Rod, view: &View, scene: &Scene) -> Result<Vec<Stroke>, Error> {
    let mut out = Vec::new();
    let spans = splinerod_core::basis::spans(rod.basis());
    for (i, (span, params)) in centreline(rod)?.iter().zip(spans).enumerate() {
        let colour = SPAN_COLOURS[i % 2];
        let radius = radius_at(scene, 0.5 * (params.start + params.end)).unwrap_or(0.0);
        let diameter = 2.0 * radius / view.metres_per_pixel();
        let pieces: Vec<&[Vector3<Real>]> = if view.camera == Camera::Oblique {
            span.windows(2).collect()
        } else {
            vec![span.as_slice()]
        };
        for piece in pieces {
            let mid = piece[piece.len() / 2];
            let f = view.farness(&mid);
            out.push(Stroke {
                points: piece.iter().map(|p| view.px(p)).collect(),
                colour: lighten(colour, f),
                width: (LINE_WIDTH * (1.0 - 0.6 * f))
                    .max(diameter)
                    .round()
                    .max(1.0) as u32,
                farness: f,
            });
        }
    }
    out.sort_by(|a, b| b.farness.total_cmp(&a.farness));
    Ok(out)
}

/// The control polygon split at cuts (no edge joins two pieces).
fn control_polygon(rod: &Rod, view: &View) -> Vec<Vec<(i32, i32)>> {
    let (t, d) = (rod.basis().knots(), rod.basis().degree());
    let (start, end) = rod.basis().domain();
    let mut out = vec![Vec::new()];
    for (i, p) in rod.positions.iter().enumerate() {
        let cut_before = i > 0 && t[i] == t[i + d] && t[i] > start && t[i] < end;
        if cut_before {
            out.push(Vec::new());
        }
        if let Some(line) = out.last_mut() {
            line.push(view.px(p));
        }
    }
    out
}

/// The caption's count of rods and pieces: "2 rods" for two rods, "3 pieces" for one
/// rod cut once, "2 rods in 3 pieces", nothing for one whole rod.
fn parts(rods: usize, pieces: usize) -> String {
    match (rods, pieces) {
        (1, p) if p <= 1 => String::new(),
        (1, p) => format!("   {p} pieces"),
        (r, p) if p <= r => format!("   {r} rods"),
        (r, p) => format!("   {r} rods in {p} pieces"),
    }
}

/// What frame `frame` shows through `view`.
fn sketch(frame: &Frame<'_>, view: &View, polygon: bool) -> Result<Sketch, Error> {
    let (system, rod) = (frame.system, &frame.system.rod);
    let mut grabs = Vec::new();
    for g in system.grabs.iter().filter(|g| g.active(frame.time)) {
        grabs.push((view.px(&rod.point(g.spring.at)?), view.px(&g.spring.target)));
    }
    let steps = match frame.total_steps {
        0 => format!("step {}", frame.step),
        n => format!("step {}/{n}", frame.step),
    };
    let pieces = parts(frame.scene.rods.len().max(1), rod.pieces());
    let caption = format!(
        "t = {:.4} s   {steps}   {} control points{pieces}   view {}   1 px = {:.3} mm",
        frame.time,
        rod.distinct_len(),
        view.camera.name(),
        view.metres_per_pixel() * 1e3,
    );
    let mut strokes = strokes(rod, view, frame.scene)?;
    if let Some(twist) = system.summary()?.twist {
        // The material frame: a dark stripe STRIPE_OFFSET px off the centreline.
        let offset = STRIPE_OFFSET * view.metres_per_pixel();
        let points = super::ribbon::stripe(rod, &twist, offset, STRIPE_SAMPLES)?;
        strokes.push(Stroke {
            points: points.iter().map(|p| view.px(p)).collect(),
            colour: STRIPE,
            width: 2,
            farness: 0.0,
        });
    }
    Ok(Sketch {
        strokes,
        polygon: match polygon {
            true => control_polygon(rod, view),
            false => Vec::new(),
        },
        pins: system.pins.iter().map(|p| view.px(&p.position)).collect(),
        grabs,
        caption,
        axes: axes(view.camera),
        scenery: scenery::shapes(frame, view)?,
        labels: scenery::labels(frame, view)?,
    })
}

impl Drawing for Sketch {
    /// Draws the sketch on a white background. In the bitmap (`raster`), thick
    /// polylines are drawn segment by segment with round joints (the bitmap backend's
    /// own thick-polyline outline is ragged on densely sampled curves); lone segments
    /// always get round joints.
    fn draw<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        raster: bool,
    ) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
        area.fill(&WHITE)?;
        for shape in &self.scenery {
            draw_shape(area, shape)?;
        }
        for line in &self.polygon {
            area.draw(&PathElement::new(line.clone(), GREY.stroke_width(1)))?;
        }
        for s in &self.strokes {
            let style = s.colour.stroke_width(s.width);
            if raster || s.points.len() == 2 {
                for pair in s.points.windows(2) {
                    area.draw(&PathElement::new(pair.to_vec(), style))?;
                }
                for &p in &s.points {
                    area.draw(&Circle::new(p, s.width / 2, s.colour.filled()))?;
                }
            } else {
                area.draw(&PathElement::new(s.points.clone(), style))?;
            }
        }
        for &p in self.polygon.iter().flatten() {
            area.draw(&Circle::new(p, 3, GREY.filled()))?;
        }
        for &(x, y) in &self.pins {
            let corners = [(x - 6, y - 6), (x + 6, y + 6)];
            area.draw(&Rectangle::new(corners, BLACK.filled()))?;
        }
        for &(point, target) in &self.grabs {
            area.draw(&PathElement::new(vec![point, target], RED.stroke_width(1)))?;
            area.draw(&Cross::new(target, 7, RED.stroke_width(2)))?;
            area.draw(&Circle::new(point, 6, RED.filled()))?;
        }
        for (name, point) in &self.labels {
            let font = (FONT, LABEL_FONT).into_font().color(&BLACK);
            let (corner, foot) = label_place(name, *point);
            area.draw(&PathElement::new(vec![*point, foot], BLACK.stroke_width(1)))?;
            area.draw(&Text::new(name.clone(), corner, font))?;
        }
        caption(area, self)
    }
}

/// Where a rod's name beside `point` goes: the text's top-left corner and the end of
/// the short line from `point` to it. Up and to the right, or to the left near the
/// picture's right edge and below near its top (the width is estimated at 0.6 of the
/// font size per character).
fn label_place(name: &str, (x, y): (i32, i32)) -> ((i32, i32), (i32, i32)) {
    let width = (0.6 * LABEL_FONT * name.chars().count() as f64).ceil() as i32;
    let height = LABEL_FONT as i32;
    let right = x + 10 + width < WIDTH as i32 - 4;
    let up = y - 14 - height > 4;
    let foot = (
        if right { x + 8 } else { x - 8 },
        if up { y - 8 } else { y + 8 },
    );
    let left = if right {
        foot.0 + 2
    } else {
        foot.0 - 2 - width
    };
    let top = if up { foot.1 - 4 - height } else { foot.1 + 4 };
    ((left, top), foot)
}

/// Light grey where the floor and obstacles are, outlined in grey.
fn draw_shape<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    shape: &Shape,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (fill, outline) = match shape {
        Shape::Solid { fill, edge } => (fill, edge),
        Shape::Outline(outline) => (outline, outline),
    };
    if fill.len() >= 3 {
        area.draw(&Polygon::new(fill.clone(), SCENERY.filled()))?;
    }
    area.draw(&PathElement::new(outline.clone(), GREY.stroke_width(2)))
}

/// The caption strip (blanked first: a falling piece may have strayed into it) and a
/// small triad of the world axes in its right corner.
fn caption<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    sketch: &Sketch,
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (w, h) = (WIDTH as i32, HEIGHT as i32);
    let top = h - CAPTION as i32;
    area.draw(&Rectangle::new([(0, top), (w, h)], WHITE.filled()))?;
    let rule = vec![(0, top), (w, top)];
    area.draw(&PathElement::new(rule, GREY.stroke_width(1)))?;
    let font = (FONT, 16).into_font().color(&BLACK);
    let at = (MARGIN as i32, top + 8);
    area.draw(&Text::new(sketch.caption.clone(), at, font.clone()))?;
    let origin = (w - 60, top - 40);
    for (name, (dx, dy)) in &sketch.axes {
        let tip = (origin.0 + dx, origin.1 + dy);
        area.draw(&PathElement::new(vec![origin, tip], BLACK.stroke_width(1)))?;
        let label = (tip.0 + dx / 4 - 4, tip.1 + dy / 4 - 8);
        area.draw(&Text::new(name.to_string(), label, font.clone()))?;
    }
    Ok(())
}

/// Screen directions (px, 30 px long) of the world axes that are not seen end-on.
fn axes(camera: Camera) -> Vec<(&'static str, (i32, i32))> {
    let units = [
        ("x", Vector3::x()),
        ("y", Vector3::y()),
        ("z", Vector3::z()),
    ];
    units
        .into_iter()
        .filter_map(|(name, e)| {
            let v = camera.project(&e);
            let shown = v[0].hypot(v[1]) > 0.2;
            let d = ((30.0 * v[0]).round() as i32, (-30.0 * v[1]).round() as i32);
            shown.then_some((name, d))
        })
        .collect()
}

/// Writes pictures of the rod: `frame_00000.png`, `frame_00001.png`, … (and `.svg`
/// when asked) at the start, after every `every`-th step, and of the final state; and
/// optionally an animated GIF of all frames (see [`with_gif`](Self::with_gif)).
pub struct Pictures {
    dir: PathBuf,
    every: usize,
    camera: Camera,
    svg: bool,
    polygon: bool,
    view: Option<View>,
    frames: usize,
    written_step: Option<usize>,
    gif: Option<GifWriter>,
}

impl Pictures {
    /// Pictures into `dir` (created if missing) every `every` steps (≥ 1) through
    /// `camera`; `svg` also writes SVG files; `polygon` shows the control polygon.
    pub fn new(
        dir: &Path,
        every: usize,
        camera: Camera,
        svg: bool,
        polygon: bool,
    ) -> Result<Self, Error> {
        if every == 0 {
            return Err(Error::field("--every", 0, "must be at least 1"));
        }
        std::fs::create_dir_all(dir).map_err(|source| Error::Io {
            path: dir.display().to_string(),
            source,
        })?;
        Ok(Self {
            dir: dir.to_path_buf(),
            every,
            camera,
            svg,
            polygon,
            view: None,
            frames: 0,
            written_step: None,
            gif: None,
        })
    }

    /// Also assembles every frame into the animated GIF `path` (10 frames per second,
    /// the last shown for 1 s, looping). Frames are appended to `path` + `.partial` as
    /// they are drawn; at [`Observer::finish`] the file is completed and renamed to
    /// `path`, so a file at `path` is always a whole animation.
    pub fn with_gif(mut self, path: PathBuf) -> Self {
        self.gif = Some(GifWriter::new(path));
        self
    }

    /// The framing, fixed at the first frame (`None` before it).
    pub fn view(&self) -> Option<&View> {
        self.view.as_ref()
    }

    /// Frames written so far.
    pub fn frames(&self) -> usize {
        self.frames
    }

    /// Draws `frame` and writes its files.
    fn write_frame(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        let view = match self.view {
            Some(view) => view,
            None => *self
                .view
                .insert(View::fit(self.camera, &framing_points(frame)?)),
        };
        let sketch = sketch(frame, &view, self.polygon)?;
        let stem = self.dir.join(format!("frame_{:05}", self.frames));
        let rgb = write_images(&stem, &sketch, self.svg)?;
        if let Some(gif) = &mut self.gif {
            gif.push(&rgb)?;
        }
        self.frames += 1;
        self.written_step = Some(frame.step);
        Ok(())
    }
}

impl Observer for Pictures {
    fn start(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        self.view = None; // framed anew on this run's first frame
        self.write_frame(frame)
    }

    fn step(&mut self, frame: &Frame<'_>, _: &StepReport, _: Real) -> Result<(), Error> {
        if frame.step % self.every == 0 {
            self.write_frame(frame)?;
        }
        Ok(())
    }

    fn checkpoint(&mut self) -> Result<Option<String>, Error> {
        let state = serde_json::json!({
            "view": self.view,
            "frames": self.frames,
            "written_step": self.written_step,
        });
        Ok(Some(state.to_string()))
    }

    fn resume(&mut self, _frame: &Frame<'_>, state: Option<&str>) -> Result<(), Error> {
        let bad = || Error::field("checkpoint", self.dir.display(), "no pictures state");
        if self.gif.is_some() {
            let reason = "a GIF cannot be continued after a resume";
            return Err(Error::field("--gif", "given", reason));
        }
        let state: serde_json::Value = serde_json::from_str(state.ok_or_else(bad)?)?;
        self.view = serde_json::from_value(state["view"].clone())?;
        self.frames = serde_json::from_value(state["frames"].clone())?;
        self.written_step = serde_json::from_value(state["written_step"].clone())?;
        Ok(())
    }

    fn finish(&mut self, frame: &Frame<'_>, _: &RunResult) -> Result<(), Error> {
        // The last state, unless its step was drawn already (a static solve's one stage
        // is step 0 and is drawn by `step`).
        if self.written_step != Some(frame.step) {
            self.write_frame(frame)?;
        }
        match &mut self.gif {
            Some(gif) => gif.finish(),
            None => Ok(()),
        }
    }
}
