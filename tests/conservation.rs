//! Conservation on a free rod (no pins, gravity or damping): implicit Euler conserves
//! linear momentum exactly (the stretching forces sum to zero and the mass matrix's rows
//! sum to the lumped masses) and dissipates, never creates, energy.

use splinerod::prelude::*;

/// A wavy, slightly stretched rod, drifting and flexing.
fn free_rod() -> RodSystem {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, 16, 1.0).expect("basis");
    let end = Vector3::new(1.05, 0.0, 0.0);
    let mut rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
    for (q, v) in rod.positions.iter_mut().zip(rod.velocities.iter_mut()) {
        let u = q.x;
        q.y += 0.05 * (7.0 * u).sin();
        q.z += 0.03 * (3.0 * u).cos();
        *v = Vector3::new(0.3, -0.2 + 0.5 * u, 0.1 * (5.0 * u).sin());
    }
    RodSystem::new(rod).with_energy(Stretching::new(100.0).expect("stiffness"))
}

fn total_energy(system: &RodSystem) -> Real {
    system.rod.kinetic_energy() + system.potential_energy()
}

#[test]
fn free_rod_conserves_momentum_and_never_gains_energy() {
    let mut sim = Simulation::new(
        free_rod(),
        Box::new(ImplicitEuler::new(NewtonParams::default()).expect("params")),
    );
    let p0 = sim.system.rod.linear_momentum();
    let e0 = total_energy(&sim.system);
    let (mut energy, mut worst_drift): (Real, Real) = (e0, 0.0);
    for step in 0..1000 {
        let report = sim.step(1e-3).expect("step");
        assert!(report.solver.converged, "step {step} did not converge");
        let drift = (sim.system.rod.linear_momentum() - p0).norm() / p0.norm();
        worst_drift = worst_drift.max(drift);
        let e = total_energy(&sim.system);
        assert!(
            e <= energy * (1.0 + 1e-12),
            "step {step}: energy grew {energy} -> {e}"
        );
        energy = e;
    }
    println!(
        "1000 steps: momentum drift {worst_drift:.2e} (relative), energy {e0:.6} -> {energy:.6} J"
    );
    assert!(worst_drift <= 1e-12, "momentum drift {worst_drift:.2e}");
    assert!(energy < e0, "implicit Euler should dissipate");
}
