//! The report's calibration study (issue #48): a static cable clamped at one end and
//! hanging under its weight ([`clamped_cable`]: 1 m, EA = 50 N, EI = 1e-3 N·m²,
//! μ = 0.1 kg/m) observed by 40 markers with Gaussian noise of σ (and, to fix the
//! density, its clamp's force with noise of σ_F = σ N/m), fitted from a start far off
//! (EA 80 N, EI 2e-3 N·m², μ 0.15 kg/m) at three noise levels:
//!
//! * EA and EI, the density known (weighed);
//! * EA, EI and μ from the markers and the clamp's force.
//!
//! Per case: the recovered parameters with their reported standard deviations against
//! the truth, the residuals' root mean square (in units of σ), and the cost in
//! simulations: the least-squares fit's ([`crate::fit::fit`], exact Jacobians from
//! the sensitivities) until its residual first comes within [`SAME_RESIDUAL`] of its
//! optimum, and Nelder–Mead's ([`crate::fit::gradient_free`]) on the same objective
//! from the same start until it reaches that residual.

use crate::fit::synthetic::{noisy_markers, noisy_pin_force};
use crate::fit::SceneFit;
use crate::{Error, Real, Scene};
use std::fmt::Write;

/// Relative distance to the optimum's residual root mean square at which both methods
/// count as having reached it.
pub const SAME_RESIDUAL: Real = 1e-6;
/// Simulations Nelder–Mead may spend.
pub const SIMPLEX_BUDGET: usize = 5_000;
/// The true parameters: EA (N), EI (N·m²), μ (kg/m).
pub const TRUTH: [Real; 3] = [50.0, 1e-3, 0.1];
/// Where every fit starts.
pub const START: [Real; 3] = [80.0, 2e-3, 0.15];
/// The fitted parameters, by scene path.
pub const PARAMS: [&str; 3] = [
    "rod.stretch_stiffness",
    "rod.bending_stiffness",
    "rod.linear_density",
];
/// Markers on the cable.
pub const MARKERS: usize = 40;

/// The cable of the study with EA `ea`, EI `ei` and linear density `mu`: 16 control
/// points, clamped at `s = 0`, gravity 9.81 m/s², solved statically to 1e-12.
pub fn clamped_cable(ea: Real, ei: Real, mu: Real) -> Result<Scene, Error> {
    Scene::from_toml(&format!(
        "[rod]\nrest_length = 1.0\nlinear_density = {mu}\nstretch_stiffness = {ea}\n\
         bending_stiffness = {ei}\ncontrol_points = 16\nstart = [0.0, 0.0, 0.0]\n\
         end = [1.0, 0.0, 0.0]\n\n[[pins]]\nat = 0.0\nclamp = true\n\n\
         [world]\ngravity = [0.0, -9.81, 0.0]\n\n[solver]\nmethod = \"static\"\n\
         tolerance = 1e-12\n"
    ))
}

/// One fit of the study.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationRow {
    /// Marker noise σ, m.
    pub sigma: Real,
    /// Parameters fitted (the first two or all of [`PARAMS`]).
    pub fitted: usize,
    /// Recovered values and reported standard deviations.
    pub recovered: Vec<(Real, Real)>,
    /// Residuals' root mean square at the fit, units of σ.
    pub residual_rms: Real,
    /// The fit's simulations until within [`SAME_RESIDUAL`] of its optimum, and in all.
    pub simulations: (usize, usize),
    /// Nelder–Mead's simulations to the same residual (or its budget), and whether it
    /// reached it.
    pub simplex: (usize, bool),
}

/// The study at noise levels 10 µm, 0.1 mm and 1 mm (`quick`: 0.1 mm only).
pub fn measure(quick: bool) -> Result<Vec<CalibrationRow>, Error> {
    let sigmas: &[Real] = if quick { &[1e-4] } else { &[1e-5, 1e-4, 1e-3] };
    let mut rows = Vec::new();
    for (k, &sigma) in sigmas.iter().enumerate() {
        for fitted in [2, 3] {
            rows.push(calibrate(sigma, fitted, 17 + k as u64)?);
        }
    }
    Ok(rows)
}

/// The fit of the first `fitted` parameters at marker noise `sigma` (data seeded with
/// `seed`).
fn calibrate(sigma: Real, fitted: usize, seed: u64) -> Result<CalibrationRow, Error> {
    let truth = clamped_cable(TRUTH[0], TRUTH[1], TRUTH[2])?;
    let mut files = vec![noisy_markers(&truth, MARKERS, sigma, seed)?];
    let density = if fitted == 3 {
        files.push(noisy_pin_force(&truth, 0, sigma, seed + 1000)?);
        START[2]
    } else {
        TRUTH[2]
    };
    let start = clamped_cable(START[0], START[1], density)?;
    let mut fit = SceneFit::new(&start, &PARAMS[..fitted], &files)?;
    let report = fit.fit()?;
    let target = report.residual_rms * (1.0 + SAME_RESIDUAL);
    let reached = report.simulations_to(target).unwrap_or(report.simulations);
    let simplex = fit.nelder_mead(target, SIMPLEX_BUDGET)?;
    Ok(CalibrationRow {
        sigma,
        fitted,
        recovered: report.parameters.iter().copied().zip(report.std).collect(),
        residual_rms: report.residual_rms,
        simulations: (reached, report.simulations),
        simplex: (simplex.simulations, simplex.reached),
    })
}

/// The study's section of the report.
pub fn markdown(out: &mut String, rows: &[CalibrationRow]) {
    let _ = write!(
        out,
        "## Calibration\n\n\
         Identification of a real cable's parameters from observed shapes \
         (`splinerod fit`, `splinerod::report::calibration`): a 1 m cable clamped at one \
         end hangs under its weight (EA = {} N, EI = {} N·m², μ = {} kg/m); {MARKERS} \
         markers observe its equilibrium with Gaussian noise σ per coordinate (and its \
         clamp's force with noise σ_F = σ N/m when μ is fitted too). Every fit starts at \
         EA {} N, EI {} N·m², μ {} kg/m. Values are recovered ± the reported standard \
         deviation, with the error in those deviations. Simulations: the least-squares \
         fit's until its residual is first within {SAME_RESIDUAL:e} of its optimum (all \
         it made, with the final checks), and Nelder–Mead's on the same objective from \
         the same start to that residual.\n\n\
         | σ (m) | fitted | EA (N) | EI (N·m²) | μ (kg/m) | rms / σ | simulations: fit | \
         Nelder–Mead | ratio |\n|---|---|---|---|---|---|---|---|---|\n",
        TRUTH[0], TRUTH[1], TRUTH[2], START[0], START[1], START[2],
    );
    for r in rows {
        let value = |k: usize| match r.recovered.get(k) {
            Some(&(v, s)) => format!("{v:.5e} ± {s:.1e} ({:+.1}σ)", (v - TRUTH[k]) / s),
            None => "known".into(),
        };
        let simplex = match r.simplex {
            (n, true) => n.to_string(),
            (n, false) => format!("> {n} (not reached)"),
        };
        let _ = writeln!(
            out,
            "| {:.0e} | {} | {} | {} | {} | {:.3} | {} ({}) | {simplex} | {:.1} |",
            r.sigma,
            r.fitted,
            value(0),
            value(1),
            value(2),
            r.residual_rms,
            r.simulations.0,
            r.simulations.1,
            r.simplex.0 as Real / r.simulations.0 as Real,
        );
    }
    out.push('\n');
}
