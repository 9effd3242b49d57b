//! Static equilibrium with tolerance-driven adaptivity: the elastic catenary (L = 1 m,
//! ends 0.8 m apart, μ = 0.1 kg/m) solved from 6 control points at several tolerances
//! and stiffnesses; prints the control points, the estimate and the true error.
//!
//! `cargo run --release --example static_adaptive`

use splinerod::elastic_catenary::ElasticCatenary;
use splinerod::locking::{distance, static_error, WEIGHT};
use splinerod::StretchFormulation;
use splinerod::{Error, Scene};

fn main() -> Result<(), Error> {
    println!("EA (N) | tolerance (m) | control points | estimate (m) | error (m) | knot changes");
    for ea in [1e2, 1e4] {
        for tolerance in [1e-4, 1e-5, 1e-6] {
            let text = format!(
                "[rod]\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = {ea}\n\
                 control_points = 6\nend = [0.8, 0.0, 0.0]\n[[pins]]\nat = 0.0\n[[pins]]\nat = 1.0\n\
                 [solver]\nmethod = \"static\"\n[adaptivity]\ntolerance = {tolerance}\n"
            );
            let scene = Scene::from_toml(&text)?;
            let mut sim = scene.build()?;
            let report = sim.settle()?;
            let estimate = sim.error_estimate().map_or(f64::NAN, |e| e.max());
            let exact = ElasticCatenary::new(1.0, 0.8, WEIGHT, ea)?;
            let error = distance(&sim.system, &exact)?;
            println!(
                "{ea:.0e} | {tolerance:.0e} | {} | {estimate:.2e} | {error:.2e} | {}",
                sim.system.rod.len(),
                report.adapt.inserted + report.adapt.removed
            );
        }
    }
    println!("uniform, for comparison: EA (N) | control points | error (m)");
    for ea in [1e2, 1e4] {
        for n in [16, 32, 64] {
            let error = static_error(n, ea, StretchFormulation::Mixed)?;
            println!("{ea:.0e} | {n} | {error:.2e}");
        }
    }
    Ok(())
}
