//! The lumped mixed stretching of [`LANES`] rods at once, from their tension tables
//! ([`super::table`]; the form is in [`crate::lanes`]). The operations per function are
//! those of [`super::table::TensionTable::for_each`] and the tabulated Hessian of
//! [`super::mixed`], in the same order, each over the lanes.

use super::table::TensionTable;
use super::Stretching;
use crate::lanes::{LaneField, LaneTerm};
use splinerod_core::lanes::{mul_add, sub, ZERO};
use splinerod_core::{LaneBand, Lanes, Real, Rod, LANES};

/// Widest function block a lane evaluation takes: `2d` for degree 5.
const MAX_LANE_WIDTH: usize = 10;

/// Packed entries of a block of [`MAX_LANE_WIDTH`].
const MAX_PACKED: usize = MAX_LANE_WIDTH * (MAX_LANE_WIDTH + 1) / 2;

/// One rod's lumped mixed stretching as a lane term: its table, `EA` and multipliers.
#[derive(Debug, Clone, Copy)]
pub struct MomentTerm<'a> {
    table: &'a TensionTable,
    stiffness: Real,
    /// \\(\hat\lambda_j\\) by function index (empty: none).
    multipliers: &'a [Real],
}

impl MomentTerm<'_> {
    /// Whether the table is for `n` control points with blocks within bandwidth `bw`
    /// and of a width the lane evaluation takes.
    pub(crate) fn fits(&self, n: usize, bw: usize) -> bool {
        let width = self.table.rows().len();
        self.table.functions() + 1 == n && width <= (bw + 1).min(MAX_LANE_WIDTH)
    }

    /// Whether both tables place their functions alike.
    pub(crate) fn same_shape(&self, other: &MomentTerm<'_>) -> bool {
        self.table.same_shape(other.table)
    }

    fn multiplier(&self, index: usize) -> Real {
        self.multipliers.get(index).copied().unwrap_or(0.0)
    }
}

impl Stretching {
    /// The lane term of this energy on `rod`: the lumped mixed form on an open rod whose
    /// table is current (after [`crate::Energy::begin_step`]); `None` otherwise.
    pub(super) fn moment_term(&self, rod: &Rod) -> Option<LaneTerm<'_>> {
        let lumped = self.formulation == super::StretchFormulation::Mixed;
        if !lumped || rod.is_closed() || !self.table.matches(rod) {
            return None;
        }
        Some(LaneTerm::Moments(MomentTerm {
            table: &self.table,
            stiffness: self.axial_stiffness(),
            multipliers: self.multipliers.as_ref().map_or(&[][..], |m| &m.values),
        }))
    }
}

/// [`crate::lanes::add_lanes`] for the moment terms `terms` (checked compatible).
pub(crate) fn add_moment_lanes(
    terms: [&MomentTerm<'_>; LANES],
    q: &LaneField,
    energy: &mut Lanes,
    derivatives: Option<(&mut LaneField, &mut LaneBand)>,
) {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2 (checked on the line above).
        return unsafe { moments_avx2(terms, q, energy, derivatives) };
    }
    moments(terms, q, energy, derivatives);
}

/// [`moments`] compiled for AVX2 (four lanes per instruction instead of two).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn moments_avx2(
    terms: [&MomentTerm<'_>; LANES],
    q: &LaneField,
    energy: &mut Lanes,
    derivatives: Option<(&mut LaneField, &mut LaneBand)>,
) {
    moments(terms, q, energy, derivatives);
}

