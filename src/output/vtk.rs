//! ParaView output: [`VtkWriter`] writes every recorded frame as two VTK XML PolyData
//! files and, when the run finishes, a PVD collection of each series.
//!
//! * `centreline_NNNNN.vtp`: the curve sampled [`SAMPLES_PER_SPAN`] times per knot span,
//!   one polyline per piece (so cuts show as gaps), with point data `s` (material
//!   coordinate as a fraction of the rest length), `speed` (m/s) and `stretch`
//!   (`γ = |C'(s)|`, the active scalars), and on a rod with twist the vectors
//!   `material_director` (the material frame's director, [`super::ribbon`]);
//! * `polygon_NNNNN.vtp`: the control points, joined in order by one polyline per piece,
//!   with point data `s` (Greville abscissa, fraction of the rest length) and `speed`;
//! * `rod.pvd` and `polygon.pvd`: the two series with their time steps, written only at
//!   the end of a successful run (to a temporary name, then renamed), so a run that
//!   fails midway leaves no collection claiming to be complete.
//!
//! `NNNNN` numbers the recorded frames 0, 1, 2, … Both data sets also carry field data
//! `TimeValue` (s) and `step`. The files are ASCII (format version 0.1); a static solve
//! records the initial state and the equilibrium, listed at time steps 0 and 1.

use crate::run::observe::{Frame, Observer};
use crate::{Error, RunResult, StepReport};
use nalgebra::Vector3;
use splinerod_core::basis::greville;
use splinerod_core::{Real, Rod};
use std::fmt;
use std::fs::{self, File};
use std::io::{self, BufWriter, Write};
use std::path::{Path, PathBuf};

/// Centreline samples per non-empty knot span.
pub const SAMPLES_PER_SPAN: usize = 20;

/// Values per line in the ASCII data arrays.
const PER_LINE: usize = 6;

/// Indentation of the values in a data array.
const INDENT: &str = "          ";

/// A line break and [`INDENT`].
const NEWLINE_INDENT: &str = "\n          ";

/// An [`Observer`] writing ParaView files (see the [module docs](self)): the initial
/// state, every `every`-th step and the final state.
#[derive(Debug, Clone)]
pub struct VtkWriter {
    dir: PathBuf,
    every: usize,
    /// The PVD time step of each recorded frame, in order.
    timesteps: Vec<Real>,
    /// The step recorded last by [`Observer::step`], to avoid recording it twice.
    last_step: Option<usize>,
}

