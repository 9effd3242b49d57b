//! Cost of the adapt stage: `cargo run --release --example adapt_cost`.
fn main() -> Result<(), splinerod::Error> {
    println!(
        "adapt fraction at 16: {:.3}",
        splinerod::bench_adapt::adapt_fraction_16(5000)?
    );
    for n in [1_000, 10_000, 100_000] {
        println!(
            "adapt ns/cp at {n}: {:.1}",
            splinerod::bench_adapt::adapt_ns_per_cp(n, 64)?
        );
    }
    Ok(())
}
