//! The mixed form's integrals, tabulated once per basis: a step evaluates the energy,
//! gradient and Hessian per tension function instead of per quadrature point.
//!
//! With \\(g_0 = \sqrt{g_0}^{\,2}\\) the strain moment of tension function \\(\varphi_k\\) is a
//! quadratic form in the control points,
//!
//! \\[ b_k = \int \varphi_k\, \frac{|C'|^2 - g_0}{2 g_0}\, \sqrt{g_0}\, ds
//!     = \tfrac12\, q^T G_k\, q - \tfrac12 m_k, \qquad
//!     (G_k)_{ab} = \int \varphi_k\, g_0^{-1/2}\, b_a' b_b'\, ds, \\]
//!
//! so \\(\partial b_k/\partial q_a = \sum_b (G_k)_{ab}\, q_b\\) and the geometric stiffness is
//! \\(\sum_k \lambda_k G_k \otimes I\\). `G_k` (a symmetric `2d × 2d` block of scalars per
//! function, since \\(\varphi_k\\) spans `d` knot spans) and \\(m_k\\) depend only on the
//! basis, the quadrature and the rest metric, so they are tabulated when those change
//! ([`super::Stretching`]'s `begin_step` and `on_knot_change`), keyed by the rod's
//! topology epoch; a rod the table does not match is evaluated point by point
//! ([`super::mixed`]), with the same result up to round-off (the same quadrature sums,
//! associated differently).
//!
//! **Round-off.** The rows of `G_k` sum to zero (the derivatives of a partition of
//! unity do), so `G_k q` is evaluated on the positions relative to the function's first
//! control point: a rod far from the origin loses no more digits than one at it.
//!
//! Cost per function for a cubic: 21 tabulated numbers, about 400 multiply-adds for
//! gradient and Hessian together, against a pass over 12 quadrature points.

use super::Stretching;
use nalgebra::Vector3;
use splinerod_core::{Real, Rod, MAX_DEGREE};
use std::sync::atomic::{AtomicU64, Ordering};

/// Control points one tension function can touch: the functions of its `d` spans.
pub(super) const MAX_WIDTH: usize = 2 * MAX_DEGREE;

/// `G_k` and `m_k` of every tension function `1 ..= n − 1` of one basis.
#[derive(Debug, Clone, Default)]
pub(super) struct TensionTable {
    /// Topology epoch of the rod tabulated.
    epoch: u64,
    /// Its number of quadrature points (a second guard: the table follows them).
    points: usize,
    /// Row starts of the packed upper triangle of a `W × W` block, `W = 2d`.
    rows: Vec<usize>,
    /// Packed entries per function.
    stride: usize,
    /// Per function `j = 1 ..= n − 1` at `j − 1`: first control point touched.
    first: Vec<usize>,
    /// Per function: control points touched (0 for an empty support).
    width: Vec<usize>,
    /// Per function: \\(m_k\\).
    m: Vec<Real>,
    /// Per function: the packed upper triangle of `G_k`, rows of the full width `W`.
    g: Vec<Real>,
    /// Which tabulation this is ([`Self::stamp`]; 0: none yet).
    stamp: u64,
}

/// The stamp of the next tabulation: one counter for every table, so that no two
/// tabulations of a process share one.
static STAMPS: AtomicU64 = AtomicU64::new(1);

/// One tension function's strain moment and its derivatives at the rod's positions.
#[derive(Debug, Clone, Copy)]
pub(super) struct Moment<'a> {
    /// Index `j` of the function.
    pub index: usize,
    /// First control point touched.
    pub first: usize,
    /// Strain moment \\(b_k\\).
    pub b: Real,
    /// Weight \\(m_k\\).
    pub m: Real,
    /// \\(\partial b_k/\partial q_{first + a}\\), `a < width`.
    pub db: &'a [Vector3<Real>],
    /// `G_k` packed (see [`TensionTable::entry`]).
    pub g: &'a [Real],
    /// Row starts of the packing.
    pub rows: &'a [usize],
}

impl Moment<'_> {
    /// \\((G_k)_{ab}\\), `a ≤ b`.
    #[inline]
    pub fn entry(&self, a: usize, b: usize) -> Real {
        self.g[self.rows[a] + b - a]
    }
}

impl TensionTable {
    /// Whether the table was made for `rod`'s current basis and quadrature.
    #[inline]
    pub fn matches(&self, rod: &Rod) -> bool {
        self.epoch == rod.topology_epoch() && self.points == rod.quadrature().len()
    }

