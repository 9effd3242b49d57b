//! The consistent Gram matrix of the tension functions, which turns the strain moments
//! into the tension coefficients of the mixed form ([`super::mixed`]):
//!
//! \\[ G_{jk} = \int \varphi_j\, \varphi_k\, dl_0, \qquad
//! \lambda = EA\, G^{-1} b, \qquad E = \tfrac{EA}{2}\, b^T G^{-1} b
//! = \tfrac{EA}{2} \int (\Pi \varepsilon)^2\, dl_0, \\]
//!
//! with \\(\Pi\\) the \\(L^2(dl_0)\\) projection onto the tension space. `G` is symmetric
//! positive definite and banded: functions of degree `d − 1` overlap with `d − 1`
//! neighbours on each side. It depends only on the basis, the quadrature and the rest
//! metric, so it is built and factorised (banded Cholesky, `G = UᵀU`) once per basis,
//! alongside [`super::table`]; a rod it does not match gets one built on the fly.
//!
//! Its row sums are the lumped weights \\(m_j = \int \varphi_j\, dl_0\\) (the functions
//! sum to one), and since its entries are non-negative, \\(\mathrm{diag}(m) - G\\) is
//! diagonally dominant: \\(G \preceq \mathrm{diag}(m)\\), so
//! \\(G^{-1} \succeq \mathrm{diag}(m)^{-1}\\). The lumped material stiffness is therefore a
//! lower bound of the consistent one, which is what makes it a preconditioner for the
//! Hessian's remainder (see [`crate::HessianRemainder::add_remainder`]).
//!
//! **Closed rods.** The periodic tension space has `m` functions (the seam's split pairs
//! `j`, `j + m` are one, [`super::seam`]), and its Gram matrix is cyclic: the last
//! `t = d − 1` functions overlap the first. With those `t` as the border `B` and the rest
//! as the interior `I` (whose block is banded: no interior pair couples across the seam),
//! the solve goes through the Schur complement
//!
//! \\[ S = G_{BB} - G_{IB}^T G_{II}^{-1} G_{IB}, \qquad
//! x_B = S^{-1}(r_B - G_{IB}^T G_{II}^{-1} r_I), \qquad
//! x_I = G_{II}^{-1} r_I - Z x_B,\ Z = G_{II}^{-1} G_{IB}, \\]
//!
//! O(m t²) to factorise and O(m t) per solve. The right-hand side of a split pair is the
//! sum of its halves' (the merged moment), and both halves get the pair's solution.

use super::Stretching;
use splinerod_core::{Real, Rod};

/// The banded Gram matrix of the tension functions `1 ..= n − 1` and its Cholesky factor
/// (with the border of a closed rod's cyclic matrix, see the module docs).
#[derive(Debug, Clone, Default)]
pub(super) struct TensionGram {
    /// Topology epoch and quadrature point count of the rod it was built for.
    built_for: Option<(u64, usize)>,
    /// Entries per row: the diagonal and `d − 1` neighbours to the right.
    width: usize,
    /// Row `i` (function `i + 1`): `U_{i,i+o}` at `i·width + o` once factorised. For a
    /// closed rod, the interior rows only.
    u: Vec<Real>,
    /// The cyclic border of a closed rod.
    border: Option<Border>,
}

/// The border of a closed rod's cyclic Gram matrix (see the module docs), row-major.
#[derive(Debug, Clone, Default)]
struct Border {
    /// Distinct tension functions `m` (= distinct control points).
    functions: usize,
    /// Border size `t`.
    size: usize,
    /// \\(G_{IB}\\): interior rows, `t` entries each.
    coupling: Vec<Real>,
    /// \\(Z = G_{II}^{-1} G_{IB}\\), same layout.
    z: Vec<Real>,
    /// The Schur complement, then its upper Cholesky factor (`t × t`).
    schur: Vec<Real>,
}

impl TensionGram {
    /// Whether it was built for `rod`'s current basis and quadrature.
    #[inline]
    pub fn matches(&self, rod: &Rod) -> bool {
        self.built_for == Some((rod.topology_epoch(), rod.quadrature().len()))
    }

