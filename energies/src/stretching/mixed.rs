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
//! `examples/step_profile.rs`, steps 5–20 005, the window `splinerod bench` times): the
//! 16-point step costs 126 k instructions against the lumped form's 87 k (1.19 × the
//! pointwise step #12 was filed against), and about 2 × on long steps from a compressed
//! start (`ensemble_cables.toml`: 7 conjugate-gradient iterations per Newton iteration).
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

use super::seam;
use super::table::{add_times, Moment, MAX_WIDTH};
use super::{tangent, Stretching};
use nalgebra::{Matrix3, Vector3};
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
    fn with_consistent_tensions<R>(
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
    fn tension_of(
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
    fn lumped_stiffness(&self, m: Real) -> Real {
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

    /// [`Self::mixed_hessian`] from the tabulated integrals ([`super::table`]): per tension
    /// function, the material term \\(\\tfrac{EA}{m_k} \\partial b_k \\partial b_k^T\\), the
    /// geometric term \\(\\lambda_k G_k \\otimes I\\) and the gradient \\(\\lambda_k \\partial b_k\\).
    fn tabulated_derivatives(
        &self,
        rod: &Rod,
        kind: HessianKind,
        mut gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        #[cfg(target_arch = "x86_64")]
        if self.lumped_open(rod) && splinerod_core::lanes::wide() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            return unsafe { self.lumped_derivatives_wide(rod, kind, gradient, hessian) };
        }
        let merged = self.merged_weights(rod);
        let mut heads = rod.is_closed().then(seam::Heads::default);
        self.with_consistent_tensions(rod, |t| {
            self.for_each_moment(rod, |k| {
                let c = self.lumped_stiffness(merged.get(k.index).map_or(k.m, |p| p.1));
                let tension = self.tension_of(t, k.index, k.b, k.m);
                if let Some(g) = gradient.as_deref_mut() {
                    add_scaled(g, k.first, k.db, tension);
                }
                add_function_blocks::<false>(hessian, k, c, geometric_tension(kind, tension));
                if let Some(heads) = heads.as_mut() {
                    match seam::partner(rod, k.index) {
                        Some(tail) if tail > k.index => heads.keep(k.index, k.first, k.db),
                        Some(head) => {
                            seam::add_cross_term(hessian, c, heads.get(head), (k.first, k.db))
                        }
                        None => {}
                    }
                }
            });
        });
    }

    /// Whether `rod` takes the lumped form's tabulated derivatives on an open rod: the
    /// energy's own table matches it, and no tension solve or seam is involved.
    #[inline]
    fn lumped_open(&self, rod: &Rod) -> bool {
        !self.consistent() && !rod.is_closed() && self.table.matches(rod)
    }

    /// [`Self::lumped_derivatives`] with fused products, compiled for AVX2 and FMA (the
    /// same sums as [`Self::tabulated_derivatives`], each product rounded once).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn lumped_derivatives_wide(
        &self,
        rod: &Rod,
        kind: HessianKind,
        gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        self.lumped_derivatives::<true>(rod, kind, gradient, hessian);
    }

    /// [`Self::tabulated_derivatives`] where [`Self::lumped_open`] holds: per function
    /// its tension \\(\\hat\\lambda_k + EA\\, b_k/m_k\\) from its own moment, one pass.
    /// Plain loops and `#[inline(always)]` callees only, so that all of it is compiled
    /// for the caller's instruction set (fused multiply-add where `FUSED`).
    #[inline(always)]
    fn lumped_derivatives<const FUSED: bool>(
        &self,
        rod: &Rod,
        kind: HessianKind,
        mut gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        let mut scratch = [[Vector3::zeros(); MAX_WIDTH]; 2];
        for j in 0..self.table.functions() {
            let g = gradient.as_deref_mut();
            match self.table.width(j) {
                // A cubic's interior functions touch 6 points: with the width a
                // constant, every loop of their sums unrolls.
                6 => self.lumped_function::<FUSED, 6>(rod, kind, j, &mut scratch, (g, hessian)),
                _ => self.lumped_function::<FUSED, 0>(rod, kind, j, &mut scratch, (g, hessian)),
            }
        }
    }

    /// [`Self::lumped_derivatives`]' terms of function `j + 1`, whose width is `W` (if
    /// not 0; else the table's), added to the gradient (if any) and the Hessian.
    #[inline(always)]
    fn lumped_function<const FUSED: bool, const W: usize>(
        &self,
        rod: &Rod,
        kind: HessianKind,
        j: usize,
        scratch: &mut [[Vector3<Real>; MAX_WIDTH]; 2],
        (gradient, hessian): (Option<&mut [Vector3<Real>]>, &mut BlockBanded),
    ) {
        let width = if W > 0 { W } else { self.table.width(j) };
        let k = self.table.moment_at::<FUSED>(rod, (j, width), scratch);
        let c = self.lumped_stiffness(k.m);
        let tension = self.tension_of(None, k.index, k.b, k.m);
        if let Some(g) = gradient {
            for (g, v) in g[k.first..].iter_mut().zip(k.db) {
                add_times::<FUSED>(g, v, tension);
            }
        }
        add_function_blocks::<FUSED>(hessian, &k, c, geometric_tension(kind, tension));
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

/// The tension the geometric stiffness uses: all of it for the exact Hessian, only
/// its positive part for the definite one.
#[inline]
fn geometric_tension(kind: HessianKind, tension: Real) -> Real {
    match kind {
        HessianKind::Exact => tension,
        _ => tension.max(0.0),
    }
}

/// `gradient[first + a] += tension · db[a]`.
#[inline]
fn add_scaled(gradient: &mut [Vector3<Real>], first: usize, db: &[Vector3<Real>], tension: Real) {
    for (g, v) in gradient[first..].iter_mut().zip(db) {
        *g += v * tension;
    }
}

/// Adds one tension function's material and geometric stiffness,
/// \\(c\\, \\partial b_a \\partial b_b^T + \\lambda (G_k)_{ab} I\\) at blocks `(first + a, first + b)`,
/// `a ≤ b`, in one pass over its blocks of the band (the same sums, in the same order,
/// as [`add_outer_products`] then [`add_scaled_identities`], which take a band too
/// narrow for it).
/// With `FUSED` the rank-one products are fused (see [`super::table::add_scaled`]).
#[inline(always)]
fn add_function_blocks<const FUSED: bool>(
    hessian: &mut BlockBanded,
    k: &Moment<'_>,
    c: Real,
    lambda: Real,
) {
    let v = k.db;
    if v.len() > hessian.bandwidth() + 1 {
        add_outer_products(hessian, k.first, c, v);
        add_scaled_identities(hessian, k, lambda);
        return;
    }
    for (a, va) in v.iter().enumerate() {
        let u = va * c;
        let g = &k.g[k.rows[a]..];
        let row = hessian.band_row_mut(k.first + a);
        for ((block, vb), &gab) in row.iter_mut().zip(&v[a..]).zip(g) {
            // The block summed in registers and stored once (adding `d` to the stored
            // diagonal would reload entries just stored, and wait on the store).
            let mut sum = *block;
            add_rank_one::<FUSED>(&mut sum, &u, vb);
            let d = lambda * gab;
            let e = sum.as_mut_slice();
            e[0] += d;
            e[4] += d;
            e[8] += d;
            *block = sum;
        }
    }
}

/// Adds \\(\\lambda (G_k)_{ab} I\\) at blocks `(first + a, first + b)`, `a ≤ b`, into the
/// band (or block by block where it is narrower, see [`add_any`]).
#[inline]
fn add_scaled_identities(hessian: &mut BlockBanded, k: &Moment<'_>, lambda: Real) {
    let width = k.db.len();
    let wide = width <= hessian.bandwidth() + 1;
    for a in 0..width {
        if wide {
            let row = hessian.band_row_mut(k.first + a);
            for (b, block) in (a..width).zip(row.iter_mut()) {
                let g = lambda * k.entry(a, b);
                block[(0, 0)] += g;
                block[(1, 1)] += g;
                block[(2, 2)] += g;
            }
        } else {
            for b in a..width {
                let block = Matrix3::identity() * (lambda * k.entry(a, b));
                add_any(hessian, k.first + a, k.first + b, &block);
            }
        }
    }
}

/// Adds \\(c\\, v_a v_b^T\\) at blocks `(first + a, first + b)` for every pair `a ≤ b` of
/// `v`: one tension function's material stiffness. Row by row into the band when it is
/// wide enough (no per-block bounds check), else block by block (far blocks for a matrix
/// sized narrower, see [`add_any`]).
#[inline]
fn add_outer_products(hessian: &mut BlockBanded, first: usize, c: Real, v: &[Vector3<Real>]) {
    if v.len() <= hessian.bandwidth() + 1 {
        for (a, va) in v.iter().enumerate() {
            let u = va * c;
            let row = hessian.band_row_mut(first + a);
            for (block, vb) in row.iter_mut().zip(&v[a..]) {
                add_rank_one::<false>(block, &u, vb);
            }
        }
    } else {
        for (a, va) in v.iter().enumerate() {
            let u = va * c;
            for (b, vb) in v.iter().enumerate().skip(a) {
                add_any(hessian, first + a, first + b, &(u * vb.transpose()));
            }
        }
    }
}

/// `block += u vᵀ`, written out (the compiler keeps it in registers; a temporary 3×3
/// product through nalgebra's operators was measured 2–3 times slower here), each
/// product fused with `FUSED`.
#[inline(always)]
fn add_rank_one<const FUSED: bool>(
    block: &mut Matrix3<Real>,
    u: &Vector3<Real>,
    v: &Vector3<Real>,
) {
    // Column-major: entry (r, c) at 3c + r.
    let e = block.as_mut_slice();
    for (column, &vc) in e.chunks_exact_mut(3).zip(v.iter()) {
        for (x, &ur) in column.iter_mut().zip(u.iter()) {
            *x = if FUSED {
                ur.mul_add(vc, *x)
            } else {
                *x + ur * vc
            };
        }
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

/// Adds a block inside the band, or as a far block for a matrix sized with a narrower
/// band than [`crate::Energy::bandwidth`] (a caller that sized it by the degree).
#[inline]
fn add_any(hessian: &mut BlockBanded, i: usize, j: usize, block: &Matrix3<Real>) {
    if j - i <= hessian.bandwidth() {
        hessian.add_block(i, j, block);
    } else {
        hessian.add_coupling(i, j, block);
    }
}
