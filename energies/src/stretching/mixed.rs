//! The mixed (assumed-strain) form of the stretching energy: the strain is projected
//! onto a tension space before it is squared.
//!
//! With tension functions \\(\varphi_k\\) and the rest length element
//! \\(dl_0 = \sqrt{g_0}\, ds\\), each function carries a strain moment and a weight
//!
//! \\[ b_k = \int \varphi_k\, \varepsilon\, dl_0, \qquad m_k = \int \varphi_k\, dl_0, \qquad
//! \varepsilon = \frac{|C'|^2 - g_0}{2 g_0}, \\]
//!
//! and the energy is \\(E = \sum_k \tfrac{EA}{2}\, b_k^2 / m_k\\): a Hellinger–Reissner
//! form whose tension \\(T = \sum_k \lambda_k \varphi_k\\), \\(\lambda_k = EA\, b_k/m_k\\),
//! is eliminated with the lumped (row-sum) Gram matrix, so the energy stays a function of
//! the control points alone. Its derivatives, with
//! \\(\partial b_k/\partial q_a = \int \varphi_k\, g_0^{-1/2}\, b_a' C'\, ds\\):
//!
//! \\[ \frac{\partial E}{\partial q_a} = \sum_k \lambda_k \frac{\partial b_k}{\partial q_a},
//! \qquad \frac{\partial^2 E}{\partial q_a \partial q_c} = \sum_k \frac{EA}{m_k}
//! \frac{\partial b_k}{\partial q_a} \frac{\partial b_k}{\partial q_c}^T
//! + \int T\, g_0^{-1/2}\, b_a' b_c'\, ds\; I. \\]
//!
//! [`HessianKind::Definite`] keeps the first (positive semi-definite) term and only the
//! positive part of `T` in the second.
//!
//! As `EA → ∞` the energy enforces \\(b_k = 0\\) for every `k`: inextensibility held
//! weakly, one constraint per tension function, not one per quadrature point — which is
//! what removes membrane locking.
//!
//! **The tension space** is the B-splines of degree `d − 1` on the rod's knots,
//! functions `1 ..= n − 1` (`n − 1` constraints for `3n` coordinates; their values are
//! tabulated as [`splinerod_core::QuadPoint::lower`]). It contains the derivative space
//! of the curve, follows every knot insertion, removal and cut (a cut's multiplicity
//! `d + 1` splits it into independent pieces), and each function spans `d` knot spans, so
//! the Hessian couples control points up to `2d − 1` apart ([`crate::Energy::bandwidth`]).
//!
//! **Why this form** (measured with `cargo run --release --example locking_table`: the
//! static catenary against the exact elastic catenary, 16 / 32 / 64 control points):
//!
//! | form | EA = 10² N | EA = 10⁶ N | EA = 10⁹ N |
//! |---|---|---|---|
//! | pointwise (paper eq. 12) | 2.1e-5 / 2.2e-7 / 7.8e-9 | 8.5e-3 / 3.8e-4 / 6.0e-6 | 1.2e-2 / 1.1e-2 / fails |
//! | reduced integration, 2–3 Gauss points | – | 7.7e-3 – 7.9e-3 at 16 | – |
//! | span means (tension piecewise constant) | 6.8e-4 / 7.5e-5 / 7.4e-6 | same | same |
//! | this form | 1.5e-5 / 2.8e-6 / 6.3e-7 | 4.3e-6 / 1.4e-7 / 7.6e-9 | same as 10⁶ |
//! | consistent Gram, one Neumann term | 4.5e-6 / 4.2e-7 / 7.8e-8 | 4.3e-6 / 1.4e-7 / 7.6e-9 | (bandwidth 3d − 2) |
//! | consistent Gram ([`super::StretchFormulation::MixedConsistent`]) | 4.5e-6 / 1.5e-7 / 7.9e-9 | 4.3e-6 / 1.4e-7 / 7.6e-9 | same as 10⁶ |
//! | local dual test functions (below) | 1.2e-4 / 1.5e-5 / 2.1e-6 | same | same |
//!
//! *Local dual test functions* (measured, not kept): test functions \\(\\psi_j\\) on the
//! support of \\(\\varphi_j\\) with \\(\\int \\psi_j \\varphi_k = U_{jk}\\) (`G = UᵀU`)
//! make \\(\\tfrac{EA}{2}\\sum_j (\\int \\psi_j \\varepsilon)^2\\) exact on the tension space with the
//! lumped form's band (checked to 1e-12 for degrees 2–4), but in the stiff limit they
//! hold \\(\\int \\psi_j \\varepsilon = 0\\), a worse approximation of inextensibility than
//! \\(b_j = 0\\): third order and 27 × the error at 16 points.
//!
//! Reduced integration keeps too many constraints (`d − 1` or more per span); span means
//! are EA-independent but only first order in the tension. The degree-`d − 1` tension
//! with the exact (consistent) Gram matrix would be the Hellinger–Reissner optimum, but
//! its condensed energy \\(b^T M^{-1} b\\) couples every control point with every other;
//! lumping keeps the band (2d − 1) and is exactly what the stiff regime needs: there the
//! tension is fixed by equilibrium, and the constitutive relation, the only place the
//! lumping enters, does not matter.
//!
//! **The price**, on stretchy rods: the lumped projection smooths a varying strain by
//! O(h²), so where the strain varies along the rod the convergence order drops from
//! `d + 1` to 2 (the EA = 10² N column; the longitudinal mode of a string stretched by
//! 20 % is off by 6e-3 at 16 control points, against 1e-5 pointwise). Uniform tension is
//! exact (the transverse string modes keep 3e-9).
//!
//! **The consistent Gram matrix** removes the price:
//! [`super::StretchFormulation::MixedConsistent`] takes the tension coefficients from
//! \\(\\lambda = EA\\, G^{-1} b\\) ([`super::gram`], [`super::tensions`]), i.e. the energy
//! \\(\\tfrac{EA}{2}\\lVert\\Pi\\varepsilon\\rVert^2\\) with the L² projection Π: order 4.1 at
//! EA = 10² N, the longitudinal string mode within 3.4e-9, and the stiff columns
//! unchanged. The energy and gradient stay O(n) (one banded solve with `G`; on a closed
//! rod a cyclic one, see [`super::gram`]); the Hessian's dense part goes through
//! Newton's conjugate-gradient correction. Measured (callgrind,
//! `examples/step_profile.rs 3000 consistent`, instructions per step): the 16-point step
//! costs 89.5 k against the lumped form's 50.7 k (125.5 k before its fused pass over the
//! table, [`super::tabulated`], and the cheaper remainder products and conjugate
//! gradients, [`super::rows`]; of the difference, 3.3 conjugate-gradient iterations per
//! step make about 36 k), and about 2 × on long steps from a compressed start
//! (`ensemble_cables.toml`: 7 conjugate-gradient iterations per Newton iteration).
//! Made the default for one commit, it cost 1.4–3.5 × across `splinerod bench` (the
//! ensembles, static Newton, the error estimator, 44 % more memory; figures in
//! ARCHITECTURE.md), so the lumped form stays the default and
//! [`super::StretchFormulation::Pointwise`] stays available.
//!
//! **Knot insertion** maps the curve and the velocities exactly, as always; the mixed
//! energy is not invariant, because the tension space refines with the knots. By
//! Cauchy–Schwarz \\(b_k^2 \\le m_k \\int \\varphi_k \\varepsilon^2 dl_0\\), and the tension
//! functions sum to one, so \\(E_{pointwise} - G \\le E \\le E_{pointwise}\\) with the
//! *unresolved strain energy* \\(G = \\tfrac{EA}{2}\\sum_k \\int \\varphi_k (\\varepsilon -
//! b_k/m_k)^2 dl_0 \\ge 0\\). The pointwise energy is invariant, so an insertion changes
//! the energy by at most \\(\\max(G_{before}, G_{after})\\), a quantity that vanishes as the
//! rod converges (tested in `tests/adaptivity.rs`: the bound holds on 2 000 random
//! insertions, and G falls from 46 % to 1.7 % of the strain energy of a wiggly rod
//! refined from 10 to 201 control points). With the consistent Gram matrix the bound is
//! sharper: the tension spaces are nested, so an insertion can only raise the energy
//! (the projection onto a larger space), by at most the unresolved
//! \\(\\tfrac{EA}{2}\\lVert\\varepsilon - \\Pi\\varepsilon\\rVert^2\\) before it, and it stays
//! below the pointwise energy (`tests/consistent_gram.rs`).

