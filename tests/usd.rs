//! USD output ([`UsdWriter`]): runs short scenes, reads the `.usda` text back without
//! USD, and checks its structure (stage metadata, prims, every time-sampled attribute
//! on the same codes, counts that add up) and that the exact control points read back
//! bit for bit equal to the rod's at every recorded step (the float `points` to the
//! float nearest them); a closed rod's periodic form; refused paths and options.

use splinerod::output::usd::UsdWriter;
use splinerod::{Error, Frame, Observer, Real, Scene, StepReport};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Two cables in one system, the second cut at mid-length after 0.05 s, with a sphere
/// moving up and a floor.
const TWO_CABLES: &str = r#"[[rods]]
name = "long one"
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 10
radius = 0.01
start = [0.0, 0.0, 0.0]
end = [0.8, 0.0, 0.0]
[[rods]]
name = "short"
rest_length = 0.5
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 6
radius = 0.01
start = [0.0, 0.0, 0.5]
end = [0.5, 0.0, 0.5]
[[pins]]
rod = "long one"
at = 0.0
[[pins]]
rod = "long one"
at = 1.0
[[pins]]
rod = "short"
at = 0.0
[[cuts]]
rod = "short"
at = 0.5
time = 0.05
[contact]
floor = -1.0
[[obstacles]]
kind = "sphere"
centre = [0.4, -0.8, 0.0]
radius = 0.1
path = [[0.0, 0.0, 0.0, 0.0], [0.1, 0.0, 0.05, 0.0]]
[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.1
"#;

/// A closed ring of 10 control points falling for 0.05 s.
const RING: &str = r#"[rod]
rest_length = 0.5
linear_density = 0.05
stretch_stiffness = 50.0
bending_stiffness = 2e-4
control_points = 10
[rod.ring]
radius = 0.07957747154594767
[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.05
"#;

/// Keeps the rod's control points at every step (the time code).
#[derive(Default)]
struct Positions(BTreeMap<i64, Vec<[Real; 3]>>);

impl Observer for Positions {
    fn start(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        self.keep(frame)
    }
    fn step(&mut self, frame: &Frame<'_>, _: &StepReport, _: Real) -> Result<(), Error> {
        self.keep(frame)
    }
}

impl Positions {
    fn keep(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        let points = frame.system.rod.positions.iter().map(|p| [p.x, p.y, p.z]);
        self.0.insert(frame.step as i64, points.collect());
        Ok(())
    }
}

/// Runs `toml` into `name`.usda in a fresh temporary directory, recording every
/// `every`-th step; the file's text and the rod's control points at every step.
fn run(toml: &str, name: &str, every: usize) -> (String, Positions) {
    let dir = std::env::temp_dir().join(format!("splinerod-usd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join(format!("{name}.usda"));
    let scene = Scene::from_toml(toml).expect("scene");
    let mut writer = UsdWriter::new(&path, every).expect("writer");
    let mut positions = Positions::default();
    splinerod::run_observed(&scene, &mut [&mut writer, &mut positions]).expect("run");
    assert!(!partial(&path).exists(), "the partial file is renamed");
    let text = std::fs::read_to_string(&path).expect("written");
    std::fs::remove_file(&path).ok();
    (text, positions)
}

fn partial(path: &Path) -> PathBuf {
    PathBuf::from(format!("{}.partial", path.display()))
}

/// The body of prim `kind "name"`: the lines between its braces.
fn prim<'a>(text: &'a str, kind: &str, name: &str) -> Vec<&'a str> {
    let head = format!("def {kind} \"{name}\"");
    let mut lines = text.lines().skip_while(|l| l.trim() != head).skip(2);
    let mut body = Vec::new();
    let mut depth = 0;
    for line in lines.by_ref() {
        depth += line.matches('{').count() as i32 - line.matches('}').count() as i32;
        if depth < 0 {
            return body;
        }
        body.push(line);
    }
    panic!("prim {head} not closed");
}

/// The time samples of attribute `declaration` in `body`: code → the text of its value.
fn samples<'a>(body: &[&'a str], declaration: &str) -> BTreeMap<i64, &'a str> {
    let head = format!("{declaration}.timeSamples = {{");
    let start = body.iter().position(|l| l.trim() == head);
    let start = start.unwrap_or_else(|| panic!("no {declaration}")) + 1;
    let mut out = BTreeMap::new();
    for line in &body[start..] {
        if line.trim() == "}" {
            return out;
        }
        let (code, value) = line.trim().split_once(": ").expect("code: value");
        let value = value.strip_suffix(',').expect("a sample ends with a comma");
        out.insert(code.parse().expect("integer code"), value);
    }
    panic!("{declaration} not closed")
}

