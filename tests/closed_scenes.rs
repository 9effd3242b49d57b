//! Closed rods in scenes (#20): `[rod.ring]` and `closed = true`, with contact, pins,
//! cuts and adaptivity; bad input named.

use crate::common;

use common::*;
use splinerod::prelude::*;
use splinerod::run;

/// A ring of 16 control points (rest radius 0.1 m, at rest) under gravity, held at one
/// material point.
const RING: &str = r#"[rod]
rest_length = 0.6283185307179586
linear_density = 0.05
stretch_stiffness = 50.0
bending_stiffness = 1e-4
damping = 1.0
control_points = 16

[rod.ring]
radius = 0.1
center = [0.0, 0.0, 0.0]
normal = [0.0, 0.0, 1.0]

[[pins]]
at = 0.25

[solver]
method = "implicit-euler"
dt = 0.002
duration = 0.3

[output]
samples = 41
probes = [0.0, 0.5]
"#;

#[test]
fn the_bundled_ring_lands_flat_on_the_floor() {
    let scene = Scene::load("scenes/ring_drop.toml").expect("scene");
    let result = run(&scene).expect("run");
    assert_eq!(result.control_points, 16);
    assert_eq!(result.pieces, 1);
    let r = scene.rod.radius.expect("radius");
    let ys: Vec<Real> = result.samples.positions.iter().map(|p| p[1]).collect();
    let (low, high) = ys
        .iter()
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), &y| {
            (a.min(y), b.max(y))
        });
    println!("ring on the floor: centre line between y = {low:.5} and {high:.5} m (radius {r} m)");
    // Lying flat on the floor: every point at one radius above it, within the
    // penalty's indentation.
    assert!(low > 0.5 * r && high < 1.5 * r, "{low} {high}");
    // The sampled curve closes: s = 0 and s = L are one point.
    let (first, last) = (
        result.samples.positions[0],
        *result.samples.positions.last().expect("samples"),
    );
    let gap = (Vector3::from(first) - Vector3::from(last)).norm();
    assert!(gap < 1e-12, "{gap}");
}

#[test]
fn a_ring_hangs_from_a_pin_without_a_seam() {
    // The seam (s = 0) hangs to one side; the ring is symmetric about the pin's
    // vertical, so the material points a quarter turn either side of the pin (one of
    // them the seam) end mirror images.
    let result = run(&accepted(RING)).expect("run");
    let p = |k: usize| Vector3::from(result.probes[k].positions.last().copied().expect("probe"));
    let (seam, opposite) = (p(0), p(1));
    let pin = Vector3::new(0.0, 0.1, 0.0);
    println!("seam at {seam:?}, opposite at {opposite:?}");
    assert!((seam.y - opposite.y).abs() < 1e-9 && (seam.x + opposite.x).abs() < 1e-9);
    assert!(seam.y < pin.y, "the ring hangs");
}

#[test]
fn a_ring_can_be_cut_at_its_seam() {
    for at in ["0.0", "1.0"] {
        let seam = format!("{RING}\n[[cuts]]\nat = {at}\ntime = 0.1\n");
        let result = run(&accepted(&seam)).expect("run");
        assert_eq!(result.pieces, 1, "the seam cut opens the loop");
        let both = format!("{seam}\n[[cuts]]\nat = 0.5\ntime = 0.1\n");
        assert_eq!(run(&accepted(&both)).expect("run").pieces, 2);
    }
    // An open rod's ends are no cut.
    let open = "[rod]\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 10.0\ncontrol_points = 8\n[[cuts]]\nat = 0.0\ntime = 0.0\n[solver]\nmethod = \"implicit-euler\"\ndt = 0.01\nduration = 0.1\n";
    assert_field(&rejected(open), "cuts[0].at");
    // A twisted loop cut at its seam releases its twist.
    let text = std::fs::read_to_string("scenes/michell_ring.toml").expect("scene");
    let text = set_in(&text, "duration", "0.6") + "\n[[cuts]]\nat = 0.0\ntime = 0.5\n";
    let result = run(&accepted(&text)).expect("run");
    assert_eq!(result.energy.get("twist").copied().unwrap_or(0.0), 0.0);
}

