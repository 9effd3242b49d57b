//! Newton matrices with far blocks (self-contact couplings outside the block band):
//! both linear solver kinds agree with a dense Cholesky solve, the banded factorisation
//! refuses them with an error, and the sparse path re-analyses exactly when the set of
//! far block positions changes.
//!
//! The matrices are a random, diagonally dominant (hence SPD) block band plus rank-one
//! terms \\(k\, u u^T\\), `k > 0`, with `u` supported on two distant groups of four
//! control points: each term adds in-band blocks and 16 far blocks, assembled through
//! `add_coupling` in either orientation, so that positions repeat and must be summed.

use nalgebra::{DMatrix, Matrix3, Vector3};
use splinerod_core::{BlockBanded, Real};
use splinerod_integrators::block_sparse::BlockSparseCholesky;
use splinerod_integrators::linear::{LinearSolver, SparseCholesky};
use splinerod_integrators::{BandedCholesky, IntegratorError, LinearSolverKind};

/// Deterministic xorshift64* generator (no dev-dependency needed).
struct Rng(u64);

impl Rng {
    /// Uniform in [-1, 1).
    fn next(&mut self) -> Real {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let bits = self.0.wrapping_mul(0x2545_f491_4f6c_dd1d) >> 11;
        2.0 * (bits as Real / (1u64 << 53) as Real) - 1.0
    }

    fn vector(&mut self) -> Vector3<Real> {
        Vector3::new(self.next(), self.next(), self.next())
    }

    fn matrix(&mut self) -> Matrix3<Real> {
        Matrix3::from_fn(|_, _| self.next())
    }
}

/// A random symmetric block band, made SPD by diagonal dominance: every row has at most
/// `3 (2 bw + 1)` entries of magnitude below 1 off the diagonal.
fn random_band(n: usize, bw: usize, rng: &mut Rng) -> BlockBanded {
    let mut a = BlockBanded::zeros(n, bw);
    let dominance = (3 * (2 * bw + 1) + 1) as Real;
    for i in 0..n {
        let d = rng.matrix();
        a.add_block(i, i, &((d + d.transpose()) * 0.5));
        a.add_block(i, i, &Matrix3::from_diagonal_element(dominance));
        for j in i + 1..(i + bw + 1).min(n) {
            a.add_block(i, j, &rng.matrix());
        }
    }
    a
}

/// Adds \\(k\, u u^T\\) with `u` random on control points `g..g + 4` and `h..h + 4`,
/// assembling each block pair once; `flip` assembles the lower blocks `(j, i)` instead.
fn add_rank_one(a: &mut BlockBanded, groups: [usize; 2], k: Real, flip: bool, rng: &mut Rng) {
    let support: Vec<usize> = groups.iter().flat_map(|&g| g..g + 4).collect();
    let u: Vec<Vector3<Real>> = support.iter().map(|_| rng.vector()).collect();
    for (x, &i) in support.iter().enumerate() {
        for (y, &j) in support.iter().enumerate().skip(x) {
            let b = u[x] * u[y].transpose() * k;
            if flip && i != j {
                a.add_coupling(j, i, &b.transpose());
            } else {
                a.add_coupling(i, j, &b);
            }
        }
    }
}

/// Right-hand sides, column after column.
fn rhs(dofs: usize, count: usize, rng: &mut Rng) -> Vec<Real> {
    (0..dofs * count).map(|_| rng.next()).collect()
}

/// Largest relative error of `x` against the dense Cholesky solution of `a x = b`, per
/// right-hand side. Tolerance 1e-10: these matrices have condition numbers below ~10²,
/// so both factorisations are accurate to ~1e-14.
fn dense_error(a: &BlockBanded, b: &[Real], x: &[Real]) -> Real {
    let dofs = 3 * a.dim();
    let chol = a.to_dense().cholesky().expect("test matrix is SPD");
    let mut worst: Real = 0.0;
    for (b, x) in b.chunks_exact(dofs).zip(x.chunks_exact(dofs)) {
        let exact = chol.solve(&DMatrix::from_column_slice(dofs, 1, b));
        let got = DMatrix::from_column_slice(dofs, 1, x);
        worst = worst.max((got - &exact).norm() / exact.norm());
    }
    worst
}