use super::blocks::{add_outer_products, add_scaled, geometric_tension};
use super::table::MAX_WIDTH;
use super::{tangent, Stretching};
use nalgebra::Vector3;
use splinerod_core::bspline::bspline_values;
use splinerod_core::{BasisValues, BlockBanded, HessianKind, Real, Rod, MAX_DEGREE};
use std::cell::RefCell;

/// Stride of the per-span geometric sums: pairs up to `MAX_DEGREE` apart.
const BAND: usize = MAX_DEGREE + 1;

thread_local! {
    /// The `d` open tension functions of a sweep (scratch, reused across calls).
    static RING: RefCell<Vec<Projection>> = const { RefCell::new(Vec::new()) };
}

/// One tension function's projection of the current strain, accumulated over its support.
#[derive(Debug, Clone, Copy)]
pub(super) struct Projection {
    /// Index `j` of the tension function (B-spline `j` of degree `d − 1` on the knots).
    pub index: usize,
    /// Strain moment \(b_k\).
    pub b: Real,
    /// Weight \(m_k\), m.
    pub m: Real,
    /// First control point touched.
    pub first: usize,
    /// Number of control points touched.
    pub width: usize,
    /// \(\partial b_k / \partial q_{first + a}\).
    pub db: [Vector3<Real>; MAX_WIDTH],
}

