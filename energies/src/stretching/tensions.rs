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
//! is applied to vectors by [`crate::Energy::add_hessian_remainder`] in O(n): one product
//! with `B`, one banded solve with `G`, one product with \\(B^T\\). Newton's method
//! solves with the banded part factorised and corrects the step by preconditioned
//! conjugate gradients (`splinerod_integrators::remainder`).

use super::gram::TensionGram;
use super::seam::Merged;
use super::table::{Moment, TensionTable, MAX_WIDTH};
use super::{tangent, Stretching};
use nalgebra::Vector3;
use splinerod_core::{Real, Rod, MAX_DEGREE};
use std::cell::RefCell;

thread_local! {
    /// Per tension function: (λ, b), see [`Stretching::with_tensions`].
    static TENSIONS: RefCell<Vec<(Real, Real)>> = const { RefCell::new(Vec::new()) };
    /// Scratch of the Gram solves.
    static SOLVE: RefCell<Vec<Real>> = const { RefCell::new(Vec::new()) };
    /// The Gram matrix of a rod the energy's own does not match, and the energy (address)
    /// it was built for.
    static GRAM: RefCell<(usize, TensionGram)> = RefCell::new((0, TensionGram::default()));
    /// `B = ∂b/∂q` at the state of the last remainder product (see [`Rows`]).
    static ROWS: RefCell<RowsCache> = RefCell::new(RowsCache::default());
    /// The table of a closed rod the energy's own does not match, and the energy (address)
    /// it was built for.
    static TABLE: RefCell<(usize, TensionTable)> = RefCell::new((0, TensionTable::default()));
}

/// The rows of `B = ∂b/∂q` at one state, kept between the remainder products of one
/// Newton step (conjugate gradients apply `R` several times at the same positions). Keyed
/// by the energy, the rod's topology epoch and its positions (compared bit for bit), so
/// a product at any other state recomputes them.
#[derive(Debug, Default)]
struct Rows {
    /// The energy (address and stiffness bits), the rod's topology epoch, its number of
    /// quadrature points, and whether the rows came from the energy's table (a sweep
    /// differs from it in the last bits, and a table built later for the same epoch
    /// must not find them).
    key: Option<(usize, u64, u64, usize, bool)>,
    positions: Vec<Vector3<Real>>,
    /// Per tension function: index, first control point, width, weight, moment.
    functions: Vec<(usize, usize, usize, Real, Real)>,
    /// `∂b_j/∂q`, `MAX_WIDTH` entries per function.
    db: Vec<Vector3<Real>>,
    /// Scratch of the remainder products: `B v`, then `G⁻¹ B v` (per function `0 ..= n`).
    y: Vec<Real>,
    /// Scratch of the remainder products: `m⁻¹ B v`.
    lumped: Vec<Real>,
    /// A closed rod's distinct control points and degree: its split pairs `j`, `j + m`
    /// (`1 ≤ j < d`) have one lumped weight ([`super::seam`]).
    pairs: Option<(usize, usize)>,
    /// Address of the energy whose slot this is ([`RowsCache`]).
    owner: usize,
}

/// The rows of up to [`ROW_SLOTS`] energies (the rods of a joined system each have their
/// own stretching: one slot would refill at every remainder product), replaced round
/// robin beyond that.
#[derive(Debug, Default)]
struct RowsCache {
    slots: Vec<Rows>,
    next: usize,
}

/// Energies whose rows a thread keeps at once.
const ROW_SLOTS: usize = 8;

impl RowsCache {
    /// The slot of `energy`, if it has one.
    fn find(&self, energy: &Stretching) -> Option<&Rows> {
        let owner = energy as *const Stretching as usize;
        self.slots.iter().find(|r| r.owner == owner)
    }

    /// The rows of `energy` at `rod`'s state, filled if they are not.
    fn filled(&mut self, energy: &Stretching, rod: &Rod) -> &mut Rows {
        let owner = energy as *const Stretching as usize;
        let index = match self.slots.iter().position(|r| r.owner == owner) {
            Some(i) => i,
            None if self.slots.len() < ROW_SLOTS => {
                self.slots.push(Rows::default());
                self.slots.len() - 1
            }
            None => {
                self.next = (self.next + 1) % ROW_SLOTS;
                self.next
            }
        };
        let rows = &mut self.slots[index];
        if !rows.hold(energy, rod) {
            rows.fill(energy, rod);
        }
        rows
    }
}

impl Rows {
    /// Whether the rows are those of `energy` at `rod`'s state.
    fn hold(&self, energy: &Stretching, rod: &Rod) -> bool {
        self.key == Some(Self::key_of(energy, rod))
            && self.positions.len() == rod.len()
            && self.positions.iter().zip(&rod.positions).all(|(a, b)| {
                a.iter()
                    .zip(b.iter())
                    .all(|(x, y)| x.to_bits() == y.to_bits())
            })
    }

    fn key_of(energy: &Stretching, rod: &Rod) -> (usize, u64, u64, usize, bool) {
        let address = energy as *const Stretching as usize;
        let points = rod.quadrature().len();
        (
            address,
            energy.stiffness.to_bits(),
            rod.topology_epoch(),
            points,
            energy.table.matches(rod),
        )
    }