    /// Builds and factorises `G` for `rod` with the rest metric of `energy`. Functions
    /// with an empty support (inside a cut) get a unit diagonal: their moment is zero,
    /// and so is their tension.
    pub fn build(&mut self, energy: &Stretching, rod: &Rod) {
        let d = rod.basis().degree();
        let stored = rod.len().saturating_sub(1);
        self.width = d.max(1);
        let (functions, size) = match rod.basis().periodic_count() {
            Some(m) => (m, (d - 1).min(m)),
            None => (stored, 0),
        };
        let interior = functions - size;
        self.u.clear();
        self.u.resize(interior * self.width, 0.0);
        let mut border = self.border.take().unwrap_or_default();
        border.functions = functions;
        border.size = size;
        for v in [&mut border.coupling, &mut border.z] {
            v.clear();
            v.resize(interior * size, 0.0);
        }
        border.schur.clear();
        border.schur.resize(size * size, 0.0);
        // Tension function f (1 ..= stored) is periodic function f − 1 or f − 1 − m.
        let periodic = |f: usize| {
            if f > functions {
                f - 1 - functions
            } else {
                f - 1
            }
        };
        let table = rod.quadrature();
        for p in 0..table.len() {
            let qp = table.point(p);
            let root = energy.root_g0(p);
            // lower[k] is function first + 1 + k.
            for (k, &phi) in qp.lower.iter().enumerate() {
                let f = qp.first + 1 + k;
                if f > stored {
                    break;
                }
                let w = qp.weight * root * phi;
                for (o, &other) in qp.lower[k..].iter().enumerate() {
                    if f + o <= stored {
                        let (a, b) = (periodic(f), periodic(f + o));
                        let value = if o > 0 && a == b { 2.0 } else { 1.0 } * w * other;
                        self.add(&mut border, a.min(b), a.max(b), value);
                    }
                }
            }
        }
        factor(&mut self.u, self.width);
        border.eliminate(&self.u, self.width);
        self.border = (size > 0).then_some(border);
        self.built_for = Some((rod.topology_epoch(), table.len()));
    }

    /// Adds `value` to the entry `(a, b)`, `a ≤ b`, of the (periodic) Gram matrix.
    fn add(&mut self, border: &mut Border, a: usize, b: usize, value: Real) {
        let (size, interior) = (border.size, border.functions - border.size);
        if b < interior {
            debug_assert!(
                b - a < self.width,
                "an interior pair couples across the seam"
            );
            self.u[a * self.width + (b - a)] += value;
        } else if a < interior {
            border.coupling[a * size + (b - interior)] += value;
        } else {
            let (i, j) = (a - interior, b - interior);
            border.schur[i * size + j] += value;
            if i != j {
                border.schur[j * size + i] += value;
            }
        }
    }

    /// Solves \\(G x = r\\) in place, with `r[j]` the entry of function `j` (`j = 0 ..= n`;
    /// entries `0` and `n` are not tension functions and are left alone; on a closed rod
    /// a split pair's entries are summed and both halves get the pair's solution).
    pub fn solve(&self, r: &mut [Real]) {
        let w = self.width.max(1);
        let Some(border) = &self.border else {
            let n = self.u.len() / w;
            return band_solve(&self.u, w, &mut r[1..=n]);
        };
        let (m, stored) = (border.functions, r.len().saturating_sub(2));
        for f in m + 1..=stored {
            r[f - m] += r[f];
        }
        border.solve(&self.u, w, &mut r[1..=m]);
        for f in m + 1..=stored {
            r[f] = r[f - m];
        }
    }
}

impl Border {
    /// `Z = G_II⁻¹ G_IB` and the Cholesky factor of the Schur complement, with `u` the
    /// factorised interior.
    fn eliminate(&mut self, u: &[Real], width: usize) {
        let (t, interior) = (self.size, self.functions - self.size);
        if t == 0 {
            return;
        }
        self.z.copy_from_slice(&self.coupling);
        let mut column = vec![0.0; interior];
        for c in 0..t {
            for (x, row) in column.iter_mut().zip(self.z.chunks_exact(t)) {
                *x = row[c];
            }
            band_solve(u, width, &mut column);
            for (x, row) in column.iter().zip(self.z.chunks_exact_mut(t)) {
                row[c] = *x;
            }
        }
        for (g, z) in self.coupling.chunks_exact(t).zip(self.z.chunks_exact(t)) {
            for i in 0..t {
                for j in 0..t {
                    self.schur[i * t + j] -= g[i] * z[j];
                }
            }
        }
        factor_dense(&mut self.schur, t);
    }

    /// Solves the periodic system in place (`x` the `m` merged entries).
    fn solve(&self, u: &[Real], width: usize, x: &mut [Real]) {
        let (t, interior) = (self.size, self.functions - self.size);
        let (inner, outer) = x.split_at_mut(interior);
        band_solve(u, width, inner);
        for (row, &y) in self.coupling.chunks_exact(t).zip(inner.iter()) {
            for (o, g) in outer.iter_mut().zip(row) {
                *o -= g * y;
            }
        }
        solve_dense(&self.schur, t, outer);
        for (row, y) in self.z.chunks_exact(t).zip(inner.iter_mut()) {
            *y -= row
                .iter()
                .zip(outer.iter())
                .map(|(z, x)| z * x)
                .sum::<Real>();
        }
    }
}

