//! Prints every hard case with its solver counters (`cargo run --release --example hard_cases_table`).
fn main() -> Result<(), splinerod::Error> {
    for case in splinerod::hard_cases::hard_cases()? {
        let start = std::time::Instant::now();
        match splinerod::run(&case.scene) {
            Ok(r) => println!(
                "{:<40} its {:>6} unconv {} sub {:>5} rej {:>4} hmin {:.2e} cont {:>3} wall {:.3} s",
                case.name,
                r.solver.newton_iterations,
                r.solver.unconverged_steps,
                r.solver.substeps,
                r.solver.rejected_steps,
                r.solver.smallest_dt.unwrap_or(0.0),
                r.solver.continuation_steps,
                start.elapsed().as_secs_f64()
            ),
            Err(e) => println!("{:<40} FAILED: {e}", case.name),
        }
    }
    Ok(())
}
