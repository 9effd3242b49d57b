//! Adaptive (tolerance-driven) against uniform on the grab scene: true error against a
//! 255-point reference, estimated error, control points, wall time.
//! `cargo run --release --example tolerance_study -- [tolerances...]`
use splinerod::prelude::*;
use splinerod::RunResult;

const GRAB: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 2.0
control_points = {N}
{KNOTS}
[[pins]]
at = 0.0
[[pins]]
at = 1.0
[world]
gravity = [0.0, -9.81, 0.0]
[[grabs]]
at = 0.3
to = [0.3, -0.2, 0.0]
end_time = 0.2
stiffness = 1000.0
[solver]
method = "implicit-euler"
dt = 0.001
duration = 1.0
[output]
samples = 201
{OUT}
{ADAPT}
"#;

fn grab_run(n: usize, knots: &str, adapt: &str, out: &str) -> RunResult {
    let text = GRAB
        .replace("{N}", &n.to_string())
        .replace("{KNOTS}", knots)
        .replace("{OUT}", out)
        .replace("{ADAPT}", adapt)
        .replace("duration = 1.0", &format!("duration = {}", std::env::var("DURATION").unwrap_or("1.0".into())));
    splinerod::run(&Scene::from_toml(&text).expect("scene")).expect("run")
}

fn deviation(a: &RunResult, b: &RunResult) -> Real {
    let pairs = a.samples.positions.iter().zip(&b.samples.positions);
    pairs
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<Real>().sqrt())
        .fold(0.0, Real::max)
}

fn main() {
    let mut knots = vec![0.0; 4];
    knots.extend((1..250).map(|i| i as Real / 250.0));
    knots.extend([0.3, 0.3, 1.0, 1.0, 1.0, 1.0]);
    knots.sort_by(Real::total_cmp);
    let list: Vec<String> = knots.iter().map(|k| format!("{k:?}")).collect();
    let reference = grab_run(knots.len() - 4, &format!("knots = [{}]", list.join(", ")), "", "");
    if std::env::var("REFCHECK").is_ok() {
        for spans in [125usize, 500] {
            let mut k = vec![0.0; 4];
            k.extend((1..spans).map(|i| i as Real / spans as Real));
            k.extend([0.3, 0.3, 1.0, 1.0, 1.0, 1.0]);
            k.sort_by(Real::total_cmp);
            let l: Vec<String> = k.iter().map(|x| format!("{x:?}")).collect();
            let r = grab_run(k.len() - 4, &format!("knots = [{}]", l.join(", ")), "", "");
            println!("reference with {spans} spans vs 250: {:.2e}", deviation(&r, &reference));
        }
    }
    let args: Vec<String> = std::env::args().skip(1).collect();
    let adapts: Vec<String> = if args.is_empty() {
        vec!["[adaptivity]".into()]
    } else {
        args.iter().map(|t| format!("[adaptivity]\ntolerance = {t}")).collect()
    };
    for a in &adapts {
        let r = grab_run(8, "", a, "");
        let est = r.adaptivity.as_ref().map_or(Real::NAN, |x| x.estimated_error);
        let e = deviation(&r, &reference);
        let most = r.control_points_history.iter().map(|h| h[1] as usize).max().unwrap_or(0);
        println!(
            "{:<30} true {e:.2e} est {est:.2e} eff {:.2} cps {} (max {most}) wall {:.3}s",
            a.replace('\n', " "),
            est / e,
            r.control_points,
            r.wall_seconds
        );
        if std::env::var("HISTORY").is_ok() {
            history(&r);
        }
    }
    for n in [8, 16, 32, 64, 128] {
        let r = grab_run(n, "", "", "error_estimate = true");
        let est = r.adaptivity.as_ref().map_or(Real::NAN, |x| x.estimated_error);
        let e = deviation(&r, &reference);
        println!("uniform {n:<4} true {e:.2e} est {est:.2e} eff {:.2} wall {:.3}s", est / e, r.wall_seconds);
    }
}

#[allow(dead_code)]
fn history(r: &RunResult) {
    if let Some(a) = &r.adaptivity {
        for h in &a.history {
            println!("  t {:.3} cps {} est {:.2e}", h[0], h[1], h[2]);
        }
    }
    println!("  knots {:?}", r.knots);
}
