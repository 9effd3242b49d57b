//! The discrete holonomy of a rod's tangent: the angle by which a director, carried by
//! parallel transport from the start clamp along the centreline to the end clamp, misses
//! the end clamp's director.
//!
//! The tangent is sampled at points \\(s_1 < \dots < s_N\\) ([`Samples`]): the domain
//! ends, the rod's Gauss points and the interior knots where \\(C'\\) is continuous.
//! With \\(a_k = C'(s_k)\\), \\(T_k = a_k/|a_k|\\), and the clamp axes as \\(T_0\\) and
//! \\(T_{N+1}\\), the director \\(D_0\\) of the start clamp is carried from \\(T_k\\) to
//! \\(T_{k+1}\\) by the rotation about \\(T_k \times T_{k+1}\\) that takes one to the
//! other (discrete parallel transport, Bergou et al. 2008); the holonomy ψ is the signed
//! angle about \\(T_{N+1}\\) from the transported director to the end director `E`
//! (defined mod 2π; callers keep it continuous in time).
//!
//! **Gradient.** Moving one tangent changes ψ only through the spherical triangle it
//! spans with its neighbours, which gives the local formula (Bergou et al. 2008, §6)
//!
//! \\[ \frac{\partial\psi}{\partial T_k} = \tfrac12 (\kappa b_k + \kappa b_{k+1}),
//!     \qquad \kappa b_k = \frac{2\, T_{k-1}\times T_k}{1 + T_{k-1}\cdot T_k}, \\]
//!
//! tangent to the sphere at \\(T_k\\), so with \\(T = a/|a|\\):
//! \\(h_k := \partial\psi/\partial a_k = (\kappa b_k + \kappa b_{k+1})/(2|a_k|)\\), and
//! \\(\partial\psi/\partial q_i = \sum_k b_i'(s_k)\, h_k\\).
//!
//! **Hessian.** The exact derivative of that formula. With
//! \\(K(x, y) = 2\,x\times y/(1 + x\cdot y)\\),
//! \\(K_x = (-2[y]_\times - K y^T)/(1 + x\cdot y)\\),
//! \\(K_y = (2[x]_\times - K x^T)/(1 + x\cdot y)\\) and \\(P_k = I - T_k T_k^T\\):
//! \\(\partial h_k/\partial a_{k+1} = K_y(T_k, T_{k+1}) P_{k+1} / (2|a_k||a_{k+1}|)\\)
//! and \\(\partial h_k/\partial a_k = (K_y(T_{k-1}, T_k) + K_x(T_k, T_{k+1}))
//! P_k/(2|a_k|^2) - (\kappa b_k + \kappa b_{k+1}) a_k^T/(2|a_k|^3)\\). Consecutive samples
//! share a span or meet at a knot, so the Hessian stays in the band of the rod (one
//! more at a kink, where the knot is not sampled: see [`required_bandwidth`]).
//!
//! Everything is a walk over the samples with a window of three: O(n), no allocation.

use nalgebra::{Matrix3, Vector3};
use splinerod_core::basis::{spans, MAX_ORDER};
use splinerod_core::{BasisValues, Real, Rod};

/// One tangent sample: the non-zero first derivatives of the basis functions there
/// (exact zeros trimmed), \\(a = C'(s)\\), its length and direction.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Sample {
    /// First control point of the row.
    pub first: usize,
    /// Number of entries in `d1`.
    pub len: usize,
    /// \\(b'_{first+k}(s)\\).
    pub d1: [Real; MAX_ORDER],
    /// \\(a = C'(s)\\).
    pub a: Vector3<Real>,
    /// \\(|a|\\).
    pub norm: Real,
    /// \\(T = a/|a|\\).
    pub t: Vector3<Real>,
}

impl Sample {
    fn new(first: usize, d1: &[Real], positions: &[Vector3<Real>]) -> Self {
        let lead = d1.iter().take_while(|v| **v == 0.0).count();
        let trail = d1[lead..].iter().rev().take_while(|v| **v == 0.0).count();
        let len = d1.len() - lead - trail;
        let mut row = [0.0; MAX_ORDER];
        row[..len].copy_from_slice(&d1[lead..lead + len]);
        let first = first + lead;
        let a = (0..len).fold(Vector3::zeros(), |a, k| a + positions[first + k] * row[k]);
        let norm = a.norm();
        Self {
            first,
            len,
            d1: row,
            a,
            norm,
            t: a / norm,
        }
    }

    /// Last control point of the row.
    pub fn last(&self) -> usize {
        self.first + self.len.max(1) - 1
    }
}

