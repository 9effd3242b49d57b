//! The Newton step for a Hessian with a remainder that is not banded
//! ([`crate::System::add_hessian_remainder`]): conjugate gradients preconditioned by the
//! factorised banded matrix.
//!
//! The Newton matrix is \\(A = P + sR\\): `P` the banded matrix Newton assembles and
//! factorises, `R` the remainder (positive semi-definite) and `s` the problem's
//! [`crate::newton::NewtonProblem::hessian_scale`]. With the pins \\(G\Delta x = c\\), the step
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

/// The relative accuracy of a static scene's tangent (sensitivity) solves' correction:
/// with 1e-9 a pin moved by the parameter left its force's derivative 2.5e-6 off (a
/// catenary's end pin moved along the span), with this 3e-10. (A run's tangents keep
/// [`RELATIVE_TOLERANCE`]: they are solved every step, and this one cost a 48-point
/// cable's run with three parameters 2.2–2.6 × the run instead of 1.8 ×.)
pub const TANGENT_TOLERANCE: Real = 1e-13;

/// `out += c · s R v` for the remainder `R` times its scale `s`, with `c` the second
/// argument.
pub type Remainder<'a> = dyn FnMut(&[Vector3<Real>], Real, &mut [Vector3<Real>]) + 'a;

/// `z ← 𝒫⁻¹ z`: the solve with the factorised banded matrix (and homogeneous pins).
pub type Preconditioner<'a> = dyn FnMut(&mut [Real]) -> Result<(), IntegratorError> + 'a;

/// A corrected step larger than this multiple of `P`'s is taken as divergence (a
/// safety net: with `P ⪯ A` the correction is smaller than the step): the correction is
/// dropped.
pub const DIVERGENCE: Real = 1e3;

/// Buffers of the correction (no allocation once sized). The preconditioner works on
/// flat coordinates (`z`), the remainder on 3-vectors (the rest).
#[derive(Debug, Default)]
pub struct RemainderCg {
    /// The preconditioned residual, flat.
    z: Vec<Real>,
    /// `z` as 3-vectors, the remainder's input.
    v: Vec<Vector3<Real>>,
    rho: Vec<Vector3<Real>>,
    p: Vec<Vector3<Real>>,
    /// \\(A p\\), then \\(\\beta A p + \\rho\\) for the next product to complete.
    ap: Vec<Vector3<Real>>,
    e: Vec<Vector3<Real>>,
    /// The relative accuracy asked for (0: [`RELATIVE_TOLERANCE`]).
    relative: Real,
}

impl RemainderCg {
    /// Asks the next corrections for the relative accuracy `relative` (`None`: the
    /// Newton steps' [`RELATIVE_TOLERANCE`]).
    pub fn set_relative_tolerance(&mut self, relative: Option<Real>) {
        self.relative = relative.unwrap_or(0.0);
    }

