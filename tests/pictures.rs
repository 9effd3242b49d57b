//! Pictures and plots: frames written at the right steps, decodable at the right size,
//! showing the rod where the camera puts it; the GIF; bad options; line plots.

use nalgebra::Vector3;
use splinerod::output::picture::{Camera, Pictures};
use splinerod::output::plot::{line_plot, Series, HEIGHT, WIDTH};
use splinerod::{run_observed, Error, RunResult, Scene};
use std::path::{Path, PathBuf};

/// A 1 m cable with 12 control points pinned at both ends 0.8 m apart, under gravity.
fn cable(method: &str, timing: &str) -> Scene {
    let text = format!(
        r#"
[rod]
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
method = "{method}"
{timing}
"#
    );
    Scene::from_toml(&text).expect("the test scene is valid")
}

fn dynamic_cable() -> Scene {
    cable("implicit-euler", "dt = 0.01\nduration = 0.2")
}

/// A fresh directory under the system's temporary directory.
fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("splinerod-pictures-{}-{name}", std::process::id()));
    cleanup(&dir);
    dir
}

/// Removes a scratch directory, unless `SPLINEROD_KEEP_TEST_OUTPUT` is set (to look
/// at the pictures).
fn cleanup(dir: &Path) {
    if std::env::var_os("SPLINEROD_KEEP_TEST_OUTPUT").is_none() {
        let _ = std::fs::remove_dir_all(dir);
    }
}

/// Decodes a PNG into (width, height, RGB bytes).
fn decode(path: &Path) -> (u32, u32, Vec<u8>) {
    let file = std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut reader = png::Decoder::new(std::io::BufReader::new(file))
        .read_info()
        .expect("PNG header");
    let mut buf = vec![0; reader.output_buffer_size().expect("buffer size")];
    let info = reader.next_frame(&mut buf).expect("PNG data");
    assert_eq!(info.color_type, png::ColorType::Rgb);
    buf.truncate(info.buffer_size());
    (info.width, info.height, buf)
}

/// Whether some pixel within `radius` of `(x, y)` is not white.
fn inked(rgb: &[u8], (x, y): (f64, f64), radius: i64) -> bool {
    let (cx, cy) = (x.round() as i64, y.round() as i64);
    (cx - radius..=cx + radius).any(|px| {
        (cy - radius..=cy + radius).any(|py| {
            let inside = (0..WIDTH as i64).contains(&px) && (0..HEIGHT as i64).contains(&py);
            let i = 3 * (py * WIDTH as i64 + px) as usize;
            inside && rgb[i..i + 3] != [255, 255, 255]
        })
    })
}

/// Frames expected from the start, every `every`-th step and the final state.
fn expected_frames(steps: usize, every: usize) -> usize {
    1 + steps / every + usize::from(steps % every != 0)
}

fn run_with(scene: &Scene, pictures: &mut Pictures) -> RunResult {
    run_observed(scene, &mut [pictures]).expect("the run succeeds")
}

#[test]
fn frames_show_the_rod_where_the_camera_puts_it() {
    let dir = scratch("xy");
    let gif = dir.join("run.gif");
    let mut pictures = Pictures::new(&dir, 3, Camera::Xy, true, true)
        .expect("pictures")
        .with_gif(gif.clone());
    let result = run_with(&dynamic_cable(), &mut pictures);
    assert_eq!(result.steps, 20);
    let count = expected_frames(result.steps, 3);
    assert_eq!(count, 8, "start, steps 3, 6, …, 18, and the final state");
    assert_eq!(pictures.frames(), count);
    for i in 0..count {
        let png = dir.join(format!("frame_{i:05}.png"));
        let (w, h, _) = decode(&png);
        assert_eq!((w, h), (WIDTH, HEIGHT), "{}", png.display());
        let svg = std::fs::read_to_string(dir.join(format!("frame_{i:05}.svg"))).expect("svg");
        assert!(svg.contains("<svg") && svg.contains("control points"));
    }
    assert!(!dir.join(format!("frame_{count:05}.png")).exists());
    let view = *pictures.view().expect("a view after the run");

    // The first frame shows the initial straight rod from (0,0,0) to (0.8,0,0).
    let (_, _, first) = decode(&dir.join("frame_00000.png"));
    for k in 0..=8 {
        let p = Vector3::new(0.1 * k as f64, 0.0, 0.0);
        assert!(
            inked(&first, view.pixel(&p), 3),
            "initial point {p:?} not drawn"
        );
    }
    // The last frame shows the sagging rod at the reported end positions.
    let (_, _, last) = decode(&dir.join(format!("frame_{:05}.png", count - 1)));
    for p in &result.samples.positions {
        let p = Vector3::from(*p);
        assert!(
            inked(&last, view.pixel(&p), 3),
            "final point {p:?} not drawn"
        );
    }
    let sag = result
        .samples
        .positions
        .iter()
        .map(|p| p[1])
        .fold(0.0, f64::min);
    assert!(sag < -0.05, "the cable sags ({sag})");
    let (x, y) = view.pixel(&Vector3::new(0.4, -0.4 * sag, 0.0));
    assert!(!inked(&last, (x, y), 2), "blank above the rod");
    assert!(!inked(&last, (5.0, 5.0), 2), "blank corner");

    let decoder = gif::DecodeOptions::new();
    let file = std::fs::File::open(&gif).expect("the GIF exists");
    let mut frames = decoder.read_info(file).expect("GIF header");
    let mut n = 0;
    while let Some(frame) = frames.read_next_frame().expect("GIF frame") {
        assert_eq!((frame.width as u32, frame.height as u32), (WIDTH, HEIGHT));
        n += 1;
    }
    assert_eq!(n, count);
    assert!(
        !dir.join("run.gif.partial").exists(),
        "no partial file left"
    );
    cleanup(&dir);
}