impl Projection {
    fn empty() -> Self {
        Self {
            index: 0,
            b: 0.0,
            m: 0.0,
            first: usize::MAX,
            width: 0,
            db: [Vector3::zeros(); MAX_WIDTH],
        }
    }

    /// Zeroes what a sweep accumulates (the first `2d` entries).
    fn reset(&mut self, index: usize, d: usize) {
        self.index = index;
        self.b = 0.0;
        self.m = 0.0;
        self.first = usize::MAX;
        self.width = 0;
        self.db[..2 * d]
            .iter_mut()
            .for_each(|v| *v = Vector3::zeros());
    }
}

impl Stretching {
    /// Sweeps the quadrature points once, accumulating every tension function of degree
    /// `d − 1` (functions `1 ..= n − 1` of the rod's knot vector) and handing each to
    /// `finish` once its support is complete (in increasing order, also functions whose
    /// support is empty, with `width` 0). Allocation-free after the first call: the `d`
    /// open functions live in a thread-local ring.
    pub(super) fn sweep(&self, rod: &Rod, finish: impl FnMut(&Projection)) {
        RING.with(|ring| {
            let mut ring = ring.borrow_mut();
            let d = rod.basis().degree();
            if ring.len() < d {
                ring.resize(d, Projection::empty());
            }
            self.sweep_with(rod, &mut ring[..d], finish);
        });
    }

    fn sweep_with(&self, rod: &Rod, ring: &mut [Projection], mut finish: impl FnMut(&Projection)) {
        let (table, d) = (rod.quadrature(), rod.basis().degree());
        // Functions below `open` are finished; `open..next` are being accumulated.
        let (mut open, mut next) = (1, 1);
        // The span of the previous point, and the ring slot of its first open function.
        let (mut span, mut base) = (usize::MAX, 0);
        for p in 0..table.len() {
            let qp = table.point(p);
            if qp.first + d != span {
                span = qp.first + d;
                while open + d <= span {
                    if open < next {
                        finish(&ring[open % d]);
                    }
                    open += 1;
                }
                next = next.max(open);
                while next <= span {
                    ring[next % d].reset(next, d);
                    next += 1;
                }
                base = (span + 1) % d;
            }
            let c1 = tangent(&qp, &rod.positions);
            let (eps, root) = self.strain(p, &c1);
            let mut slot = base;
            for &phi in qp.lower {
                accumulate(&mut ring[slot], &qp, phi, eps, root, &c1);
                slot = if slot + 1 == d { 0 } else { slot + 1 };
            }
        }
        for j in open..next {
            finish(&ring[j % d]);
        }
    }

    /// Strain ε and \\(\\sqrt{g_0}\\) at quadrature point `p` with tangent `c1`.
    #[inline]
    pub(super) fn strain(&self, p: usize, c1: &Vector3<Real>) -> (Real, Real) {
        let g0 = self.g0(p);
        (0.5 * (c1.norm_squared() - g0) / g0, self.root_g0(p))
    }