/// In-place banded Cholesky `G = UᵀU` (upper rows of `w` entries). `G` is a Gram matrix
/// of linearly independent functions, so its pivots are positive; a non-positive one
/// (a degenerate quadrature, an empty support) is replaced by the unit pivot of a
/// decoupled function.
fn factor(u: &mut [Real], w: usize) {
    let n = u.len() / w.max(1);
    for i in 0..n {
        let mut pivot = u[i * w];
        if pivot.is_nan() || pivot <= 0.0 {
            u[i * w + 1..(i + 1) * w].iter_mut().for_each(|x| *x = 0.0);
            pivot = 1.0;
        }
        let pivot = pivot.sqrt();
        u[i * w] = pivot;
        for o in 1..w.min(n - i) {
            u[i * w + o] /= pivot;
        }
        // Update the trailing rows i + a (a ≥ 1) with row i's entries.
        for a in 1..w.min(n - i) {
            let ua = u[i * w + a];
            for b in a..w.min(n - i) {
                u[(i + a) * w + (b - a)] -= ua * u[i * w + b];
            }
        }
    }
}

/// Solves `UᵀU x = r` in place with the banded factor `u` (rows of `w` entries); the
/// rows of a cubic's factor (3 entries) with the width a constant, which unrolls them.
fn band_solve(u: &[Real], w: usize, x: &mut [Real]) {
    match w {
        3 => band_solve_with::<3>(u, x),
        _ => band_solve_rows(u, w, x, 0..x.len().min(u.len() / w.max(1))),
    }
}

/// [`band_solve`] with rows of `W` entries: the rows whose entries all lie inside `x`
/// unrolled, the last `W − 1` by the general loops.
#[inline(always)]
fn band_solve_with<const W: usize>(u: &[Real], x: &mut [Real]) {
    let n = x.len().min(u.len() / W);
    let inner = n.saturating_sub(W - 1);
    // Uᵀ y = r, row by row of U.
    for (i, row) in u[..inner * W].chunks_exact(W).enumerate() {
        let yi = x[i] / row[0];
        x[i] = yi;
        let next = &mut x[i + 1..i + W];
        for o in 1..W {
            next[o - 1] -= row[o] * yi;
        }
    }
    forward_rows(u, W, x, inner..n);
    backward_rows(u, W, x, inner..n);
    // U x = y.
    for (i, row) in u[..inner * W].chunks_exact(W).enumerate().rev() {
        let (head, tail) = x[i..i + W].split_at_mut(1);
        let mut s = row[1] * tail[0];
        for o in 2..W {
            s += row[o] * tail[o - 1];
        }
        head[0] = (head[0] - s) / row[0];
    }
}

/// [`band_solve`] on the rows `range` (all of `x`'s) of a factor with rows of `w`.
fn band_solve_rows(u: &[Real], w: usize, x: &mut [Real], range: std::ops::Range<usize>) {
    forward_rows(u, w, x, range.clone());
    backward_rows(u, w, x, range);
}

/// The forward substitution `Uᵀ y = r` on rows `range` (those before it done).
#[inline(always)]
fn forward_rows(u: &[Real], w: usize, x: &mut [Real], range: std::ops::Range<usize>) {
    for i in range {
        let row = &u[i * w..(i + 1) * w];
        let yi = x[i] / row[0];
        x[i] = yi;
        for (x, &u) in x[i + 1..].iter_mut().zip(&row[1..]) {
            *x -= u * yi;
        }
    }
}

/// The back substitution `U x = y` on rows `range` (those after it done).
#[inline(always)]
fn backward_rows(u: &[Real], w: usize, x: &mut [Real], range: std::ops::Range<usize>) {
    for i in range.rev() {
        let row = &u[i * w..(i + 1) * w];
        let (head, tail) = x[i..].split_at_mut(1);
        let s: Real = tail.iter().zip(&row[1..]).map(|(x, &u)| u * x).sum();
        head[0] = (head[0] - s) / row[0];
    }
}

/// In-place dense Cholesky `S = UᵀU` of a symmetric `t × t` matrix (row-major; the
/// upper triangle gets `U`), with [`factor`]'s unit pivot for a non-positive one.
fn factor_dense(s: &mut [Real], t: usize) {
    for i in 0..t {
        for j in i..t {
            let sum = s[i * t + j] - (0..i).map(|k| s[k * t + i] * s[k * t + j]).sum::<Real>();
            s[i * t + j] = match (i == j, sum.is_nan() || sum <= 0.0) {
                (true, true) => 1.0,
                (true, false) => sum.sqrt(),
                (false, _) => sum / s[i * t + i],
            };
        }
    }
}