/// Energy, gradient and Hessian of the moment terms, function by function.
#[inline(always)]
fn moments(
    terms: [&MomentTerm<'_>; LANES],
    q: &LaneField,
    energy: &mut Lanes,
    mut derivatives: Option<(&mut LaneField, &mut LaneBand)>,
) {
    let rows = terms[0].table.rows();
    let mut g = [ZERO; MAX_PACKED];
    let mut r = [[ZERO; 3]; MAX_LANE_WIDTH];
    let mut db = [[ZERO; 3]; MAX_LANE_WIDTH];
    for slot in 0..terms[0].table.functions() {
        let (first, width, _, packed) = terms[0].table.function(slot);
        let mut m = ZERO;
        for (l, term) in terms.iter().enumerate() {
            let (_, _, ml, gl) = term.table.function(slot);
            m[l] = ml;
            for (e, &v) in g.iter_mut().zip(gl) {
                e[l] = v;
            }
        }
        let g = &g[..packed.len()];
        moment_derivatives(q, first, width, g, rows, &mut r, &mut db);
        let mut quad = ZERO;
        for (ra, da) in r[..width].iter().zip(&db[..width]) {
            for c in 0..3 {
                mul_add(&mut quad, ra[c], da[c]);
            }
        }
        let (mut c, mut tension) = (ZERO, ZERO);
        for l in 0..LANES {
            let b = 0.5 * (quad[l] - m[l]);
            let hat = terms[l].multiplier(slot + 1);
            c[l] = if m[l] > 0.0 {
                terms[l].stiffness / m[l]
            } else {
                0.0
            };
            tension[l] = hat + c[l] * b;
            energy[l] += 0.5 * (tension[l] + hat) * b;
        }
        if let Some((gradient, hessian)) = derivatives.as_mut() {
            for (a, da) in db[..width].iter().enumerate() {
                for coord in 0..3 {
                    mul_add(&mut gradient[3 * (first + a) + coord], da[coord], tension);
                }
            }
            add_function_blocks(hessian, first, &db[..width], g, rows, c, tension);
        }
    }
}

/// `r = q − q_first` and `db = G r` over the function's `width` points, lane by lane.
#[inline(always)]
fn moment_derivatives(
    q: &LaneField,
    first: usize,
    width: usize,
    g: &[Lanes],
    rows: &[usize],
    r: &mut [[Lanes; 3]; MAX_LANE_WIDTH],
    db: &mut [[Lanes; 3]; MAX_LANE_WIDTH],
) {
    let origin = [q[3 * first], q[3 * first + 1], q[3 * first + 2]];
    for (a, ra) in r[..width].iter_mut().enumerate() {
        *ra = std::array::from_fn(|c| sub(q[3 * (first + a) + c], origin[c]));
    }
    db[..width].iter_mut().for_each(|d| *d = [ZERO; 3]);
    for a in 0..width {
        let row = &g[rows[a]..];
        let mut sum: [Lanes; 3] =
            std::array::from_fn(|c| splinerod_core::lanes::mul(r[a][c], row[0]));
        for b in a + 1..width {
            let gab = row[b - a];
            for c in 0..3 {
                mul_add(&mut sum[c], r[b][c], gab);
                mul_add(&mut db[b][c], r[a][c], gab);
            }
        }
        for c in 0..3 {
            db[a][c] = splinerod_core::lanes::add(db[a][c], sum[c]);
        }
    }
}

/// Adds \\(c\, \partial b_a \partial b_b^T + \lambda (G_k)_{ab} I\\) at blocks
/// `(first + a, first + b)`, `a ≤ b`, lane by lane.
#[inline(always)]
fn add_function_blocks(
    hessian: &mut LaneBand,
    first: usize,
    db: &[[Lanes; 3]],
    g: &[Lanes],
    rows: &[usize],
    c: Lanes,
    lambda: Lanes,
) {
    for (a, va) in db.iter().enumerate() {
        let u: [Lanes; 3] = std::array::from_fn(|k| splinerod_core::lanes::mul(va[k], c));
        let row = hessian.row_mut(first + a);
        for ((block, vb), gab) in row.iter_mut().zip(&db[a..]).zip(&g[rows[a]..]) {
            for (col, vc) in vb.iter().enumerate() {
                for (r, ur) in u.iter().enumerate() {
                    mul_add(&mut block[3 * col + r], *ur, *vc);
                }
            }
            let d = splinerod_core::lanes::mul(lambda, *gab);
            for e in [0, 4, 8] {
                block[e] = splinerod_core::lanes::add(block[e], d);
            }
        }
    }
}