#[test]
fn oblique_view_draws_the_rod_and_pins() {
    let dir = scratch("oblique");
    let mut pictures = Pictures::new(&dir, 20, Camera::Oblique, false, false).expect("pictures");
    let result = run_with(&dynamic_cable(), &mut pictures);
    assert_eq!(pictures.frames(), expected_frames(result.steps, 20));
    assert_eq!(pictures.frames(), 2);
    assert!(!dir.join("frame_00000.svg").exists(), "no SVG unless asked");
    let view = *pictures.view().expect("view");
    let (_, _, last) = decode(&dir.join("frame_00001.png"));
    for p in &result.samples.positions {
        let p = Vector3::from(*p);
        assert!(
            inked(&last, view.pixel(&p), 3),
            "final point {p:?} not drawn"
        );
    }
    // Pins are black squares.
    let (x, y) = view.pixel(&Vector3::zeros());
    let i = 3 * (y.round() as usize * WIDTH as usize + x.round() as usize + 4);
    assert_eq!(last[i..i + 3], [0, 0, 0], "pin square at the origin");
    cleanup(&dir);
}

#[test]
fn a_static_solve_gives_the_initial_and_the_final_frame() {
    let dir = scratch("static");
    let mut pictures = Pictures::new(&dir, 1, Camera::Xz, false, true).expect("pictures");
    run_with(&cable("static", ""), &mut pictures);
    assert_eq!(pictures.frames(), 2);
    for name in ["frame_00000.png", "frame_00001.png"] {
        assert_eq!(decode(&dir.join(name)).0, WIDTH);
    }
    cleanup(&dir);
}

/// Two named rods (radius 1 cm) 0.3 m above a floor at y = 0, a sphere below the gap
/// between them.
const SCENERY: &str = r#"
[[rods]]
name = "alpha"
rest_length = 0.4
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 8
radius = 0.01
start = [-0.5, 0.3, 0.0]
end = [-0.1, 0.3, 0.0]

[[rods]]
name = "beta"
rest_length = 0.4
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 8
radius = 0.01
start = [0.1, 0.3, 0.0]
end = [0.5, 0.3, 0.0]

[contact]
stiffness = 1e4
floor = 0.0

[[obstacles]]
kind = "sphere"
centre = [0.0, 0.1, 0.0]
radius = 0.05

