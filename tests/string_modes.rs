//! The taut string of `tests/data/string_L1_D1.2_mu0.1_EA100.json`: modal frequencies of
//! the linearised system about the stretched state, and the first transverse mode
//! simulated in time with implicit Euler (frequency and numerical amplitude loss).

mod common;

use common::{numbers, reference};
use splinerod::integrators::modal::{self, Mode};
use splinerod::prelude::*;
use std::f64::consts::PI;

const SPAN: Real = 1.2;

fn string(n: usize) -> RodSystem {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, 1.0).expect("basis");
    let end = Vector3::new(SPAN, 0.0, 0.0);
    let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
    let pins = [Pin::here(&rod, 0.0), Pin::here(&rod, 1.0)];
    RodSystem::new(rod)
        .with_energy(Stretching::new(100.0).expect("stiffness"))
        .with_pin(pins[0].clone().expect("pin"))
        .with_pin(pins[1].clone().expect("pin"))
}

/// Share of a mode's (mass-normalised) motion that is along the string axis.
fn axial_share(mode: &Mode) -> Real {
    let axial: Real = mode.shape.iter().map(|v| v.x * v.x).sum();
    let all: Real = mode.shape.iter().map(|v| v.norm_squared()).sum();
    axial / all
}

fn first_modes(n: usize) -> (Mode, Mode) {
    let modes = modal::modes(&string(n), 12).expect("modal analysis");
    let transverse = modes.iter().find(|m| axial_share(m) < 1e-9);
    let longitudinal = modes.iter().find(|m| axial_share(m) > 1.0 - 1e-9);
    (
        transverse.expect("a transverse mode").clone(),
        longitudinal.expect("a longitudinal mode").clone(),
    )
}

#[test]
fn modal_frequencies_match_the_analytic_string() {
    let r = reference("string_L1_D1.2_mu0.1_EA100.json");
    let (ft, fl) = (
        numbers(&r["transverse_hz"])[0],
        numbers(&r["longitudinal_hz"])[0],
    );
    let (t, l) = first_modes(16);
    let (et, el) = ((t.frequency - ft).abs() / ft, (l.frequency - fl).abs() / fl);
    println!(
        "16 cps: transverse {:.7} Hz (rel err {et:.2e}), longitudinal {:.7} Hz (rel err {el:.2e})",
        t.frequency, l.frequency
    );
    assert!(et <= 1e-5 && el <= 1e-5);
}

/// Upward zero crossings of a sampled signal, linearly interpolated.
fn upward_crossings(t: &[Real], y: &[Real]) -> Vec<Real> {
    (1..y.len())
        .filter(|&k| y[k - 1] < 0.0 && y[k] >= 0.0)
        .map(|k| t[k - 1] + (t[k] - t[k - 1]) * y[k - 1] / (y[k - 1] - y[k]))
        .collect()
}

/// Starts the string displaced in its first transverse mode (10⁻⁴ m at most) and records
/// the midpoint's displacement for `periods` analytic periods of step `dt`.
fn pluck(dt: Real, periods: Real) -> (Vec<Real>, Vec<Real>, Real) {
    let mut system = string(16);
    let (mode, _) = first_modes(16);
    let biggest = mode.shape.iter().map(|v| v.norm()).fold(0.0, Real::max);
    for (q, v) in system.rod.positions.iter_mut().zip(&mode.shape) {
        *q += v * (1e-4 / biggest);
    }
    let axis = mode.shape[mode.shape.len() / 2].normalize();
    let mut sim = Simulation::new(
        system,
        Box::new(ImplicitEuler::new(NewtonParams::default()).expect("params")),
    );
    let steps = (periods / mode.frequency / dt).ceil() as usize;
    let (mut t, mut y) = (vec![0.0], vec![midpoint(&sim, &axis)]);
    for _ in 0..steps {
        sim.step(dt).expect("step");
        t.push(sim.time);
        y.push(midpoint(&sim, &axis));
    }
    (t, y, mode.omega)
}

fn midpoint(sim: &Simulation, axis: &Vector3<Real>) -> Real {
    sim.system.rod.point(0.5).expect("midpoint").dot(axis)
}

#[test]
fn time_stepping_reproduces_the_first_transverse_frequency() {
    let f_exact = numbers(&reference("string_L1_D1.2_mu0.1_EA100.json")["transverse_hz"])[0];
    let (t, y, _) = pluck(1e-4, 3.0);
    let crossings = upward_crossings(&t, &y);
    assert!(crossings.len() >= 2, "no oscillation");
    let period = (crossings[crossings.len() - 1] - crossings[0]) / (crossings.len() - 1) as Real;
    let error = (1.0 / period - f_exact).abs() / f_exact;
    println!("dt = 0.1 ms: {:.5} Hz, rel err {error:.2e}", 1.0 / period);
    assert!(error <= 5e-3);
}

#[test]
fn amplitude_loss_per_period_follows_implicit_euler_theory() {
    // Implicit Euler multiplies a mode's amplitude by 1/√(1+(ωh)²) per step and turns by
    // atan(ωh) per step, so one period takes 2π/atan(ωh) steps.
    let dt = 1e-3;
    let (t, y, omega) = pluck(dt, 4.0);
    let peaks: Vec<Real> = (1..y.len() - 1)
        .filter(|&k| y[k] > y[k - 1] && y[k] >= y[k + 1] && y[k] > 0.0)
        .map(|k| y[k])
        .collect();
    assert!(peaks.len() >= 3, "too few peaks: {}", peaks.len());
    let per_period = (peaks[peaks.len() - 1] / peaks[0]).powf(1.0 / (peaks.len() - 1) as Real);
    let wh: Real = omega * dt;
    let theory = (1.0 + wh * wh).powf(-PI / wh.atan());
    println!(
        "dt = 1 ms: amplitude loss per period {:.2} % (theory {:.2} %), {} samples over {:.3} s",
        100.0 * (1.0 - per_period),
        100.0 * (1.0 - theory),
        t.len(),
        t[t.len() - 1]
    );
    assert!(((1.0 - per_period) - (1.0 - theory)).abs() <= 0.05 * (1.0 - theory));
}
