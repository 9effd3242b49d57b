//! Every Cholesky factorisation of the crate, and its solve, against one table of band
//! shapes ([`SHAPES`]) and one oracle (nalgebra's dense Cholesky of the same matrix).
//!
//! **Variants** ([`VARIANTS`]): the public solvers as the process's kernel set runs them
//! ([`BandedCholesky`], [`LinearSolver`]'s in-place banded path,
//! [`BatchedBandedCholesky`]'s copying and in-place factors, the indefinite
//! [`BandedLdlt`], the sparse [`BlockSparseCholesky`] and [`SparseCholesky`]) and each
//! compiled instance of the banded kernels whatever that set is: the scalar plain,
//! fused column-form and fused row-form factors ([`Instance`]) and the batched plain
//! and fused ones. The fused instances run where the processor has AVX2 and FMA.
//!
//! **Matrices.** Per shape, [`LANES`] SPD matrices of `n` blocks and block bandwidth
//! `b` (one per lane of the batched variants; the others solve each alone) and one
//! right-hand side each: either diagonally dominant pseudo-random bands, or
//! \\(\varepsilon I + D^T W D\\) with `D` the second difference along the blocks and
//! `W` a rotated diagonal of weights 1, ½, ¼ (the null space of `D`, the points on a
//! line, left to \\(\varepsilon\\): a condition number about \\(16/\varepsilon\\), 1.6e5).
//!
//! **Tolerances.** For every lane, with the oracle's solution \\(x^*\\):
//! \\(\|x - x^*\|_\infty \le 10^{-10} \|x^*\|_\infty\\) (agreement) and
//! \\(\|b - A x\|_\infty \le 10^{-12} \|A\|_\infty \|x\|_\infty\\) (backward error).

use crate::banded_cholesky::Instance;
use crate::banded_ldlt::BandedLdlt;
use crate::batched::BatchedBandedCholesky;
use crate::block_sparse::BlockSparseCholesky;
use crate::linear::{LinearSolver, LinearSolverKind, SparseCholesky};
use crate::BandedCholesky;
use nalgebra::{DMatrix, DVector, Matrix3, Rotation3, Unit, Vector3};
use splinerod_core::{BlockBanded, LaneBand, Lanes, Real, LANES};

/// How a shape's matrices are filled.
#[derive(Debug, Clone, Copy)]
pub(crate) enum Fill {
    /// Pseudo-random blocks, the diagonal made dominant.
    Dominant,
    /// \\(\varepsilon I + D^T W D\\) (module docs); needs `bw ≥ 2`.
    SecondDifference(Real),
}

/// One row of the table: `n` blocks, block bandwidth `bw`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Shape {
    /// Control points (3×3 blocks per side).
    pub n: usize,
    /// Block bandwidth.
    pub bw: usize,
    /// The matrices' entries.
    pub fill: Fill,
}

const fn shape(n: usize, bw: usize, fill: Fill) -> Shape {
    Shape { n, bw, fill }
}

/// The band shapes every variant is tested on: one block; bandwidth 0; bandwidth
/// `n − 1` and beyond (dense); sizes not divisible by [`LANES`]; the rods' usual
/// bandwidths 2, 3 and 5; ill-conditioned SPD matrices.
pub(crate) const SHAPES: &[Shape] = &[
    shape(1, 0, Fill::Dominant),
    shape(1, 2, Fill::Dominant),
    shape(2, 1, Fill::Dominant),
    shape(3, 5, Fill::Dominant),
    shape(5, 0, Fill::Dominant),
    shape(7, 3, Fill::Dominant),
    shape(16, 3, Fill::Dominant),
    shape(16, 5, Fill::Dominant),
    shape(23, 5, Fill::Dominant),
    shape(30, 2, Fill::Dominant),
    shape(13, 2, Fill::SecondDifference(1e-4)),
    shape(21, 5, Fill::SecondDifference(1e-4)),
];

impl Shape {
    /// Lane `lane`'s matrix.
    pub(crate) fn matrix(&self, lane: usize) -> BlockBanded {
        let (n, bw) = (self.n, self.bw);
        let mut a = BlockBanded::zeros(n, bw);
        let seed = 0.3 + lane as Real;
        match self.fill {
            Fill::Dominant => {
                for i in 0..n {
                    for j in i..(i + bw + 1).min(n) {
                        let b = Matrix3::from_fn(|r, c| {
                            ((i * 31 + j * 17 + r * 7 + c * 3) as Real * seed).sin()
                        });
                        let b = if i == j {
                            b + b.transpose() + Matrix3::identity() * (6.0 + 12.0 * bw as Real)
                        } else {
                            b
                        };
                        a.add_block(i, j, &b);
                    }
                }
            }
            Fill::SecondDifference(eps) => {
                assert!(bw >= 2, "a second difference needs bandwidth 2");
                let axis = Vector3::new(1.0, seed.sin(), 0.3);
                let r = Rotation3::from_axis_angle(&Unit::new_normalize(axis), seed);
                let weights = Matrix3::from_diagonal(&Vector3::new(1.0, 0.5, 0.25));
                let mix = r.matrix() * weights * r.matrix().transpose();
                let floor = Matrix3::identity() * (eps * (1.0 + 0.1 * lane as Real));
                for i in 0..n {
                    a.add_block(i, i, &floor);
                }
                // Σ_i |x_i − 2 x_{i+1} + x_{i+2}|² in the mixed weights.
                let w = [1.0, -2.0, 1.0];
                for i in 0..n.saturating_sub(2) {
                    for p in 0..3 {
                        for q in p..3 {
                            a.add_block(i + p, i + q, &(mix * (w[p] * w[q])));
                        }
                    }
                }
            }
        }
        a
    }