/// Band (n = 30, bw = 3) plus three rank-one terms on groups 2.. and 20.. (so their far
/// blocks coincide: duplicates), one of them assembled from the lower side, and one on
/// groups 0.. and 26..: long loops, factorised in AMD order.
fn contact_matrix(rng: &mut Rng) -> BlockBanded {
    let mut a = random_band(30, 3, rng);
    add_rank_one(&mut a, [2, 20], 5.0, false, rng);
    add_rank_one(&mut a, [2, 20], 1.0, true, rng);
    add_rank_one(&mut a, [0, 26], 2.0, false, rng);
    add_rank_one(&mut a, [2, 20], 0.5, false, rng);
    a
}

/// Band (n = 60, bw = 3) plus two rank-one terms on groups 2.. and 9..: far blocks
/// between nearby control points, which keep the natural ordering.
fn near_contact_matrix(rng: &mut Rng) -> BlockBanded {
    let mut a = random_band(60, 3, rng);
    add_rank_one(&mut a, [2, 9], 3.0, false, rng);
    add_rank_one(&mut a, [2, 9], 1.0, true, rng);
    a
}

#[test]
fn both_kinds_solve_far_blocks_like_a_dense_cholesky() {
    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    for (a, far) in [
        (contact_matrix(&mut rng), (2, 20)),
        (near_contact_matrix(&mut rng), (2, 9)),
    ] {
        assert!(a.has_far_blocks());
        // The far part matters: the dense matrix is not the band alone.
        let entry = a.to_dense()[(3 * far.0, 3 * far.1)];
        assert!(entry.abs() > 1e-3, "far entry {entry}");
        let b = rhs(3 * a.dim(), 2, &mut rng);
        for kind in [LinearSolverKind::Banded, LinearSolverKind::Sparse] {
            let mut solver = LinearSolver::new(kind);
            solver.factor(&a, 0).unwrap();
            assert_eq!(solver.factored_with(), Some(LinearSolverKind::Sparse));
            let mut x = b.clone();
            solver.solve_in_place(&mut x).unwrap();
            let error = dense_error(&a, &b, &x);
            assert!(error < 1e-10, "{kind:?}: relative error {error:e}");
        }
    }
}

#[test]
fn the_solver_returns_to_the_banded_path_without_far_blocks() {
    let mut rng = Rng(7);
    let (a, band) = (contact_matrix(&mut rng), random_band(30, 3, &mut rng));
    let mut solver = LinearSolver::new(LinearSolverKind::Banded);
    let b = rhs(90, 1, &mut rng);
    for m in [&a, &band, &a] {
        solver.factor(m, 0).unwrap();
        let expected = if m.has_far_blocks() {
            LinearSolverKind::Sparse
        } else {
            LinearSolverKind::Banded
        };
        assert_eq!(solver.factored_with(), Some(expected));
        let mut x = b.clone();
        solver.solve_in_place(&mut x).unwrap();
        assert!(dense_error(m, &b, &x) < 1e-10);
    }
}

#[test]
fn the_banded_cholesky_refuses_far_blocks() {
    let a = contact_matrix(&mut Rng(3));
    let mut banded = BandedCholesky::new();
    let err = banded.factor(&a).unwrap_err();
    assert!(matches!(err, IntegratorError::SolverState(_)), "{err}");
    // And it does not keep a stale factorisation around to solve with.
    banded.factor(&random_band(30, 3, &mut Rng(4))).unwrap();
    assert!(banded.factor(&a).is_err());
    let mut x = vec![1.0; 90];
    assert!(banded.solve_in_place(&mut x).is_err());
}