#[test]
fn cutting_a_ring_opens_it_then_splits_it() {
    let once = with_line_in(RING, "[solver]", "");
    let once = format!("{once}\n[[cuts]]\nat = 0.6\ntime = 0.1\n");
    let result = run(&accepted(&once)).expect("run");
    assert_eq!(result.pieces, 1, "one cut opens the loop");
    let twice = format!("{once}\n[[cuts]]\nat = 0.9\ntime = 0.1\n");
    let result = run(&accepted(&twice)).expect("run");
    assert_eq!(result.pieces, 2, "two cuts make two pieces");
}

#[test]
fn a_ring_refines_where_it_is_pulled() {
    let pulled = format!(
        "{RING}\n[[grabs]]\nat = 0.75\nto = [0.0, -0.25, 0.0]\nstart_time = 0.0\nend_time = 0.2\nstiffness = 500.0\n\n[adaptivity]\nmax_control_points = 40\n"
    );
    let result = run(&accepted(&pulled)).expect("run");
    println!("pulled ring: {} control points", result.control_points);
    assert!(result.control_points > 16);
    let gap = (Vector3::from(result.samples.positions[0])
        - Vector3::from(*result.samples.positions.last().expect("s")))
    .norm();
    assert!(gap < 1e-12);
}

#[test]
fn bad_closed_rods_are_named() {
    let closed = set_in(
        &without_in(&without_in(RING, "center"), "normal"),
        "radius",
        "0.1",
    );
    let clamped = with_line_in(&closed, "[rod]", "knots = \"clamped\"");
    assert_field(&rejected(&clamped), "rod.knots");
    assert_field(
        &rejected(&set_in(&closed, "control_points", "3")),
        "rod.control_points",
    );
    for radius in ["0.0", "-0.1", "nan", "inf"] {
        assert_field(
            &rejected(&set_in(&closed, "radius", radius)),
            "rod.ring.radius",
        );
    }
    let flat = with_line_in(&closed, "[rod.ring]", "normal = [0.0, 0.0, 0.0]");
    assert_field(&rejected(&flat), "rod.ring.normal");
    let started = with_line_in(&closed, "[rod]", "start = [0.0, 0.0, 0.0]");
    assert_field(&rejected(&started), "rod.start");
    let no_shape = RING
        .replace(
            "[rod.ring]\nradius = 0.1\ncenter = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n",
            "",
        )
        .replace("control_points = 16", "control_points = 16\nclosed = true");
    assert_field(&rejected(&no_shape), "rod.closed");
    let clamp = with_line_in(&closed, "[[pins]]", "clamp = true");
    assert_field(&rejected(&clamp), "pins[0].clamp");
    // A twisted loop needs bending; an open rod cannot start twisted.
    let twist = with_line_in(&closed, "[rod]", "twist_stiffness = 1e-4");
    accepted(&twist);
    let unbent = without_in(
        &with_line_in(&closed, "[rod]", "twist_stiffness = 1e-4"),
        "bending_stiffness",
    );
    assert_field(&rejected(&unbent), "rod.twist_stiffness");
    let loose = with_line_in(&closed, "[rod]", "twist = 1.0");
    assert_field(&rejected(&loose), "rod.twist");
    let open = "[rod]\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 10.0\nbending_stiffness = 1e-3\ntwist_stiffness = 1e-3\ntwist = 1.0\ncontrol_points = 8\n[[pins]]\nat = 0.0\nclamp = true\n[[pins]]\nat = 1.0\nclamp = true\n[solver]\nmethod = \"static\"\n";
    assert_field(&rejected(open), "rod.twist");
    // Explicit periodic breakpoints: control_points + 1 of them.
    let knots: Vec<String> = (0..=16).map(|k| format!("{}", k as f64)).collect();
    accepted(&with_line_in(
        &closed,
        "[rod]",
        &format!("knots = [{}]", knots.join(", ")),
    ));
    let short = &knots[..16];
    assert_field(
        &rejected(&with_line_in(
            &closed,
            "[rod]",
            &format!("knots = [{}]", short.join(", ")),
        )),
        "rod.knots",
    );
}