/// Whether the rod is cut somewhere (an interior knot of multiplicity above the degree:
/// the pieces are separate, and a piece with a free end carries no twist).
pub(crate) fn is_cut(rod: &Rod) -> bool {
    let basis = rod.basis();
    let d = basis.degree();
    interior_multiplicities(rod).any(|(_, m)| m > d)
}

/// Interior knot values with their multiplicities.
fn interior_multiplicities(rod: &Rod) -> impl Iterator<Item = (Real, usize)> + '_ {
    let basis = rod.basis();
    let (d, n) = (basis.degree(), basis.count());
    let knots = &basis.knots()[d + 1..n];
    let mut i = 0;
    std::iter::from_fn(move || {
        let v = *knots.get(i)?;
        let m = knots[i..].iter().take_while(|k| **k == v).count();
        i += m;
        Some((v, m))
    })
}

/// Calls `f` on every tangent sample of `rod`, in order of `s`.
pub(crate) fn for_each_sample(rod: &Rod, mut f: impl FnMut(&Sample)) {
    let basis = rod.basis();
    let d = basis.degree();
    let positions = &rod.positions;
    let mut values = BasisValues::default();
    let mut at = |s: Real, f: &mut dyn FnMut(&Sample)| {
        if basis.evaluate(s, &mut values).is_ok() {
            f(&Sample::new(
                values.first,
                &values.d1[..values.order],
                positions,
            ));
        }
    };
    let (start, end) = basis.domain();
    at(start, &mut f);
    let quadrature = rod.quadrature();
    for span in spans(basis) {
        if span.start > start && multiplicity(basis.knots(), span.start) < d {
            at(span.start, &mut f);
        }
        for p in quadrature.points_in((span.start, span.end)) {
            let qp = quadrature.point(p);
            f(&Sample::new(qp.first, qp.d1, positions));
        }
    }
    at(end, &mut f);
}

fn multiplicity(knots: &[Real], v: Real) -> usize {
    knots.iter().filter(|k| **k == v).count()
}

/// The block bandwidth the holonomy's Hessian needs on `rod`: the largest distance
/// between control points of consecutive samples (the degree, or one more across an
/// unsampled kink).
pub(crate) fn required_bandwidth(rod: &Rod) -> usize {
    let mut width = rod.basis().degree();
    let mut previous: Option<Sample> = None;
    for_each_sample(rod, |s| {
        if let Some(p) = &previous {
            width = width.max(s.last().saturating_sub(p.first));
        }
        previous = Some(*s);
    });
    width
}

/// \\(K(x, y) = 2\, x \times y / (1 + x \cdot y)\\) (the discrete curvature binormal).
pub(crate) fn curvature_binormal(x: &Vector3<Real>, y: &Vector3<Real>) -> Vector3<Real> {
    x.cross(y) * (2.0 / (1.0 + x.dot(y)))
}

/// \\(\partial K/\partial x\\) and \\(\partial K/\partial y\\) at `(x, y)`.
pub(crate) fn curvature_binormal_jacobians(
    x: &Vector3<Real>,
    y: &Vector3<Real>,
) -> (Matrix3<Real>, Matrix3<Real>) {
    let c = 1.0 / (1.0 + x.dot(y));
    let k = x.cross(y) * (2.0 * c);
    let kx = (-y.cross_matrix() * 2.0 - k * y.transpose()) * c;
    let ky = (x.cross_matrix() * 2.0 - k * x.transpose()) * c;
    (kx, ky)
}

/// Parallel transport of `v` from unit vector `a` to unit vector `b` (the rotation about
/// \\(a \times b\\) taking `a` to `b`).
pub(crate) fn transport(a: &Vector3<Real>, b: &Vector3<Real>, v: &Vector3<Real>) -> Vector3<Real> {
    let c = a.cross(b);
    let cos = a.dot(b);
    v * cos + c.cross(v) + c * (c.dot(v) / (1.0 + cos))
}

/// Signed angle from `u` to `w` about unit `axis` (both across it), in (−π, π].
pub(crate) fn signed_angle(u: &Vector3<Real>, w: &Vector3<Real>, axis: &Vector3<Real>) -> Real {
    u.cross(w).dot(axis).atan2(u.dot(w))
}

/// Wraps an angle to (−π, π].
pub(crate) fn wrap(angle: Real) -> Real {
    let two_pi = 2.0 * std::f64::consts::PI;
    let w = angle - two_pi * (angle / two_pi).round();
    if w <= -std::f64::consts::PI {
        w + two_pi
    } else {
        w
    }
}
