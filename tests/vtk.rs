//! ParaView output ([`VtkWriter`]): runs short scenes into temporary directories, parses
//! every `.pvd` and `.vtp` file back with quick-xml and checks the structure ParaView
//! expects, the frame times, the sampled values against the final rod, the gaps that
//! cuts leave, and that bad options and unwritable directories are errors, not panics.

use splinerod::output::vtk::{VtkWriter, SAMPLES_PER_SPAN};
use splinerod::{Error, Frame, Observer, Real, Rod, RunResult, Scene, StepReport};
use std::fs;
use std::path::{Path, PathBuf};

mod files;

use files::*;

/// A 1 m cable with 12 control points, pinned at both ends 0.8 m apart, falling under
/// gravity for 0.2 s (20 implicit-Euler steps).
const CABLE: &str = r#"[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 12
start = [0.0, 0.0, 0.0]
end = [0.8, 0.0, 0.0]
[[pins]]
at = 0.0
[[pins]]
at = 1.0
[world]
gravity = [0.0, -9.81, 0.0]
[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.2
[output]
samples = 19
"#;

/// [`CABLE`] cut at mid-length after 0.1 s.
fn cut_cable() -> String {
    format!("{CABLE}\n[[cuts]]\nat = 0.5\ntime = 0.1\n")
}

/// An empty directory of this test process under the system temp directory.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("splinerod-vtk-{}-{name}", std::process::id()));
    if dir.exists() {
        fs::remove_dir_all(&dir).expect("clear temp dir");
    }
    fs::create_dir_all(&dir).expect("temp dir");
    dir
}

// ------------------------------------------------------------------ running scenes

/// Watches a run: the time of every step, and the final rod and result.
#[derive(Default)]
struct Recorder {
    /// `(step, time)` at start and after every step.
    times: Vec<(usize, Real)>,
    last: Option<(Rod, RunResult)>,
    /// Fail after this step (to simulate a run that dies midway).
    fail_after: Option<usize>,
}

impl Observer for Recorder {
    fn start(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        self.times.push((frame.step, frame.time));
        Ok(())
    }

    fn step(&mut self, frame: &Frame<'_>, _: &StepReport, _: Real) -> Result<(), Error> {
        self.times.push((frame.step, frame.time));
        match self.fail_after {
            Some(n) if frame.step >= n => Err(Error::Stopped("the test".into())),
            _ => Ok(()),
        }
    }

    fn finish(&mut self, frame: &Frame<'_>, result: &RunResult) -> Result<(), Error> {
        self.last = Some((frame.system.rod.clone(), result.clone()));
        Ok(())
    }
}

/// Runs `toml` writing every `every`-th step into `dir`; returns the recorder.
fn run_into(toml: &str, dir: &Path, every: usize) -> Recorder {
    let scene = Scene::from_toml(toml).expect("scene");
    let mut writer = VtkWriter::new(dir, every).expect("writer");
    let mut recorder = Recorder::default();
    splinerod::run_observed(&scene, &mut [&mut writer, &mut recorder]).expect("run");
    assert_eq!(
        writer.frame_count(),
        read_collection(&dir.join("rod.pvd")).len()
    );
    recorder
}

/// Reads both collections and every frame; checks the entries and the times against
/// what the run reported at the expected steps. Returns the centreline and polygon
/// frames.
fn read_series(dir: &Path, rec: &Recorder, steps: &[usize]) -> (Vec<PolyData>, Vec<PolyData>) {
    let expected: Vec<Real> = (steps.iter())
        .map(|&n| rec.times.iter().find(|t| t.0 == n).expect("step was run").1)
        .collect();
    let mut series = Vec::new();
    for (collection, prefix) in [("rod.pvd", "centreline"), ("polygon.pvd", "polygon")] {
        let entries = read_collection(&dir.join(collection));
        let times: Vec<Real> = entries.iter().map(|e| e.0).collect();
        assert_eq!(
            times, expected,
            "{collection}: one entry per recorded frame"
        );
        assert!(
            times.windows(2).all(|w| w[1] > w[0]),
            "increasing timesteps"
        );
        let frames: Vec<PolyData> = (entries.iter().enumerate())
            .map(|(i, (t, file))| {
                assert_eq!(file, &format!("{prefix}_{i:05}.vtp"));
                let frame = PolyData::read(&dir.join(file));
                assert_eq!((frame.time, frame.step), (*t, steps[i]));
                frame
            })
            .collect();
        series.push(frames);
    }
    let polygons = series.pop().unwrap();
    (series.pop().unwrap(), polygons)
}