/// Solves `UᵀU x = r` in place with the dense factor of [`factor_dense`].
fn solve_dense(s: &[Real], t: usize, x: &mut [Real]) {
    for i in 0..t {
        let sum: Real = (0..i).map(|k| s[k * t + i] * x[k]).sum();
        x[i] = (x[i] - sum) / s[i * t + i];
    }
    for i in (0..t).rev() {
        let sum: Real = (i + 1..t).map(|k| s[i * t + k] * x[k]).sum();
        x[i] = (x[i] - sum) / s[i * t + i];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector, Vector3};
    use splinerod_core::{BSplineSpace, BasisSpace, Material, PeriodicBSplineSpace};

    /// The Gram matrix of the (periodic) tension functions, dense, by direct sums.
    fn dense_gram(rod: &Rod, functions: usize) -> DMatrix<Real> {
        let stored = rod.len() - 1;
        let index = |f: usize| (f - 1) % functions;
        let mut g = DMatrix::zeros(functions, functions);
        let table = rod.quadrature();
        for p in 0..table.len() {
            let qp = table.point(p);
            for (a, &pa) in qp.lower.iter().enumerate() {
                for (b, &pb) in qp.lower.iter().enumerate() {
                    let (fa, fb) = (qp.first + 1 + a, qp.first + 1 + b);
                    if fa <= stored && fb <= stored {
                        g[(index(fa), index(fb))] += qp.weight * pa * pb;
                    }
                }
            }
        }
        g
    }

    fn rod_on(space: Box<dyn BasisSpace>) -> Rod {
        let material = Material {
            rest_length: 1.3,
            linear_density: 0.1,
        };
        // Distinct points (the Gram matrix does not depend on them); a closed rod's copies.
        let distinct = space.periodic_count().unwrap_or(space.count());
        let positions = (0..space.count())
            .map(|i| i % distinct)
            .map(|i| Vector3::new(i as Real, (i * i) as Real * 0.1, 0.0))
            .collect();
        Rod::new(material, space, positions)
            .expect("rod")
            .with_quadrature_points(8)
            .expect("quadrature")
    }

    /// Solves with the factorised (cyclic) Gram matrix and checks `G x = r` densely, for
    /// open and closed rods of degrees 1 to 5 on irregular knots.
    #[test]
    fn the_solve_inverts_the_gram_matrix() {
        let breaks = [
            0.0, 0.07, 0.2, 0.26, 0.41, 0.5, 0.62, 0.7, 0.83, 0.9, 1.02, 1.1,
        ];
        for d in 1..=5 {
            let periodic = PeriodicBSplineSpace::new(d, breaks.to_vec(), 1.3).expect("space");
            let m = periodic.periodic_count().expect("periodic");
            let mut knots = vec![0.0; d + 1];
            knots.extend_from_slice(&breaks[1..]);
            knots.extend(std::iter::repeat_n(1.3, d + 1));
            let open = BSplineSpace::new(d, knots).expect("space");
            let cases: [(Box<dyn BasisSpace>, bool); 2] =
                [(Box::new(periodic), true), (Box::new(open), false)];
            for (space, closed) in cases {
                let rod = rod_on(space);
                let functions = if closed { m } else { rod.len() - 1 };
                let energy = Stretching::new(10.0).expect("stretching");
                let mut gram = TensionGram::default();
                gram.build(&energy, &rod);
                let dense = dense_gram(&rod, functions);
                let rhs = DVector::from_fn(functions, |j, _| (1.0 + j as Real * 0.7).sin());
                // r per stored function; a split pair's halves share the pair's entry.
                let mut r = vec![0.0; rod.len() + 1];
                for f in 1..rod.len() {
                    let share = if closed && f < d { 0.5 } else { 1.0 };
                    let j = (f - 1) % functions;
                    r[f] = rhs[j] * if closed && f > m { 0.5 } else { share };
                }
                gram.solve(&mut r);
                let x = DVector::from_fn(functions, |j, _| r[j + 1]);
                let residual = (&dense * &x - &rhs).amax();
                assert!(residual < 1e-12, "d = {d}, closed {closed}: {residual:e}");
                for f in m + 1..rod.len() {
                    if closed {
                        assert_eq!(r[f], r[f - m], "d = {d}: halves differ");
                    }
                }
            }
        }
    }
}