    /// The relative accuracy asked for.
    fn relative(&self) -> Real {
        if self.relative > 0.0 {
            self.relative
        } else {
            RELATIVE_TOLERANCE
        }
    }

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
        let Some((mut gamma, mut p_max)) = self.begin(dx, remainder, precondition)? else {
            return Ok(0);
        };
        let (start, relative) = (largest(dx), self.relative());
        let (mut iterations, mut previous) = (0, Real::INFINITY);
        // Σ of the changes: with `start`, a bound of the corrected step's largest entry.
        let mut moved = 0.0;
        while iterations < MAX_ITERATIONS {
            iterations += 1;
            // A p = (β A p₋₁ + ρ) + sR z.
            remainder(&self.v, 1.0, &mut self.ap);
            let pap: Real = self.p.iter().zip(&self.ap).map(|(p, a)| p.dot(a)).sum();
            if breakdown(pap) {
                break;
            }
            let alpha = gamma / pap;
            for (e, p) in self.e.iter_mut().zip(&self.p) {
                *e += p * alpha;
            }
            // max |α p| exactly (rounding is monotone and symmetric).
            let change = alpha.abs() * p_max;
            moved += change;
            let size = Bound {
                start,
                moved,
                floor,
                relative,
            }
            .size(dx, &self.e);
            if remaining(change, previous) <= floor.max(relative * size) {
                break;
            }
            previous = change;
            if size.is_nan() || size > DIVERGENCE * start {
                // Not a contraction after all (round-off): keep P's step.
                self.e.iter_mut().for_each(|e| *e = Vector3::zeros());
                break;
            }
            let next = self.next_residual(alpha, precondition)?;
            if breakdown(next) {
                break;
            }
            p_max = self.next_direction(next / gamma);
            gamma = next;
        }
        for (d, e) in dx.chunks_exact_mut(3).zip(&self.e) {
            d.iter_mut().zip(e.iter()).for_each(|(d, e)| *d += e);
        }
        Ok(iterations)
    }

    /// Sizes the buffers, sets \\(\\rho_0 = -sR\\, \\Delta x_0\\), `z₀ = 𝒫⁻¹ρ₀`, `p₀ = z₀`,
    /// `e = 0` and `ap = ρ₀` (the product's start); returns \\(\\gamma_0 = \\rho_0 \\cdot
    /// z_0\\) and the largest entry of `p₀`, or `None` on a breakdown.
    fn begin(
        &mut self,
        dx: &[Real],
        remainder: &mut Remainder<'_>,
        precondition: &mut Preconditioner<'_>,
    ) -> Result<Option<(Real, Real)>, IntegratorError> {
        self.resize(dx.len() / 3);
        for ((v, r), d) in self.v.iter_mut().zip(&mut self.rho).zip(dx.chunks_exact(3)) {
            (*v, *r) = (Vector3::new(d[0], d[1], d[2]), Vector3::zeros());
        }
        remainder(&self.v, -1.0, &mut self.rho);
        for (z, r) in self.z.chunks_exact_mut(3).zip(&self.rho) {
            z.copy_from_slice(r.as_slice());
        }
        let gamma = self.preconditioned(precondition)?;
        if breakdown(gamma) {
            return Ok(None);
        }
        let mut p_max: Real = 0.0;
        for ((p, e), (ap, (v, rho))) in self
            .p
            .iter_mut()
            .zip(self.e.iter_mut())
            .zip(self.ap.iter_mut().zip(self.v.iter().zip(&self.rho)))
        {
            (*p, *e, *ap) = (*v, Vector3::zeros(), *rho);
            p_max = p.iter().fold(p_max, |m, x| larger(m, x.abs()));
        }
        Ok(Some((gamma, p_max)))
    }

    /// `ρ −= α A p` and `z = 𝒫⁻¹ρ`; returns \\(\\rho \\cdot z\\).
    fn next_residual(
        &mut self,
        alpha: Real,
        precondition: &mut Preconditioner<'_>,
    ) -> Result<Real, IntegratorError> {
        for ((r, ap), z) in self
            .rho
            .iter_mut()
            .zip(&self.ap)
            .zip(self.z.chunks_exact_mut(3))
        {
            *r -= ap * alpha;
            z.copy_from_slice(r.as_slice());
        }
        self.preconditioned(precondition)
    }

    /// `p = z + β p` and `ap = β A p + ρ` (so that the next product only adds `sR z`);
    /// returns the largest entry of the new `p`.
    fn next_direction(&mut self, beta: Real) -> Real {
        let mut p_max: Real = 0.0;
        for ((p, v), (ap, rho)) in self
            .p
            .iter_mut()
            .zip(&self.v)
            .zip(self.ap.iter_mut().zip(&self.rho))
        {
            *p = v + *p * beta;
            p_max = p.iter().fold(p_max, |m, x| larger(m, x.abs()));
            *ap = *ap * beta + rho;
        }
        p_max
    }

    /// `z ← 𝒫⁻¹z` (`z` holding ρ), also as 3-vectors in `v`; returns \\(\\rho \\cdot z\\).
    fn preconditioned(
        &mut self,
        precondition: &mut Preconditioner<'_>,
    ) -> Result<Real, IntegratorError> {
        precondition(&mut self.z)?;
        let mut dot = 0.0;
        for ((v, z), r) in self.v.iter_mut().zip(self.z.chunks_exact(3)).zip(&self.rho) {
            *v = Vector3::new(z[0], z[1], z[2]);
            dot += r.dot(v);
        }
        Ok(dot)
    }

    fn resize(&mut self, n: usize) {
        self.z.resize(3 * n, 0.0);
        for v in [
            &mut self.v,
            &mut self.rho,
            &mut self.p,
            &mut self.ap,
            &mut self.e,
        ] {
            v.resize(n, Vector3::zeros());
        }
    }
}

/// What decides the corrected step's size without measuring it: `start` (the largest
/// entry of `P`'s step) plus `moved` (the sum of the changes so far) bounds every entry
/// of `dx + e`, and below [`DIVERGENCE`] `· start` and `floor / relative` (the relative
/// accuracy asked for) the size changes neither test it enters.
struct Bound {
    start: Real,
    moved: Real,
    floor: Real,
    relative: Real,
}

impl Bound {
    /// The largest entry of `dx + e`, or a bound of it that decides the same tests (a
    /// factor 2 above the sum, for the rounding of the sums).
    fn size(&self, dx: &[Real], e: &[Vector3<Real>]) -> Real {
        let bound = 2.0 * (self.start + self.moved);
        if bound <= DIVERGENCE * self.start && self.relative * bound <= self.floor {
            return bound;
        }
        let mut size: Real = 0.0;
        for (d, e) in dx.chunks_exact(3).zip(e) {
            for (d, e) in d.iter().zip(e.iter()) {
                size = larger(size, (d + e).abs());
            }
        }
        size
    }
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
    v.iter().fold(0.0, |m, x| larger(m, x.abs()))
}

/// `m.max(x)` for an `m` that is not NaN (a NaN `x` leaves `m`, as `max` does), in one
/// comparison: the NaN-propagating form of `max` costs several instructions per entry.
#[inline]
fn larger(m: Real, x: Real) -> Real {
    if x > m {
        x
    } else {
        m
    }
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