    /// Tabulates `G_k`, `m_k` for `rod` with the rest metric of `energy`.
    pub fn build(&mut self, energy: &Stretching, rod: &Rod) {
        let d = rod.basis().degree();
        let w = 2 * d;
        self.rows.clear();
        self.rows.extend((0..w).scan(0, |start, a| {
            let row = *start;
            *start += w - a;
            Some(row)
        }));
        self.stride = w * (w + 1) / 2;
        self.place_functions(rod);
        let functions = self.first.len();
        self.m.clear();
        self.m.resize(functions, 0.0);
        self.g.clear();
        self.g.resize(functions * self.stride, 0.0);
        let table = rod.quadrature();
        for p in 0..table.len() {
            let qp = table.point(p);
            let root = energy.root_g0(p);
            for (k, &phi) in qp.lower.iter().enumerate() {
                // lower[k] is function first + 1 + k, stored at first + k.
                let f = qp.first + k;
                if f >= functions {
                    continue;
                }
                let offset = qp.first - self.first[f];
                self.m[f] += qp.weight * phi * root;
                let c = qp.weight * phi / root;
                let g = &mut self.g[f * self.stride..(f + 1) * self.stride];
                for (a, &da) in qp.d1.iter().enumerate() {
                    let row = self.rows[offset + a] - (offset + a);
                    for (b, &db) in qp.d1.iter().enumerate().skip(a) {
                        g[row + offset + b] += c * da * db;
                    }
                }
            }
        }
        (self.epoch, self.points) = (rod.topology_epoch(), table.len());
        self.stamp = STAMPS.fetch_add(1, Ordering::Relaxed);
    }

    /// A number that identifies this tabulation (its places, weights and `G_k`): each
    /// [`Self::build`] takes a new one, shared by no other table (clones keep it, with
    /// the contents); 0 before the first.
    pub fn stamp(&self) -> u64 {
        self.stamp
    }

    /// The first control point and the width of every function's block: the points
    /// its support touches.
    fn place_functions(&mut self, rod: &Rod) {
        let (n, table) = (rod.len(), rod.quadrature());
        let functions = n.saturating_sub(1);
        self.first.clear();
        self.first.resize(functions, usize::MAX);
        self.width.clear();
        self.width.resize(functions, 0);
        for p in 0..table.len() {
            let (first, order) = (table.first_function(p), table.order());
            for f in first..(first + order - 1).min(functions) {
                self.first[f] = self.first[f].min(first);
                self.width[f] = self.width[f].max(first + order - self.first[f]);
            }
        }
        for (first, width) in self.first.iter_mut().zip(&mut self.width) {
            if *width == 0 {
                *first = 0;
            }
        }
    }

    /// Number of tension functions tabulated (`n − 1`).
    pub fn functions(&self) -> usize {
        self.first.len()
    }

    /// Function `index − 1`'s first control point, width, weight \(m_k\) and packed
    /// `G_k` (see [`Moment::entry`]).
    #[inline]
    pub fn function(&self, slot: usize) -> (usize, usize, Real, &[Real]) {
        let g = &self.g[slot * self.stride..(slot + 1) * self.stride];
        (self.first[slot], self.width[slot], self.m[slot], g)
    }

    /// Row starts of the packed blocks.
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// Whether `other` places its functions on the same control points with the same
    /// packing (the tables of rods with the same knots do).
    pub fn same_shape(&self, other: &TensionTable) -> bool {
        (self.first == other.first && self.width == other.width) && self.rows == other.rows
    }

    /// The weight \(m_k\) of function `index` (`1 ..= n − 1`).
    #[inline]
    pub fn weight(&self, index: usize) -> Real {
        self.m[index - 1]
    }

    /// The [`Moment`] of function `index` from its strain moment, weight and derivatives
    /// computed before (by [`Self::for_each`] at the same positions).
    pub fn moment<'a>(
        &'a self,
        (index, first): (usize, usize),
        (b, m): (Real, Real),
        db: &'a [Vector3<Real>],
    ) -> Moment<'a> {
        let j = index - 1;
        Moment {
            index,
            first,
            b,
            m,
            db,
            g: &self.g[j * self.stride..(j + 1) * self.stride],
            rows: &self.rows,
        }
    }

    /// Calls `f` with every tension function's [`Moment`] at the rod's positions, in
    /// increasing order (functions with an empty support have width 0). No allocation.
    pub fn for_each(&self, rod: &Rod, mut f: impl FnMut(&Moment<'_>)) {
        let mut scratch = [[Vector3::zeros(); MAX_WIDTH]; 2];
        for (j, &width) in self.width.iter().enumerate() {
            f(&self.moment_at::<false>(rod, (j, width), &mut scratch));
        }
    }

    /// Control points function `j + 1` touches.
    #[inline(always)]
    pub fn width(&self, j: usize) -> usize {
        self.width[j]
    }

    /// The [`Moment`] of function `j + 1`, which touches `width` points (its
    /// [`Self::width`]; a caller passing a constant lets every loop unroll), with
    /// `scratch` room for `q − q₀` and the derivatives; the products of `G_k q` fused
    /// with `FUSED` (for callers compiled with fused multiply-add, where `f64::mul_add`
    /// is one instruction).
    #[inline(always)]
    pub fn moment_at<'a, const FUSED: bool>(
        &'a self,
        rod: &Rod,
        (j, width): (usize, usize),
        [r, db]: &'a mut [[Vector3<Real>; MAX_WIDTH]; 2],
    ) -> Moment<'a> {
        let b = self.derivatives_at::<FUSED>(rod, (j, width), r, db);
        let j = j + 1;
        self.moment((j, self.first[j - 1]), (b, self.m[j - 1]), &db[..width])
    }

    /// The strain moment \(b_k\) of function `j + 1`, which touches `width` points (see
    /// [`Self::moment_at`]), with its derivatives written to `db[..width]` and `q − q₀`
    /// to `r[..width]` (both at least `width` long).
    #[inline(always)]
    pub fn derivatives_at<const FUSED: bool>(
        &self,
        rod: &Rod,
        (j, width): (usize, usize),
        r: &mut [Vector3<Real>],
        db: &mut [Vector3<Real>],
    ) -> Real {
        let first = self.first[j];
        let g = &self.g[j * self.stride..(j + 1) * self.stride];
        let q = &rod.positions[first..first + width];
        moment_derivatives::<FUSED>(q, g, &self.rows, r, db);
        let quad: Real = r[..width]
            .iter()
            .zip(&db[..width])
            .map(|(r, d)| dot::<FUSED>(r, d))
            .sum();
        0.5 * (quad - self.m[j])
    }
}

