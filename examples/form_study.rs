//! The default-form study of issue #44 (`cargo run --release --example form_study`):
//! static catenaries of four shapes from EA = 10² to 10⁹ N at 16, 32 and 64 control
//! points, each stretching form's error against the exact elastic catenary, the
//! default's, and its ratio to the best form's.
use splinerod::locking::{form_study, RESOLUTIONS};
use splinerod::Error;

fn main() -> Result<(), Error> {
    let cell = |e: Option<f64>| e.map_or("fails".to_string(), |e| format!("{e:.2e}"));
    for row in form_study()? {
        let (l, d, mu) = row.shape;
        for (k, n) in RESOLUTIONS.into_iter().enumerate() {
            let e = row.errors[k];
            let best = e[..3]
                .iter()
                .flatten()
                .fold(f64::INFINITY, |a, &b| a.min(b));
            println!(
                "L {l} D {d} mu {mu} EA {:.0e} n {n}: pointwise {} mixed {} consistent {} default {} ({}, {:.2} x the best)",
                row.stiffness,
                cell(e[0]),
                cell(e[1]),
                cell(e[2]),
                cell(e[3]),
                row.chosen[k],
                e[3].unwrap_or(f64::NAN) / best
            );
        }
    }
    Ok(())
}
