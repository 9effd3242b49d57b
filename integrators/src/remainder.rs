//! The Newton step for a Hessian with a remainder that is not banded
//! ([`System::add_hessian_remainder`]): conjugate gradients preconditioned by the
//! factorised banded matrix.
//!
//! The Newton matrix is \\(A = P + sR\\): `P` the banded matrix Newton assembles and
//! factorises, `R` the remainder (positive semi-definite) and `s` the problem's
//! [`NewtonProblem::hessian_scale`]. With the pins \\(G\Delta x = c\\), the step
//! \\(\Delta x_0\\) from `P` satisfies the constraints; the exact step is
//! \\(\Delta x_0 + e\\) with \\(G e = 0\\) and
//!
//! \\[ A e + G^T \nu = -sR\, \Delta x_0 . \\]
//!
//! Conjugate gradients run in the null space of `G`, preconditioned by the KKT solve
//! with `P` and homogeneous constraints, \\(z = \mathcal{P}^{-1}\rho\\): `z` satisfies
//! \\(Gz = 0\\) and \\(Pz = \rho - G^T\nu\\), so the product needs no multiplication by `P`:
//!
//! \\[ A z_k \equiv \rho_k + sR\, z_k, \qquad A p_k = A z_k + \beta_k A p_{k-1}
//! \pmod{\operatorname{range} G^T}, \\]
//!
//! and the dropped \\(G^T\\) terms vanish in every inner product with a null-space vector
//! (`p`, `z`) and in the next preconditioner solve. Since \\(P \preceq A\\), the
//! preconditioned operator's eigenvalues lie in \\([1, \kappa]\\) with κ the ratio the
//! energy bounds (about 7.5 for the cubic rod's mixed stretching, where it matters only
//! in the stiff axial directions), so a few iterations reach the tolerance. Each costs
//! one back-substitution with the factor and one O(n) remainder product.
//!
//! The pins' multipliers stay those of the step from `P`: they are exact once Newton has
//! converged (the step, and with it the difference, is then zero). `P` must be
//! definite: Newton skips the correction when it factorised an indefinite matrix (the
//! exact Hessian of a compressed rod), and converges linearly there.

use crate::IntegratorError;
use nalgebra::Vector3;
use splinerod_core::Real;

/// Most conjugate-gradient iterations per Newton step.
pub const MAX_ITERATIONS: usize = 60;

/// Newton's correction ends once a change is below this fraction of the Newton
/// tolerance (in the unknowns' units).
pub const REMAINDER_FLOOR: Real = 1e-1;

/// The correction's floor is also at most this fraction of the largest entry of the
/// solve's first step from `P`: near rest, where a whole step is below the Newton
/// tolerance, the correction still resolves it, so a settling rod's motion keeps decaying
/// instead of jittering at the floor (measured on a damped 16-point cable: its speed
/// stalls at 3e-10 m/s with the floor alone, and decays to round-off, 1e-14 m/s, with
/// this bound, as with the lumped form).
pub const MOTION_FRACTION: Real = 1e-3;

/// Relative accuracy of the corrected step (largest entry of the last correction over
/// the step's).
pub const RELATIVE_TOLERANCE: Real = 1e-9;

/// `out += c · s R v` for the remainder `R` times its scale `s`, with `c` the second
/// argument.
pub type Remainder<'a> = dyn FnMut(&[Vector3<Real>], Real, &mut [Vector3<Real>]) + 'a;

/// `z ← 𝒫⁻¹ z`: the solve with the factorised banded matrix (and homogeneous pins).
pub type Preconditioner<'a> = dyn FnMut(&mut [Real]) -> Result<(), IntegratorError> + 'a;

/// A corrected step larger than this multiple of `P`'s is taken as divergence (a
/// safety net: with `P ⪯ A` the correction is smaller than the step): the correction is
/// dropped.
pub const DIVERGENCE: Real = 1e3;

