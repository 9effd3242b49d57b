//! The rows of `B = ∂b/∂q` of the consistent form, kept once per state, and the
//! remainder product \\(R v = EA\, B^T (G^{-1} - \mathrm{diag}(m)^{-1}) B v\\) made from them
//! ([`super::tensions`]).
//!
//! The rows come with the strain moments (one pass over the tension table, or a sweep
//! for a rod the table does not match), are stored at a stride of `2d` (a function's
//! widest block), and serve the tensions, the gradient and Hessian pass
//! ([`super::tabulated`]) and every remainder product of the conjugate gradients that
//! follow at the same positions. On processors with AVX2 and FMA the table's pass and
//! the products run with fused multiply-adds on four-wide registers (detected at run
//! time; equal to the plain ones to round-off, tested in `rows/tests.rs`).

use super::table::{Moment, TensionTable, MAX_WIDTH};
use super::Stretching;
use nalgebra::Vector3;
use splinerod_core::{Real, Rod, MAX_DEGREE};
use std::cell::RefCell;

#[cfg(all(test, target_arch = "x86_64"))]
mod tests;

thread_local! {
    /// `B = ∂b/∂q` at the state of the last use (see [`Rows`]).
    static ROWS: RefCell<RowsCache> = RefCell::new(RowsCache::default());
}

/// One tension function's row of `B`: where it sits, its weight and strain moment.
#[derive(Debug, Clone, Copy)]
pub(super) struct Row {
    /// Index `j` of the function.
    pub index: usize,
    /// First control point touched.
    pub first: usize,
    /// Control points touched.
    pub width: usize,
    /// Weight \\(m_j\\).
    pub m: Real,
    /// Strain moment \\(b_j\\).
    pub b: Real,
}

/// The rows of `B = ∂b/∂q` at one state, kept between the remainder products of one
/// Newton step (conjugate gradients apply `R` several times at the same positions). Keyed
/// by the energy, the rod's topology epoch and its positions (compared bit for bit), so
/// a use at any other state recomputes them.
#[derive(Debug, Default)]
pub(super) struct Rows {
    /// The energy (address and stiffness bits), the rod's topology epoch, its number of
    /// quadrature points, and whether the rows came from the energy's table (a sweep
    /// differs from it in the last bits, and a table built later for the same epoch
    /// must not find them).
    key: Option<(usize, u64, u64, usize, bool)>,
    positions: Vec<Vector3<Real>>,
    /// Per tension function, in increasing order.
    pub functions: Vec<Row>,
    /// Entries of `db` per function (`2d`).
    stride: usize,
    /// `∂b_j/∂q_{first..}` of function `k` of `functions` at `k · stride`.
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
    /// The slot of `energy`, if it holds `rod`'s state.
    fn held(&self, energy: &Stretching, rod: &Rod) -> Option<&Rows> {
        let owner = energy as *const Stretching as usize;
        let rows = self.slots.iter().find(|r| r.owner == owner)?;
        rows.hold(energy, rod).then_some(rows)
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

    /// Recomputes the rows of `energy` at `rod`'s state: from the energy's table when it
    /// matches the rod, else by a sweep.
    fn fill(&mut self, energy: &Stretching, rod: &Rod) {
        self.key = None;
        self.owner = energy as *const Stretching as usize;
        self.functions.clear();
        self.stride = 2 * rod.basis().degree();
        if energy.table.matches(rod) {
            self.fill_from_table(&energy.table, rod);
        } else {
            self.db.clear();
            energy.sweep(rod, |pr| {
                if pr.width > 0 {
                    let db = &pr.db[..pr.width];
                    self.functions.push(Row {
                        index: pr.index,
                        first: pr.first,
                        width: pr.width,
                        m: pr.m,
                        b: pr.b,
                    });
                    let start = self.db.len();
                    self.db.resize(start + self.stride, Vector3::zeros());
                    self.db[start..start + db.len()].copy_from_slice(db);
                }
            });
        }
        self.positions.clear();
        self.positions.extend_from_slice(&rod.positions);
        self.pairs = rod
            .basis()
            .periodic_count()
            .map(|m| (m, rod.basis().degree()));
        self.key = Some(Self::key_of(energy, rod));
    }

    /// The rows of every tabulated function (also those with an empty support), fused
    /// where the processor has AVX2 and FMA.
    fn fill_from_table(&mut self, table: &TensionTable, rod: &Rod) {
        self.db.clear();
        self.db
            .resize(table.functions() * self.stride, Vector3::zeros());
        #[cfg(target_arch = "x86_64")]
        if splinerod_core::lanes::wide() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            return unsafe { self.table_rows_wide(table, rod) };
        }
        self.table_rows::<false>(table, rod);
    }

