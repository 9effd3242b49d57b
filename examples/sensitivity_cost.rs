//! The cost of static sensitivities against the static solve they follow (issue #48:
//! five parameters at most 1.5 × the solve): `cargo run --release --example
//! sensitivity_cost`. For the bundled cantilever and catenary (with a point load), the
//! median wall time of the static run alone and of the run with the sensitivities to
//! five parameters (the solve included), over 50 repetitions each.

use splinerod::sensitivity::static_sensitivities;
use splinerod::{Real, Scene};
use std::time::Instant;

/// Median wall time of `f` over `n` runs, s.
fn median(n: usize, mut f: impl FnMut()) -> Real {
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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = env!("CARGO_MANIFEST_DIR");
    let catenary = std::fs::read_to_string(format!("{dir}/scenes/catenary_static.toml"))?
        + "\n[[loads]]\nat = 0.3\nforce = [0.2, -0.5, 0.1]\n";
    let cases = [
        (
            "cantilever",
            Scene::load(format!("{dir}/scenes/cantilever.toml"))?,
            vec![
                "rod.bending_stiffness",
                "rod.stretch_stiffness",
                "rod.linear_density",
                "world.gravity[0]",
                "world.gravity[1]",
            ],
        ),
        (
            "catenary + load",
            Scene::from_toml(&catenary)?,
            vec![
                "rod.stretch_stiffness",
                "rod.linear_density",
                "world.gravity[1]",
                "loads[0].force[1]",
                "loads[0].force[2]",
            ],
        ),
    ];
    println!("| scene | control points | static solve, ms | with 5 sensitivities, ms | ratio |");
    println!("|---|---|---|---|---|");
    for (name, scene, params) in cases {
        let solve = median(50, || {
            splinerod::run(&scene).expect("solve");
        });
        let with = median(50, || {
            static_sensitivities(&scene, &params).expect("sensitivities");
        });
        let n = scene.rod.control_points;
        println!(
            "| {name} | {n} | {:.3} | {:.3} | {:.2} |",
            solve * 1e3,
            with * 1e3,
            with / solve
        );
    }
    Ok(())
}
