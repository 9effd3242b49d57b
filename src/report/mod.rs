//! The speed-vs-error report (`splinerod report [--quick] --out DIR`): every problem with
//! a known answer swept over resolution and time step, timed, and written to
//! `DIR/report.md` with PNG and SVG plots. Every number in the report comes from the run
//! that wrote it.
//!
//! * Static catenary: max material-point error and wall time vs control points; the
//!   observed order from a least-squares fit of log error against log knot spacing
//!   h = L/(n − 3).
//! * Dynamic catenary: damped implicit Euler (α = 4/s, 6 s) to rest; error and wall time
//!   vs time step and control points.
//! * String: modal frequency errors vs control points; time-stepped first transverse
//!   mode for each integrator: frequency error and amplitude loss per period vs dt.
//! * Pareto: wall time against error, one curve per solver configuration.
//! * Locking: the static catenary against the exact elastic catenary from EA = 10² to
//!   10⁹ N for both stretching formulations, with the lumped-chain peers' EA-independent
//!   error ([`crate::problems::locking`]).
//! * Adaptivity: tolerance-driven against uniform resolution, error against control
//!   points and wall time, effectivity of the error estimate
//!   ([`crate::report::adaptive`]); on two contact problems, the crossing ropes' lift
//!   ([`crate::report::crossing`]) and the capstan's slip threshold
//!   ([`crate::report::capstan`]).
//! * Calibration: parameters recovered from noisy observations of a clamped cable, and
//!   the fit's simulations against Nelder–Mead's ([`crate::report::calibration`]).
//!
//! The catenary and string sweeps use the default (mixed) stretching; the static
//! catenary is also swept with the pointwise form, whose Galerkin order on this stretchy
//! rod is the one `order` states.

pub mod adaptive;
pub mod adaptive_study;
pub mod calibration;
pub mod capstan;
pub mod crossing;
mod markdown;

use crate::output::plot::{line_plot, Series};
use crate::problems::locking::{self, LockingRow};
use crate::problems::{
    catenary_error, catenary_scene, catenary_scene_with, pluck, string_modes, string_reference,
};
use crate::scene::Scene;
use crate::{run, Error};
use splinerod_core::Real;
use splinerod_energies::StretchFormulation;
use splinerod_integrators::{Integrator, NewtonParams, StaticParams};
use std::path::Path;

/// One solver configuration at one resolution: error and cost.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Control points.
    pub control_points: usize,
    /// Time step, s (0 for static solves).
    pub dt: Real,
    /// Max material-point error, m.
    pub error: Real,
    /// Wall time of the solve, s (best of the repeats).
    pub wall_seconds: Real,
}

/// One integrator on the plucked string at one time step.
#[derive(Debug, Clone, PartialEq)]
pub struct StringSample {
    /// Integrator name.
    pub integrator: String,
    /// Time step, s.
    pub dt: Real,
    /// Relative error of the first transverse frequency.
    pub frequency_error: Real,
    /// Fraction of the amplitude lost per period.
    pub amplitude_loss: Real,
}

/// Everything the report measured.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// Static catenary, one sample per resolution.
    pub statics: Vec<Sample>,
    /// Observed convergence order of the static catenary, pointwise stretching.
    pub order: Real,
    /// The static catenary with the pointwise stretching of the paper's eq. 12.
    pub statics_pointwise: Vec<Sample>,
    /// Observed convergence order of the static catenary, default (mixed) stretching.
    pub order_mixed: Real,
    /// The locking study: each formulation's name and rows.
    pub locking: Vec<(&'static str, Vec<LockingRow>)>,
    /// The default-form study (issue #44): every form and the default on four shapes.
    pub forms: Vec<locking::FormRow>,
    /// Damped implicit Euler catenary, one sample per (dt, resolution).
    pub dynamics: Vec<Sample>,
    /// Modal frequency errors: (control points, transverse, longitudinal).
    pub modal: Vec<(usize, Real, Real)>,
    /// Time-stepped string.
    pub strings: Vec<StringSample>,
    /// Adaptive against uniform resolution, per problem.
    pub adaptive: Vec<crate::report::adaptive::AdaptiveSweep>,
    /// The crossing ropes' lift, adaptive against uniform.
    pub crossing: crate::report::crossing::CrossingSweep,
    /// The capstan's slip threshold per resolution (none with `quick`).
    pub capstan: Vec<crate::report::capstan::CapstanRow>,
    /// The calibration study: fits of a clamped cable over noise levels.
    pub calibration: Vec<crate::report::calibration::CalibrationRow>,
}