/// `r = q − q₀` and `db = G r` for one function's block `G` (packed rows `rows`) and
/// positions `q` (`q.len() ≤ r.len()`; the rest of `r` and `db` is left as it was),
/// each product fused with `FUSED`. Each `db_b = Σ_a G_ab r_a` is summed in registers
/// and stored once (a sum scattered into `db` row by row would reload every entry it
/// had just stored, and wait on it).
#[inline(always)]
fn moment_derivatives<const FUSED: bool>(
    q: &[Vector3<Real>],
    g: &[Real],
    rows: &[usize],
    r: &mut [Vector3<Real>],
    db: &mut [Vector3<Real>],
) {
    #[cfg(target_arch = "x86_64")]
    if FUSED {
        // SAFETY: the fused pass runs only where the processor has AVX2 and FMA
        // (`Stretching::lumped_derivatives_wide`).
        unsafe { moment_derivatives_wide(q, g, rows, r, db) };
        return;
    }
    let width = q.len();
    let origin = q.first().copied().unwrap_or_default();
    for (r, q) in r.iter_mut().zip(q) {
        *r = q - origin;
    }
    for b in 0..width {
        let mut sum = Vector3::zeros();
        for (a, r) in r[..width].iter().enumerate() {
            // G is symmetric: entry (a, b) is stored at its upper place.
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            add_times::<FUSED>(&mut sum, r, g[rows[lo] + hi - lo]);
        }
        db[b] = sum;
    }
}

/// [`moment_derivatives`] fused, each 3-vector in a four-wide register
/// ([`splinerod_core::simd`]): the same products in the same order, lane by lane.
///
/// # Safety
/// The processor must have AVX2 and FMA; `r` and `db` must hold `q.len()` entries.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
unsafe fn moment_derivatives_wide(
    q: &[Vector3<Real>],
    g: &[Real],
    rows: &[usize],
    r: &mut [Vector3<Real>],
    db: &mut [Vector3<Real>],
) {
    use core::arch::x86_64::*;
    use splinerod_core::simd::{load3, store3};
    let width = q.len().min(MAX_WIDTH).min(r.len()).min(db.len());
    let Some(first) = q.first() else {
        return;
    };
    let origin = load3(first.as_ptr());
    // Plain loops, no closures (see `splinerod_core::simd`).
    let mut offsets = [_mm256_setzero_pd(); MAX_WIDTH];
    for a in 0..width {
        offsets[a] = _mm256_sub_pd(load3(q[a].as_ptr()), origin);
        store3(r[a].as_mut_ptr(), offsets[a]);
    }
    for b in 0..width {
        let mut sum = _mm256_setzero_pd();
        for (a, offset) in offsets.iter().enumerate().take(width) {
            // G is symmetric: entry (a, b) is stored at its upper place.
            let (lo, hi) = if a <= b { (a, b) } else { (b, a) };
            sum = _mm256_fmadd_pd(*offset, _mm256_set1_pd(g[rows[lo] + hi - lo]), sum);
        }
        store3(db[b].as_mut_ptr(), sum);
    }
}

/// `acc += v · s`, each coordinate fused with `FUSED`.
#[inline(always)]
pub(super) fn add_times<const FUSED: bool>(acc: &mut Vector3<Real>, v: &Vector3<Real>, s: Real) {
    for (a, &x) in acc.iter_mut().zip(v.iter()) {
        *a = if FUSED { x.mul_add(s, *a) } else { *a + x * s };
    }
}

/// `a · b` (nalgebra's order, \((a_0 b_0 + a_1 b_1) + a_2 b_2\)), fused with `FUSED`.
#[inline(always)]
fn dot<const FUSED: bool>(a: &Vector3<Real>, b: &Vector3<Real>) -> Real {
    if FUSED {
        a.z.mul_add(b.z, a.y.mul_add(b.y, a.x * b.x))
    } else {
        a.dot(b)
    }
}