#[test]
fn initial_control_points_wrap_around() {
    // A square loop of 8 points: the curve closes and is smooth at the seam.
    let points = "[[0.1, 0.0, 0.0], [0.1, 0.1, 0.0], [0.0, 0.1, 0.0], [-0.1, 0.1, 0.0], [-0.1, 0.0, 0.0], [-0.1, -0.1, 0.0], [0.0, -0.1, 0.0], [0.1, -0.1, 0.0]]";
    let text = RING
        .replace(
            "[rod.ring]\nradius = 0.1\ncenter = [0.0, 0.0, 0.0]\nnormal = [0.0, 0.0, 1.0]\n",
            "",
        )
        .replace(
            "control_points = 16",
            &format!("control_points = 8\nclosed = true\ninitial_control_points = {points}"),
        );
    let scene = accepted(&text);
    let system = scene.build_system().expect("system");
    let rod = &system.rod;
    assert!(rod.is_closed());
    assert_eq!((rod.len(), rod.distinct_len()), (11, 8));
    let l = rod.material().rest_length;
    for (a, b) in [
        (rod.point(0.0), rod.point(l)),
        (rod.tangent(0.0), rod.tangent(l)),
    ] {
        assert!((a.expect("a") - b.expect("b")).norm() < 1e-14);
    }
}

#[test]
fn a_rubber_band_on_two_pegs_pulls_each_with_twice_its_tension() {
    let text = std::fs::read_to_string("scenes/rubber_band.toml").expect("scene");
    let scene = accepted(&set_in(&text, "samples", "801"));
    let result = run(&scene).expect("run");
    let points: Vec<Vector3<Real>> = result
        .samples
        .positions
        .iter()
        .map(|p| Vector3::from(*p))
        .collect();
    let length: Real = points.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let gamma = length / scene.rod.rest_length;
    let ea = scene.rod.stretch_stiffness;
    // Green–Lagrange: the axial force at stretch γ is EA γ (γ² − 1) / 2.
    let tension = ea * gamma * (gamma * gamma - 1.0) / 2.0;
    let forces: Vec<Vector3<Real>> = result
        .obstacle_forces
        .iter()
        .map(|f| Vector3::from(*f))
        .collect();
    let reach = points.iter().map(|p| p.x.abs()).fold(0.0, Real::max);
    println!(
        "band: stretch {gamma:.4}, tension {tension:.4} N; peg forces {:.4} and {:.4} N; reaches x = ±{reach:.5} m",
        forces[0].norm(),
        forces[1].norm()
    );
    // Around both pegs (axes at ±0.1 m, radius 1 cm, band radius 2 mm).
    assert!((reach - 0.112).abs() < 1e-3, "{reach}");
    for f in &forces {
        assert!(
            (f.norm() / (2.0 * tension) - 1.0).abs() < 0.03,
            "{f:?} against 2 × {tension}"
        );
        assert!(
            f.x.abs() > 0.999 * f.norm(),
            "the pegs are pulled towards each other"
        );
    }
}

