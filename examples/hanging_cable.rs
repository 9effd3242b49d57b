//! A cable released straight between two pins, stepped with implicit Euler until it
//! rests, then compared with the static solver's equilibrium.
//!
//! `cargo run --release --example hanging_cable`

use splinerod::prelude::*;

fn cable(damping: Real) -> Result<RodSystem, Error> {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, 16, 1.0)?;
    let end = Vector3::new(0.8, 0.0, 0.0);
    let mut rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end)?;
    rod.damping = damping;
    let pins = [Pin::here(&rod, 0.0)?, Pin::here(&rod, 1.0)?];
    Ok(RodSystem::new(rod)
        .with_energy(Stretching::new(100.0)?)
        .with_energy(Gravity::new(Vector3::new(0.0, -9.81, 0.0))?)
        .with_pin(pins[0])
        .with_pin(pins[1]))
}

fn main() -> Result<(), Error> {
    let euler = ImplicitEuler::new(NewtonParams::default())?;
    let mut sim = Simulation::new(cable(3.0)?, Box::new(euler));
    let dt = 0.01;
    println!("    t (s)   midpoint y (m)   kinetic (J)");
    for step in 1..=800 {
        sim.step(dt)?;
        if step % 100 == 0 {
            let mid = sim.system.rod.point(0.5)?;
            let kinetic = sim.system.rod.kinetic_energy();
            println!("{:9.2} {:16.9} {:13.3e}", sim.time, mid.y, kinetic);
        }
    }
    let mut statics = cable(0.0)?;
    StaticSolver::new(StaticParams::default())?.solve(&mut statics)?;
    let gap = (0..=40)
        .map(|k| {
            let s = k as Real / 40.0;
            Ok((sim.system.rod.point(s)? - statics.rod.point(s)?).norm())
        })
        .collect::<Result<Vec<_>, Error>>()?
        .into_iter()
        .fold(0.0, Real::max);
    println!("largest distance to the static equilibrium: {gap:.2e} m");
    Ok(())
}