    /// Lane `lane`'s right-hand side.
    pub(crate) fn rhs(&self, lane: usize) -> Vec<Real> {
        (0..3 * self.n)
            .map(|k| ((k * 13 + lane * 5) as Real * 0.71).cos())
            .collect()
    }
}

/// A variant's factor and solve: the solutions of `a[l] x = b[l]` for every lane, or
/// `None` where this processor cannot run it.
type Solve = fn(&[BlockBanded], &[Vec<Real>]) -> Option<Vec<Vec<Real>>>;

/// One factorisation under test.
struct Variant {
    /// What it is.
    name: &'static str,
    /// Whether it needs AVX2 and FMA (the other variants run everywhere).
    fused: bool,
    /// Its factor and solve.
    solve: Solve,
}

/// A variant that runs everywhere.
const fn any(name: &'static str, solve: Solve) -> Variant {
    Variant {
        name,
        fused: false,
        solve,
    }
}

/// A variant that needs AVX2 and FMA.
const fn fused(name: &'static str, solve: Solve) -> Variant {
    Variant {
        name,
        fused: true,
        solve,
    }
}

/// Each lane's matrix and right-hand side solved by `solve` (a scalar variant).
fn each(
    a: &[BlockBanded],
    b: &[Vec<Real>],
    mut solve: impl FnMut(&BlockBanded, &mut Vec<Real>),
) -> Option<Vec<Vec<Real>>> {
    Some(
        a.iter()
            .zip(b)
            .map(|(a, b)| {
                let mut x = b.clone();
                solve(a, &mut x);
                x
            })
            .collect(),
    )
}

/// A scalar kernel instance on each lane, where the processor runs it.
fn instance(kernel: Instance, a: &[BlockBanded], b: &[Vec<Real>]) -> Option<Vec<Vec<Real>>> {
    kernel.available().then_some(())?;
    each(a, b, |a, x| {
        let mut u = a.band_blocks().to_vec();
        kernel
            .factor_and_solve(&mut u, a.dim(), a.bandwidth(), x)
            .expect("definite");
    })
}

/// The matrices in lane form and the right-hand sides interleaved.
fn lanes(a: &[BlockBanded], b: &[Vec<Real>]) -> (LaneBand, Vec<Lanes>) {
    let (n, bw) = (a[0].dim(), a[0].bandwidth());
    let mut band = LaneBand::default();
    band.reset(n, bw);
    for i in 0..n {
        for (k, slot) in band.row_mut(i).iter_mut().enumerate() {
            for (lane, m) in a.iter().enumerate() {
                for (e, &v) in slot.iter_mut().zip(m.upper(i, k).as_slice()) {
                    e[lane] = v;
                }
            }
        }
    }
    let x = (0..3 * n)
        .map(|k| std::array::from_fn(|l| b[l][k]))
        .collect();
    (band, x)
}

/// Lane-form solutions, lane by lane.
fn unlanes(x: &[Lanes]) -> Vec<Vec<Real>> {
    (0..LANES)
        .map(|l| x.iter().map(|v| v[l]).collect())
        .collect()
}

/// A batched kernel instance (`fused` or plain), where the processor runs it.
fn batched_instance(fused: bool, a: &[BlockBanded], b: &[Vec<Real>]) -> Option<Vec<Vec<Real>>> {
    let (mut band, mut x) = lanes(a, b);
    let ok = BatchedBandedCholesky::default().factor_and_solve_with(fused, &mut band, &mut x)?;
    assert_eq!(ok, [true; LANES]);
    Some(unlanes(&x))
}