fn sizes(
    quick: bool,
) -> (
    &'static [usize],
    &'static [Real],
    &'static [usize],
    &'static [Real],
) {
    if quick {
        (&[8, 16, 32], &[0.01], &[8, 16], &[1e-3, 1e-4])
    } else {
        (
            &[6, 8, 12, 16, 24, 32, 48, 64],
            &[0.02, 0.01, 0.005],
            &[6, 8, 12, 16, 24],
            &[1e-3, 5e-4, 2e-4, 1e-4],
        )
    }
}

/// Runs every sweep (`quick`: a few points each).
pub fn measure(quick: bool) -> Result<Report, Error> {
    let (static_n, dts, modal_n, string_dts) = sizes(quick);
    let repeats = if quick { 1 } else { 3 };
    let mut report = Report::default();
    for &n in static_n {
        report.statics.push(catenary_sample(n, None, repeats)?);
        let pointwise = static_sample(n, repeats, "pointwise")?;
        report.statics_pointwise.push(pointwise);
    }
    report.order = fitted_order(&report.statics_pointwise);
    report.order_mixed = fitted_order(&report.statics);
    for (name, formulation) in [
        ("pointwise", StretchFormulation::Pointwise),
        ("mixed", StretchFormulation::Mixed),
        ("mixed-consistent", StretchFormulation::MixedConsistent),
    ] {
        report.locking.push((name, locking::study(formulation)));
    }
    report.forms = match quick {
        // One shape, the softest and the stiffest rod: both regimes of the default.
        true => locking::form_study_of(&locking::SHAPES[..1], &[1e2, 1e9])?,
        false => locking::form_study()?,
    };
    // From 8 control points: with 6, the compressed straight start can settle in an
    // upward arch (compression-resistant material, too coarse to buckle), not the catenary.
    let dynamic_n: Vec<usize> = static_n
        .iter()
        .copied()
        .filter(|&n| n >= 8)
        .take(4)
        .collect();
    for &dt in dts {
        for &n in &dynamic_n {
            report.dynamics.push(catenary_sample(n, Some(dt), 1)?);
        }
    }
    let reference = string_reference()?;
    let (ft, fl) = (reference.transverse_hz[0], reference.longitudinal_hz[0]);
    for &n in modal_n {
        let (t, l) = string_modes(n)?;
        report
            .modal
            .push((n, rel(t.frequency, ft), rel(l.frequency, fl)));
    }
    for name in ["implicit-euler", "implicit-midpoint", "bdf2"] {
        for &dt in string_dts {
            report.strings.push(string_sample(name, dt, ft)?);
        }
    }
    report.adaptive = crate::report::adaptive::measure(quick)?;
    report.crossing = crate::report::crossing::measure(quick)?;
    report.capstan = crate::report::capstan::measure(quick)?;
    report.calibration = crate::report::calibration::measure(quick)?;
    Ok(report)
}

fn rel(x: Real, exact: Real) -> Real {
    (x - exact).abs() / exact
}

fn static_sample(n: usize, repeats: usize, formulation: &str) -> Result<Sample, Error> {
    let scene = catenary_scene_with(n, 0.0, "method = \"static\"", formulation)?;
    timed_sample(&scene, n, None, repeats)
}

fn catenary_sample(n: usize, dt: Option<Real>, repeats: usize) -> Result<Sample, Error> {
    let scene = match dt {
        None => catenary_scene(n, 0.0, "method = \"static\"")?,
        Some(dt) => catenary_scene(
            n,
            4.0,
            &format!("method = \"implicit-euler\"\ndt = {dt}\nduration = 6.0"),
        )?,
    };
    timed_sample(&scene, n, dt, repeats)
}

/// Runs `scene` `repeats` times: its catenary error and best wall time.
fn timed_sample(
    scene: &Scene,
    n: usize,
    dt: Option<Real>,
    repeats: usize,
) -> Result<Sample, Error> {
    let mut best = Real::INFINITY;
    let mut error = 0.0;
    for _ in 0..repeats.max(1) {
        let result = run(scene)?;
        best = best.min(result.wall_seconds);
        error = catenary_error(&result)?;
    }
    Ok(Sample {
        control_points: n,
        dt: dt.unwrap_or(0.0),
        error,
        wall_seconds: best,
    })
}

