//! The report's capstan (issue #46): a rope wound a full turn around a capsule
//! ([`crate::problems::capstan`], μ = 0.3) holds while the load ratio of its ends stays
//! below e^{2πμ} and slips above it. What is measured, per resolution (uniform fits of
//! 8 — refined at the start, it overlaps the capsule —, 16, 32 and 64 control points,
//! and tolerance-driven adaptivity from 8 and from 16): whether the rope holds at
//! 0.9 e^{2πμ} and slips at 1.1 e^{2πμ}; the slip threshold found by bisection over the
//! load ratio between the two, with its relative error against e^{2πμ}; the smallest
//! clearance ratio over all runs; the control points after the start and at the end;
//! the wall time.
//!
//! Each run raises the heavy end's load from 1 N to the ratio in 0.5 s, holds it, and
//! watches from 1 s to 2 s whether the end moves faster than 1 cm/s (averaged over
//! 0.1 s); it stops at a slip.

use crate::output::plot::{line_plot, Series};
use crate::problems::capstan::{self, Turn, TurnRun};
use crate::{Error, Real};
use std::fmt::Write;
use std::path::Path;

/// Friction coefficient of the study.
pub const MU: Real = 0.3;
/// The load ratios, fractions of e^{2πμ}, of the first two runs: the rope should hold
/// at the first and slip at the second.
pub const BELOW: Real = 0.9;
/// See [`BELOW`].
pub const ABOVE: Real = 1.1;
/// Bisection steps after the bracket: the threshold is known to ±0.1/2^steps.
pub const BISECTIONS: usize = 5;

/// One resolution of the study.
#[derive(Debug, Clone, PartialEq)]
pub struct CapstanCase {
    /// Row label.
    pub label: String,
    /// Control points of the fitted wrap.
    pub control_points: usize,
    /// `[adaptivity]` table body (`None`: uniform).
    pub adaptivity: Option<String>,
}

/// What the bisection found at one resolution.
#[derive(Debug, Clone, PartialEq)]
pub struct CapstanRow {
    /// The resolution.
    pub case: CapstanCase,
    /// The run at [`BELOW`].
    pub below: TurnRun,
    /// The run at [`ABOVE`].
    pub above: TurnRun,
    /// The threshold lies between these load ratios, fractions of e^{2πμ}.
    pub bracket: (Real, Real),
    /// Runs made.
    pub runs: usize,
    /// Smallest clearance ratio over every run.
    pub clearance: Real,
    /// Most control points at the end of any run.
    pub most_points: usize,
    /// Wall time of all the runs, s.
    pub wall_seconds: Real,
}

impl CapstanRow {
    /// The measured threshold, fraction of e^{2πμ}: the bracket's middle.
    pub fn threshold(&self) -> Real {
        0.5 * (self.bracket.0 + self.bracket.1)
    }

    /// Relative error of the measured threshold against e^{2πμ}.
    pub fn error(&self) -> Real {
        self.threshold() - 1.0
    }

    /// Half the bracket: how far the threshold may be from [`Self::threshold`].
    pub fn resolution(&self) -> Real {
        0.5 * (self.bracket.1 - self.bracket.0)
    }
}

/// The resolutions of the study.
pub fn cases() -> Vec<CapstanCase> {
    let uniform = |n: usize| CapstanCase {
        label: format!("uniform {n}"),
        control_points: n,
        adaptivity: None,
    };
    let adaptive = |n: usize| CapstanCase {
        label: format!("adaptive from {n}, default tolerance"),
        control_points: n,
        adaptivity: Some(String::new()),
    };
    let uniform = [8, 16, 32, 64].into_iter().map(uniform);
    uniform.chain([8, 16].into_iter().map(adaptive)).collect()
}

/// One run at `fraction` of e^{2πμ}.
fn attempt(case: &CapstanCase, fraction: Real) -> Result<TurnRun, Error> {
    let turn = Turn {
        mu: MU,
        control_points: case.control_points,
        contact_stiffness: None,
        adaptivity: case.adaptivity.clone(),
        ratio: vec![[0.0, 1.0], [0.5, fraction * capstan::capstan_ratio(MU)]],
        duration: 2.0,
    };
    capstan::run(&turn, 1.0)
}

