//! USD output (`--usd OUT.usda`): [`UsdWriter`] writes the run as one text layer that
//! usdview, Omniverse/Isaac Sim and Blender open, with the exact curves kept alongside
//! what viewers draw.
//!
//! **The stage.** `upAxis = "Y"` (gravity's default direction and the floor's normal),
//! `metersPerUnit = 1`, `defaultPrim = "World"`. Time code `k` is step `k` and
//! `timeCodesPerSecond = framesPerSecond = 1/dt`, so code / timeCodesPerSecond is the
//! step's time `k·dt`; the simulation's own time at every recorded code (which sums
//! the steps, and so differs from `k·dt` by rounding) is the time-sampled
//! `custom double splinerod:time` of `/World`. `startTimeCode` and `endTimeCode` are
//! the first and last recorded codes. A static solve records its initial state and its
//! equilibrium at codes 0 and 1 (`timeCodesPerSecond = 1`). Recorded: the start, every
//! `every`-th step, the end (as the ParaView output).
//!
//! **Rods** (`/World/Rods/<name>`, the rod's `name` made an identifier, `rod` or
//! `rod_K` without one): one `BasisCurves` per rod of the scene, every attribute below
//! time-sampled at every recorded code, so the number of control points may change
//! (adaptivity) and so may the number of curves (cuts):
//! * `type = "cubic"`, `basis = "bspline"` for degree ≥ 2 (degree 2 or above 3: the
//!   control points drawn as a cubic, an approximation), `type = "linear"` for
//!   degree 1 (the drawn polyline is the curve);
//! * `wrap = "pinned"` for an open rod (drawn through its end points), `"periodic"`
//!   for a closed rod the scene never cuts, `"nonperiodic"` for a closed rod it cuts
//!   (the closed phase as `m + d` points whose last `d` repeat the first: the same
//!   closed curve) and for degree 1;
//! * `curveVertexCounts`: one curve per piece (a rod cut in two is one prim with two
//!   curves from the cut's time on);
//! * `point3f[] points`: the control points rounded to float (a periodic curve
//!   without its last `d`, copies of the first); `float[] widths` (`vertex`): the
//!   diameter `2·rod.radius`, or 1 % of the rest length without a radius; `extent`.
//!
//! USD's `bspline` basis is uniform: a viewer draws the curve of uniform knots through
//! these points, which is not the rod's curve where its knots are not uniform (near
//! clamped ends, after adaptive refinement); the ends of an open rod are exact
//! (`pinned`), the rest is within about a control-point spacing times the knots'
//! non-uniformity. **The exact curve is in the `splinerod:` attributes** (doubles,
//! written with the digits that read back to the same value):
//! * `custom double3[] splinerod:controlPoints` and `custom int[]
//!   splinerod:curveVertexCounts`: every curve's control points;
//! * `custom double[] splinerod:knots`: every curve's `n + degree + 1` knots, m of the
//!   rod's material coordinate (a closed rod uncut: its unclamped periodic form, `m + d`
//!   control points whose last `d` repeat the first and `m + 2d + 1` knots; a cut
//!   closed rod's piece across the seam: knots past the period, up to `c + L`);
//! * `custom int splinerod:degree`, `custom bool splinerod:closed`, `custom double
//!   splinerod:restLength`, `custom string splinerod:name`.
//!
//! Curve `i` is `C(s) = Σ_j P_j N_{j,d}(s)` on its knots, `s` in `[t_d, t_n]`.
//!
//! **Obstacles** (`/World/Obstacles`): the floor (`floor`) and every `[[obstacles]]`
//! entry (`obstacle_I`) as transformed primitives — planes and the floor a `Mesh`
//! square, spheres `Sphere`, capsules `Capsule` — whose first op, `double3
//! xformOp:translate`, is the obstacle's reference point (a plane's `point`, a
//! sphere's `centre`, a capsule's `a`) where the simulation has it, time-sampled for
//! an obstacle with a `path`; then `quatd xformOp:orient`. Ensembles: member 0, as
//! every output.
//!
//! **Bodies** (`/World/Bodies`, only for a scene with `[[bodies]]`): an `Xform` per
//! body with its centre of mass (`double3 xformOp:translate`) and orientation (`quatd
//! xformOp:orient`) time-sampled at every recorded code, its mass and inertia exactly,
//! and a child `shape` showing it: the box of its principal moments (see `bodies.rs`).
//!
//! `points` is `point3f[]` because the schema says so: a layer with `point3d[] points`
//! opens, and `UsdGeom.BasisCurves(prim).GetPointsAttr().Get(t)` returns the doubles
//! in Python, but usd-core's validation reports `AttributeTypeMismatch` and typed reads
//! (`ComputeExtentFromPlugins`, bounding boxes) find no points.
//!
//! The layer is assembled at the end of the run (the samples of each attribute are
//! kept in memory as text, about the file's size) and written to `OUT.usda.partial`,
//! then renamed: a run that fails leaves no file claiming to be complete. A
//! checkpoint carries the samples so far.