    /// [`Self::table_rows`] fused, compiled for AVX2 and FMA.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn table_rows_wide(&mut self, table: &TensionTable, rod: &Rod) {
        self.table_rows::<true>(table, rod);
    }

    /// The rows of the table's functions into `functions` and `db` (sized), each
    /// product fused with `FUSED`. Plain loops and `#[inline(always)]` callees only (see
    /// [`splinerod_core::simd`]).
    #[inline(always)]
    fn table_rows<const FUSED: bool>(&mut self, table: &TensionTable, rod: &Rod) {
        let mut r = [Vector3::zeros(); MAX_WIDTH];
        for (j, db) in self.db.chunks_exact_mut(self.stride).enumerate() {
            let (first, width, m, _) = table.function(j);
            let b = match width {
                // A cubic's interior functions: a constant width unrolls the sums.
                6 => table.derivatives_at::<FUSED>(rod, (j, 6), &mut r, &mut db[..6]),
                _ => table.derivatives_at::<FUSED>(rod, (j, width), &mut r, db),
            };
            let index = j + 1;
            self.functions.push(Row {
                index,
                first,
                width,
                m,
                b,
            });
        }
    }

    /// Calls `f` with every function's [`Moment`] (`table` must be the one the rows
    /// were computed from).
    pub fn for_each_moment(&self, table: &TensionTable, mut f: impl FnMut(&Moment<'_>)) {
        for (k, row) in self.functions.iter().enumerate() {
            let db = self.derivatives(k, row.width);
            f(&table.moment((row.index, row.first), (row.b, row.m), db));
        }
    }

    /// `∂b/∂q` of function `k` of [`Self::functions`], its width long.
    #[inline(always)]
    pub fn derivatives(&self, k: usize, width: usize) -> &[Vector3<Real>] {
        &self.db[k * self.stride..k * self.stride + width]
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
        // Functions `1 ..= n − 1` all written (a table's rows): no zeros needed.
        if self.y.len() != len || self.functions.len() + 2 != len {
            self.y.clear();
            self.y.resize(len, 0.0);
        }
        self.lumped.resize(len, 0.0);
        self.project_any(v);
        if let Some((m, d)) = self.pairs {
            self.merge_pairs(m, d);
        }
        solve(&mut self.y);
        self.spread_any(c, out);
    }

    /// [`Self::project`], fused where the processor has AVX2 and FMA.
    fn project_any(&mut self, v: &[Vector3<Real>]) {
        #[cfg(target_arch = "x86_64")]
        if splinerod_core::lanes::wide() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            return unsafe { self.project_wide(v) };
        }
        self.project::<false>(v);
    }

    /// [`Self::spread`], fused where the processor has AVX2 and FMA.
    fn spread_any(&self, c: Real, out: &mut [Vector3<Real>]) {
        #[cfg(target_arch = "x86_64")]
        if splinerod_core::lanes::wide() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            return unsafe { self.spread_wide(c, out) };
        }
        self.spread::<false>(c, out);
    }

    /// [`Self::project`] fused, compiled for AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    #[cfg(target_arch = "x86_64")]
    unsafe fn project_wide(&mut self, v: &[Vector3<Real>]) {
        self.project::<true>(v);
    }

    /// `y = B v` and its lumped image `m⁻¹ B v`, per function.
    #[inline(always)]
    fn project<const FUSED: bool>(&mut self, v: &[Vector3<Real>]) {
        for (k, row) in self.functions.iter().enumerate() {
            let db = &self.db[k * self.stride..];
            let v = &v[row.first..];
            let bv = match row.width {
                6 => row_dot::<FUSED>(&db[..6], &v[..6]),
                w => row_dot::<FUSED>(&db[..w], &v[..w]),
            };
            self.y[row.index] = bv;
            self.lumped[row.index] = if row.m > 0.0 { bv / row.m } else { 0.0 };
        }
    }

    /// [`Self::spread`] fused, compiled for AVX2 and FMA.
    #[target_feature(enable = "avx2,fma")]
    #[cfg(target_arch = "x86_64")]
    unsafe fn spread_wide(&self, c: Real, out: &mut [Vector3<Real>]) {
        self.spread::<true>(c, out);
    }

    /// `out += c · Bᵀ (y − lumped)`.
    #[inline(always)]
    fn spread<const FUSED: bool>(&self, c: Real, out: &mut [Vector3<Real>]) {
        for (k, row) in self.functions.iter().enumerate() {
            let yi = c * (self.y[row.index] - self.lumped[row.index]);
            let db = &self.db[k * self.stride..];
            let out = &mut out[row.first..];
            match row.width {
                6 => add_row::<FUSED>(&mut out[..6], &db[..6], yi),
                w => add_row::<FUSED>(&mut out[..w], &db[..w], yi),
            }
        }
    }
}

