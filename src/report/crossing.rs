//! The report's crossing (issue #46): two pinned ropes with bending, the upper resting
//! on the lower ([`crate::problems::crossing`], a static solve). What is measured: the
//! relative error of the lift (the share of the upper rope's weight the lower rope
//! carries) against a uniform run with 256 control points per rope, and the wall time,
//! for adaptive runs from 16 control points per rope over a sweep of tolerances and for
//! uniform runs from 16 to 128 per rope; and, in the full report, how far the reference
//! itself is from a uniform run with 512 per rope.

use crate::output::plot::{line_plot, Series};
use crate::problems::crossing::{self, Resolution, REFERENCE_POINTS};
use crate::{Error, Real};
use std::fmt::Write;
use std::path::Path;

/// Control points per rope of the adaptive runs' start.
pub const ADAPTIVE_START: usize = 16;

/// One run of the crossing.
#[derive(Debug, Clone, PartialEq)]
pub struct CrossingRun {
    /// Tolerance, m (adaptive runs); `None`: uniform.
    pub tolerance: Option<Real>,
    /// Control points of each rope at the end (lower, upper).
    pub per_rope: Vec<usize>,
    /// Control points of both ropes at the end.
    pub control_points: usize,
    /// The lift.
    pub lift: Real,
    /// |lift − reference| / reference.
    pub error: Real,
    /// Wall time of the solve, s (best of the repeats).
    pub wall_seconds: Real,
}

/// The crossing's sweeps.
#[derive(Debug, Clone, Default)]
pub struct CrossingSweep {
    /// The reference lift (uniform, 256 control points per rope).
    pub reference: Real,
    /// The lift with 512 per rope (full report only).
    pub finer: Option<Real>,
    /// The tolerance of the scene's `[adaptivity]` table, m.
    pub scene_tolerance: Option<Real>,
    /// Adaptive runs, by decreasing tolerance.
    pub adaptive: Vec<CrossingRun>,
    /// Uniform runs, by increasing control points.
    pub uniform: Vec<CrossingRun>,
}

/// Runs the crossing at `resolution` `repeats` times against `reference`.
fn sample(resolution: Resolution, reference: Real, repeats: usize) -> Result<CrossingRun, Error> {
    let mut best = Real::INFINITY;
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let (lift, run) = crossing::run(resolution, None)?;
        best = best.min(run.wall_seconds);
        last = Some((lift, run));
    }
    let (lift, run) = last.ok_or_else(|| Error::study("crossing", "no run"))?;
    Ok(CrossingRun {
        tolerance: match resolution {
            Resolution::Uniform(_) => None,
            Resolution::Adaptive { tolerance, .. } => tolerance,
        },
        per_rope: run.rods.iter().map(|r| r.control_points).collect(),
        control_points: run.control_points,
        lift,
        error: (lift - reference).abs() / reference,
        wall_seconds: best,
    })
}

/// Runs the sweeps (`quick`: fewer tolerances and sizes, one repeat, no 512 check).
pub fn measure(quick: bool) -> Result<CrossingSweep, Error> {
    let (tolerances, sizes, repeats): (&[Real], &[usize], usize) = if quick {
        (&[1e-3, 1e-4], &[16, 32, 64], 1)
    } else {
        (&[1e-3, 3e-4, 1e-4, 1e-5, 1e-6], &[16, 24, 32, 64, 128], 3)
    };
    let reference = crossing::run(Resolution::Uniform(REFERENCE_POINTS), None)?.0;
    let finer = match quick {
        true => None,
        false => Some(crossing::run(Resolution::Uniform(2 * REFERENCE_POINTS), None)?.0),
    };
    let adaptive_scene = crossing::scene(
        Resolution::Adaptive {
            start: ADAPTIVE_START,
            tolerance: None,
        },
        None,
    )?;
    let adaptive = tolerances
        .iter()
        .map(|&t| {
            let resolution = Resolution::Adaptive {
                start: ADAPTIVE_START,
                tolerance: Some(t),
            };
            sample(resolution, reference, repeats)
        })
        .collect::<Result<_, _>>()?;
    let uniform = sizes
        .iter()
        .map(|&n| sample(Resolution::Uniform(n), reference, repeats))
        .collect::<Result<_, _>>()?;
    Ok(CrossingSweep {
        reference,
        finer,
        scene_tolerance: adaptive_scene.adaptivity.and_then(|a| a.tolerance),
        adaptive,
        uniform,
    })
}

/// The crossing's subsection.
pub fn markdown(out: &mut String, s: &CrossingSweep) {
    let finer = s.finer.map_or(String::new(), |f| {
        format!(
            "; 512 per rope gives {f:.6}, {:.1e} from it: the floor below which the \
             errors are the reference's",
            (f - s.reference).abs() / s.reference
        )
    });
    let _ = write!(
        out,
        "### crossing\n\n\
         `scenes/ropes_crossing_pinned.toml`, a static solve: the relative error of the \
         lift, the share of the upper rope's weight the lower rope carries, against a \
         uniform run with {REFERENCE_POINTS} control points per rope (lift \
         {:.6}{finer}). Adaptive runs start from {ADAPTIVE_START} per rope with the \
         scene's `[adaptivity]` table, the tolerance swept (the scene's is {}). Control \
         points are both ropes' at the end; wall times the best of the repeats.\n\n\
         ![lift error vs control points](adaptive_crossing_points.png)\n\n\
         ![lift error vs wall time](adaptive_crossing_time.png)\n\n\
         | run | control points (lower + upper) | lift | relative error | wall (s) |\n\
         |---|---|---|---|---|\n",
        s.reference,
        s.scene_tolerance
            .map_or("the default".into(), |t| format!("{t:.0e} m")),
    );
    for r in s.adaptive.iter().chain(&s.uniform) {
        let label = match r.tolerance {
            None => "uniform".into(),
            Some(t) if Some(t) == s.scene_tolerance => format!("tolerance {t:.0e} (the scene's)"),
            Some(t) => format!("tolerance {t:.0e}"),
        };
        let ropes: Vec<String> = r.per_rope.iter().map(|n| n.to_string()).collect();
        let _ = writeln!(
            out,
            "| {label} | {} = {} | {:.6} | {:.2e} | {:.3} |",
            r.control_points,
            ropes.join(" + "),
            r.lift,
            r.error,
            r.wall_seconds
        );
    }
    out.push('\n');
}

/// Lift error against control points and against wall time, adaptive and uniform.
pub fn plot(dir: &Path, s: &CrossingSweep) -> Result<(), Error> {
    let series = |f: fn(&CrossingRun) -> Real| {
        [("adaptive", &s.adaptive), ("uniform", &s.uniform)].map(|(label, runs)| {
            let mut points: Vec<(Real, Real)> = runs.iter().map(|r| (f(r), r.error)).collect();
            points.sort_by(|a, b| a.0.total_cmp(&b.0));
            Series {
                label: label.into(),
                points,
            }
        })
    };
    line_plot(
        &dir.join("adaptive_crossing_points"),
        "crossing: lift error vs control points",
        "control points, both ropes (end of run)",
        "relative lift error",
        &series(|r| r.control_points as Real),
        true,
        true,
    )?;
    line_plot(
        &dir.join("adaptive_crossing_time"),
        "crossing: lift error vs wall time",
        "wall time (s)",
        "relative lift error",
        &series(|r| r.wall_seconds),
        true,
        true,
    )
}
