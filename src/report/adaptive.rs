//! The report's adaptive-versus-uniform section (issue #13): the problems of
//! [`crate::report::adaptive_study`] run adaptively over a sweep of tolerances and uniformly over
//! a sweep of control points; true error against control points and against wall time,
//! and the effectivity index (estimate / true error) of every run. The section goes on
//! with two contact problems, [`crate::report::crossing`] and [`crate::report::capstan`].

use crate::output::plot::{line_plot, Series};
use crate::report::adaptive_study::{adaptive_start, study_run, Answer, Problem, StudyRun};
use crate::Error;
use splinerod_core::Real;
use std::fmt::Write;
use std::path::Path;

/// One problem's sweeps.
#[derive(Debug, Clone)]
pub struct AdaptiveSweep {
    /// Problem name, as in the report.
    pub name: &'static str,
    /// Adaptive runs, by decreasing tolerance.
    pub adaptive: Vec<StudyRun>,
    /// Uniform runs, by increasing control points.
    pub uniform: Vec<StudyRun>,
}

/// Runs both problems' sweeps (`quick`: fewer tolerances and sizes).
pub fn measure(quick: bool) -> Result<Vec<AdaptiveSweep>, Error> {
    let tolerances: &[Real] = if quick {
        &[1e-2, 1e-3, 1e-4]
    } else {
        &[1e-2, 1e-3, 1e-4, 1e-5, 1e-6]
    };
    let sizes: &[usize] = if quick {
        &[8, 16, 32]
    } else {
        &[6, 8, 12, 16, 24, 32, 64, 128]
    };
    let mut out = Vec::new();
    for (name, problem) in [("grab", Problem::Grab), ("hanging cable", Problem::Cable)] {
        let answer = Answer::of(problem)?;
        let start = adaptive_start(problem);
        let adaptive = tolerances
            .iter()
            .map(|&t| study_run(problem, &answer, Some(t), start))
            .collect::<Result<_, _>>()?;
        let uniform = sizes
            .iter()
            .map(|&n| study_run(problem, &answer, None, n))
            .collect::<Result<_, _>>()?;
        out.push(AdaptiveSweep {
            name,
            adaptive,
            uniform,
        });
    }
    Ok(out)
}

/// The section's markdown.
pub fn markdown(out: &mut String, sweeps: &[AdaptiveSweep]) {
    let _ = write!(
        out,
        "## Adaptive against uniform resolution\n\n\
         Tolerance-driven adaptivity (`[adaptivity] tolerance`) against fixed uniform \
         knots, on the grabbed string (253-point reference, compared at t = 1 s while it \
         still rings down) and on the hanging cable settled from a straight 4-point start \
         (exact elastic catenary at t = 10 s); problems in `splinerod::adaptive_study`. \
         Uniform runs report their estimate too (`[output] error_estimate`). Plots: \
         `adaptive_<problem>_points.png` and `adaptive_<problem>_time.png`. Two contact \
         problems follow: the **crossing** ropes, where the quantity is the lift (the \
         share of the upper rope's weight the lower one carries), its relative error \
         against control points and wall time; and the **capstan**, a rope wound a full \
         turn around a capsule, where the quantity is the load ratio at which it slips, \
         its relative error against e^(2πμ) per resolution.\n\n"
    );
    for s in sweeps {
        let _ = write!(
            out,
            "### {}\n\n| run | control points (end / most) | true error (m) | estimate (m) \
             | effectivity | wall (s) |\n|---|---|---|---|---|---|\n",
            s.name
        );
        for r in s.adaptive.iter().chain(&s.uniform) {
            let label = r
                .tolerance
                .map_or("uniform".into(), |t| format!("tolerance {t:.0e}"));
            let _ = writeln!(
                out,
                "| {label} | {} / {} | {:.2e} | {:.2e} | {:.2} | {:.3} |",
                r.control_points,
                r.most_control_points,
                r.error,
                r.estimate,
                r.effectivity(),
                r.wall_seconds
            );
        }
        out.push('\n');
    }
}

/// Error against control points and against wall time, adaptive and uniform.
pub fn plot(dir: &Path, sweeps: &[AdaptiveSweep]) -> Result<(), Error> {
    for s in sweeps {
        let file = s.name.replace(' ', "_");
        let series = |f: fn(&StudyRun) -> Real| {
            [("adaptive", &s.adaptive), ("uniform", &s.uniform)].map(|(label, runs)| Series {
                label: label.into(),
                points: runs.iter().map(|r| (f(r), r.error)).collect(),
            })
        };
        line_plot(
            &dir.join(format!("adaptive_{file}_points")),
            &format!("{}: true error vs control points", s.name),
            "control points (end of run)",
            "max error (m)",
            &series(|r| r.control_points as Real),
            true,
            true,
        )?;
        line_plot(
            &dir.join(format!("adaptive_{file}_time")),
            &format!("{}: true error vs wall time", s.name),
            "wall time (s)",
            "max error (m)",
            &series(|r| r.wall_seconds),
            true,
            true,
        )?;
    }
    Ok(())
}