/// Polylines with per-point scalar arrays: what one `.vtp` file holds.
struct Polylines {
    points: Vec<Vector3<Real>>,
    /// One past the last point of each polyline (VTK's `offsets`).
    ends: Vec<usize>,
    /// Named point-data arrays, one value per point.
    arrays: Vec<(&'static str, Vec<Real>)>,
    /// Named point-data vector arrays, one vector per point.
    vectors: Vec<(&'static str, Vec<Vector3<Real>>)>,
    /// The array ParaView colours by.
    scalars: &'static str,
}

impl VtkWriter {
    /// A writer into `dir` (created if missing) recording every `every`-th step.
    /// Errors if `every` is 0 or the directory cannot be created.
    pub fn new(dir: &Path, every: usize) -> Result<Self, Error> {
        if every == 0 {
            return Err(Error::field("--every", 0, "must be at least 1"));
        }
        fs::create_dir_all(dir).map_err(io_error(dir))?;
        Ok(Self {
            dir: dir.to_path_buf(),
            every,
            timesteps: Vec::new(),
            last_step: None,
        })
    }

    /// The output directory.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Frames recorded so far in the current run.
    pub fn frame_count(&self) -> usize {
        self.timesteps.len()
    }

    /// Writes both data sets of `frame` as the next frame.
    fn record(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        let index = self.timesteps.len();
        let rod = &frame.system.rod;
        let centre = self.dir.join(data_file("centreline", index));
        let mut line = centreline(rod)?;
        if let Some(twist) = frame.system.summary()?.twist {
            let l = rod.material().rest_length;
            let s: Vec<Real> = line.arrays[0].1.iter().map(|f| f * l).collect();
            let directors = super::ribbon::directors(rod, &twist, &s)?;
            line.vectors.push(("material_director", directors));
        }
        write_polydata(&centre, &line, frame)?;
        let polygon = self.dir.join(data_file("polygon", index));
        write_polydata(&polygon, &control_polygon(rod), frame)?;
        // A static solve stays at t = 0: number its two states instead.
        let timestep = if frame.total_steps == 0 {
            index as Real
        } else {
            frame.time
        };
        self.timesteps.push(timestep);
        Ok(())
    }

    /// Writes `rod.pvd` and `polygon.pvd` listing every recorded frame.
    fn write_collections(&self) -> Result<(), Error> {
        for (series, collection) in [("centreline", "rod.pvd"), ("polygon", "polygon.pvd")] {
            let entries: Vec<(Real, String)> = (self.timesteps.iter().enumerate())
                .map(|(i, &t)| (t, data_file(series, i)))
                .collect();
            write_collection(&self.dir.join(collection), &entries)?;
        }
        Ok(())
    }

    /// Removes collections left by an earlier run into the same directory.
    fn remove_stale_collections(&self) -> Result<(), Error> {
        for name in ["rod.pvd", "polygon.pvd"] {
            let path = self.dir.join(name);
            match fs::remove_file(&path) {
                Err(e) if e.kind() != io::ErrorKind::NotFound => return Err(io_error(&path)(e)),
                _ => {}
            }
        }
        Ok(())
    }
}

impl Observer for VtkWriter {
    fn start(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        self.timesteps.clear();
        self.last_step = None;
        self.remove_stale_collections()?;
        self.record(frame)
    }

    fn step(&mut self, frame: &Frame<'_>, _report: &StepReport, _wall: Real) -> Result<(), Error> {
        if frame.step % self.every == 0 {
            self.record(frame)?;
            self.last_step = Some(frame.step);
        }
        Ok(())
    }

    fn checkpoint(&mut self) -> Result<Option<String>, Error> {
        let state = serde_json::json!({ "timesteps": self.timesteps, "last_step": self.last_step });
        Ok(Some(state.to_string()))
    }

    fn resume(&mut self, _frame: &Frame<'_>, state: Option<&str>) -> Result<(), Error> {
        let bad = || Error::field("checkpoint", self.dir.display(), "no ParaView state");
        let state: serde_json::Value = serde_json::from_str(state.ok_or_else(bad)?)?;
        self.timesteps = serde_json::from_value(state["timesteps"].clone())?;
        self.last_step = serde_json::from_value(state["last_step"].clone())?;
        Ok(())
    }

    fn finish(&mut self, frame: &Frame<'_>, _result: &RunResult) -> Result<(), Error> {
        if self.last_step != Some(frame.step) {
            self.record(frame)?;
        }
        self.write_collections()
    }
}

/// `series_NNNNN.vtp`.
fn data_file(series: &str, index: usize) -> String {
    format!("{series}_{index:05}.vtp")
}

/// Maps an I/O error on `path` to [`Error::Io`].
fn io_error(path: &Path) -> impl FnOnce(io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.display().to_string(),
        source,
    }
}

/// The centreline sampled [`SAMPLES_PER_SPAN`] times per knot span, one polyline per
/// piece. A piece ending at a cut is evaluated just left of it (its left limit).
fn centreline(rod: &Rod) -> Result<Polylines, Error> {
    let l = rod.material().rest_length;
    let (start, end) = rod.basis().domain();
    let mut bounds = vec![start];
    bounds.extend(rod.cuts());
    bounds.push(end);
    let mut breaks: Vec<Real> = (rod.basis().knots().iter())
        .copied()
        .filter(|&t| t >= start && t <= end)
        .collect();
    breaks.dedup();
    let mut line = Polylines {
        points: Vec::new(),
        ends: Vec::new(),
        arrays: vec![
            ("s", Vec::new()),
            ("speed", Vec::new()),
            ("stretch", Vec::new()),
        ],
        scalars: "stretch",
        vectors: Vec::new(),
    };
    for piece in bounds.windows(2) {
        let (a, b) = (piece[0], piece[1]);
        let inside: Vec<Real> = breaks
            .iter()
            .copied()
            .filter(|&t| t >= a && t <= b)
            .collect();
        let limit = if b < end { left_of(b) } else { b };
        sample(rod, &mut line, a, a, l)?;
        for span in inside.windows(2) {
            let (u0, u1) = (span[0], span[1]);
            for k in 1..=SAMPLES_PER_SPAN {
                let s = if k == SAMPLES_PER_SPAN {
                    u1
                } else {
                    u0 + (u1 - u0) * k as Real / SAMPLES_PER_SPAN as Real
                };
                let at = if s >= b { limit } else { s };
                sample(rod, &mut line, s, at, l)?;
            }
        }
        line.ends.push(line.points.len());
    }
    Ok(line)
}

/// Appends the centreline point of material coordinate `s`, evaluated at `at`.
fn sample(rod: &Rod, line: &mut Polylines, s: Real, at: Real, l: Real) -> Result<(), Error> {
    let b = rod.basis_at(at)?;
    line.points.push(b.combine(&b.value, &rod.positions));
    let speed = b.combine(&b.value, &rod.velocities).norm();
    let stretch = b.combine(&b.d1, &rod.positions).norm();
    for (array, value) in line.arrays.iter_mut().zip([s / l, speed, stretch]) {
        array.1.push(value);
    }
    Ok(())
}

/// The largest float below `x > 0`: evaluating there gives the left limit at a cut.
fn left_of(x: Real) -> Real {
    if x > 0.0 && x.is_finite() {
        Real::from_bits(x.to_bits() - 1)
    } else {
        x
    }
}

/// The control points, one polyline per piece (the first control point of a piece is
/// the first basis function whose support starts at its cut).
fn control_polygon(rod: &Rod) -> Polylines {
    let space = rod.basis();
    let knots = space.knots();
    let mut ends: Vec<usize> = (rod.cuts().iter())
        .map(|&c| knots.partition_point(|&t| t < c))
        .collect();
    ends.push(rod.len());
    let l = rod.material().rest_length;
    let s = (0..rod.len()).map(|i| greville(space, i) / l).collect();
    let speed = rod.velocities.iter().map(|v| v.norm()).collect();
    Polylines {
        points: rod.positions.clone(),
        ends,
        arrays: vec![("s", s), ("speed", speed)],
        scalars: "speed",
        vectors: Vec::new(),
    }
}

/// Writes `lines` as a VTK XML PolyData file at `path`.
fn write_polydata(path: &Path, lines: &Polylines, frame: &Frame<'_>) -> Result<(), Error> {
    let file = File::create(path).map_err(io_error(path))?;
    let mut out = BufWriter::new(file);
    polydata_xml(&mut out, lines, frame)
        .and_then(|()| out.flush())
        .map_err(io_error(path))
}

/// The PolyData document.
fn polydata_xml(out: &mut impl Write, lines: &Polylines, frame: &Frame<'_>) -> io::Result<()> {
    writeln!(out, r#"<?xml version="1.0"?>"#)?;
    writeln!(
        out,
        r#"<VTKFile type="PolyData" version="0.1" byte_order="LittleEndian">"#
    )?;
    writeln!(out, "  <PolyData>")?;
    writeln!(out, "    <FieldData>")?;
    let time = r#"type="Float64" Name="TimeValue" NumberOfTuples="1""#;
    data_array(out, time, [Num(frame.time)])?;
    data_array(
        out,
        r#"type="Int64" Name="step" NumberOfTuples="1""#,
        [frame.step],
    )?;
    writeln!(out, "    </FieldData>")?;
    writeln!(
        out,
        r#"    <Piece NumberOfPoints="{}" NumberOfVerts="0" NumberOfLines="{}" NumberOfStrips="0" NumberOfPolys="0">"#,
        lines.points.len(),
        lines.ends.len()
    )?;
    point_data(out, lines)?;
    writeln!(out, "      <Points>")?;
    let coordinates = lines.points.iter().flat_map(|p| p.iter().map(|&x| Num(x)));
    let header = r#"type="Float64" Name="Points" NumberOfComponents="3""#;
    data_array(out, header, coordinates)?;
    writeln!(out, "      </Points>")?;
    writeln!(out, "      <Lines>")?;
    let connectivity = 0..lines.points.len();
    data_array(out, r#"type="Int64" Name="connectivity""#, connectivity)?;
    data_array(out, r#"type="Int64" Name="offsets""#, lines.ends.iter())?;
    writeln!(out, "      </Lines>")?;
    writeln!(out, "    </Piece>")?;
    writeln!(out, "  </PolyData>")?;
    writeln!(out, "</VTKFile>")
}

/// The `<PointData>` element with every array of `lines`.
fn point_data(out: &mut impl Write, lines: &Polylines) -> io::Result<()> {
    writeln!(out, r#"      <PointData Scalars="{}">"#, lines.scalars)?;
    for (name, values) in &lines.arrays {
        let header = format!(r#"type="Float64" Name="{name}""#);
        data_array(out, &header, values.iter().map(|&v| Num(v)))?;
    }
    for (name, values) in &lines.vectors {
        let header = format!(r#"type="Float64" Name="{name}" NumberOfComponents="3""#);
        data_array(
            out,
            &header,
            values.iter().flat_map(|v| v.iter().map(|&c| Num(c))),
        )?;
    }
    writeln!(out, "      </PointData>")
}

/// One ASCII `<DataArray>` with the attributes `header`, [`PER_LINE`] values a line.
fn data_array<T: fmt::Display>(
    out: &mut impl Write,
    header: &str,
    values: impl IntoIterator<Item = T>,
) -> io::Result<()> {
    writeln!(out, r#"        <DataArray {header} format="ascii">"#)?;
    let mut count = 0;
    for value in values {
        let sep = if count % PER_LINE != 0 {
            " "
        } else if count == 0 {
            INDENT
        } else {
            NEWLINE_INDENT
        };
        write!(out, "{sep}{value}")?;
        count += 1;
    }
    if count > 0 {
        writeln!(out)?;
    }
    writeln!(out, "        </DataArray>")
}

/// Writes a PVD collection of `(timestep, file)` entries to `path` via a temporary file,
/// so the collection appears complete or not at all.
fn write_collection(path: &Path, entries: &[(Real, String)]) -> Result<(), Error> {
    let mut temp = path.as_os_str().to_owned();
    temp.push(".tmp");
    let temp = PathBuf::from(temp);
    let file = File::create(&temp).map_err(io_error(&temp))?;
    let mut out = BufWriter::new(file);
    collection_xml(&mut out, entries)
        .and_then(|()| out.flush())
        .map_err(io_error(&temp))?;
    drop(out);
    fs::rename(&temp, path).map_err(io_error(path))
}

/// The Collection document.
fn collection_xml(out: &mut impl Write, entries: &[(Real, String)]) -> io::Result<()> {
    writeln!(out, r#"<?xml version="1.0"?>"#)?;
    writeln!(
        out,
        r#"<VTKFile type="Collection" version="0.1" byte_order="LittleEndian">"#
    )?;
    writeln!(out, "  <Collection>")?;
    for (t, file) in entries {
        writeln!(
            out,
            r#"    <DataSet timestep="{}" group="" part="0" file="{file}"/>"#,
            Num(*t)
        )?;
    }
    writeln!(out, "  </Collection>")?;
    writeln!(out, "</VTKFile>")
}

/// A float written exactly (shortest round-trip digits), in plain notation for moderate
/// magnitudes and in scientific notation otherwise.
struct Num(Real);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || (1e-3..1e7).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}