/// Buffers of the correction (no allocation once sized).
#[derive(Debug, Default)]
pub struct RemainderCg {
    rho: Vec<Real>,
    z: Vec<Real>,
    p: Vec<Real>,
    ap: Vec<Real>,
    e: Vec<Real>,
    v: Vec<Vector3<Real>>,
    out: Vec<Vector3<Real>>,
}

impl RemainderCg {
    /// Corrects the flat step `dx` (from `P`, satisfying the pins) towards the step of
    /// `P + sR`, until a correction's largest entry is below `floor` or
    /// [`RELATIVE_TOLERANCE`] of the step's; returns the iterations taken.
    pub fn correct(
        &mut self,
        dx: &mut [Real],
        floor: Real,
        remainder: &mut Remainder<'_>,
        precondition: &mut Preconditioner<'_>,
    ) -> Result<usize, IntegratorError> {
        self.resize(dx.len() / 3);
        // ρ₀ = −sR Δx₀, z₀ = 𝒫⁻¹ρ₀.
        self.rho.iter_mut().for_each(|r| *r = 0.0);
        self.add_product(remainder, dx, -1.0, Target::Rho);
        self.z.copy_from_slice(&self.rho);
        precondition(&mut self.z)?;
        let mut gamma = dot(&self.rho, &self.z);
        if breakdown(gamma) {
            return Ok(0);
        }
        let start = largest(dx);
        self.p.copy_from_slice(&self.z);
        self.e.iter_mut().for_each(|e| *e = 0.0);
        self.ap.iter_mut().for_each(|a| *a = 0.0);
        let mut iterations = 0;
        let mut previous = Real::INFINITY;
        while iterations < MAX_ITERATIONS {
            iterations += 1;
            self.add_product_of_z(remainder);
            let pap = dot(&self.p, &self.ap);
            if breakdown(pap) {
                break;
            }
            let alpha = gamma / pap;
            let mut change: Real = 0.0;
            for (e, p) in self.e.iter_mut().zip(&self.p) {
                *e += alpha * p;
                change = change.max((alpha * p).abs());
            }
            let size = dx
                .iter()
                .zip(&self.e)
                .map(|(d, e)| (d + e).abs())
                .fold(0.0, Real::max);
            if remaining(change, previous) <= floor.max(RELATIVE_TOLERANCE * size) {
                break;
            }
            previous = change;
            if size.is_nan() || size > DIVERGENCE * start {
                // Not a contraction after all (round-off): keep P's step.
                self.e.iter_mut().for_each(|e| *e = 0.0);
                break;
            }
            for (r, ap) in self.rho.iter_mut().zip(&self.ap) {
                *r -= alpha * ap;
            }
            self.z.copy_from_slice(&self.rho);
            precondition(&mut self.z)?;
            let next = dot(&self.rho, &self.z);
            if breakdown(next) {
                break;
            }
            let beta = next / gamma;
            gamma = next;
            for ((p, z), ap) in self.p.iter_mut().zip(&self.z).zip(self.ap.iter_mut()) {
                *p = z + beta * *p;
                // Scaled here so that the next product only adds ρ + sR z.
                *ap *= beta;
            }
        }
        dx.iter_mut().zip(&self.e).for_each(|(d, e)| *d += e);
        Ok(iterations)
    }

    /// `ap += ρ + sR z`: with `ap` holding \\(\\beta A p_{k-1}\\), the product \\(A p_k\\).
    fn add_product_of_z(&mut self, remainder: &mut Remainder<'_>) {
        for (ap, r) in self.ap.iter_mut().zip(&self.rho) {
            *ap += r;
        }
        let z = std::mem::take(&mut self.z);
        self.add_product(remainder, &z, 1.0, Target::Ap);
        self.z = z;
    }

