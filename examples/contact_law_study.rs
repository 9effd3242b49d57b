//! The contact-law study of issue #46 (`cargo run --release --example contact_law_study
//! -- [resting|scenes] [cap seconds]`): the barrier (the default without `stiffness`)
//! against the adaptive penalty (`stiffness` and `tolerance`) and the fixed penalty of
//! earlier versions (`stiffness` alone), on ropes resting on a plane, a sphere and
//! another rope (rest gap over the tolerance, Newton iterations, wall time) and on the
//! bundled contact scenes (clearance, end gap, Newton iterations, rejected steps, wall
//! time; runs capped at `cap` simulated seconds, default the scenes' own durations).
//!
//! The adaptive penalty starts from `k₀ = 2 r w / τ`, the penalty that carries the same
//! line load `w` at half the tolerance as the barrier's default `κ` (`k₀ = 1.19 κ`).

use splinerod::{run, Real, RunResult, Scene};
use std::time::Instant;

/// The laws compared: the `[contact]` lines each adds, given the barrier's default
/// stiffness `kappa`, the tolerance `tau` and the scene's own stiffness `k`.
fn laws(kappa: Real, tau: Real, k: Real) -> [(&'static str, String); 3] {
    [
        ("barrier", String::new()),
        (
            "adaptive",
            format!("stiffness = {}\ntolerance = {tau}\n", 1.1931 * kappa),
        ),
        ("penalty", format!("stiffness = {k}\n")),
    ]
}

/// The scene text with `lines` added to its `[contact]` table and its own `stiffness`
/// removed.
fn with_contact(text: &str, lines: &str) -> String {
    let mut out = String::new();
    let mut table = String::new();
    for l in text.lines() {
        if l.starts_with('[') {
            table = l.trim().to_string();
        }
        if table == "[contact]" && l.trim_start().starts_with("stiffness =") {
            continue;
        }
        out.push_str(l);
        out.push('\n');
        if l.trim() == "[contact]" {
            out.push_str(lines);
        }
    }
    out
}

/// Runs `text`, returning the result and the wall time.
fn timed(text: &str, cap: Option<Real>) -> Result<(RunResult, Real), splinerod::Error> {
    let mut scene = Scene::from_toml(text)?;
    if let Some(cap) = cap {
        scene.solver.duration = scene.solver.duration.map(|d| d.min(cap));
    }
    let start = Instant::now();
    let result = run(&scene)?;
    Ok((result, start.elapsed().as_secs_f64()))
}

/// The barrier's default stiffness and tolerance for `text` (without its stiffness).
fn barrier_defaults(text: &str) -> Result<(Real, Real), splinerod::Error> {
    let scene = Scene::from_toml(&with_contact(text, ""))?;
    let sim = scene.build()?;
    let c = sim.system.summary()?.contact.expect("contact");
    Ok((c.stiffness, c.tolerance.expect("tolerance")))
}

fn report(name: &str, law: &str, outcome: Result<(RunResult, Real), splinerod::Error>) {
    match outcome {
        Ok((r, wall)) => {
            let c = r.contact.unwrap_or_default();
            let (gap, tau) = (c.end_gap, c.tolerance);
            let relative = match (gap, tau) {
                (Some(g), Some(t)) => format!("{:+.3}", g / t),
                _ => "-".into(),
            };
            println!(
                "{name:22} {law:9} clearance {:.4} end gap {:>10} m ({relative} tol) k {:.3e} newton {:6} rejected {:3} wall {wall:.2} s",
                c.min_clearance_ratio.unwrap_or(Real::NAN),
                gap.map_or("-".into(), |g| format!("{g:.3e}")),
                c.stiffness_used.unwrap_or(Real::NAN),
                r.solver.newton_iterations,
                r.solver.rejected_steps,
            );
        }
        Err(e) => println!("{name:22} {law:9} failed: {e}"),
    }
}

/// A rope of radius `r` and density `rho` resting on a plane, on a sphere (friction 0.5)
/// and across a pinned rope of radius 1 cm (friction 0.5).
fn resting(r: Real, rho: Real) -> [(String, String); 3] {
    let rod = |l: Real, a: [Real; 3], b: [Real; 3]| {
        format!(
            "rest_length = {l}\nlinear_density = {rho}\nstretch_stiffness = 500.0\nbending_stiffness = 1e-5\n\
             damping = 5.0\ncontrol_points = 16\nradius = {r}\nstart = {a:?}\nend = {b:?}\n"
        )
    };
    let solver =
        |t: Real| format!("[solver]\nmethod = \"implicit-euler\"\ndt = 0.005\nduration = {t}\n");
    let (y, top) = (1.3 * r, 0.1 + 1.3 * r);
    let lower = "rest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 2000.0\nbending_stiffness = 1e-4\n\
                 damping = 5.0\ncontrol_points = 16\nradius = 0.01\nstart = [-0.5, 0.0, 0.0]\nend = [0.5, 0.0, 0.0]\n";
    let cross = 0.01 + 1.3 * r;
    [
        (
            format!("plane r {r} rho {rho}"),
            format!(
                "[rod]\n{}[contact]\nstiffness = 1e4\n[[obstacles]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\n{}",
                rod(0.5, [0.0, y, 0.0], [0.5, y, 0.0]),
                solver(1.5)
            ),
        ),
        (
            format!("sphere r {r} rho {rho}"),
            format!(
                "[rod]\n{}[contact]\nstiffness = 1e4\nfriction = 0.5\n[[obstacles]]\nkind = \"sphere\"\ncentre = [0.0, 0.0, 0.0]\nradius = 0.1\n{}",
                rod(0.5, [-0.25, top, 0.0], [0.25, top, 0.0]),
                solver(2.0)
            ),
        ),
        (
            format!("rope r {r} rho {rho}"),
            format!(
                "[[rods]]\nname = \"lower\"\n{lower}[[rods]]\nname = \"upper\"\n{}\
                 [[pins]]\nrod = \"lower\"\nat = 0.0\n[[pins]]\nrod = \"lower\"\nat = 1.0\n\
                 [contact]\nstiffness = 1e4\nfriction = 0.5\n{}",
                rod(0.4, [0.0, cross, -0.2], [0.0, cross, 0.2]),
                solver(3.0)
            ),
        ),
    ]
}

fn scene_stiffness(text: &str) -> Real {
    let spec = Scene::from_toml(text).ok().and_then(|s| s.contact);
    spec.and_then(|c| c.stiffness).unwrap_or(1e4)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let part = args.get(1).map_or("all", String::as_str);
    let cap = args.get(2).and_then(|a| a.parse::<Real>().ok());
    if part != "scenes" {
        for (r, rho) in [(0.005, 0.1), (0.01, 0.5), (0.002, 0.02)] {
            for (name, text) in resting(r, rho) {
                let (kappa, tau) = barrier_defaults(&text)?;
                for (law, lines) in laws(kappa, tau, scene_stiffness(&text)) {
                    report(&name, law, timed(&with_contact(&text, &lines), cap));
                }
            }
        }
    }
    if part == "resting" {
        return Ok(());
    }
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");
    let mut paths: Vec<_> = std::fs::read_dir(dir)?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    paths.sort();
    for path in paths {
        let text = std::fs::read_to_string(&path)?;
        if !text.contains("\n[contact]") {
            continue;
        }
        let name = path
            .file_stem()
            .unwrap_or_default()
            .to_string_lossy()
            .to_string();
        let (kappa, tau) = barrier_defaults(&text)?;
        for (law, lines) in laws(kappa, tau, scene_stiffness(&text)) {
            report(&name, law, timed(&with_contact(&text, &lines), cap));
        }
    }
    Ok(())
}
