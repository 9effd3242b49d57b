//! The report's calibration section alone (`cargo run --release --example
//! calibration_study [quick]`): fits of a clamped cable's EA, EI (and density) from
//! noisy markers over noise levels, and the simulations they cost against Nelder–Mead's
//! ([`splinerod::report::calibration`]).
fn main() -> Result<(), splinerod::Error> {
    let quick = std::env::args().nth(1).as_deref() == Some("quick");
    let rows = splinerod::report::calibration::measure(quick)?;
    let mut out = String::new();
    splinerod::report::calibration::markdown(&mut out, &rows);
    println!("{out}");
    Ok(())
}