/// The loop pulled flat between a pin and a grab keeps its two strands apart and
/// uncrossed. (With 32 control points its ends cannot turn tighter than a few
/// centimetres: the strands stay about 16 mm apart mid-way, as with the pointwise
/// stretching. The lumped mixed form once turned tighter by bunching its material at
/// the turns, which its projection did not see, and its strands touched there; the
/// compression guard stopped that.)
#[test]
fn a_loop_pulled_flat_keeps_its_strands_apart() {
    let scene = Scene::load("scenes/loop_pulled.toml").expect("scene");
    let result = run(&scene).expect("run");
    let r = scene.rod.radius.expect("radius");
    let contact = result.contact.as_ref().expect("contact statistics");
    let clearance = contact.min_clearance_ratio.unwrap_or(Real::INFINITY);
    let p = |k: usize| Vector3::from(result.probes[k].positions.last().copied().expect("probe"));
    let (a, b) = (p(0), p(1));
    println!(
        "loop: clearance {clearance:.4}; strand midpoints {:.5} m apart, mirror error {:.1e} m",
        (a - b).norm(),
        (a.x + b.x).abs() + (a.y - b.y).abs()
    );
    assert!(clearance >= 0.95, "{clearance}");
    assert!(
        (a - b).norm() >= 2.0 * r,
        "the strands are side by side, not crossed"
    );
    // The seam (s = 0, probe 0) is on one strand: the loop stays symmetric regardless.
    assert!((a.x + b.x).abs() < 1e-9 && (a.y - b.y).abs() < 1e-9);
}

#[test]
fn the_michell_ring_folds_into_a_figure_eight_keeping_its_link() {
    let scene = Scene::load("scenes/michell_ring.toml").expect("scene");
    let result = run(&scene).expect("run");
    let twist = result.twist.as_ref().expect("twist output");
    let contact = result.contact.as_ref().expect("contact statistics");
    let turns = scene.rod.twist.expect("twist") / std::f64::consts::TAU;
    println!(
        "michell ring: twist {:.4} turns, writhe {:.4}, link {:.5} (started {turns}); clearance {:?}",
        twist.twist / std::f64::consts::TAU,
        twist.writhe,
        twist.link,
        contact.min_clearance_ratio
    );
    // Buckled out of plane (a planar loop has no writhe), through writhe ≈ 1.
    assert!(twist.writhe > 0.8, "{}", twist.writhe);
    // Călugăreanu: the link is kept (the writhe is sampled: 401 points).
    assert!((twist.link - turns).abs() < 2e-3, "{}", twist.link);
    assert!(contact.min_clearance_ratio.unwrap_or(1.0) > 0.85);
}

#[test]
fn rings_run_in_ensembles_and_write_paraview_files() {
    let ensemble = format!("{RING}\n[ensemble]\ncount = 4\nseed = 3\nstretch_stiffness = [30.0, 80.0]\nperturbation = 0.005\n");
    let result = run(&accepted(&ensemble)).expect("ensemble");
    assert_eq!(result.ensemble.len(), 4);
    assert!(result.ensemble.iter().all(|m| m.control_points == 16));
    let dir = std::env::temp_dir().join(format!("splinerod-closed-vtk-{}", std::process::id()));
    let mut vtk = splinerod::output::vtk::VtkWriter::new(&dir, 50).expect("writer");
    let scene = accepted(RING);
    splinerod::run_observed(&scene, &mut [&mut vtk]).expect("run with VTK");
    let frames = std::fs::read_dir(&dir).expect("dir").filter(|e| {
        e.as_ref()
            .is_ok_and(|e| e.path().extension().is_some_and(|x| x == "vtp"))
    });
    assert!(frames.count() >= 3);
    std::fs::remove_dir_all(&dir).expect("cleanup");
}

#[test]
fn the_command_line_refuses_bad_closed_rods_with_exit_2() {
    let dir = common::cli::fresh_dir("closed-bad");
    for (edit, field) in [
        (("radius = 0.08", "radius = 0.0"), "rod.ring.radius"),
        (
            ("normal = [0.0, 0.94, 0.342]", "normal = [0.0, 0.0, 0.0]"),
            "rod.ring.normal",
        ),
        (
            ("control_points = 16", "control_points = 3"),
            "rod.control_points",
        ),
        (
            (
                "control_points = 16",
                "control_points = 16\nknots = \"clamped\"",
            ),
            "rod.knots",
        ),
    ] {
        let path = common::cli::scene_variant(&dir, "ring_drop.toml", &[edit]);
        let line = common::cli::refused(&["run", path.to_str().expect("path")]);
        assert_field(&line, field);
    }
    std::fs::remove_dir_all(&dir).expect("cleanup");
}