    /// Adds `sign · sR input` to the target buffer.
    fn add_product(
        &mut self,
        remainder: &mut Remainder<'_>,
        input: &[Real],
        sign: Real,
        target: Target,
    ) {
        for (v, c) in self.v.iter_mut().zip(input.chunks_exact(3)) {
            *v = Vector3::new(c[0], c[1], c[2]);
        }
        self.out.iter_mut().for_each(|o| *o = Vector3::zeros());
        remainder(&self.v, sign, &mut self.out);
        let buffer = match target {
            Target::Rho => &mut self.rho,
            Target::Ap => &mut self.ap,
        };
        for (b, o) in buffer.chunks_exact_mut(3).zip(&self.out) {
            b.iter_mut().zip(o.iter()).for_each(|(b, o)| *b += o);
        }
    }

    fn resize(&mut self, n: usize) {
        for v in [
            &mut self.rho,
            &mut self.z,
            &mut self.p,
            &mut self.ap,
            &mut self.e,
        ] {
            v.resize(3 * n, 0.0);
        }
        self.v.resize(n, Vector3::zeros());
        self.out.resize(n, Vector3::zeros());
    }
}

/// Which buffer a product goes to.
#[derive(Clone, Copy)]
enum Target {
    Rho,
    Ap,
}

/// The error left in the step after a correction of largest entry `change` that
/// followed one of `previous`: with the contraction `r = change / previous` seen, the
/// corrections still to come sum to about `change · r / (1 − r)`. Taken only for a clear
/// contraction (`r ≤ 1/2`); otherwise the change itself.
fn remaining(change: Real, previous: Real) -> Real {
    let r = change / previous;
    if previous.is_finite() && r <= 0.5 {
        change * r / (1.0 - r)
    } else {
        change
    }
}

/// An inner product that is not positive (possible only through round-off, `P` and
/// `A` being definite) ends the iteration.
fn breakdown(x: Real) -> bool {
    x.is_nan() || x <= Real::MIN_POSITIVE
}

fn largest(v: &[Real]) -> Real {
    v.iter().fold(0.0, |m: Real, x| m.max(x.abs()))
}

fn dot(a: &[Real], b: &[Real]) -> Real {
    a.iter().zip(b).map(|(a, b)| a * b).sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    /// A random-looking SPD matrix of size `m` (deterministic).
    fn spd(m: usize, seed: Real, shift: Real) -> DMatrix<Real> {
        let b = DMatrix::from_fn(m, m, |i, j| ((i * 7 + j * 13) as Real * seed).sin());
        &b * b.transpose() + DMatrix::identity(m, m) * shift
    }

    #[test]
    fn the_corrected_step_solves_the_whole_matrix() {
        let n = 5;
        let m = 3 * n;
        let p = spd(m, 0.37, 1.0);
        let r = spd(m, 0.91, 0.0) * 3.0;
        let b = DVector::from_fn(m, |i, _| (i as Real * 0.5).cos());
        let p_inv = p.clone().cholesky().expect("spd");
        let mut dx: Vec<Real> = p_inv.solve(&b).iter().copied().collect();
        let mut cg = RemainderCg::default();
        let iterations = cg
            .correct(
                &mut dx,
                0.0,
                &mut |v, sign, out| {
                    let flat = DVector::from_iterator(m, v.iter().flat_map(|v| [v.x, v.y, v.z]));
                    let y = &r * flat * sign;
                    for (o, c) in out.iter_mut().zip(y.as_slice().chunks_exact(3)) {
                        *o += Vector3::new(c[0], c[1], c[2]);
                    }
                },
                &mut |z| {
                    let x = p_inv.solve(&DVector::from_column_slice(z));
                    z.copy_from_slice(x.as_slice());
                    Ok(())
                },
            )
            .expect("correct");
        let exact = (&p + &r).cholesky().expect("spd").solve(&b);
        let error = (DVector::from_column_slice(&dx) - &exact).amax() / exact.amax();
        assert!(
            error < 1e-8,
            "error {error:e} after {iterations} iterations"
        );
        assert!(iterations <= m + 1);
    }
}