/// Every number of a value's text (`[(x, y, z), …]`, `[1, 2]`), parsed as `T`.
fn numbers<T: std::str::FromStr>(value: &str) -> Vec<T>
where
    T::Err: std::fmt::Debug,
{
    let clean: String = value.chars().filter(|c| !"[]()".contains(*c)).collect();
    (clean.split(',').map(str::trim).filter(|s| !s.is_empty()))
        .map(|s| s.parse().expect("a number"))
        .collect()
}

/// The stage metadata `key = value`'s value.
fn metadata<'a>(text: &'a str, key: &str) -> &'a str {
    let prefix = format!("    {key} = ");
    let line = text.lines().find(|l| l.starts_with(&prefix));
    line.unwrap_or_else(|| panic!("no {key}"))[prefix.len()..].trim()
}

/// Every sampled attribute of a rod prim has the same codes; the counts add up; the
/// float points are the exact ones rounded to float (`drop` per curve left out);
/// returns the exact control points per code.
fn check_rod(body: &[&str], degree: usize, drop: usize) -> BTreeMap<i64, Vec<Real>> {
    let counts = samples(body, "int[] curveVertexCounts");
    let exact_counts = samples(body, "custom int[] splinerod:curveVertexCounts");
    let points = samples(body, "point3f[] points");
    let widths = samples(body, "float[] widths");
    let exact = samples(body, "custom double3[] splinerod:controlPoints");
    let knots = samples(body, "custom double[] splinerod:knots");
    let codes: Vec<_> = counts.keys().collect();
    for other in [&exact_counts, &points, &widths, &exact, &knots] {
        assert_eq!(other.keys().collect::<Vec<_>>(), codes);
    }
    let extent = samples(body, "float3[] extent");
    assert_eq!(extent.keys().collect::<Vec<_>>(), codes);
    let mut out = BTreeMap::new();
    for code in counts.keys() {
        let n: Vec<usize> = numbers(exact_counts[code]);
        let drawn: Vec<usize> = numbers(counts[code]);
        assert_eq!(drawn, n.iter().map(|c| c - drop).collect::<Vec<_>>());
        let x: Vec<Real> = numbers(exact[code]);
        let p: Vec<f32> = numbers(points[code]);
        assert_eq!(x.len(), 3 * n.iter().sum::<usize>());
        assert_eq!(p.len(), 3 * drawn.iter().sum::<usize>());
        assert_eq!(
            numbers::<f32>(widths[code]).len(),
            drawn.iter().sum::<usize>()
        );
        let k: Vec<Real> = numbers(knots[code]);
        assert_eq!(k.len(), n.iter().map(|c| c + degree + 1).sum::<usize>());
        assert!(k.windows(2).all(|w| w[0] <= w[1]) || n.len() > 1);
        let (mut i, mut j) = (0, 0);
        for (c, d) in n.iter().zip(&drawn) {
            assert_eq!(
                &p[3 * j..3 * (j + d)],
                &x[3 * i..3 * (i + d)]
                    .iter()
                    .map(|&v| v as f32)
                    .collect::<Vec<_>>()[..]
            );
            (i, j) = (i + c, j + d);
        }
        out.insert(*code, x);
    }
    out
}

fn flat(points: &[[Real; 3]]) -> Vec<Real> {
    points.iter().flatten().copied().collect()
}

#[test]
fn two_cables_round_trip_exactly() {
    let (text, positions) = run(TWO_CABLES, "two", 1);
    assert!(text.starts_with("#usda 1.0\n("));
    assert_eq!(metadata(&text, "upAxis"), "\"Y\"");
    assert_eq!(metadata(&text, "metersPerUnit"), "1");
    assert_eq!(metadata(&text, "defaultPrim"), "\"World\"");
    assert_eq!(metadata(&text, "startTimeCode"), "0");
    assert_eq!(metadata(&text, "endTimeCode"), "10");
    assert_eq!(metadata(&text, "timeCodesPerSecond"), "100");
    assert_eq!(text.matches('{').count(), text.matches('}').count());
    let long = prim(&text, "BasisCurves", "long_one");
    let short = prim(&text, "BasisCurves", "short");
    for body in [&long, &short] {
        assert!(body.contains(&"            uniform token type = \"cubic\""));
        assert!(body.contains(&"            uniform token basis = \"bspline\""));
        assert!(body.contains(&"            uniform token wrap = \"pinned\""));
    }
    let (a, b) = (check_rod(&long, 3, 0), check_rod(&short, 3, 0));
    assert_eq!(
        a.keys().copied().collect::<Vec<_>>(),
        (0..=10).collect::<Vec<_>>()
    );
    for (code, all) in &positions.0 {
        // The joined rod's control points are the two rods' curves, in order.
        let joined: Vec<Real> = a[code].iter().chain(&b[code]).copied().collect();
        assert!(
            joined == flat(all),
            "code {code}: exact control points differ"
        );
    }
    let pieces = samples(&short, "int[] curveVertexCounts");
    assert_eq!(numbers::<usize>(pieces[&0]).len(), 1);
    assert_eq!(
        numbers::<usize>(pieces[&10]).len(),
        2,
        "the cut makes two curves"
    );
    let sphere = prim(&text, "Sphere", "obstacle_0");
    let moves = samples(&sphere, "double3 xformOp:translate");
    assert_eq!(moves.len(), 11);
    assert_eq!(numbers::<Real>(moves[&10]), vec![0.4, -0.75, 0.0]);
    assert!(prim(&text, "Mesh", "floor")
        .contains(&"            double3 xformOp:translate = (0, -1, 0)"));
}

