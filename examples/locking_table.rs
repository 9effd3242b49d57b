//! Static catenary error against the exact elastic catenary at growing EA
//! (`cargo run --release --example locking_table`): the membrane-locking study of #12.
use splinerod::elastic_catenary::ElasticCatenary;
use splinerod::prelude::*;
use splinerod::problems::pinned_cable;

fn error(n: usize, ea: Real) -> Result<(Real, usize), Error> {
    let exact = ElasticCatenary::new(1.0, 0.8, 0.1 * 9.81, ea)?;
    let mut system = pinned_cable(n, 0.8, ea)?;
    // Start next to the exact curve: control points at the Greville abscissae.
    let knots = system.rod.basis().knots().to_vec();
    let d = system.rod.basis().degree();
    for (i, q) in system.rod.positions.iter_mut().enumerate() {
        let s = knots[i + 1..=i + d].iter().sum::<Real>() / d as Real;
        let p = exact.point(s);
        *q = Vector3::new(p[0], p[1], 0.0);
    }
    let mut solver = StaticSolver::new(StaticParams::default())?;
    let stats = solver.solve(&mut system)?;
    let mut worst: Real = 0.0;
    for k in 0..=40 {
        let s = k as Real / 40.0;
        let p = exact.point(s);
        let q = system.rod.point(s)?;
        worst = worst.max((q - Vector3::new(p[0], p[1], 0.0)).norm());
    }
    Ok((worst, stats.newton_iterations))
}

fn main() -> Result<(), Error> {
    println!("EA (N)    16 points    32 points    64 points");
    for ea in [1e2, 1e4, 1e6, 1e7, 1e8, 1e9] {
        let row: Vec<String> = [16, 32, 64]
            .iter()
            .map(|&n| match error(n, ea) {
                Ok((e, _)) => format!("{e:.2e}"),
                Err(e) => format!("fails: {e}"),
            })
            .collect();
        println!("{ea:.0e}    {}", row.join("    "));
    }
    Ok(())
}
