//! The discrete holonomy of a rod's tangent: the angle by which a director, carried by
//! parallel transport from the start clamp along the centreline to the end clamp, misses
//! the end clamp's director.
//!
//! The tangent is sampled at points \\(s_1 < \dots < s_N\\) (`Samples`): the domain
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
//! \\(K_x = (-2\[y\]_\times - K y^T)/(1 + x\cdot y)\\),
//! \\(K_y = (2\[x\]_\times - K x^T)/(1 + x\cdot y)\\) and \\(P_k = I - T_k T_k^T\\):
//! \\(\partial h_k/\partial a_{k+1} = K_y(T_k, T_{k+1}) P_{k+1} / (2|a_k||a_{k+1}|)\\)
//! and \\(\partial h_k/\partial a_k = (K_y(T_{k-1}, T_k) + K_x(T_k, T_{k+1}))
//! P_k/(2|a_k|^2) - (\kappa b_k + \kappa b_{k+1}) a_k^T/(2|a_k|^3)\\). Consecutive samples
//! share a span or meet at a knot, so the Hessian stays in the band of the rod (one
//! more at a kink, where the knot is not sampled: see `Samples::bandwidth`).
//!
//! Everything is a pass over the samples: O(n), no allocation once sized.

use nalgebra::{Matrix3, Vector3};
use splinerod_core::basis::{spans, MAX_ORDER};
use splinerod_core::{BasisValues, Real, Rod};

/// The basis row of one tangent sample: the non-zero first derivatives of the basis
/// functions there (exact zeros trimmed).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Row {
    /// First control point of the row.
    pub first: usize,
    /// Number of entries in `d1`.
    pub len: usize,
    /// \\(b'_{first+k}(s)\\).
    pub d1: [Real; MAX_ORDER],
}

impl Row {
    fn new(first: usize, d1: &[Real]) -> Self {
        let lead = d1.iter().take_while(|v| **v == 0.0).count();
        let trail = d1[lead..].iter().rev().take_while(|v| **v == 0.0).count();
        let len = d1.len() - lead - trail;
        let mut row = [0.0; MAX_ORDER];
        row[..len].copy_from_slice(&d1[lead..lead + len]);
        Self {
            first: first + lead,
            len,
            d1: row,
        }
    }

    /// Last control point of the row.
    pub fn last(&self) -> usize {
        self.first + self.len.max(1) - 1
    }
}

/// The tangent samples of a rod: their rows (rebuilt when the rod's topology epoch
/// changes) and, for the current positions, \\(a_k = C'(s_k)\\), \\(|a_k|\\) and
/// \\(T_k\\). Reused across calls: no allocation unless the knots changed.
#[derive(Debug, Clone, Default)]
pub(crate) struct Samples {
    epoch: Option<u64>,
    /// Basis rows, in order of `s`.
    pub rows: Vec<Row>,
    /// Block bandwidth the rows need (see [`Samples::bandwidth`]).
    bandwidth: usize,
    /// \\(a_k\\).
    pub a: Vec<Vector3<Real>>,
    /// \\(|a_k|\\).
    pub norm: Vec<Real>,
    /// \\(T_k = a_k / |a_k|\\).
    pub t: Vec<Vector3<Real>>,
    /// The two polygons, as sample indices: [`FINE`] (every sample) and [`COARSE`]
    /// (the knots and the domain ends).
    pub polygons: [Vec<usize>; 2],
}

/// Index of the fine polygon (knots and span midpoints).
pub(crate) const FINE: usize = 0;
/// Index of the coarse polygon (knots only).
pub(crate) const COARSE: usize = 1;
/// Richardson weights of the two polygons' holonomies: \\((4\psi_f - \psi_c)/3\\)
/// cancels their O(h²) sampling error.
pub(crate) const WEIGHTS: [Real; 2] = [4.0 / 3.0, -1.0 / 3.0];

impl Samples {
    /// Rows for `rod`'s basis (rebuilt if its topology epoch changed) and the tangents
    /// at its current positions.
    pub fn prepare(&mut self, rod: &Rod) {
        self.prepare_rows(rod);
        let positions = &rod.positions;
        self.a.clear();
        self.a.extend(self.rows.iter().map(|r| {
            (0..r.len).fold(Vector3::zeros(), |a, k| {
                a + positions[r.first + k] * r.d1[k]
            })
        }));
        self.norm.clear();
        self.norm.extend(self.a.iter().map(|a| a.norm()));
        self.t.clear();
        self.t
            .extend(self.a.iter().zip(&self.norm).map(|(a, n)| a / *n));
    }

    /// The block bandwidth the holonomy's Hessian needs on `rod`: the largest distance
    /// between control points of consecutive samples (the degree, or more across an
    /// unsampled kink).
    pub fn bandwidth(&mut self, rod: &Rod) -> usize {
        self.prepare_rows(rod);
        self.bandwidth
    }

    fn prepare_rows(&mut self, rod: &Rod) {
        if self.epoch == Some(rod.topology_epoch()) {
            return;
        }
        self.rows.clear();
        self.polygons.iter_mut().for_each(Vec::clear);
        let basis = rod.basis();
        let d = basis.degree();
        let mut values = BasisValues::default();
        let mut at = |s: Real, rows: &mut Vec<Row>| {
            // Inside the domain by construction; a failure leaves an empty row (a zero
            // tangent, which makes the energy NaN rather than misaligning the samples).
            match basis.evaluate(s, &mut values) {
                Ok(()) => rows.push(Row::new(values.first, &values.d1[..values.order])),
                Err(_) => rows.push(Row::new(0, &[])),
            }
        };
        let (start, end) = basis.domain();
        let coarse = &mut self.polygons[COARSE];
        coarse.push(self.rows.len());
        at(start, &mut self.rows);
        for span in spans(basis) {
            // Every interior knot, by its right limit (where the tangent jumps, at a knot
            // of multiplicity ≥ d, the geodesic from the left sample crosses the jump).
            if span.start > start {
                coarse.push(self.rows.len());
                at(span.start, &mut self.rows);
            }
            at(0.5 * (span.start + span.end), &mut self.rows);
        }
        // A closed rod's end is its start: its polygons close on themselves.
        if !rod.is_closed() {
            coarse.push(self.rows.len());
            at(end, &mut self.rows);
        }
        self.polygons[FINE].extend(0..self.rows.len());
        let rows = &self.rows;
        self.bandwidth = self.polygons.iter().fold(d, |width, polygon| {
            polygon.windows(2).fold(width, |width, pair| {
                let (a, b) = (&rows[pair[0]], &rows[pair[1]]);
                width.max(b.last().saturating_sub(a.first))
            })
        });
        self.epoch = Some(rod.topology_epoch());
    }
}

/// Whether the rod is cut somewhere (an interior knot of multiplicity above the degree:
/// the pieces are separate, and a piece with a free end carries no twist).
pub(crate) fn is_cut(rod: &Rod) -> bool {
    let basis = rod.basis();
    let (d, n) = (basis.degree(), basis.count());
    let knots = &basis.knots()[d + 1..n];
    knots.windows(d + 1).any(|w| w[0] == w[d]) || rod.is_cut_at_seam()
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
pub fn transport(a: &Vector3<Real>, b: &Vector3<Real>, v: &Vector3<Real>) -> Vector3<Real> {
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