#[test]
fn a_far_block_moved_into_the_band_is_an_error_not_a_panic() {
    let mut a = contact_matrix(&mut Rng(5));
    let row = a.far_blocks()[0].row;
    a.far_blocks_mut()[0].col = row + 1;
    for kind in [LinearSolverKind::Banded, LinearSolverKind::Sparse] {
        let mut solver = LinearSolver::new(kind);
        let err = solver.factor(&a, 0).unwrap_err();
        assert!(matches!(err, IntegratorError::SolverState(_)), "{err}");
        assert!(solver.solve_in_place(&mut [0.0; 90]).is_err());
    }
}

#[test]
fn a_non_definite_matrix_with_far_blocks_is_reported() {
    let mut a = contact_matrix(&mut Rng(6));
    a.add_coupling(1, 25, &Matrix3::from_diagonal_element(1e6));
    let err = LinearSolver::new(LinearSolverKind::Banded)
        .factor(&a, 0)
        .unwrap_err();
    assert!(
        matches!(err, IntegratorError::NotPositiveDefinite { .. }),
        "{err}"
    );
}

/// The two sparse factorisations: faer's scalar one and the block one the Newton
/// solves use.
trait Sparse {
    fn factor(&mut self, a: &BlockBanded, epoch: u64) -> Result<bool, IntegratorError>;
    fn solve_in_place(&mut self, x: &mut [Real]) -> Result<(), IntegratorError>;
    fn analyses(&self) -> usize;
}

impl Sparse for SparseCholesky {
    fn factor(&mut self, a: &BlockBanded, epoch: u64) -> Result<bool, IntegratorError> {
        SparseCholesky::factor(self, a, epoch)
    }
    fn solve_in_place(&mut self, x: &mut [Real]) -> Result<(), IntegratorError> {
        SparseCholesky::solve_in_place(self, x)
    }
    fn analyses(&self) -> usize {
        SparseCholesky::analyses(self)
    }
}

impl Sparse for BlockSparseCholesky {
    fn factor(&mut self, a: &BlockBanded, epoch: u64) -> Result<bool, IntegratorError> {
        BlockSparseCholesky::factor(self, a, epoch)
    }
    fn solve_in_place(&mut self, x: &mut [Real]) -> Result<(), IntegratorError> {
        BlockSparseCholesky::solve_in_place(self, x)
    }
    fn analyses(&self) -> usize {
        BlockSparseCholesky::analyses(self)
    }
}

/// Factors `a` and checks the solve; returns whether a symbolic analysis ran.
fn factor_checked(solver: &mut dyn Sparse, a: &BlockBanded, epoch: u64) -> bool {
    let analysed = solver.factor(a, epoch).unwrap();
    let b = rhs(3 * a.dim(), 1, &mut Rng(11));
    let mut x = b.clone();
    solver.solve_in_place(&mut x).unwrap();
    let error = dense_error(a, &b, &x);
    assert!(error < 1e-10, "relative error {error:e}");
    analysed
}

#[test]
fn re_analysis_happens_exactly_when_the_far_pattern_changes() {
    re_analysis_follows_the_far_pattern(&mut SparseCholesky::new());
    re_analysis_follows_the_far_pattern(&mut BlockSparseCholesky::new());
}

