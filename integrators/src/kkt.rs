//! Pins as linear equality constraints, solved by a Schur complement on the few
//! constraint rows: with `A` factorised, the KKT system
//!
//! \\[ \begin{pmatrix} A & G^T \\ G & 0 \end{pmatrix}
//! \begin{pmatrix} \Delta x \\ -\mu \end{pmatrix} =
//! \begin{pmatrix} -r \\ c - G x \end{pmatrix} \\]
//!
//! is solved as \\(y = -A^{-1} r\\), \\(Y = A^{-1} G^T\\), \\(S = G Y\\) (3k × 3k for k pins),
//! \\(\mu = S^{-1}(c - G x - G y)\\), \\(\Delta x = y + Y \mu\\): `3k + 1` back-substitutions.

use crate::linear::SparseCholesky;
use crate::IntegratorError;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BasisValues, BlockBanded, Pin, Real, Rod};

/// Constraint rows of the pins and the Schur complement workspace.
#[derive(Debug, Default)]
pub(crate) struct Constraints {
    rows: Vec<BasisValues>,
    /// Constraint right-hand sides `c`, one 3-vector per pin.
    pub targets: Vec<Vector3<Real>>,
    /// `Y = A⁻¹ Gᵀ`, 3k columns of length 3n, column-major.
    y: Vec<Real>,
    /// Cholesky factor of `S`, 3k × 3k row-major.
    schur: Vec<Real>,
    /// Scratch for the multipliers, 3k.
    sol: Vec<Real>,
    n: usize,
}

impl Constraints {
    /// Evaluates the pins' rows on the rod's current basis.
    pub fn setup(&mut self, rod: &Rod, pins: &[Pin]) -> Result<(), IntegratorError> {
        self.rows.clear();
        for pin in pins {
            self.rows.push(pin.row(rod)?);
        }
        self.targets.resize(pins.len(), Vector3::zeros());
        self.n = rod.len();
        Ok(())
    }

    /// Number of pins.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// The pins' rows.
    pub fn rows(&self) -> &[BasisValues] {
        &self.rows
    }

    /// `G x` for pin `p`.
    pub fn apply_row(&self, p: usize, x: &[Vector3<Real>]) -> Vector3<Real> {
        let b = &self.rows[p];
        b.combine(&b.value, x)
    }

    /// `out += scale · Gᵀ μ`.
    pub fn add_transpose(&self, mu: &[Vector3<Real>], scale: Real, out: &mut [Vector3<Real>]) {
        for (b, m) in self.rows.iter().zip(mu) {
            for k in 0..b.order {
                out[b.first + k] += m * (scale * b.value[k]);
            }
        }
    }

    /// Adds the augmented Lagrangian term `ρ GᵀG` to `a` (within the band: a pin's row
    /// spans `d + 1` consecutive control points).
    pub fn add_gram(&self, rho: Real, a: &mut BlockBanded) {
        if rho == 0.0 {
            return;
        }
        for b in &self.rows {
            for i in 0..b.order {
                for j in i..b.order {
                    let w = rho * b.value[i] * b.value[j];
                    a.add_block(b.first + i, b.first + j, &Matrix3::from_diagonal_element(w));
                }
            }
        }
    }

    /// `out += ρ Gᵀ (c − G x)`, the right-hand side matching [`add_gram`](Self::add_gram).
    pub fn add_gram_rhs(&self, rho: Real, x: &[Vector3<Real>], out: &mut [Vector3<Real>]) {
        if rho == 0.0 {
            return;
        }
        for (p, b) in self.rows.iter().enumerate() {
            let e = (self.targets[p] - self.apply_row(p, x)) * rho;
            for k in 0..b.order {
                out[b.first + k] += e * b.value[k];
            }
        }
    }