    /// \\(\\sqrt{g_0}\\) at quadrature point `p` (no square root for the default rest state).
    #[inline]
    pub(super) fn root_g0(&self, p: usize) -> Real {
        match self.g0(p) {
            1.0 => 1.0,
            g0 => g0.sqrt(),
        }
    }

    /// Tension \\(T(s) = \\sum_k \\lambda_k \\varphi_k(s)\\) times \\(|C'|/\\sqrt{g_0}\\) (the axial
    /// force, N) at the parameters `s`, added into `out`.
    pub(super) fn mixed_tension(&self, rod: &Rod, s: &[Real], out: &mut [Real]) {
        let lambda: Vec<Real> = self.with_tensions(rod, |t| t.iter().map(|t| t.0).collect());
        let (d, knots) = (rod.basis().degree(), rod.basis().knots());
        let mut b = BasisValues::default();
        for (&s, t) in s.iter().zip(out) {
            if rod.basis().evaluate(s, &mut b).is_err() {
                continue;
            }
            let phi = bspline_values(knots, d - 1, b.first + d, s);
            let field: Real = (0..d).map(|k| lambda[b.first + 1 + k] * phi[k]).sum();
            let speed = b.combine(&b.d1, &rod.positions).norm();
            *t += field * speed / self.rest_metric_at(s).sqrt();
        }
    }

    /// Energy of the mixed form, \\(\\sum_j \\tfrac12 \\lambda_j b_j\\) (with multipliers
    /// \\(\\sum_j (\\hat\\lambda_j + \\tfrac\\rho2 b_j/m_j) b_j = \\sum_j \\tfrac12 (\\lambda_j +
    /// \\hat\\lambda_j) b_j\\)).
    pub(super) fn mixed_energy(&self, rod: &Rod) -> Real {
        self.with_tensions(rod, |t| {
            t.iter()
                .enumerate()
                .map(|(j, (l, b))| 0.5 * (l + self.multiplier(j)) * b)
                .sum()
        })
    }

