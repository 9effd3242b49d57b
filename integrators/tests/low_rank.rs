//! Low-rank (Sherman–Morrison) terms of a Newton matrix: solves on the banded, sparse
//! and indefinite paths agree with a dense Cholesky solve.

use nalgebra::{DVector, Matrix3, Vector3};
use splinerod_core::{BlockBanded, Real};
use splinerod_integrators::linear::{LinearSolver, LinearSolverKind};

/// A banded SPD chain plus two rank-one terms (and a far block if `far`).
fn matrix(n: usize, far: bool) -> BlockBanded {
    let mut a = BlockBanded::zeros(n, 3);
    for i in 0..n {
        a.add_block(i, i, &(Matrix3::identity() * 4.0));
        if i + 1 < n {
            a.add_block(i, i + 1, &(Matrix3::identity() * -1.0));
        }
    }
    if far {
        a.add_coupling(1, n - 2, &(Matrix3::identity() * 0.5));
        a.add_coupling(1, 1, &(Matrix3::identity() * 0.5));
        a.add_coupling(n - 2, n - 2, &(Matrix3::identity() * 0.5));
    }
    let u: Vec<Vector3<Real>> = (0..n)
        .map(|i| Vector3::new((i as Real).sin(), 1.0, (i as Real * 0.3).cos()))
        .collect();
    let v: Vec<Vector3<Real>> = (0..n).map(|i| Vector3::new(0.0, i as Real, -1.0)).collect();
    a.add_low_rank(2.5, &u);
    a.add_low_rank(0.7, &v);
    a
}

#[test]
fn solves_with_low_rank_terms_match_the_dense_solve() {
    for (kind, far) in [
        (LinearSolverKind::Banded, false),
        (LinearSolverKind::Sparse, false),
        (LinearSolverKind::Banded, true),
    ] {
        let n = 12;
        let a = matrix(n, far);
        let mut solver = LinearSolver::new(kind);
        solver.factor(&a, 1).unwrap();
        let b: Vec<Real> = (0..6 * n).map(|i| (i % 7) as Real - 3.0).collect();
        let mut x = b.clone();
        solver.solve_in_place(&mut x).unwrap();
        let dense = a.to_dense();
        for (column, solved) in b.chunks(3 * n).zip(x.chunks(3 * n)) {
            let exact = dense
                .clone()
                .cholesky()
                .unwrap()
                .solve(&DVector::from_column_slice(column));
            let error = (DVector::from_column_slice(solved) - &exact).norm() / exact.norm();
            assert!(error < 1e-12, "{kind:?}, far {far}: {error:e}");
        }
        // The indefinite factorisation takes the same path.
        if !far {
            solver.factor_indefinite(&a).unwrap();
            let mut y = b[..3 * n].to_vec();
            solver.solve_in_place(&mut y).unwrap();
            let exact = dense
                .cholesky()
                .unwrap()
                .solve(&DVector::from_column_slice(&b[..3 * n]));
            assert!((DVector::from(y) - &exact).norm() < 1e-12 * exact.norm());
        }
    }
}