    /// Computes `Y = A⁻¹ Gᵀ` and factorises `S = G Y`.
    pub fn factor(&mut self, solver: &mut SparseCholesky) -> Result<(), IntegratorError> {
        let (m, dofs) = (3 * self.len(), 3 * self.n);
        if m == 0 {
            return Ok(());
        }
        self.y.clear();
        self.y.resize(m * dofs, 0.0);
        for (p, b) in self.rows.iter().enumerate() {
            for a in 0..3 {
                let col = &mut self.y[(3 * p + a) * dofs..(3 * p + a + 1) * dofs];
                for k in 0..b.order {
                    col[3 * (b.first + k) + a] = b.value[k];
                }
            }
        }
        solver.solve_in_place(&mut self.y)?;
        self.schur.clear();
        self.schur.resize(m * m, 0.0);
        for i in 0..m {
            for j in 0..m {
                self.schur[i * m + j] = self.row_dot(i, &self.y[j * dofs..(j + 1) * dofs]);
            }
        }
        dense_cholesky(&mut self.schur, m).map_err(|_| IntegratorError::RedundantPins)
    }

    /// Row `i` of `G` (pin `i / 3`, coordinate `i % 3`) dotted with a flat vector.
    fn row_dot(&self, i: usize, flat: &[Real]) -> Real {
        let (b, a) = (&self.rows[i / 3], i % 3);
        (0..b.order)
            .map(|k| b.value[k] * flat[3 * (b.first + k) + a])
            .sum()
    }

    /// Given `flat = -A⁻¹ r` and the current iterate `x`, turns `flat` into `Δx` and
    /// writes the multipliers `μ`.
    pub fn correct(&mut self, x: &[Vector3<Real>], flat: &mut [Real], mu: &mut [Vector3<Real>]) {
        let (m, dofs) = (3 * self.len(), 3 * self.n);
        let mut rhs = [0.0; 3];
        for p in 0..self.len() {
            let gx = self.apply_row(p, x);
            for (a, r) in rhs.iter_mut().enumerate() {
                *r = self.targets[p][a] - gx[a] - self.row_dot(3 * p + a, flat);
            }
            mu[p] = Vector3::from(rhs);
        }
        self.sol.clear();
        self.sol.extend(mu.iter().flat_map(|v| [v.x, v.y, v.z]));
        dense_cholesky_solve(&self.schur, m, &mut self.sol);
        for (p, v) in mu.iter_mut().enumerate() {
            *v = Vector3::new(self.sol[3 * p], self.sol[3 * p + 1], self.sol[3 * p + 2]);
        }
        for (j, s) in self.sol.iter().enumerate() {
            let col = &self.y[j * dofs..(j + 1) * dofs];
            flat.iter_mut().zip(col).for_each(|(f, c)| *f += s * c);
        }
    }
}

/// In-place lower Cholesky of a row-major `m × m` SPD matrix; fails on a pivot that is
/// not positive relative to the diagonal's scale (linearly dependent rows).
fn dense_cholesky(a: &mut [Real], m: usize) -> Result<(), ()> {
    let scale = (0..m).map(|i| a[i * m + i].abs()).fold(0.0, Real::max);
    for j in 0..m {
        let mut d = a[j * m + j];
        for k in 0..j {
            d -= a[j * m + k] * a[j * m + k];
        }
        if d.is_nan() || d <= 1e-12 * scale {
            return Err(());
        }
        let d = d.sqrt();
        a[j * m + j] = d;
        for i in j + 1..m {
            let mut s = a[i * m + j];
            for k in 0..j {
                s -= a[i * m + k] * a[j * m + k];
            }
            a[i * m + j] = s / d;
        }
    }
    Ok(())
}

/// Solves `L Lᵀ x = b` in place with the factor from [`dense_cholesky`].
fn dense_cholesky_solve(l: &[Real], m: usize, b: &mut [Real]) {
    for i in 0..m {
        let s: Real = (0..i).map(|k| l[i * m + k] * b[k]).sum();
        b[i] = (b[i] - s) / l[i * m + i];
    }
    for i in (0..m).rev() {
        let s: Real = (i + 1..m).map(|k| l[k * m + i] * b[k]).sum();
        b[i] = (b[i] - s) / l[i * m + i];
    }
}