[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.02
"#;

/// The RGB colour at a point of the picture.
fn colour(rgb: &[u8], (x, y): (f64, f64)) -> [u8; 3] {
    let i = 3 * (y.round() as usize * WIDTH as usize + x.round() as usize);
    [rgb[i], rgb[i + 1], rgb[i + 2]]
}

/// Shaded: a light grey, neither white nor ink.
fn shaded(c: [u8; 3]) -> bool {
    c[0] == c[1] && c[1] == c[2] && (200..=240).contains(&c[0])
}

#[test]
fn pictures_show_the_floor_obstacles_rod_names_and_thickness() {
    let dir = scratch("scenery");
    let scene = Scene::from_toml(SCENERY).expect("the test scene is valid");
    let mut pictures = Pictures::new(&dir, 100, Camera::Xy, true, false).expect("pictures");
    run_with(&scene, &mut pictures);
    let view = *pictures.view().expect("view");
    let (_, _, first) = decode(&dir.join("frame_00000.png"));
    let at = |x: f64, y: f64| view.pixel(&Vector3::new(x, y, 0.0));
    let mm = 1e-3 / view.metres_per_pixel(); // pixels per millimetre
    assert!(mm > 0.5, "the framing shows millimetres: {mm} px/mm");

    // The floor: shaded below y = 0, white just above it away from the rods.
    let (fx, fy) = at(0.3, 0.0);
    assert!(
        shaded(colour(&first, (fx, fy + 8.0))),
        "{:?}",
        colour(&first, (fx, fy + 8.0))
    );
    assert!(!inked(&first, at(0.3, 0.05), 2), "blank above the floor");
    // The sphere: shaded inside, outlined at its radius, blank just outside.
    assert!(
        shaded(colour(&first, at(0.0, 0.1))),
        "{:?}",
        colour(&first, at(0.0, 0.1))
    );
    assert!(inked(&first, at(0.05, 0.1), 1), "the sphere's outline");
    assert!(!inked(&first, at(0.0, 0.17), 2), "blank above the sphere");
    // A rod 20 mm thick is drawn 20 mm thick (the plain line is 5 px).
    let (x, y) = at(-0.3, 0.3);
    let half = 10.0 * mm;
    assert!(
        half > 5.0,
        "the rod's diameter is wider than the plain line"
    );
    assert!(inked(&first, (x, y - half + 1.5), 0) && inked(&first, (x, y + half - 1.5), 0));
    assert!(
        !inked(&first, (x, y - half - 2.0), 0),
        "no wider than the rod"
    );
    // Both rods are named, and the caption counts rods, not pieces.
    let svg = std::fs::read_to_string(dir.join("frame_00000.svg")).expect("svg");
    // Each name is a text element of its own, inside the picture ("alpha" is 5
    // characters of at most 11 px).
    for name in ["alpha", "beta"] {
        let at = svg
            .find(&format!("\n{name}\n"))
            .expect("the rod's name in the SVG");
        let tag = &svg[svg[..at].rfind("<text").expect("its text element")..at];
        let x = tag.split("x=\"").nth(1).and_then(|t| t.split('"').next());
        let x: f64 = x.and_then(|x| x.parse().ok()).expect("its x");
        assert!(
            x >= 0.0 && x + 55.0 <= f64::from(WIDTH),
            "{name} at x = {x}"
        );
    }
    assert!(
        svg.contains("2 rods") && !svg.contains("pieces"),
        "the caption's count"
    );
    cleanup(&dir);
}

/// The error's message, which must name `what`.
fn assert_names(result: Result<impl std::fmt::Debug, Error>, what: &str) {
    let message = result.expect_err("an error").to_string();
    assert!(message.contains(what), "{message:?} does not name {what:?}");
}

#[test]
fn bad_options_are_errors_naming_the_field_or_path() {
    let dir = scratch("bad");
    assert_names(
        Pictures::new(&dir, 0, Camera::Xy, false, false).map(|_| ()),
        "--every",
    );
    assert_names(Camera::from_name("bogus"), "--camera");
    assert_names(Camera::from_name("bogus"), "bogus");
    for name in ["xy", "xz", "yz", "oblique"] {
        assert_eq!(Camera::from_name(name).expect("a camera").name(), name);
    }
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let file = dir.join("regular-file");
    std::fs::write(&file, b"not a directory").expect("a file");
    let under = file.join("frames");
    let shown = under.display().to_string();
    assert_names(
        Pictures::new(&under, 1, Camera::Xy, false, false).map(|_| ()),
        &shown,
    );

    // A GIF that cannot be written fails the run, naming the file, without a panic.
    let gif = file.join("run.gif");
    let mut pictures = Pictures::new(&dir.join("frames"), 5, Camera::Xy, false, false)
        .expect("pictures")
        .with_gif(gif);
    let result = run_observed(&dynamic_cable(), &mut [&mut pictures]);
    assert_names(result, &file.join("run.gif.partial").display().to_string());
    cleanup(&dir);
}

#[test]
fn line_plot_writes_decodable_png_and_svg_with_the_title() {
    let dir = scratch("plot");
    std::fs::create_dir_all(&dir).expect("scratch dir");
    let stem = dir.join("speed_vs_error");
    let series = [
        Series {
            label: "uniform".into(),
            points: vec![
                (1e-3, 1e-2),
                (1e-2, 3e-3),
                (1e-1, 4e-4),
                (0.0, 1.0),
                (1.0, -1.0),
            ],
        },
        Series {
            label: "adaptive".into(),
            points: vec![(2e-3, 5e-3), (2e-2, 1e-3), (f64::NAN, 1.0)],
        },
    ];
    let title = "Speed vs error";
    for (log_x, log_y) in [(false, false), (true, false), (true, true)] {
        line_plot(
            &stem,
            title,
            "wall time [s]",
            "error [m]",
            &series,
            log_x,
            log_y,
        )
        .expect("plot");
        let (w, h, rgb) = decode(&dir.join("speed_vs_error.png"));
        assert_eq!((w, h), (WIDTH, HEIGHT));
        assert!(
            rgb.chunks(3).any(|c| c != [255, 255, 255]),
            "something drawn"
        );
        let svg = std::fs::read_to_string(dir.join("speed_vs_error.svg")).expect("svg");
        assert!(svg.contains(title) && svg.contains("adaptive"));
    }
    let empty = dir.join("empty");
    line_plot(&empty, "empty", "x", "y", &[], true, true).expect("an empty plot");
    assert_eq!(decode(&dir.join("empty.png")).0, WIDTH);
    let bad = dir.join("missing-dir").join("plot");
    assert_names(
        line_plot(&bad, title, "x", "y", &series, false, false),
        "missing-dir",
    );
    cleanup(&dir);
}