/// Checks a centreline: `s` increases from 0 to 1 within each polyline, and every point
/// matches `rod` (a polyline ending at a cut holds the curve's left limit there).
fn check_centreline(line: &PolyData, rod: &Rod) {
    assert_eq!(line.scalars, "stretch");
    let (s, speed, stretch) = (
        line.values("s"),
        line.values("speed"),
        line.values("stretch"),
    );
    assert_eq!(s.first(), Some(&0.0));
    assert_eq!(s.last(), Some(&1.0));
    let l = rod.material().rest_length;
    for (k, &(a, b)) in line.lines.iter().enumerate() {
        assert!(s[a..b].windows(2).all(|w| w[1] > w[0]), "s increases");
        for i in a..b {
            let at_cut = i + 1 == b && k + 1 < line.lines.len();
            let m = if at_cut { s[i] * l - 1e-13 } else { s[i] * l };
            let d = distance(rod.point(m).expect("point").into(), line.points[i]);
            assert!(d < 1e-10, "point {i} (s = {}) off by {d:e}", s[i]);
            let v = rod.velocity(m).expect("velocity").norm();
            let g = rod.tangent(m).expect("tangent").norm();
            let (dv, dg) = ((v - speed[i]).abs(), (g - stretch[i]).abs());
            assert!(
                dv < 1e-9 && dg < 1e-9,
                "speed, stretch at {i} off by {dv:e}, {dg:e}"
            );
        }
    }
}

/// Largest coordinate difference of two points.
fn distance(a: [Real; 3], b: [Real; 3]) -> Real {
    (0..3).map(|c| (a[c] - b[c]).abs()).fold(0.0, Real::max)
}

/// Checks a control polygon against `rod`: exactly its control points and speeds.
fn check_polygon(polygon: &PolyData, rod: &Rod) {
    let expected: Vec<[Real; 3]> = rod.positions.iter().map(|p| [p.x, p.y, p.z]).collect();
    assert_eq!(polygon.points, expected);
    let speeds: Vec<Real> = rod.velocities.iter().map(|v| v.norm()).collect();
    assert_eq!(polygon.values("speed"), &speeds[..]);
    assert_eq!(polygon.values("s").len(), rod.len());
    assert_eq!(polygon.lines.len(), rod.pieces());
}

// ------------------------------------------------------------------------- tests