    /// Gradient of the mixed form, \\(\\int T\\, g_0^{-1/2} b_a' C'\\, ds\\) with the tension
    /// field `T` at each quadrature point.
    pub(super) fn mixed_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        if self.table.matches(rod) || rod.is_closed() {
            return self.with_consistent_tensions(rod, |t| {
                self.for_each_moment(rod, |k| {
                    let tension = self.tension_of(t, k.index, k.b, k.m);
                    add_scaled(gradient, k.first, k.db, tension);
                });
            });
        }
        self.with_tensions(rod, |t| {
            let table = rod.quadrature();
            for p in 0..table.len() {
                let qp = table.point(p);
                let tension: Real = t[qp.first + 1..]
                    .iter()
                    .zip(qp.lower)
                    .map(|(t, phi)| t.0 * phi)
                    .sum();
                let c1 = tangent(&qp, &rod.positions);
                let f = c1 * (qp.weight * tension / self.root_g0(p));
                for (g, &da) in gradient[qp.first..].iter_mut().zip(qp.d1) {
                    *g += f * da;
                }
            }
        });
    }

    /// [`Self::with_tensions`] for the consistent form (whose tensions need a solve over
    /// the whole rod first); `None` for the lumped one, whose tension function `j` has
    /// its tension from its own moment ([`Self::tension_of`]): one pass instead of two.
    pub(super) fn with_consistent_tensions<R>(
        &self,
        rod: &Rod,
        f: impl FnOnce(Option<&[(Real, Real)]>) -> R,
    ) -> R {
        // A closed rod's split pairs share a tension: from the merged moments.
        if self.consistent() || rod.is_closed() {
            self.with_tensions(rod, |t| f(Some(t)))
        } else {
            f(None)
        }
    }

    /// The tension coefficient of function `index` with moment `b` and weight `m`:
    /// from `tensions` if given (the consistent form), else
    /// \\(\\hat\\lambda + EA\\, b/m\\).
    #[inline]
    pub(super) fn tension_of(
        &self,
        tensions: Option<&[(Real, Real)]>,
        index: usize,
        b: Real,
        m: Real,
    ) -> Real {
        match tensions {
            Some(t) => t[index].0,
            None => self.multiplier(index) + self.lumped_stiffness(m) * b,
        }
    }

    /// The lumped material stiffness `EA/m` of a tension function of weight `m` (0 for
    /// an empty support): the banded part of its Hessian ([`super::tensions`]).
    #[inline]
    pub(super) fn lumped_stiffness(&self, m: Real) -> Real {
        if m > 0.0 {
            self.axial_stiffness() / m
        } else {
            0.0
        }
    }

    /// Hessian of the mixed form (see the module docs), and with `gradient` the gradient
    /// too, \\(\\sum_k \\lambda_k\\, \\partial b_k/\\partial q_a\\), from the same sweep.
    pub(super) fn mixed_hessian(
        &self,
        rod: &Rod,
        kind: HessianKind,
        mut gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        if self.table.matches(rod) || rod.is_closed() {
            return self.tabulated_derivatives(rod, kind, gradient, hessian);
        }
        let d = rod.basis().degree();
        // λ of the last d finished tension functions, at j mod d.
        let mut lambda = [0.0; MAX_DEGREE];
        // The first quadrature point not yet given its geometric term.
        let mut cursor = 0;
        self.with_consistent_tensions(rod, |t| {
            self.sweep(rod, |pr| {
                let c = self.lumped_stiffness(pr.m);
                let tension = self.tension_of(t, pr.index, pr.b, pr.m);
                lambda[pr.index % d] = geometric_tension(kind, tension);
                let db = &pr.db[..pr.width];
                if let Some(g) = gradient.as_deref_mut() {
                    add_scaled(g, pr.first, db, tension);
                }
                add_outer_products(hessian, pr.first, c, db);
                // Span `pr.index` has all its tension functions (index − d + 1 ..= index).
                if pr.index >= d {
                    cursor = self.add_geometric(rod, pr.index, cursor, &lambda[..d], hessian);
                }
            });
        });
    }

    /// The geometric term \\(\\int T g_0^{-1/2} b_a' b_c'\\, ds\\; I\\) of knot span `span`,
    /// with \\(T = \\sum_k \\lambda_k \\varphi_k\\) from `lambda` (function `j` at `j mod d`).
    /// Spans come in increasing order: the span's points are found from `cursor` on (no
    /// search), and the point after them is returned as the next cursor.
    fn add_geometric(
        &self,
        rod: &Rod,
        span: usize,
        mut cursor: usize,
        lambda: &[Real],
        hessian: &mut BlockBanded,
    ) -> usize {
        let (table, d) = (rod.quadrature(), lambda.len());
        let first = span - d;
        while cursor < table.len() && table.first_function(cursor) < first {
            cursor += 1;
        }
        let mut sum = [0.0; BAND * BAND];
        let mut any = false;
        while cursor < table.len() && table.first_function(cursor) == first {
            let qp = table.point(cursor);
            let mut slot = (span + 1) % d;
            let mut tension = 0.0;
            for &phi in qp.lower {
                tension += lambda[slot] * phi;
                slot = if slot + 1 == d { 0 } else { slot + 1 };
            }
            let w = qp.weight * tension / self.root_g0(cursor);
            for (a, &da) in qp.d1.iter().enumerate() {
                let wa = w * da;
                for (g, &db) in sum[a * BAND..].iter_mut().zip(&qp.d1[a..]) {
                    *g += wa * db;
                }
            }
            (any, cursor) = (true, cursor + 1);
        }
        if any {
            for a in 0..=d {
                let row = hessian.band_row_mut(first + a);
                for (block, &g) in row.iter_mut().zip(&sum[a * BAND..a * BAND + d + 1 - a]) {
                    block[(0, 0)] += g;
                    block[(1, 1)] += g;
                    block[(2, 2)] += g;
                }
            }
        }
        cursor
    }
}

/// Adds one quadrature point's contribution, weighted by the tension function's value
/// `phi` there, to that function's projection `pr`.
#[inline]
fn accumulate(
    pr: &mut Projection,
    qp: &splinerod_core::QuadPoint<'_>,
    phi: Real,
    eps: Real,
    root: Real,
    c1: &Vector3<Real>,
) {
    if pr.first == usize::MAX {
        pr.first = qp.first;
    }
    let order = qp.d1.len();
    let offset = qp.first - pr.first;
    pr.width = offset + order;
    let w = qp.weight * phi;
    pr.b += w * eps * root;
    pr.m += w * root;
    let f = c1 * (w / root);
    for (db, &da) in pr.db[offset..offset + order].iter_mut().zip(qp.d1) {
        *db += f * da;
    }
}
