//! Derivatives by the rest length `L` (the parameter `"rest_length"` of [`Parameters`](crate::parameters::Parameters),
//! issue #48): the rod's parametric domain is `[0, L]` with its knots, quadrature
//! weights and every material coordinate of the scene at fixed fractions of it, so for
//! fixed control points `q` a point at the fraction `u` stays where it is
//! (\\(b_i(uL; L) = B_i(u)\\)) while \\(C' = C_u/L\\), \\(C'' = C_{uu}/L^2\\) and
//! \\(ds = L\,du\\) change. What each energy's gradient does then, \\(\partial_L\nabla E\\) at
//! fixed `q`:
//!
//! * **Energies homogeneous in the lengths.** If scaling every length by `λ` — the
//!   positions and the rest length together — scales the energy by \\(\lambda^k\\),
//!   \\(E(\lambda q; \lambda L) = \lambda^k E(q; L)\\), then its gradient scales by
//!   \\(\lambda^{k-1}\\) and differentiating at \\(\lambda = 1\\) gives exactly
//!
//!   \\[ \frac{\partial \nabla E}{\partial L} = \frac{(k - 1)\,\nabla E - K\,(q - q_0)}{L}, \\]
//!
//!   with `K` the exact Hessian (its remainder included) and any fixed `q_0` (the
//!   energies are translation invariant: `K` annihilates a rigid shift; `q_0 = q_0` of
//!   the rod keeps the product free of the positions' offset). Stretching (every
//!   formulation: the Green–Lagrange strain is dimensionless, the mixed forms' Gram
//!   matrices and tension integrals scale with `ds`) has `k = 1`; bending
//!   (\\(\kappa^2\, ds\\), its fold guard a function of the dimensionless \\(|C'|^2\\))
//!   has `k = -1` ([`add_homogeneous`]).
//! * **Energies with an explicit power of `L`.** Twist \\(GJ\,\mathrm{Tw}^2/(2L)\\) with
//!   `Tw` a function of the tangents' directions at fixed fractions: \\(-\nabla E/L\\).
//!   Gravity, \\(-g\cdot\sum_i m_i q_i\\) with \\(m_i = \int\mu b_i\, ds \propto L\\):
//!   \\(\nabla E/L\\). A penalty clamp \\(\tfrac k2|P C'(s)|^2\\) at a fixed fraction, `k`
//!   fixed: \\(-2\nabla E/L\\) (a scene's clamp stiffness \\(10^6 EI/L\\) follows `L` too:
//!   its caller adds that). Point forces and springs at fixed fractions: zero. Contact:
//!   the obstacles' and floor's sums \\(\sum_a w_a \phi/(2r)\\) and the frozen friction
//!   forces have weights \\(\propto L\\) (\\(\nabla E/L\\)), the self-contact's double sum
//!   \\(\sum w_a w_b \phi/(2r)^2\\) has \\(\propto L^2\\) (\\(2\nabla E/L\\)); the samples'
//!   count (a whole number of rest-length spacings) is held.

use crate::Energy;
use nalgebra::Vector3;
use splinerod_core::{BlockBanded, CoreError, HessianKind, Real, Rod};

/// The name of the rest-length parameter in [`crate::Parameters`].
pub const REST_LENGTH: &str = "rest_length";

/// `out += scale · ∇E / L` (an energy whose gradient is \\(\propto L^{scale}\\) at fixed
/// control points); an error unless the rod's rest length is finite and positive.
pub fn add_power(
    energy: &dyn Energy,
    rod: &Rod,
    scale: Real,
    out: &mut [Vector3<Real>],
) -> Result<bool, CoreError> {
    let l = rest_length(rod)?;
    crate::parameters::add_linear(energy, rod, l / scale, out)
}

/// `out += ((k − 1) ∇E − K (q − q₀)) / L` for an energy homogeneous of degree `k` in
/// the lengths (see the module docs), with `K` its exact Hessian and its remainder.
pub fn add_homogeneous(
    energy: &dyn Energy,
    rod: &Rod,
    degree: i32,
    out: &mut [Vector3<Real>],
) -> Result<bool, CoreError> {
    let l = rest_length(rod)?;
    let n = rod.len();
    let origin = rod.positions[0];
    let shifted: Vec<Vector3<Real>> = rod.positions.iter().map(|q| q - origin).collect();
    let mut hessian = BlockBanded::zeros(n, energy.bandwidth(rod));
    energy.add_hessian(rod, HessianKind::Exact, &mut hessian);
    let mut product = vec![Vector3::zeros(); n];
    hessian.mul_vec(&shifted, &mut product);
    if let Some(r) = energy.capabilities().remainder {
        if r.has_remainder(rod) {
            r.add_remainder(rod, &shifted, 1.0, &mut product);
        }
    }
    let mut gradient = vec![Vector3::zeros(); n];
    energy.add_gradient(rod, &mut gradient);
    let k = Real::from(degree);
    for ((o, g), p) in out.iter_mut().zip(&gradient).zip(&product) {
        *o += (g * (k - 1.0) - p) / l;
    }
    Ok(true)
}

/// The rod's rest length, checked finite and positive.
fn rest_length(rod: &Rod) -> Result<Real, CoreError> {
    let l = rod.material().rest_length;
    if l.is_finite() && l > 0.0 {
        Ok(l)
    } else {
        Err(CoreError::InvalidParameter {
            name: "rest_length",
            value: l,
            reason: "a derivative by the rest length needs it finite and positive",
        })
    }
}