#[test]
fn a_ring_is_periodic_and_every_k_keeps_the_end() {
    let (text, positions) = run(RING, "ring", 2);
    let body = prim(&text, "BasisCurves", "rod");
    assert!(body.contains(&"            uniform token wrap = \"periodic\""));
    assert!(body.contains(&"            custom bool splinerod:closed = 1"));
    let exact = check_rod(&body, 3, 3);
    assert_eq!(exact.keys().copied().collect::<Vec<_>>(), vec![0, 2, 4, 5]);
    for (code, x) in &exact {
        // The unclamped periodic form: all m + d control points, copies included.
        assert!(x == &flat(&positions.0[code]), "code {code}");
    }
}

#[test]
fn bad_paths_and_options_are_refused() {
    let missing = std::env::temp_dir().join("splinerod-no-such-dir/out.usda");
    let e = UsdWriter::new(&missing, 1).expect_err("no directory");
    assert_eq!(e.field_name(), Some("--usd"));
    assert!(e.to_string().contains(&missing.display().to_string()));
    let e = UsdWriter::new(Path::new("x.usda"), 0).expect_err("every 0");
    assert_eq!(e.field_name(), Some("--every"));
}

#[test]
fn a_body_is_a_transformed_prim_at_its_json_pose() {
    let toml = std::fs::read_to_string("scenes/body_pendulum.toml").expect("scene");
    let scene = Scene::from_toml(&toml.replace("duration = 4.3", "duration = 0.5"));
    let scene = scene.expect("scene");
    let dir = std::env::temp_dir().join(format!("splinerod-usd-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let path = dir.join("body.usda");
    let mut writer = UsdWriter::new(&path, 1).expect("writer");
    let result = splinerod::run_observed(&scene, &mut [&mut writer]).expect("run");
    let text = std::fs::read_to_string(&path).expect("written");
    std::fs::remove_file(&path).ok();
    let bob = prim(&text, "Xform", "bob");
    assert!(bob.contains(&"            custom string splinerod:kind = \"body\""));
    assert!(bob.contains(&"            custom double splinerod:mass = 2"));
    let translate = samples(&bob, "double3 xformOp:translate");
    let orient = samples(&bob, "quatd xformOp:orient");
    let track = &result.bodies[0];
    assert_eq!(translate.len(), track.t.len());
    assert_eq!(
        orient.keys().collect::<Vec<_>>(),
        translate.keys().collect::<Vec<_>>()
    );
    let (mut moved, mut turned): (Real, Real) = (0.0, 0.0);
    for (k, code) in translate.keys().enumerate() {
        let x: Vec<Real> = numbers(translate[code]);
        let q: Vec<Real> = numbers(orient[code]);
        let rv = nalgebra::Vector3::from(track.orientation[k]);
        let e = nalgebra::UnitQuaternion::from_scaled_axis(rv);
        let sign = if e.w * q[0] < 0.0 { -1.0 } else { 1.0 };
        let e = [e.w, e.i, e.j, e.k].map(|c| sign * c);
        for i in 0..3 {
            moved = moved.max((x[i] - track.position[k][i]).abs());
        }
        for i in 0..4 {
            turned = turned.max((q[i] - e[i]).abs());
        }
    }
    println!("body: translate − JSON position {moved:e} m, orient − JSON rotation {turned:e}");
    assert!(moved <= 1e-12 && turned <= 1e-12);
    let shape = prim(&text, "Cube", "shape");
    // The box of I = 0.01 kg m² about every axis for 2 kg: sides √(6·0.01/2).
    let scale = shape
        .iter()
        .find_map(|l| l.trim().strip_prefix("double3 xformOp:scale = "));
    let sides: Vec<Real> = numbers(scale.expect("scaled"));
    assert!(sides
        .iter()
        .all(|s| (s - (0.03 as Real).sqrt()).abs() < 1e-15));
}
