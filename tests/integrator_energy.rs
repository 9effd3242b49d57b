//! Energy behaviour of the three integrators on the taut string of
//! `tests/data/string_L1_D1.2_mu0.1_EA100.json` (L = 1 m, μ = 0.1 kg/m, EA = 100 N, pins
//! 1.2 m apart, 16 cubic control points) started in its first transverse mode
//! (7.416198 Hz), over 100 periods at dt = 1 ms.
//!
//! The oscillation energy is measured with the linearisation about the stretched rest
//! state, \\(E = \tfrac12 v^T M v + \tfrac12 u^T K u\\) (`u` the displacement, `K` the exact
//! Hessian at rest): the amplitude is 10⁻⁴ m, so the nonlinear terms are ~10⁻⁸ relative,
//! and the quadratic form avoids subtracting the 2.4 J of static strain energy.
//! Theory for a linear mode of angular frequency ω and step h:
//! * implicit midpoint: amplification of modulus 1, the energy is conserved;
//! * implicit Euler: amplitude × \\(1/\sqrt{1 + (\omega h)^2}\\) per step, energy
//!   × \\(1/(1 + (\omega h)^2)\\);
//! * BDF2: energy × \\(|\rho|^2\\) per step, ρ the principal root of
//!   \\((1 - \tfrac23 i\omega h)\rho^2 - \tfrac43\rho + \tfrac13 = 0\\).

use nalgebra::Complex;
use splinerod::core::{BlockBanded, HessianKind};
use splinerod::integrators::{Bdf2, ImplicitMidpoint};
use splinerod::prelude::*;
use splinerod::problems::{string_modes, string_reference, taut_string};

const DT: Real = 1e-3;
const PERIODS: Real = 100.0;

/// Runs `integrator` for 100 periods from the first transverse mode; returns the ratio of
/// final to initial oscillation energy, the mode's ω and the number of steps.
fn run(integrator: Box<dyn Integrator>) -> (Real, Real, usize) {
    let mut system = taut_string(16).expect("string");
    let rest = system.rod.positions.clone();
    let n = rest.len();
    let mut k = BlockBanded::zeros(n, 3);
    system.add_potential_hessian(HessianKind::Exact, &mut k);
    let (mode, _) = string_modes(16).expect("modes");
    let f = string_reference().expect("reference").transverse_hz[0];
    assert!(
        (mode.frequency - f).abs() < 1e-5 * f,
        "{} Hz",
        mode.frequency
    );
    let biggest = mode.shape.iter().map(|v| v.norm()).fold(0.0, Real::max);
    for (q, v) in system.rod.positions.iter_mut().zip(&mode.shape) {
        *q += v * (1e-4 / biggest);
    }
    let mut ku = vec![Vector3::zeros(); n];
    let mut energy = |rod: &Rod| {
        let u: Vec<Vector3<Real>> = rod
            .positions
            .iter()
            .zip(&rest)
            .map(|(q, r)| q - r)
            .collect();
        k.mul_vec(&u, &mut ku);
        let potential: Real = u.iter().zip(&ku).map(|(a, b)| a.dot(b)).sum();
        rod.kinetic_energy() + 0.5 * potential
    };
    let e0 = energy(&system.rod);
    let steps = (PERIODS / mode.frequency / DT).round() as usize;
    let mut sim = Simulation::new(system, integrator);
    for _ in 0..steps {
        sim.step(DT).expect("step");
    }
    (energy(&sim.system.rod) / e0, mode.omega, steps)
}

fn newton() -> NewtonParams {
    NewtonParams::default()
}

#[test]
fn implicit_midpoint_conserves_the_energy() {
    let (ratio, _, steps) = run(Box::new(ImplicitMidpoint::new(newton()).expect("params")));
    println!(
        "implicit-midpoint: {steps} steps, energy change {:.2e}",
        ratio - 1.0
    );
    assert!((ratio - 1.0).abs() < 1e-2);
}

#[test]
fn implicit_euler_loses_what_theory_predicts() {
    let (ratio, omega, steps) = run(Box::new(ImplicitEuler::new(newton()).expect("params")));
    let wh = omega * DT;
    // ln(E_N / E_0) = −N ln(1 + (ωh)²).
    let theory = -(steps as Real) * (1.0 + wh * wh).ln();
    let error = (ratio.ln() - theory).abs() / theory.abs();
    println!(
        "implicit-euler: {steps} steps, E_N/E_0 = {ratio:.4e} (theory {:.4e}), ln-ratio rel err {error:.2e}",
        theory.exp()
    );
    assert!(error < 1e-2);
}

#[test]
fn bdf2_loses_what_theory_predicts() {
    let (ratio, omega, steps) = run(Box::new(Bdf2::new(newton()).expect("params")));
    let z = Complex::new(0.0, omega * DT);
    let a = Complex::new(1.0, 0.0) - z * (2.0 / 3.0);
    let (b, c) = (Complex::new(-4.0 / 3.0, 0.0), Complex::new(1.0 / 3.0, 0.0));
    let disc = (b * b - a * c * 4.0).sqrt();
    let roots = [(-b + disc) / (a * 2.0), (-b - disc) / (a * 2.0)];
    let principal = roots[0].norm().max(roots[1].norm());
    let theory = 2.0 * steps as Real * principal.ln();
    let error = (ratio.ln() - theory).abs() / theory.abs();
    println!(
        "bdf2: {steps} steps, E_N/E_0 = {ratio:.6} (theory {:.6}), ln-ratio rel err {error:.2e}",
        theory.exp()
    );
    assert!(error < 2e-2);
}