impl Rows {
    /// Gives both halves of each split pair the lumped image of the pair,
    /// \((y_j + y_{j+m}) / (m_j + m_{j+m})\) (`lumped` holding each half's own).
    fn merge_pairs(&mut self, m: usize, d: usize) {
        let mut weights = [(0.0, 0.0); MAX_DEGREE];
        for row in &self.functions {
            let head = if row.index > m {
                row.index - m
            } else {
                row.index
            };
            if head >= 1 && head < d {
                let slot = &mut weights[head - 1];
                slot.0 += self.y[row.index];
                slot.1 += row.m;
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

/// `Σ_a db_a · v_a` (nalgebra's dot per entry, summed in order), fused on four-wide
/// registers with `FUSED`.
#[inline(always)]
fn row_dot<const FUSED: bool>(db: &[Vector3<Real>], v: &[Vector3<Real>]) -> Real {
    #[cfg(target_arch = "x86_64")]
    if FUSED {
        use core::arch::x86_64::*;
        // SAFETY: the fused kernels run only where the processor has AVX2 and FMA; every
        // pointer covers a 3-vector.
        unsafe {
            let mut sum = _mm256_setzero_pd();
            for (d, v) in db.iter().zip(v) {
                sum = _mm256_fmadd_pd(masked3(d.as_ptr()), masked3(v.as_ptr()), sum);
            }
            // Lanes 0 + 2, then + 1 (lane 3 is zero).
            let half = _mm_add_pd(_mm256_castpd256_pd128(sum), _mm256_extractf128_pd::<1>(sum));
            return _mm_cvtsd_f64(_mm_add_sd(half, _mm_unpackhi_pd(half, half)));
        }
    }
    db.iter().zip(v).map(|(d, v)| d.dot(v)).sum()
}

/// The 3-vector at `p` in one masked load (lane 3 zero, nothing read past `p + 2`).
///
/// # Safety
/// `p` must point at 3 readable values; the processor must have AVX.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn masked3(p: *const Real) -> core::arch::x86_64::__m256d {
    use core::arch::x86_64::*;
    _mm256_maskload_pd(p, _mm256_set_epi64x(0, -1, -1, -1))
}

/// `out_a += db_a · y`, fused on four-wide registers with `FUSED`.
#[inline(always)]
fn add_row<const FUSED: bool>(out: &mut [Vector3<Real>], db: &[Vector3<Real>], y: Real) {
    #[cfg(target_arch = "x86_64")]
    if FUSED {
        use core::arch::x86_64::*;
        use splinerod_core::simd::{load3, store3};
        // SAFETY: as in `row_dot`.
        unsafe {
            let y = _mm256_set1_pd(y);
            for (o, d) in out.iter_mut().zip(db) {
                // `out` as the simd helpers load and store it (a masked store would not
                // forward to the next function's load of the same entry).
                let p = o.as_mut_ptr();
                store3(p, _mm256_fmadd_pd(masked3(d.as_ptr()), y, load3(p)));
            }
        }
        return;
    }
    for (o, d) in out.iter_mut().zip(db) {
        *o += d * y;
    }
}

impl Stretching {
    /// Calls `f` with the rows of `B` at `rod`'s state (filled if the thread's cache does
    /// not hold them). `f` must not call back into the cache.
    pub(super) fn with_rows<R>(&self, rod: &Rod, f: impl FnOnce(&mut Rows) -> R) -> R {
        ROWS.with(|cache| f(cache.borrow_mut().filled(self, rod)))
    }

    /// Calls `f` with the rows of `B` if the thread's cache holds them at `rod`'s state;
    /// `None` if not.
    pub(super) fn with_held_rows<R>(&self, rod: &Rod, f: impl FnOnce(&Rows) -> R) -> Option<R> {
        ROWS.with(|cache| cache.borrow().held(self, rod).map(f))
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
        self.with_rows(rod, |rows| {
            let c = scale * self.stiffness;
            rows.remainder(v, c, |y| self.solve_gram(rod, y), out);
        });
    }
}