    /// Recomputes the rows of `energy` at `rod`'s state.
    fn fill(&mut self, energy: &Stretching, rod: &Rod) {
        self.key = None;
        self.owner = energy as *const Stretching as usize;
        self.functions.clear();
        self.db.clear();
        energy.for_each_derivative(rod, |index, first, (m, b), db| {
            self.functions.push((index, first, db.len(), m, b));
            let start = self.db.len();
            self.db.resize(start + MAX_WIDTH, Vector3::zeros());
            self.db[start..start + db.len()].copy_from_slice(db);
        });
        self.positions.clear();
        self.positions.extend_from_slice(&rod.positions);
        self.pairs = rod
            .basis()
            .periodic_count()
            .map(|m| (m, rod.basis().degree()));
        self.key = Some(Self::key_of(energy, rod));
    }

    /// Calls `f` with every function's [`Moment`] (`table` must be the one the rows
    /// were computed from).
    fn for_each_moment(&self, table: &TensionTable, mut f: impl FnMut(&Moment<'_>)) {
        for (k, &(index, first, width, m, b)) in self.functions.iter().enumerate() {
            let db = &self.db[k * MAX_WIDTH..k * MAX_WIDTH + width];
            f(&table.moment((index, first), (b, m), db));
        }
    }

    /// `out += c · Bᵀ (G⁻¹ − m⁻¹) B v` with `solve` the solve with `G` (see
    /// [`Stretching::mixed_remainder`]).
    fn remainder(
        &mut self,
        v: &[Vector3<Real>],
        c: Real,
        solve: impl FnOnce(&mut [Real]),
        out: &mut [Vector3<Real>],
    ) {
        let len = self.positions.len() + 1;
        for buffer in [&mut self.y, &mut self.lumped] {
            buffer.clear();
            buffer.resize(len, 0.0);
        }
        // y = B v, and its lumped image m⁻¹ B v.
        let rows = self.db.chunks_exact(MAX_WIDTH);
        for (&(index, first, width, m, _), db) in self.functions.iter().zip(rows) {
            let bv: Real = db[..width]
                .iter()
                .zip(&v[first..first + width])
                .map(|(d, v)| d.dot(v))
                .sum();
            self.y[index] = bv;
            self.lumped[index] = if m > 0.0 { bv / m } else { 0.0 };
        }
        if let Some((m, d)) = self.pairs {
            self.merge_pairs(m, d);
        }
        solve(&mut self.y);
        let rows = self.db.chunks_exact(MAX_WIDTH);
        for (&(index, first, width, _, _), db) in self.functions.iter().zip(rows) {
            let yi = c * (self.y[index] - self.lumped[index]);
            for (o, d) in out[first..first + width].iter_mut().zip(&db[..width]) {
                *o += d * yi;
            }
        }
    }
}

impl Rows {
    /// Gives both halves of each split pair the lumped image of the pair,
    /// \((y_j + y_{j+m}) / (m_j + m_{j+m})\) (`lumped` holding each half's own).
    fn merge_pairs(&mut self, m: usize, d: usize) {
        let mut weights = [(0.0, 0.0); MAX_DEGREE];
        for &(index, _, _, w, _) in &self.functions {
            let head = if index > m { index - m } else { index };
            if head >= 1 && head < d {
                let slot = &mut weights[head - 1];
                slot.0 += self.y[index];
                slot.1 += w;
            }
        }
        for (j, &(y, w)) in weights.iter().enumerate().take(d.saturating_sub(1)) {
            let image = if w > 0.0 { y / w } else { 0.0 };
            for index in [j + 1, j + 1 + m] {
                if index < self.lumped.len() {
                    self.lumped[index] = image;
                }
            }
        }
    }
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
            return ROWS.with(|cache| {
                let mut cache = cache.borrow_mut();
                let rows = cache.filled(self, rod);
                for &(index, _, _, m, b) in &rows.functions {
                    moments[index] = (b, m);
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
            && ROWS.with(|cache| {
                let cache = cache.borrow();
                let rows = cache.find(self).filter(|rows| rows.hold(self, rod));
                if let Some(rows) = rows {
                    rows.for_each_moment(&self.table, &mut f);
                }
                rows.is_some()
            });
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
    fn solve_gram(&self, rod: &Rod, r: &mut [Real]) {
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

    /// `out += scale · R v` with the remainder `R` of the module docs (nothing for the
    /// lumped inextensible form).
    pub(super) fn mixed_remainder(
        &self,
        rod: &Rod,
        v: &[Vector3<Real>],
        scale: Real,
        out: &mut [Vector3<Real>],
    ) {
        if !self.consistent() {
            return;
        }
        ROWS.with(|cache| {
            let mut cache = cache.borrow_mut();
            let rows = cache.filled(self, rod);
            let c = scale * self.stiffness;
            rows.remainder(v, c, |y| self.solve_gram(rod, y), out);
        });
    }

    /// Calls `f(j, first, (m_j, b_j), ∂b_j/∂q_first..)` for every tension function at the
    /// rod's positions: from the table when it matches, else by a sweep.
    fn for_each_derivative(
        &self,
        rod: &Rod,
        mut f: impl FnMut(usize, usize, (Real, Real), &[Vector3<Real>]),
    ) {
        if self.table.matches(rod) {
            self.table
                .for_each(rod, |k| f(k.index, k.first, (k.m, k.b), k.db));
        } else {
            self.sweep(rod, |pr| {
                if pr.width > 0 {
                    f(pr.index, pr.first, (pr.m, pr.b), &pr.db[..pr.width]);
                }
            });
        }
    }
}