mod bodies;
mod curves;
mod shapes;
mod text;

use crate::run::observe::{Frame, Observer};
use crate::{Error, RunResult, Scene, StepReport};
use bodies::{BodyStreams, BodyStyle};
use curves::{Layout, Piece, RodStreams, Style};
use serde::{Deserialize, Serialize};
use shapes::Shape;
use splinerod_core::{Real, Rod};
use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use text::{prim_name, quoted, time_samples, Num};

/// Widths of a rod without a radius: this fraction of its rest length.
pub const DEFAULT_WIDTH: Real = 0.01;

/// An [`Observer`] writing a USD layer (see the [module docs](self)).
#[derive(Debug)]
pub struct UsdWriter {
    path: PathBuf,
    partial: PathBuf,
    every: usize,
    rods: Vec<Style>,
    shapes: Vec<Shape>,
    bodies: Vec<BodyStyle>,
    recorded: Recorded,
    pieces: Vec<Piece>,
    done: bool,
}

/// What has been recorded: the samples so far (what a checkpoint keeps).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
struct Recorded {
    /// The time codes, increasing.
    codes: Vec<i64>,
    /// The simulation time at each.
    times: Vec<Real>,
    /// Per rod, its attributes' samples.
    rods: Vec<RodStreams>,
    /// Per shape, its translate's samples (empty for a static one).
    moves: Vec<String>,
    /// Per shape, half the side of a plane's square (set at the start).
    half_sides: Vec<Real>,
    /// Per body, its pose's samples.
    #[serde(default)]
    bodies: Vec<BodyStreams>,
    /// The step recorded last by [`Observer::step`].
    last_step: Option<usize>,
}

