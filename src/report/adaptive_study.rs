//! Adaptive against uniform resolution (issue #13), on two problems with known answers:
//!
//! * **the grab**: a string (L = 1 m, μ = 0.1 kg/m, EA = 100 N, no bending) pinned at
//!   both ends 1 m apart, grabbed at 0.3 L by a stiff spring pulled 0.2 m down in
//!   0.2 s, damped (α = 2/s), implicit Euler at 1 ms for 1 s; the answer is a uniform
//!   run with 250 spans and the grab's knot tripled (a run with 500 spans agrees with
//!   it to 1e-8 m);
//! * **the hanging cable**: the default scene's cable (pins 0.8 m apart) released from a
//!   straight, 4-point start and settled for 10 s (dt = 5 ms); the answer is the exact
//!   elastic catenary ([`ElasticCatenary`]).
//!
//! Errors are the largest distance between material points (201 on the grab, 41 on the
//! cable). The effectivity index is the final estimate over the true error.

use crate::problems::elastic_catenary::ElasticCatenary;
use crate::{Error, Real, RunResult, Scene};

const GRAB: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 2.0
control_points = {N}
{KNOTS}
[[pins]]
at = 0.0
[[pins]]
at = 1.0
[world]
gravity = [0.0, -9.81, 0.0]
[[grabs]]
at = 0.3
to = [0.3, -0.2, 0.0]
end_time = 0.2
stiffness = 1000.0
[solver]
method = "implicit-euler"
dt = 0.001
duration = 1.0
[output]
samples = 201
error_estimate = true
{ADAPT}
"#;

const CABLE: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 2.0
control_points = {N}
start = [0.0, 0.0, 0.0]
end = [0.8, 0.0, 0.0]
[[pins]]
at = 0.0
[[pins]]
at = 1.0
[world]
gravity = [0.0, -9.81, 0.0]
[solver]
method = "implicit-euler"
dt = 0.005
duration = 10.0
[output]
samples = 41
error_estimate = true
{ADAPT}
"#;

/// Which problem.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Problem {
    /// The grabbed string.
    Grab,
    /// The hanging cable settling from a straight start.
    Cable,
}

/// `[adaptivity]` with `tolerance` (m); the rod may coarsen down to 4 control points.
pub fn adaptivity_table(tolerance: Real) -> String {
    format!("[adaptivity]\ntolerance = {tolerance:e}\nmin_control_points = 4")
}

/// The scene of `problem` with `n` uniform control points (clamped knots, or `knots`
/// if given) and the `adapt` table (empty for none).
pub fn scene(
    problem: Problem,
    n: usize,
    knots: Option<&[Real]>,
    adapt: &str,
) -> Result<Scene, Error> {
    let knots = knots.map_or(String::new(), |k| {
        let list: Vec<String> = k.iter().map(|x| format!("{x:?}")).collect();
        format!("knots = [{}]", list.join(", "))
    });
    let text = match problem {
        Problem::Grab => GRAB,
        Problem::Cable => CABLE,
    };
    Scene::from_toml(
        &text
            .replace("{N}", &n.to_string())
            .replace("{KNOTS}", &knots)
            .replace("{ADAPT}", adapt),
    )
}

/// The answer of a problem, to measure true errors against.
#[derive(Debug, Clone)]
pub enum Answer {
    /// The fine run's material points.
    Points(Vec<[Real; 3]>),
    /// The exact catenary.
    Catenary(ElasticCatenary),
}

impl Answer {
    /// The answer of `problem` (the grab's costs a 253-point run, about a second).
    pub fn of(problem: Problem) -> Result<Self, Error> {
        Ok(match problem {
            Problem::Grab => {
                let mut knots = vec![0.0; 4];
                knots.extend((1..250).map(|i| i as Real / 250.0));
                knots.extend([0.3, 0.3, 1.0, 1.0, 1.0, 1.0]);
                knots.sort_by(Real::total_cmp);
                let fine = crate::run(&scene(problem, knots.len() - 4, Some(&knots), "")?)?;
                Self::Points(fine.samples.positions)
            }
            Problem::Cable => Self::Catenary(ElasticCatenary::new(1.0, 0.8, 0.1 * 9.81, 100.0)?),
        })
    }

    /// Largest material-point distance of `run` from the answer, m.
    pub fn error(&self, run: &RunResult) -> Real {
        let distance = |p: &[Real; 3], q: [Real; 3]| {
            (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<Real>().sqrt()
        };
        let samples = run.samples.s.iter().zip(&run.samples.positions);
        match self {
            Self::Points(points) => samples
                .zip(points)
                .map(|((_, p), q)| distance(p, *q))
                .fold(0.0, Real::max),
            Self::Catenary(exact) => samples
                .map(|(&s, p)| {
                    let q = exact.point(s);
                    distance(p, [q[0], q[1], 0.0])
                })
                .fold(0.0, Real::max),
        }
    }
}

/// One run of the study.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StudyRun {
    /// Tolerance (adaptive runs), m.
    pub tolerance: Option<Real>,
    /// Control points at the end.
    pub control_points: usize,
    /// Most control points during the run.
    pub most_control_points: usize,
    /// True error at the end, m.
    pub error: Real,
    /// Final error estimate, m.
    pub estimate: Real,
    /// Wall time of the run, s.
    pub wall_seconds: Real,
}

impl StudyRun {
    /// Estimate over true error.
    pub fn effectivity(&self) -> Real {
        self.estimate / self.error
    }
}

/// Runs `problem` adaptively at `tolerance` (from 4 points for the cable, 8 for the
/// grab), or uniformly with `n` points when `tolerance` is `None`.
pub fn study_run(
    problem: Problem,
    answer: &Answer,
    tolerance: Option<Real>,
    n: usize,
) -> Result<StudyRun, Error> {
    let adapt = tolerance.map_or(String::new(), adaptivity_table);
    let run = crate::run(&scene(problem, n, None, &adapt)?)?;
    let counts = run.control_points_history.iter().map(|h| h[1] as usize);
    Ok(StudyRun {
        tolerance,
        control_points: run.control_points,
        most_control_points: counts.max().unwrap_or(run.control_points),
        error: answer.error(&run),
        estimate: run
            .adaptivity
            .as_ref()
            .map_or(Real::NAN, |a| a.estimated_error),
        wall_seconds: run.wall_seconds,
    })
}

/// Starting control points of the adaptive runs.
pub fn adaptive_start(problem: Problem) -> usize {
    match problem {
        Problem::Grab => 8,
        Problem::Cable => 4,
    }
}