/// Every factorisation (module docs), by name.
const VARIANTS: &[Variant] = &[
    any("BandedCholesky", |a, b| {
        each(a, b, |a, x| {
            let mut f = BandedCholesky::new();
            f.factor(a).expect("definite");
            f.solve_in_place(x).expect("solve");
        })
    }),
    any("LinearSolver (banded, in place)", |a, b| {
        each(a, b, |a, x| {
            let mut f = LinearSolver::new(LinearSolverKind::Banded);
            f.factor(a, 0).expect("definite");
            assert_eq!(f.factored_with(), Some(LinearSolverKind::Banded));
            f.solve_in_place(x).expect("solve");
        })
    }),
    any("scalar plain kernels", |a, b| {
        instance(Instance::Plain, a, b)
    }),
    fused("scalar fused kernels, by columns", |a, b| {
        instance(Instance::FusedColumns, a, b)
    }),
    fused("scalar fused kernels, by rows", |a, b| {
        instance(Instance::FusedRows, a, b)
    }),
    any("BatchedBandedCholesky::factor", |a, b| {
        let mut f = BatchedBandedCholesky::default();
        f.factor(std::array::from_fn(|l| &a[l])).expect("definite");
        let (_, mut x) = lanes(a, b);
        f.solve_in_place(&mut x).expect("solve");
        Some(unlanes(&x))
    }),
    any("BatchedBandedCholesky::factor_band", |a, b| {
        let (mut band, mut x) = lanes(a, b);
        let mut f = BatchedBandedCholesky::default();
        assert_eq!(f.factor_band(&mut band), [true; LANES]);
        f.solve_in_place(&mut x).expect("solve");
        f.release_band(&mut band);
        Some(unlanes(&x))
    }),
    any("batched plain kernels", |a, b| {
        batched_instance(false, a, b)
    }),
    fused("batched fused kernels", |a, b| batched_instance(true, a, b)),
    any("BandedLdlt", |a, b| {
        each(a, b, |a, x| {
            let mut f = BandedLdlt::new();
            f.factor(a).expect("nonsingular");
            f.solve_in_place(x).expect("solve");
        })
    }),
    any("BlockSparseCholesky", |a, b| {
        each(a, b, |a, x| {
            let mut f = BlockSparseCholesky::new();
            f.factor(a, 0).expect("definite");
            f.solve_in_place(x).expect("solve");
        })
    }),
    any("SparseCholesky", |a, b| {
        each(a, b, |a, x| {
            let mut f = SparseCholesky::new();
            f.factor(a, 0).expect("definite");
            f.solve_in_place(x).expect("solve");
        })
    }),
];

/// Agreement with the oracle, relative to its solution's largest entry.
const AGREEMENT: Real = 1e-10;
/// Backward error, relative to `‖A‖∞ ‖x‖∞`.
const BACKWARD: Real = 1e-12;

/// The oracle: nalgebra's dense Cholesky solve.
fn oracle(a: &BlockBanded, b: &[Real]) -> DVector<Real> {
    let dense = a.to_dense();
    let factor = dense.cholesky().expect("the table's matrices are SPD");
    factor.solve(&DVector::from_column_slice(b))
}

#[test]
fn every_cholesky_variant_solves_every_band_shape_like_the_dense_oracle() {
    let mut ran = vec![0; VARIANTS.len()];
    for shape in SHAPES {
        let a: Vec<BlockBanded> = (0..LANES).map(|l| shape.matrix(l)).collect();
        let b: Vec<Vec<Real>> = (0..LANES).map(|l| shape.rhs(l)).collect();
        let exact: Vec<DVector<Real>> = a.iter().zip(&b).map(|(a, b)| oracle(a, b)).collect();
        for (v, variant) in VARIANTS.iter().enumerate() {
            let name = variant.name;
            let Some(x) = (variant.solve)(&a, &b) else {
                continue;
            };
            ran[v] += 1;
            for l in 0..LANES {
                let (dense, xl) = (a[l].to_dense(), DVector::from_column_slice(&x[l]));
                let gap = (&xl - &exact[l]).amax() / exact[l].amax();
                let norm = dense.row_iter().map(|r| r.abs().sum()).fold(0.0, Real::max);
                let backward =
                    (DVector::from_column_slice(&b[l]) - &dense * &xl).amax() / (norm * xl.amax());
                let at = format!("{name}, n {}, bw {}, lane {l}", shape.n, shape.bw);
                assert!(gap <= AGREEMENT, "{at}: {gap:e} from the oracle");
                assert!(backward <= BACKWARD, "{at}: backward error {backward:e}");
            }
        }
    }
    // Every variant this processor runs ran on every shape.
    let fma = Instance::FusedRows.available();
    for (v, variant) in VARIANTS.iter().enumerate() {
        let expected = if variant.fused && !fma {
            0
        } else {
            SHAPES.len()
        };
        assert_eq!(ran[v], expected, "{}", variant.name);
    }
}

#[test]
fn the_oracle_sees_the_ill_conditioned_shapes_as_such() {
    for shape in SHAPES {
        if let Fill::SecondDifference(eps) = shape.fill {
            let dense: DMatrix<Real> = shape.matrix(0).to_dense();
            let eigen = dense.symmetric_eigenvalues();
            let condition = eigen.max() / eigen.min();
            assert!(eigen.min() > 0.0 && condition > 1.0 / eps, "{condition:e}");
        }
    }
}