/// Runs `case` at [`BELOW`] and [`ABOVE`], widens the bracket in steps of 0.2 while
/// the rope slips at its low end or holds at its high end (down to 0.1, taken to hold,
/// or up to 2.1, taken to slip, untried), then bisects it [`BISECTIONS`] times.
pub fn measure_case(case: &CapstanCase) -> Result<CapstanRow, Error> {
    let mut runs = Vec::new();
    let mut slips = |fraction: Real| -> Result<bool, Error> {
        let run = attempt(case, fraction)?;
        runs.push(run);
        Ok(run.slip_time.is_some())
    };
    let (mut lo, mut hi) = (BELOW, ABOVE);
    let (lo_slips, hi_slips) = (slips(lo)?, slips(hi)?);
    if lo_slips {
        hi = lo;
        lo -= 0.2;
        while lo > 0.15 && slips(lo)? {
            (hi, lo) = (lo, lo - 0.2);
        }
    } else if !hi_slips {
        lo = hi;
        hi += 0.2;
        while hi < 2.05 && !slips(hi)? {
            (lo, hi) = (hi, hi + 0.2);
        }
    }
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if slips(mid)? {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Ok(CapstanRow {
        case: case.clone(),
        below: runs[0],
        above: runs[1],
        bracket: (lo, hi),
        runs: runs.len(),
        clearance: runs
            .iter()
            .map(|r| r.clearance)
            .fold(Real::INFINITY, Real::min),
        most_points: runs.iter().map(|r| r.end_points).max().unwrap_or(0),
        wall_seconds: runs.iter().map(|r| r.wall_seconds).sum(),
    })
}

/// Runs every case (`quick`: none; each run costs seconds).
pub fn measure(quick: bool) -> Result<Vec<CapstanRow>, Error> {
    if quick {
        return Ok(Vec::new());
    }
    cases().iter().map(measure_case).collect()
}

/// The capstan's subsection.
pub fn markdown(out: &mut String, rows: &[CapstanRow], quick: bool) {
    let _ = write!(
        out,
        "### capstan\n\n\
         A rope wound a full turn around a capsule (`splinerod::problems::capstan`, μ = \
         {MU}, e^(2πμ) = {:.4}), the wrap fitted with the given control points; the \
         rope should hold below the load ratio e^(2πμ) and slip above it. Each run \
         raises the heavy end's load in 0.5 s and holds it; it slips if the end moves \
         faster than 1 cm/s (averaged over 0.1 s) between 1 s and 2 s. The rope is run \
         at {BELOW} and {ABOVE} e^(2πμ), then the threshold is bisected {BISECTIONS} \
         times between (to ±{:.2} %): its relative error against e^(2πμ). Control \
         points: after the start (a coarse fit overlapping the capsule is refined) / at \
         the end of the run at {BELOW} / the most at the end of any run. Clearance: the \
         smallest clearance ratio over all runs (below 1: overlap). Wall: all runs \
         together.\n\n",
        capstan::capstan_ratio(MU),
        100.0 * 0.1 / (1 << BISECTIONS) as Real,
    );
    if quick {
        out.push_str("Skipped by `--quick`: each run costs seconds.\n\n");
        return;
    }
    out.push_str(
        "![threshold error vs control points](adaptive_capstan_points.png)\n\n\
         ![threshold error vs wall time](adaptive_capstan_time.png)\n\n\
         | run | control points (start / end / most) | holds at 0.9 | slips at 1.1 | \
         threshold / e^(2πμ) | relative error | clearance | runs | wall (s) |\n\
         |---|---|---|---|---|---|---|---|---|\n",
    );
    let yes = |b: bool| if b { "yes" } else { "**no**" };
    for r in rows {
        let _ = writeln!(
            out,
            "| {} | {} / {} / {} | {} | {} | {:.4} ± {:.4} | {:+.2e} | {:.3} | {} | {:.1} |",
            r.case.label,
            r.below.start_points,
            r.below.end_points,
            r.most_points,
            yes(r.below.slip_time.is_none()),
            yes(r.above.slip_time.is_some()),
            r.threshold(),
            r.resolution(),
            r.error(),
            r.clearance,
            r.runs,
            r.wall_seconds
        );
    }
    out.push('\n');
}

/// Threshold error against control points (at the end of the run at [`BELOW`]) and
/// against wall time, adaptive and uniform.
pub fn plot(dir: &Path, rows: &[CapstanRow]) -> Result<(), Error> {
    if rows.is_empty() {
        return Ok(());
    }
    let series = |f: fn(&CapstanRow) -> Real| {
        [("adaptive", true), ("uniform", false)].map(|(label, adaptive)| {
            let chosen = rows
                .iter()
                .filter(|r| r.case.adaptivity.is_some() == adaptive);
            let mut points: Vec<(Real, Real)> = chosen.map(|r| (f(r), r.error().abs())).collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series {
                label: label.into(),
                points,
            }
        })
    };
    line_plot(
        &dir.join("adaptive_capstan_points"),
        "capstan: slip threshold error vs control points",
        "control points (end of the run at 0.9)",
        "|threshold / e^(2πμ) − 1|",
        &series(|r| r.below.end_points as Real),
        true,
        true,
    )?;
    line_plot(
        &dir.join("adaptive_capstan_time"),
        "capstan: slip threshold error vs wall time",
        "wall time, all runs (s)",
        "|threshold / e^(2πμ) − 1|",
        &series(|r| r.wall_seconds),
        true,
        true,
    )
}