/// Least-squares slope of ln(error) against ln(h), h = 1/(n − 3), over the resolutions
/// with n ≥ 8 whose error is above round-off (1e-12 m).
fn fitted_order(samples: &[Sample]) -> Real {
    let points: Vec<(Real, Real)> = samples
        .iter()
        .filter(|s| s.control_points >= 8 && s.error > 1e-12)
        .map(|s| ((1.0 / (s.control_points - 3) as Real).ln(), s.error.ln()))
        .collect();
    let m = points.len() as Real;
    let (sx, sy) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0, b + p.1));
    let (mx, my) = (sx / m, sy / m);
    let num: Real = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let den: Real = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    num / den
}

fn integrator(name: &str) -> Result<Box<dyn Integrator>, Error> {
    let method = crate::scene::Method::from_name(name)?;
    method.integrator(NewtonParams::default(), StaticParams::default())
}

fn string_sample(name: &str, dt: Real, exact: Real) -> Result<StringSample, Error> {
    let run = pluck(integrator(name)?, dt, 4.0)?;
    let missing = || {
        Error::study(
            format!("{name} at dt = {dt}"),
            "the string did not oscillate",
        )
    };
    Ok(StringSample {
        integrator: name.into(),
        dt,
        frequency_error: rel(run.frequency().ok_or_else(missing)?, exact),
        amplitude_loss: run.amplitude_loss_per_period().ok_or_else(missing)?,
    })
}

/// Measures, plots and writes `dir/report.md`; returns what was measured.
pub fn write_report(dir: &Path, quick: bool) -> Result<Report, Error> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.display().to_string(),
        source,
    })?;
    let report = measure(quick)?;
    plot_all(dir, &report)?;
    crate::report::adaptive::plot(dir, &report.adaptive)?;
    crate::report::crossing::plot(dir, &report.crossing)?;
    crate::report::capstan::plot(dir, &report.capstan)?;
    let text = crate::report::markdown::markdown(&report, quick);
    let path = dir.join("report.md");
    std::fs::write(&path, text).map_err(|source| Error::Io {
        path: path.display().to_string(),
        source,
    })?;
    Ok(report)
}

fn plot_all(dir: &Path, r: &Report) -> Result<(), Error> {
    let statics = |f: fn(&Sample) -> (Real, Real)| r.statics.iter().map(f).collect();
    let static_series = Series {
        label: "static Newton".into(),
        points: statics(|s| (s.control_points as Real, s.error)),
    };
    let title = "Static catenary: max error vs control points";
    line_plot(
        &dir.join("catenary_convergence"),
        title,
        "control points",
        "max error (m)",
        &[static_series],
        true,
        true,
    )?;
    let mut pareto = vec![Series {
        label: "static Newton".into(),
        points: statics(|s| (s.wall_seconds, s.error)),
    }];
    let mut dts: Vec<Real> = r.dynamics.iter().map(|s| s.dt).collect();
    dts.dedup();
    for dt in dts {
        let points = r.dynamics.iter().filter(|s| s.dt == dt);
        pareto.push(Series {
            label: format!("implicit Euler to rest, dt = {dt} s"),
            points: points.map(|s| (s.wall_seconds, s.error)).collect(),
        });
    }
    let title = "Catenary: error vs wall time (Pareto)";
    line_plot(
        &dir.join("pareto"),
        title,
        "wall time (s)",
        "max error (m)",
        &pareto,
        true,
        true,
    )?;
    let modal = [
        Series {
            label: "first transverse".into(),
            points: r.modal.iter().map(|m| (m.0 as Real, m.1)).collect(),
        },
        Series {
            label: "first longitudinal".into(),
            points: r.modal.iter().map(|m| (m.0 as Real, m.2)).collect(),
        },
    ];
    let title = "String modes: relative frequency error vs control points";
    line_plot(
        &dir.join("string_modal"),
        title,
        "control points",
        "relative error",
        &modal,
        true,
        true,
    )?;
    let per_integrator = |f: fn(&StringSample) -> Real| -> Vec<Series> {
        ["implicit-euler", "implicit-midpoint", "bdf2"]
            .iter()
            .map(|name| Series {
                label: name.to_string(),
                points: r
                    .strings
                    .iter()
                    .filter(|s| s.integrator == *name)
                    .map(|s| (s.dt, f(s)))
                    .collect(),
            })
            .collect()
    };
    let title = "String, first transverse mode: frequency error vs dt";
    line_plot(
        &dir.join("string_frequency"),
        title,
        "dt (s)",
        "relative error",
        &per_integrator(|s| s.frequency_error),
        true,
        true,
    )?;
    let title = "String, first transverse mode: amplitude lost per period vs dt";
    line_plot(
        &dir.join("string_amplitude"),
        title,
        "dt (s)",
        "fraction lost per period",
        &per_integrator(|s| s.amplitude_loss),
        true,
        true,
    )
}
