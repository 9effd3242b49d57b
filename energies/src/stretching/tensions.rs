//! The mixed form's tension coefficients and the part of its Hessian that is not banded.
//!
//! With strain moments \\(b_j\\), weights \\(m_j\\) and the consistent Gram matrix `G`
//! ([`super::gram`]), the tension coefficients are
//!
//! \\[ \lambda = \hat\lambda + EA\, G^{-1} b \quad \text{(finite EA)}, \qquad
//! \lambda_j = \hat\lambda_j + \rho\, b_j / m_j \quad \text{(inextensible, penalty } \rho),\\]
//!
//! the second lumped: there the penalty only enforces \\(b = 0\\), and the constraint, not
//! the constitutive relation, fixes the tension.
//!
//! **The Hessian** of \\(E = \tfrac{EA}{2} b^T G^{-1} b\\) is
//! \\(EA\, B^T G^{-1} B + \sum_j \lambda_j \nabla^2 b_j\\) with \\(B = \partial b/\partial q\\).
//! \\(G^{-1}\\) is dense, so [`crate::Energy::add_hessian`] adds the banded
//! \\(EA\, B^T \mathrm{diag}(m)^{-1} B + \sum_j \lambda_j \nabla^2 b_j\\) and the rest,
//!
//! \\[ R = EA\, B^T \left(G^{-1} - \mathrm{diag}(m)^{-1}\right) B \succeq 0, \\]
//!
//! is applied to vectors by [`crate::HessianRemainder::add_remainder`] in O(n): one product
//! with `B`, one banded solve with `G`, one product with \\(B^T\\), the rows of `B` kept
//! once per state ([`super::rows`]). Newton's method
//! solves with the banded part factorised and corrects the step by preconditioned
//! conjugate gradients (`splinerod_integrators::remainder`).

use super::gram::TensionGram;
use super::seam::Merged;
use super::table::{Moment, TensionTable};
use super::{tangent, Stretching};
use splinerod_core::{Real, Rod};
use std::cell::RefCell;

thread_local! {
    /// Per tension function: (λ, b), see [`Stretching::with_tensions`].
    static TENSIONS: RefCell<Vec<(Real, Real)>> = const { RefCell::new(Vec::new()) };
    /// Scratch of the Gram solves.
    static SOLVE: RefCell<Vec<Real>> = const { RefCell::new(Vec::new()) };
    /// The Gram matrix of a rod the energy's own does not match, and the energy (address)
    /// it was built for.
    static GRAM: RefCell<(usize, TensionGram)> = RefCell::new((0, TensionGram::default()));
    /// The table of a closed rod the energy's own does not match, and the energy (address)
    /// it was built for.
    static TABLE: RefCell<(usize, TensionTable)> = RefCell::new((0, TensionTable::default()));
}

impl Stretching {
    /// Whether the tension comes from the consistent Gram matrix
    /// ([`super::StretchFormulation::MixedConsistent`] with a finite `EA`), so that the
    /// Hessian has a remainder.
    #[inline]
    pub(super) fn consistent(&self) -> bool {
        self.formulation == super::StretchFormulation::MixedConsistent && self.multipliers.is_none()
    }

    /// Calls `f` with every tension function's coefficient \\(\\lambda_j\\) (see the module
    /// docs) and its strain moment \\(b_j\\), `j = 0 ..= n` (zero outside `1 ..= n − 1` and
    /// for empty supports). The buffer is thread-local and reused, so no allocation after
    /// the first call. `f` must not call back into it.
    pub(super) fn with_tensions<R>(&self, rod: &Rod, f: impl FnOnce(&[(Real, Real)]) -> R) -> R {
        TENSIONS.with(|cell| {
            let mut moments = cell.borrow_mut();
            self.moments(rod, &mut moments);
            let ea = self.axial_stiffness();
            if self.consistent() {
                SOLVE.with(|s| {
                    let mut x = s.borrow_mut();
                    x.clear();
                    x.extend(moments.iter().map(|m| m.0));
                    self.solve_gram(rod, &mut x);
                    for (m, x) in moments.iter_mut().zip(x.iter()) {
                        *m = (ea * x, m.0);
                    }
                });
            } else {
                // A closed rod's split functions take the tension of their pair.
                let merged = Merged::of(rod, |j| moments[j]);
                for (j, m) in moments.iter_mut().enumerate() {
                    let (b, w) = merged.get(j).unwrap_or(*m);
                    let stretch = if w > 0.0 { ea * b / w } else { 0.0 };
                    *m = (self.multiplier(j) + stretch, m.0);
                }
            }
            f(&moments)
        })
    }