fn re_analysis_follows_the_far_pattern(solver: &mut dyn Sparse) {
    let mut rng = Rng(0x1234_5678);
    let band = random_band(30, 3, &mut rng);
    assert!(factor_checked(solver, &band, 0), "first factorisation");
    let mut scaled = band.clone();
    scaled.scale(2.0);
    assert!(!factor_checked(solver, &scaled, 0), "band values only");

    let coupling = Matrix3::from_diagonal_element(0.5);
    let mut contact = band.clone();
    contact.add_coupling(1, 20, &coupling);
    contact.add_coupling(25, 4, &coupling);
    assert!(factor_checked(solver, &contact, 0), "far pattern appears");
    let mut values = contact.clone();
    values.far_blocks_mut()[0].block *= 3.0;
    values.add_coupling(2, 2, &coupling);
    assert!(!factor_checked(solver, &values, 0), "values only");

    // Same positions, other order, other duplicate counts.
    let mut reordered = band.clone();
    reordered.add_coupling(4, 25, &(coupling * 0.5));
    reordered.add_coupling(20, 1, &coupling);
    reordered.add_coupling(4, 25, &(coupling * 0.5));
    assert!(!factor_checked(solver, &reordered, 0), "duplicates");
    assert_eq!(reordered.to_dense(), contact.to_dense());

    let mut more = contact.clone();
    more.add_coupling(0, 29, &coupling);
    assert!(factor_checked(solver, &more, 0), "a new position");
    assert!(factor_checked(solver, &contact, 0), "a position gone");
    assert!(factor_checked(solver, &contact, 1), "a new epoch");
    assert!(factor_checked(solver, &band, 1), "contact released");
    assert!(!factor_checked(solver, &band, 1), "nothing changed");
    assert_eq!(solver.analyses(), 6);
}

#[test]
fn the_linear_solver_counts_analyses_of_far_blocks_for_either_kind() {
    let mut rng = Rng(99);
    let a = contact_matrix(&mut rng);
    for kind in [LinearSolverKind::Banded, LinearSolverKind::Sparse] {
        let mut solver = LinearSolver::new(kind);
        for _ in 0..3 {
            solver.factor(&a, 0).unwrap();
        }
        assert_eq!(solver.analyses(), 1, "{kind:?}");
    }
}

#[test]
fn the_block_factorisation_agrees_with_faer_on_random_contact_patterns() {
    let mut rng = Rng(0xdead_beef);
    for (n, bw, loops) in [(12, 2, 1), (40, 3, 4), (80, 5, 6), (300, 3, 10)] {
        let mut a = random_band(n, bw, &mut rng);
        // Disjoint groups (overlapping ones would add unsymmetric diagonal blocks): one
        // in each half of the rod.
        let half = (n / 2 - 4) as Real;
        for k in 0..loops {
            let g = ((rng.next() + 1.0) * 0.5 * half) as usize;
            let h = n / 2 + ((rng.next() + 1.0) * 0.5 * half) as usize;
            add_rank_one(&mut a, [g, h], 1.5 + rng.next(), k % 2 == 1, &mut rng);
        }
        let b = rhs(3 * n, 2, &mut rng);
        let (mut x, mut y) = (b.clone(), b.clone());
        let mut faer = SparseCholesky::new();
        faer.factor(&a, 0).unwrap();
        faer.solve_in_place(&mut x).unwrap();
        let mut block = BlockSparseCholesky::new();
        block.factor(&a, 0).unwrap();
        block.solve_in_place(&mut y).unwrap();
        let scale = x.iter().fold(0.0, |m: Real, v| m.max(v.abs()));
        let worst = x
            .iter()
            .zip(&y)
            .fold(0.0, |m: Real, (p, q)| m.max((p - q).abs()));
        assert!(worst <= 1e-12 * scale, "n = {n}: {worst:e}");
        assert!(dense_error(&a, &b, &y) < 1e-10, "n = {n}");
    }
}

#[test]
fn the_block_factorisation_reports_an_indefinite_matrix() {
    let mut a = contact_matrix(&mut Rng(6));
    a.add_coupling(1, 25, &Matrix3::from_diagonal_element(1e6));
    let mut block = BlockSparseCholesky::new();
    let err = block.factor(&a, 0).unwrap_err();
    assert!(
        matches!(err, IntegratorError::NotPositiveDefinite { .. }),
        "{err}"
    );
    assert!(block.solve_in_place(&mut [0.0; 90]).is_err());
}
