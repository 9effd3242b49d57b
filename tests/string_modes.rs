//! The taut string of `tests/data/string_L1_D1.2_mu0.1_EA100.json`: modal frequencies of
//! the linearised system about the stretched state, and the first transverse mode
//! simulated in time with implicit Euler (frequency and numerical amplitude loss).

use splinerod::prelude::*;
use splinerod::problems::{pluck, string_modes, string_reference};
use std::f64::consts::PI;

fn euler() -> Box<dyn Integrator> {
    Box::new(ImplicitEuler::new(NewtonParams::default()).expect("params"))
}

#[test]
fn modal_frequencies_match_the_analytic_string() {
    let r = string_reference().expect("reference");
    let (ft, fl) = (r.transverse_hz[0], r.longitudinal_hz[0]);
    let (t, l) = string_modes(16).expect("modes");
    let (et, el) = ((t.frequency - ft).abs() / ft, (l.frequency - fl).abs() / fl);
    println!(
        "16 cps: transverse {:.7} Hz (rel err {et:.2e}), longitudinal {:.7} Hz (rel err {el:.2e})",
        t.frequency, l.frequency
    );
    assert!(et <= 1e-5 && el <= 1e-5);
}

#[test]
fn time_stepping_reproduces_the_first_transverse_frequency() {
    let f_exact = string_reference().expect("reference").transverse_hz[0];
    let run = pluck(euler(), 1e-4, 3.0).expect("pluck");
    let f = run.frequency().expect("oscillation");
    let error = (f - f_exact).abs() / f_exact;
    println!("dt = 0.1 ms: {f:.5} Hz, rel err {error:.2e}");
    assert!(error <= 5e-3);
}

#[test]
fn amplitude_loss_per_period_follows_implicit_euler_theory() {
    // Implicit Euler multiplies a mode's amplitude by 1/√(1+(ωh)²) per step and turns by
    // atan(ωh) per step, so one period takes 2π/atan(ωh) steps.
    let dt = 1e-3;
    let run = pluck(euler(), dt, 4.0).expect("pluck");
    let loss = run.amplitude_loss_per_period().expect("peaks");
    let wh: Real = run.omega * dt;
    let theory = 1.0 - (1.0 + wh * wh).powf(-PI / wh.atan());
    println!(
        "dt = 1 ms: amplitude loss per period {:.2} % (theory {:.2} %)",
        100.0 * loss,
        100.0 * theory
    );
    assert!((loss - theory).abs() <= 0.05 * theory);
}
