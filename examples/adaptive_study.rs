//! The adaptive-versus-uniform study of `splinerod::adaptive_study`:
//! `cargo run --release --example adaptive_study -- grab|cable`.
use splinerod::adaptive_study::{adaptive_start, study_run, Answer, Problem};

fn main() -> Result<(), splinerod::Error> {
    let problem = match std::env::args().nth(1).as_deref() {
        Some("cable") => Problem::Cable,
        _ => Problem::Grab,
    };
    let answer = Answer::of(problem)?;
    for tol in [1e-2, 1e-3, 1e-4, 1e-5, 1e-6] {
        let r = study_run(problem, &answer, Some(tol), adaptive_start(problem))?;
        println!(
            "tol {tol:.0e}: error {:.2e} estimate {:.2e} effectivity {:.2} cps {} (most {}) {:.3} s",
            r.error, r.estimate, r.effectivity(), r.control_points, r.most_control_points, r.wall_seconds
        );
    }
    for n in [4, 6, 8, 12, 16, 24, 32, 64, 128] {
        let r = study_run(problem, &answer, None, n)?;
        println!(
            "uniform {n}: error {:.2e} estimate {:.2e} effectivity {:.2} {:.3} s",
            r.error,
            r.estimate,
            r.effectivity(),
            r.wall_seconds
        );
    }
    Ok(())
}
