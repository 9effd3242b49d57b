//! The cost of a run's forward sensitivities against the run they follow (issue #48: a
//! run with three parameters at most 2 × the run without): `cargo run --release
//! --example dynamic_sensitivity_cost`. For a swinging cable (pinned at one end, bending,
//! damping, a point load; 1 s at dt = 10 ms) at two resolutions, with implicit Euler and
//! BDF2: the median wall time of the plain run (`splinerod::run`), of the sensitivities'
//! run without parameters (the same steps, no tangent solves) and with three (EA, EI,
//! the density), over 15 repetitions each (after one
//! unmeasured).

use splinerod::sensitivity::dynamic_sensitivities;
use splinerod::{Real, Scene};
use std::time::Instant;

/// Median wall time of `f` over `n` runs after one unmeasured, s.
fn median(n: usize, mut f: impl FnMut()) -> Real {
    f();
    let mut t: Vec<Real> = (0..n)
        .map(|_| {
            let start = Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .collect();
    t.sort_by(Real::total_cmp);
    t[n / 2]
}

/// The swinging cable with `n` control points, stepped by `method`.
fn swinging(n: usize, method: &str) -> Result<Scene, splinerod::Error> {
    Scene::from_toml(&format!(
        "[rod]\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 200.0\n\
         bending_stiffness = 1e-3\ndamping = 0.3\ncontrol_points = {n}\n\
         start = [0.0, 0.0, 0.0]\nend = [1.0, 0.0, 0.0]\n\n[[pins]]\nat = 0.0\n\n\
         [world]\ngravity = [0.5, -9.81, 0.0]\n\n\
         [[loads]]\nat = 0.7\nforce = [0.0, 0.05, 0.02]\n\n\
         [solver]\nmethod = \"{method}\"\ndt = 0.01\nduration = 1.0\n\n\
         [output]\nsamples = 21\n"
    ))
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let params = [
        "rod.stretch_stiffness",
        "rod.bending_stiffness",
        "rod.linear_density",
    ];
    println!(
        "| scheme | control points | run, ms | sensitivities' run, 0 parameters, ms | \
         with 3, ms | ratio to the run | ratio to 0 parameters |"
    );
    println!("|---|---|---|---|---|---|---|");
    for method in ["implicit-euler", "bdf2"] {
        for n in [12, 48] {
            let scene = swinging(n, method)?;
            let run = median(15, || {
                splinerod::run(&scene).expect("run");
            });
            let bare = median(15, || {
                dynamic_sensitivities(&scene, &[]).expect("run");
            });
            let with = median(15, || {
                dynamic_sensitivities(&scene, &params).expect("sensitivities");
            });
            println!(
                "| {method} | {n} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} |",
                run * 1e3,
                bare * 1e3,
                with * 1e3,
                with / run,
                with / bare
            );
        }
    }
    Ok(())
}