    /// `(b_j, m_j)` of every tension function into `moments` (length `n + 1`): from the
    /// table when it matches the rod, else by one pass over the quadrature points.
    fn moments(&self, rod: &Rod, moments: &mut Vec<(Real, Real)>) {
        moments.clear();
        moments.resize(rod.len() + 1, (0.0, 0.0));
        if self.consistent() {
            // The rows of B come with the moments; the remainder products reuse them.
            return self.with_rows(rod, |rows| {
                for row in &rows.functions {
                    moments[row.index] = (row.b, row.m);
                }
            });
        }
        if self.table.matches(rod) {
            self.table.for_each(rod, |k| moments[k.index] = (k.b, k.m));
            return;
        }
        let table = rod.quadrature();
        for p in 0..table.len() {
            let qp = table.point(p);
            let (eps, root) = self.strain(p, &tangent(&qp, &rod.positions));
            let (wb, wm) = (qp.weight * eps * root, qp.weight * root);
            // lower[k] is function first + 1 + k.
            for (m, &phi) in moments[qp.first + 1..].iter_mut().zip(qp.lower) {
                m.0 += phi * wb;
                m.1 += phi * wm;
            }
        }
    }

    /// Calls `f` with every tension function's [`Moment`] at the rod's positions, from
    /// the rows [`Self::with_tensions`] kept for the consistent form (no second pass over
    /// the table) when the energy's table matches the rod, else from the table.
    pub(super) fn for_each_moment(&self, rod: &Rod, mut f: impl FnMut(&Moment<'_>)) {
        let cached = self.consistent()
            && self.table.matches(rod)
            && self
                .with_held_rows(rod, |rows| rows.for_each_moment(&self.table, &mut f))
                .is_some();
        if !cached {
            self.with_table(rod, |table| table.for_each(rod, f));
        }
    }

    /// Calls `f` with the tension table of `rod`: the energy's own when it matches, else
    /// one built for it (closed rods use the table even on scratch copies, for the
    /// merged pairs of [`super::seam`]).
    pub(super) fn with_table<R>(&self, rod: &Rod, f: impl FnOnce(&TensionTable) -> R) -> R {
        if self.table.matches(rod) {
            return f(&self.table);
        }
        TABLE.with(|cell| {
            let mut cached = cell.borrow_mut();
            let owner = self as *const Stretching as usize;
            if cached.0 != owner || !cached.1.matches(rod) {
                cached.1.build(self, rod);
                cached.0 = owner;
            }
            f(&cached.1)
        })
    }

    /// The merged weights of a closed rod's split tension functions (nothing merged for
    /// an open rod).
    pub(super) fn merged_weights(&self, rod: &Rod) -> Merged {
        match rod.is_closed() {
            true => self.with_table(rod, |t| Merged::of(rod, |j| (0.0, t.weight(j)))),
            false => Merged::of(rod, |_| (0.0, 0.0)),
        }
    }

    /// Solves \\(G x = r\\) in place (`r[j]` for function `j = 0 ..= n`) with the energy's
    /// Gram matrix, or one built for `rod` if that does not match it.
    pub(super) fn solve_gram(&self, rod: &Rod, r: &mut [Real]) {
        if self.gram.matches(rod) {
            return self.gram.solve(r);
        }
        GRAM.with(|g| {
            let mut cached = g.borrow_mut();
            let owner = self as *const Stretching as usize;
            if cached.0 != owner || !cached.1.matches(rod) {
                cached.1.build(self, rod);
                cached.0 = owner;
            }
            cached.1.solve(r);
        });
    }
}