#[test]
fn every_frame_parses_back_and_matches_the_run() {
    let dir = temp_dir("cable");
    let rec = run_into(CABLE, &dir, 5);
    // Start, steps 5, 10, 15 and 20; the last step is not recorded twice at finish.
    let steps = [0, 5, 10, 15, 20];
    let (lines, polygons) = read_series(&dir, &rec, &steps);
    let (rod, result) = rec.last.as_ref().expect("finished");
    assert_eq!(result.steps, 20);
    let spans = 12 - 3;
    for line in &lines {
        assert_eq!(line.points.len(), spans * SAMPLES_PER_SPAN + 1);
        assert_eq!(line.lines.len(), 1);
        // Positive (no fold) and bounded. The default (mixed-consistent, picked for this
        // compressed start) resolves only the span-mean strain, so while the sag forms
        // the stretch inside a span swings between 0.14 and 1.9 (0.95-1.12 pointwise).
        assert!(line.values("stretch").iter().all(|&g| g > 0.05 && g < 2.5));
    }
    // Straight, 1 m of material between pins 0.8 m apart, at rest.
    assert!(lines[0]
        .values("stretch")
        .iter()
        .all(|&g| (g - 0.8).abs() < 1e-12));
    assert!(
        lines[0].values("speed").iter().all(|&v| v == 0.0),
        "starts at rest"
    );
    let last = lines.last().unwrap();
    check_centreline(last, rod);
    check_polygon(polygons.last().unwrap(), rod);
    assert_eq!(polygons[0].points.len(), 12);
    // The run's own samples (fractions k/18) are centreline points of the last frame.
    for (f, p) in result.samples.s.iter().zip(&result.samples.positions) {
        let i = (last.values("s").iter())
            .position(|s| (s - f).abs() < 1e-12)
            .unwrap_or_else(|| panic!("s = {f} not sampled"));
        let d = distance(*p, last.points[i]);
        assert!(d < 1e-12, "sample s = {f} off by {d:e}");
    }
    fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn a_cut_leaves_two_polylines() {
    let dir = temp_dir("cut");
    let rec = run_into(&cut_cable(), &dir, 4);
    // 20 steps recorded every 4th: the final step 20 is one of them.
    let steps = [0, 4, 8, 12, 16, 20];
    let (lines, polygons) = read_series(&dir, &rec, &steps);
    let (rod, result) = rec.last.as_ref().expect("finished");
    assert_eq!(result.pieces, 2);
    for (line, polygon) in lines.iter().zip(&polygons) {
        let pieces = if line.time < 0.1 - 1e-9 { 1 } else { 2 };
        assert_eq!(line.lines.len(), pieces, "centreline at t = {}", line.time);
        assert_eq!(
            polygon.lines.len(),
            pieces,
            "polygon at t = {}",
            polygon.time
        );
    }
    let last = lines.last().unwrap();
    check_centreline(last, rod);
    check_polygon(polygons.last().unwrap(), rod);
    assert_eq!(polygons.last().unwrap().points.len(), result.control_points);
    // Each piece covers its half of the material, both ends included.
    let s = last.values("s");
    let (left, right) = (last.lines[0], last.lines[1]);
    assert_eq!((s[left.0], s[left.1 - 1]), (0.0, 0.5));
    assert_eq!((s[right.0], s[right.1 - 1]), (0.5, 1.0));
    // The clamped pieces end at their end control points, on both sides of the cut.
    let polygon = polygons.last().unwrap();
    let split = polygon.lines[0].1;
    for (centre, control) in [(left.1 - 1, split - 1), (right.0, split)] {
        let d = distance(last.points[centre], polygon.points[control]);
        assert!(
            d < 1e-12,
            "cut end {centre} vs control point {control}: {d:e}"
        );
    }
    fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn static_solve_records_the_initial_state_and_the_equilibrium() {
    let dir = temp_dir("static");
    let toml = CABLE.replace("method = \"implicit-euler\"", "method = \"static\"");
    let toml = toml.replace("dt = 0.01\nduration = 0.2\n", "");
    let rec = run_into(&toml, &dir, 3);
    let entries = read_collection(&dir.join("rod.pvd"));
    assert_eq!(entries.iter().map(|e| e.0).collect::<Vec<_>>(), [0.0, 1.0]);
    let equilibrium = PolyData::read(&dir.join(&entries[1].1));
    check_centreline(&equilibrium, &rec.last.as_ref().expect("finished").0);
    fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn a_failed_run_leaves_no_collection() {
    let dir = temp_dir("failed");
    fs::write(dir.join("rod.pvd"), "stale").expect("stale collection");
    let scene = Scene::from_toml(CABLE).expect("scene");
    let mut writer = VtkWriter::new(&dir, 2).expect("writer");
    let mut recorder = Recorder {
        fail_after: Some(7),
        ..Recorder::default()
    };
    let run = splinerod::run_observed(&scene, &mut [&mut writer, &mut recorder]);
    assert!(run.is_err());
    assert!(!dir.join("rod.pvd").exists(), "stale collection removed");
    assert!(!dir.join("polygon.pvd").exists());
    // Frames up to the failure were written: start, steps 2, 4, 6.
    assert_eq!(writer.frame_count(), 4);
    PolyData::read(&dir.join("centreline_00003.vtp"));
    fs::remove_dir_all(&dir).expect("clean up");
}

#[test]
fn every_zero_is_rejected() {
    match VtkWriter::new(&std::env::temp_dir(), 0) {
        Err(Error::InvalidField { field, value, .. }) => {
            assert_eq!((field.as_str(), value.as_str()), ("--every", "0"));
        }
        other => panic!("expected an invalid-field error, got {other:?}"),
    }
}

#[test]
fn a_directory_under_a_regular_file_is_an_error() {
    let dir = temp_dir("unwritable");
    let file = dir.join("not-a-directory");
    fs::write(&file, "x").expect("file");
    let target = file.join("frames");
    match VtkWriter::new(&target, 1) {
        Err(Error::Io { path, .. }) => assert_eq!(path, target.display().to_string()),
        other => panic!("expected an I/O error, got {other:?}"),
    }
    fs::remove_dir_all(&dir).expect("clean up");
}