impl UsdWriter {
    /// A writer to `path` recording every `every`-th step. Errors, naming `--usd` and
    /// the path, if `every` is 0 or the file cannot be created there.
    pub fn new(path: &Path, every: usize) -> Result<Self, Error> {
        if every == 0 {
            return Err(Error::field("--every", 0, "must be at least 1"));
        }
        let mut partial = path.as_os_str().to_owned();
        partial.push(".partial");
        let partial = PathBuf::from(partial);
        let opened = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&partial);
        if let Err(e) = opened {
            let reason = format!("cannot write {}: {e}", partial.display());
            return Err(Error::field("--usd", path.display(), reason));
        }
        Ok(Self {
            path: path.to_path_buf(),
            partial,
            every,
            rods: Vec::new(),
            shapes: Vec::new(),
            bodies: Vec::new(),
            recorded: Recorded::default(),
            pieces: Vec::new(),
            done: false,
        })
    }

    /// The file written at the end.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Time codes recorded so far.
    pub fn frame_count(&self) -> usize {
        self.recorded.codes.len()
    }

    /// The rods' styles and the shapes, from the scene and the rod (not its state).
    fn set_up(&mut self, frame: &Frame<'_>) {
        self.rods = styles(frame.scene, &frame.system.rod);
        self.shapes = shapes::of_scene(frame.scene);
        self.bodies = bodies::styles(frame.system);
    }

    /// A fresh record: empty samples, the planes' size from the rods' start.
    fn start_record(&mut self, frame: &Frame<'_>) {
        let rod = &frame.system.rod;
        let centre = rod.centre_of_mass();
        let total: Real = self.rods.iter().map(|s| s.rest_length).sum();
        self.recorded = Recorded {
            rods: vec![RodStreams::default(); self.rods.len()],
            moves: vec![String::new(); self.shapes.len()],
            bodies: vec![BodyStreams::default(); self.bodies.len()],
            half_sides: (self.shapes.iter())
                .map(|s| s.half_side(total, &centre))
                .collect(),
            ..Recorded::default()
        };
    }

    /// Records `frame` at its time code (once).
    fn record(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        let r = &mut self.recorded;
        let code = if frame.total_steps == 0 {
            r.codes.len()
        } else {
            frame.step
        } as i64;
        if r.codes.last() == Some(&code) {
            return Ok(());
        }
        r.codes.push(code);
        r.times.push(frame.time);
        let rod = &frame.system.rod;
        for (k, (style, streams)) in self.rods.iter().zip(&mut r.rods).enumerate() {
            let layout = Layout::of(rod, k);
            (streams.record(style, rod, layout, code, &mut self.pieces)).map_err(fmt_error)?;
        }
        if self.shapes.iter().any(|s| s.moving) {
            // The floor (first, when there is one) never moves.
            let floor = self.shapes.len() - frame.scene.obstacles.len();
            let obstacles = super::scenery::obstacles_at(frame)?;
            let shapes = self.shapes[floor..].iter().zip(&mut r.moves[floor..]);
            for ((_, moves), o) in shapes.zip(&obstacles).filter(|((s, _), _)| s.moving) {
                Shape::record(moves, o, code).map_err(fmt_error)?;
            }
        }
        for (streams, body) in r.bodies.iter_mut().zip(&frame.system.bodies.bodies) {
            streams.record(body, code).map_err(fmt_error)?;
        }
        Ok(())
    }

    /// The whole layer.
    fn layer(&self, frame: &Frame<'_>) -> Result<String, std::fmt::Error> {
        let r = &self.recorded;
        let mut out = String::new();
        header(&mut out, frame, &r.codes)?;
        writeln!(out, "def Xform \"World\"\n{{")?;
        writeln!(out, "    custom double splinerod:time.timeSamples = {{")?;
        for (code, t) in r.codes.iter().zip(&r.times) {
            writeln!(out, "        {code}: {},", Num(*t))?;
        }
        writeln!(out, "    }}\n\n    def Scope \"Rods\"\n    {{")?;
        for (style, streams) in self.rods.iter().zip(&r.rods) {
            write_rod(&mut out, style, streams)?;
        }
        writeln!(out, "    }}\n\n    def Scope \"Obstacles\"\n    {{")?;
        let shapes = self.shapes.iter().zip(&r.moves).zip(&r.half_sides);
        for ((shape, moves), half) in shapes {
            shape.write(
                &mut out,
                Some(moves.as_str()).filter(|m| !m.is_empty()),
                *half,
            )?;
        }
        writeln!(out, "    }}")?;
        if !self.bodies.is_empty() {
            writeln!(out, "\n    def Scope \"Bodies\"\n    {{")?;
            for (style, streams) in self.bodies.iter().zip(&r.bodies) {
                style.write(&mut out, streams)?;
            }
            writeln!(out, "    }}")?;
        }
        writeln!(out, "}}")?;
        Ok(out)
    }

    /// Writes the layer to the partial file and renames it to the path.
    fn write(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        let text = self.layer(frame).map_err(fmt_error)?;
        let io = |path: &Path| {
            let path = path.display().to_string();
            move |source| Error::Io { path, source }
        };
        std::fs::write(&self.partial, text).map_err(io(&self.partial))?;
        std::fs::rename(&self.partial, &self.path).map_err(io(&self.path))?;
        self.done = true;
        Ok(())
    }
}

/// The style of every rod of `scene` (its prims' names unique).
fn styles(scene: &Scene, rod: &Rod) -> Vec<Style> {
    let mut taken = BTreeSet::new();
    let closed = rod.is_closed();
    (0..scene.rod_count())
        .map(|k| {
            let spec = scene.rod_spec(k);
            let name = spec.name.clone().unwrap_or_default();
            let fallback = match scene.rod_count() {
                1 => "rod".to_string(),
                _ => format!("rod_{k}"),
            };
            let width = (spec.radius).map_or(DEFAULT_WIDTH * spec.rest_length, |r| 2.0 * r);
            Style {
                prim: unique(&mut taken, prim_name(&name, &fallback)),
                name,
                degree: rod.basis().degree(),
                closed,
                periodic: closed && scene.cuts.is_empty(),
                width,
                rest_length: spec.rest_length,
            }
        })
        .collect()
}

/// The layer's header: its metadata (module docs), the time codes `codes` span.
fn header(out: &mut String, frame: &Frame<'_>, codes: &[i64]) -> std::fmt::Result {
    let per_second = match frame.scene.solver.dt {
        Some(dt) if frame.total_steps > 0 => Num(1.0 / dt),
        _ => Num(1.0),
    };
    let start = codes.first().copied().unwrap_or(0);
    let end = codes.last().copied().unwrap_or(0);
    let version = env!("CARGO_PKG_VERSION");
    writeln!(out, "#usda 1.0\n(")?;
    writeln!(out, "    customLayerData = {{")?;
    writeln!(
        out,
        "        string generator = \"splinerod {version}\"\n    }}"
    )?;
    writeln!(out, "    defaultPrim = \"World\"")?;
    writeln!(out, "    doc = \"{DOC}\"")?;
    writeln!(
        out,
        "    endTimeCode = {end}\n    framesPerSecond = {per_second}"
    )?;
    writeln!(out, "    metersPerUnit = 1\n    startTimeCode = {start}")?;
    writeln!(
        out,
        "    timeCodesPerSecond = {per_second}\n    upAxis = \"Y\"\n)\n"
    )
}

