//! Times factor + solve of block-banded Newton matrices, with and without far blocks
//! (self-contact couplings), through [`LinearSolver`]: 1000 repetitions at n = 16 and
//! n = 1000 control points, bandwidth 3. Far blocks come as 10 springs, either joining
//! the two ends of the rod (`long`: a loop as long as the rod, whose elimination fill
//! roughly doubles the factor) or control points 8 apart (`short`: ten small loops).
//!
//! ```text
//! cargo run --release -p splinerod-integrators --example far_block_timing
//! ```

use nalgebra::Matrix3;
use splinerod_core::{BlockBanded, Real};
use splinerod_integrators::linear::LinearSolver;
use splinerod_integrators::LinearSolverKind;
use std::time::Instant;

/// Repetitions of factor + solve per case.
const REPEATS: usize = 1000;

/// How far blocks are placed.
#[derive(Debug, Clone, Copy)]
enum Far {
    /// No far blocks.
    None,
    /// Ten springs between the first `n / 2` and the last `n / 4` control points.
    Long,
    /// Ten springs between control points 8 apart.
    Short,
}

/// A diagonally dominant SPD block band (a chain of springs plus a mass term), with
/// far spring couplings placed as `far` says.
fn matrix(n: usize, far: Far) -> BlockBanded {
    let bw = 3;
    let mut a = BlockBanded::zeros(n, bw);
    for i in 0..n {
        for k in 1..=bw.min(n - 1 - i) {
            spring(&mut a, i, i + k, 1.0 / k as Real);
        }
        a.add_block(i, i, &Matrix3::identity());
    }
    for c in 0..10 {
        match far {
            Far::None => {}
            Far::Long => spring(&mut a, (c * 7) % (n / 2), n - 1 - (c * 5) % (n / 4), 0.5),
            Far::Short => spring(&mut a, (c * 97) % (n - 8), (c * 97) % (n - 8) + 8, 0.5),
        }
    }
    a
}

/// Adds the Hessian of a zero-rest-length spring `k |q_i − q_j|² / 2`.
fn spring(a: &mut BlockBanded, i: usize, j: usize, k: Real) {
    let b = Matrix3::from_diagonal_element(k);
    a.add_coupling(i, i, &b);
    a.add_coupling(j, j, &b);
    a.add_coupling(i, j, &-b);
}

/// Mean microseconds per factor + solve.
fn time(a: &BlockBanded, kind: LinearSolverKind) -> Real {
    let mut solver = LinearSolver::new(kind);
    let mut rhs = vec![0.0; 3 * a.dim()];
    solver.factor(a, 0).expect("SPD");
    let start = Instant::now();
    for r in 0..REPEATS {
        rhs.iter_mut()
            .enumerate()
            .for_each(|(i, x)| *x = ((i + r) % 7) as Real);
        solver.factor(a, 0).expect("SPD");
        solver.solve_in_place(&mut rhs).expect("factored");
    }
    start.elapsed().as_secs_f64() * 1e6 / REPEATS as Real
}

fn main() {
    println!("{:>6} {:>6} {:>8} {:>12}", "n", "far", "kind", "µs/(f+s)");
    for n in [16, 1000] {
        for (far, kind) in [
            (Far::None, LinearSolverKind::Banded),
            (Far::None, LinearSolverKind::Sparse),
            (Far::Long, LinearSolverKind::Banded),
            (Far::Long, LinearSolverKind::Sparse),
            (Far::Short, LinearSolverKind::Sparse),
        ] {
            let us = time(&matrix(n, far), kind);
            let (far, kind) = (format!("{far:?}"), format!("{kind:?}"));
            println!("{n:>6} {far:>6} {kind:>8} {us:>12.2}");
        }
    }
}
