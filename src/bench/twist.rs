//! The cost of twist in a step (`bench` keys `step_us_16_bending` and
//! `step_us_16_twist`): one implicit Euler step (one Newton iteration) of a 16-point rod
//! clamped at both ends and slightly bent, with stretching and bending, and with the
//! twisting energy added (turned by 3 rad, below its Greenhill twist of ≈ 11 rad).

use crate::bench::{median_step_seconds, one_iteration};
use crate::{Error, RodSystem, Simulation};
use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, Material, Pin, Real, Rod};
use splinerod_energies::{Bending, Clamp, Frame, Stretching, Twisting};

/// The clamped rod of `n` control points, with twist if `twist`.
pub(crate) fn clamped_rod(n: usize, twist: bool) -> Result<RodSystem, Error> {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, 1.0)?;
    let end = Vector3::new(1.0, 0.0, 0.0);
    let mut rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end)?;
    for (i, q) in rod.positions.iter_mut().enumerate().skip(2).take(n - 4) {
        let s = i as Real / (n - 1) as Real;
        *q += Vector3::new(0.0, (3.0 * s).sin(), (5.0 * s).cos()) * 1e-3;
    }
    let (ei, gj) = (1e-2, 8e-3);
    let k = Clamp::stiffness_for(ei, 1.0);
    let mut system = RodSystem::new(rod.clone())
        .with_energy(Stretching::new(100.0)?)
        .with_energy(Bending::for_rod(ei, &rod)?)
        .with_energy(Clamp::here(&rod, 0.0, k)?)
        .with_energy(Clamp::here(&rod, 1.0, k)?)
        .with_pin(Pin::here(&rod, 0.0)?)
        .with_pin(Pin::here(&rod, 1.0)?);
    if twist {
        let frame = Frame::along(rod.tangent(0.0)?)?;
        let mut twisting = Twisting::between_ends(gj, &rod, frame)?;
        twisting.turn = 3.0;
        system = system.with_energy(twisting);
    }
    system.rod.damping = 1.0;
    Ok(system)
}

/// The clamped 16-point rod (with or without twist) under one-iteration implicit Euler.
pub fn simulation(twist: bool) -> Result<Simulation, Error> {
    Ok(Simulation::new(clamped_rod(16, twist)?, one_iteration()?))
}

/// Median wall time (s) of one step of the clamped 16-point rod, with or without twist.
pub(crate) fn step_seconds(twist: bool, reps: usize) -> Result<Real, Error> {
    median_step_seconds(simulation(twist)?, reps)
}