/// The layer's `doc`.
const DOC: &str = "A splinerod run. Viewers draw the float points with a uniform B-spline basis; \
the exact curves are splinerod:controlPoints and splinerod:knots (double) of degree \
splinerod:degree, per splinerod:curveVertexCounts.";

/// `name`, or `name_2`, `name_3`, … if taken; marked taken.
fn unique(taken: &mut BTreeSet<String>, name: String) -> String {
    let mut candidate = name.clone();
    let mut n = 1;
    while !taken.insert(candidate.clone()) {
        n += 1;
        candidate = format!("{name}_{n}");
    }
    candidate
}

/// Formatting into a `String` does not fail; should it, say so.
fn fmt_error(_: std::fmt::Error) -> Error {
    Error::field("--usd", "text", "formatting the USD layer failed")
}

/// One rod's `BasisCurves` prim.
fn write_rod(out: &mut String, style: &Style, s: &RodStreams) -> std::fmt::Result {
    let a = text::ATTRIBUTE;
    writeln!(
        out,
        "        def BasisCurves \"{}\"\n        {{",
        style.prim
    )?;
    writeln!(out, "{a}uniform token type = \"{}\"", style.curve_type())?;
    if style.degree > 1 {
        writeln!(out, "{a}uniform token basis = \"bspline\"")?;
    }
    writeln!(out, "{a}uniform token wrap = \"{}\"", style.wrap())?;
    time_samples(out, "int[] curveVertexCounts", &s.counts)?;
    time_samples(out, "point3f[] points", &s.points)?;
    writeln!(
        out,
        "{a}float[] widths (\n{a}    interpolation = \"vertex\"\n{a})"
    )?;
    time_samples(out, "float[] widths", &s.widths)?;
    time_samples(out, "float3[] extent", &s.extent)?;
    writeln!(
        out,
        "{a}custom string splinerod:name = {}",
        quoted(&style.name)
    )?;
    writeln!(out, "{a}custom int splinerod:degree = {}", style.degree)?;
    writeln!(
        out,
        "{a}custom bool splinerod:closed = {}",
        u8::from(style.closed)
    )?;
    writeln!(
        out,
        "{a}custom double splinerod:restLength = {}",
        Num(style.rest_length)
    )?;
    time_samples(
        out,
        "custom int[] splinerod:curveVertexCounts",
        &s.exact_counts,
    )?;
    time_samples(
        out,
        "custom double3[] splinerod:controlPoints",
        &s.control_points,
    )?;
    time_samples(out, "custom double[] splinerod:knots", &s.knots)?;
    writeln!(out, "        }}")
}

impl Drop for UsdWriter {
    /// A run that did not finish leaves no partial file behind.
    fn drop(&mut self) {
        if !self.done {
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}

impl Observer for UsdWriter {
    fn start(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        self.set_up(frame);
        self.start_record(frame);
        self.record(frame)
    }

    fn step(&mut self, frame: &Frame<'_>, _report: &StepReport, _wall: Real) -> Result<(), Error> {
        if frame.step % self.every == 0 {
            self.record(frame)?;
            self.recorded.last_step = Some(frame.step);
        }
        Ok(())
    }

    fn checkpoint(&mut self) -> Result<Option<String>, Error> {
        Ok(Some(serde_json::to_string(&self.recorded)?))
    }

    fn resume(&mut self, frame: &Frame<'_>, state: Option<&str>) -> Result<(), Error> {
        let path = self.path.display().to_string();
        let bad = || Error::field("checkpoint", &path, "no USD state");
        self.set_up(frame);
        self.recorded = serde_json::from_str(state.ok_or_else(bad)?)?;
        let fits = self.recorded.rods.len() == self.rods.len()
            && self.recorded.moves.len() == self.shapes.len()
            && self.recorded.half_sides.len() == self.shapes.len()
            && self.recorded.bodies.len() == self.bodies.len();
        if !fits {
            return Err(bad());
        }
        Ok(())
    }

    fn finish(&mut self, frame: &Frame<'_>, _result: &RunResult) -> Result<(), Error> {
        if self.recorded.last_step != Some(frame.step) {
            self.record(frame)?;
        }
        self.write(frame)
    }
}
