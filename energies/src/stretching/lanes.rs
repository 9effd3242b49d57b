//! The lumped mixed stretching of [`LANES`] rods at once, from their tension tables
//! ([`super::table`]; the form is in [`crate::lanes`]). The operations per function are
//! those of [`super::table::TensionTable::for_each`] and the tabulated Hessian of
//! [`super::mixed`], in the same order, each over the lanes.

use super::lane_table::{with_lane_table, LaneTable};
use super::table::TensionTable;
use super::Stretching;
use crate::lanes::{LaneField, LaneTerm};
use splinerod_core::lanes::{fma, sub, LaneBlock, ZERO};
use splinerod_core::{Derivatives, LaneBand, Lanes, QuadratureTable, Real, Rod, LANES};

/// Widest function block a lane evaluation takes: `2d` for degree 5.
const MAX_LANE_WIDTH: usize = 10;

/// One rod's lumped mixed stretching as a lane term: its table, `EA` and multipliers.
#[derive(Debug, Clone, Copy)]
pub struct MomentTerm<'a> {
    table: &'a TensionTable,
    stiffness: Real,
    /// \\(\hat\lambda_j\\) by function index (empty: none).
    multipliers: &'a [Real],
    /// The rod's quadrature, for the projection guard's test ([`guard_idle`], each lane
    /// on its own rod's); `None`: the rod has no guard (not asked for, or inextensible).
    quadrature: Option<&'a QuadratureTable>,
}

impl MomentTerm<'_> {
    /// Whether the term carries an inextensible rod's multipliers.
    pub(crate) fn has_multipliers(&self) -> bool {
        !self.multipliers.is_empty()
    }

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

    /// The rod's tension table.
    pub(super) fn table(&self) -> &TensionTable {
        self.table
    }

    /// `EA`, N.
    pub(super) fn stiffness(&self) -> Real {
        self.stiffness
    }

    fn multiplier(&self, index: usize) -> Real {
        self.multipliers.get(index).copied().unwrap_or(0.0)
    }
}

impl Stretching {
    /// The lane term of this energy on `rod`: the lumped mixed form on an open rod whose
    /// table is current (after [`crate::Lifecycle::begin_step`]); `None` otherwise.
    /// A rod with a rest curve has none: the guard's test ([`guard_idle`]) assumes
    /// unit rest speed.
    pub(super) fn moment_term<'a>(&'a self, rod: &'a Rod) -> Option<LaneTerm<'a>> {
        let lumped = self.formulation == super::StretchFormulation::Mixed;
        if !lumped || rod.is_closed() || !self.table.matches(rod) || self.rest.is_some() {
            return None;
        }
        let guarded = self.guard && self.multipliers.is_none();
        Some(LaneTerm::Moments(MomentTerm {
            table: &self.table,
            stiffness: self.axial_stiffness(),
            multipliers: self.multipliers.as_ref().map_or(&[][..], |m| &m.values),
            quadrature: guarded.then(|| rod.quadrature()),
        }))
    }
}

/// [`crate::lanes::add_lanes`] for the moment terms `terms` (checked compatible); per
/// lane, false where the lane's projection guard would act ([`guard_idle`]): the lanes
/// do not replicate it (that member's step is taken alone). Nothing is added when no
/// lane is idle.
pub(crate) fn add_moment_lanes(
    terms: [&MomentTerm<'_>; LANES],
    q: &LaneField,
    energy: &mut Lanes,
    derivatives: Option<Derivatives<'_>>,
) -> [bool; LANES] {
    let idle = guard_idle(terms, q);
    if !idle.contains(&true) {
        return idle;
    }
    with_lane_table(terms, |table| {
        #[cfg(target_arch = "x86_64")]
        if splinerod_core::lanes::wide() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            unsafe { moments_wide(terms, table, q, energy, derivatives) };
            return;
        }
        moments::<false>(terms, table, q, energy, derivatives);
    });
    idle
}

/// Per lane, whether the guard ([`super::guard`]) is idle on the lane's rod: no guard,
/// or on each knot span every quadrature point's strain within
/// [`super::GUARD_DEVIATION`] of the span's weighted mean, \(C'\) from the lane's own
/// table (a dozen multiply-adds per point). Each lane is tested alone, so a lane's
/// answer does not depend on the others.
fn guard_idle(terms: [&MomentTerm<'_>; LANES], q: &LaneField) -> [bool; LANES] {
    std::array::from_fn(|l| terms[l].quadrature.is_none_or(|t| lane_guard_idle(t, q, l)))
}

/// [`guard_idle`] for lane `l` on the quadrature table `table`.
fn lane_guard_idle(table: &QuadratureTable, q: &LaneField, l: usize) -> bool {
    let mut points = table.walk().peekable();
    let mut strains = [0.0; MAX_SPAN_POINTS];
    let mut weights = [0.0; MAX_SPAN_POINTS];
    while let Some(head) = points.peek() {
        let first = head.first;
        let mut count = 0;
        while let Some(qp) = points.next_if(|p| p.first == first) {
            if count == MAX_SPAN_POINTS {
                return false;
            }
            let mut c1 = [0.0; 3];
            for (a, &w) in qp.d1.iter().enumerate() {
                for (c, sum) in c1.iter_mut().enumerate() {
                    *sum += w * q[3 * (qp.first + a) + c][l];
                }
            }
            strains[count] = 0.5 * (c1[0] * c1[0] + c1[1] * c1[1] + c1[2] * c1[2] - 1.0);
            weights[count] = qp.weight;
            count += 1;
        }
        let total: Real = weights[..count].iter().sum();
        let mean = (0..count).map(|p| weights[p] * strains[p]).sum::<Real>() / total;
        if strains[..count]
            .iter()
            .any(|e| (e - mean).abs() > super::GUARD_DEVIATION)
        {
            return false;
        }
    }
    true
}

/// Quadrature points per span the lanes' guard test takes (more: stepped alone).
const MAX_SPAN_POINTS: usize = 16;

/// [`moments`] compiled for AVX2 with fused multiply-add (four lanes per instruction
/// instead of two, one instruction per multiply-add).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn moments_wide(
    terms: [&MomentTerm<'_>; LANES],
    table: &LaneTable,
    q: &LaneField,
    energy: &mut Lanes,
    derivatives: Option<Derivatives<'_>>,
) {
    moments::<true>(terms, table, q, energy, derivatives);
}

/// Energy, gradient and Hessian of the moment terms, function by function, from their
/// gathered tables `table`.
#[inline(always)]
fn moments<const FUSED: bool>(
    terms: [&MomentTerm<'_>; LANES],
    table: &LaneTable,
    q: &LaneField,
    energy: &mut Lanes,
    mut derivatives: Option<Derivatives<'_>>,
) {
    let rows = terms[0].table.rows();
    let hats = terms.iter().any(|t| t.has_multipliers());
    let mut r = [[ZERO; 3]; MAX_LANE_WIDTH];
    let mut db = [[ZERO; 3]; MAX_LANE_WIDTH];
    for (slot, f) in table.functions.iter().enumerate() {
        let (first, width) = (f.first, f.width);
        let g = &table.g[f.offset..f.offset + f.len];
        moment_derivatives::<FUSED>(q, first, width, g, rows, &mut r, &mut db);
        let mut quad = ZERO;
        for (ra, da) in r[..width].iter().zip(&db[..width]) {
            for c in 0..3 {
                fma::<FUSED>(&mut quad, ra[c], da[c]);
            }
        }
        // Without multipliers every lane's is 0 (`multiplier`'s default).
        let hat: Lanes = match hats {
            true => std::array::from_fn(|l| terms[l].multiplier(slot + 1)),
            false => ZERO,
        };
        let (c, mut tension) = (f.c, ZERO);
        for l in 0..LANES {
            let b = 0.5 * (quad[l] - f.m[l]);
            tension[l] = hat[l] + c[l] * b;
            energy[l] += 0.5 * (tension[l] + hat[l]) * b;
        }
        if let Some(d) = derivatives.as_mut() {
            let (points, _) = d.gradient[3 * first..3 * (first + width)].as_chunks_mut::<3>();
            for (point, da) in points.iter_mut().zip(&db[..width]) {
                for coord in 0..3 {
                    fma::<FUSED>(&mut point[coord], da[coord], tension);
                }
            }
            let h = d.hessian_scale;
            let (c, lambda) = (c.map(|c| c * h), tension.map(|t| t * h));
            add_function_blocks::<FUSED>(d.hessian, first, &db[..width], g, rows, c, lambda);
        }
    }
}

/// `r = q − q_first` and `db = G r` over the function's `width` points, lane by lane.
#[inline(always)]
fn moment_derivatives<const FUSED: bool>(
    q: &LaneField,
    first: usize,
    width: usize,
    g: &[Lanes],
    rows: &[usize],
    r: &mut [[Lanes; 3]; MAX_LANE_WIDTH],
    db: &mut [[Lanes; 3]; MAX_LANE_WIDTH],
) {
    let origin = [q[3 * first], q[3 * first + 1], q[3 * first + 2]];
    let (points, _) = q[3 * first..3 * (first + width)].as_chunks::<3>();
    for (ra, point) in r[..width].iter_mut().zip(points) {
        *ra = std::array::from_fn(|c| sub(point[c], origin[c]));
    }
    // The first row starts every sum of `db` (no pass zeroing it first).
    if width > 0 {
        add_row::<FUSED, true>(0, width, &g[rows[0]..], r, db);
    }
    for a in 1..width {
        add_row::<FUSED, false>(a, width, &g[rows[a]..], r, db);
    }
}

/// Row `a` of `G r` (its entries `row` from the diagonal on): `db_a += Σ_{b≥a} G_ab r_b`
/// and `db_b += G_ab r_a` for `b > a`; with `START`, the sums start here, from zero (the
/// same bits as adding to stored zeros).
#[inline(always)]
fn add_row<const FUSED: bool, const START: bool>(
    a: usize,
    width: usize,
    row: &[Lanes],
    r: &[[Lanes; 3]; MAX_LANE_WIDTH],
    db: &mut [[Lanes; 3]; MAX_LANE_WIDTH],
) {
    let mut sum: [Lanes; 3] = std::array::from_fn(|c| splinerod_core::lanes::mul(r[a][c], row[0]));
    for b in a + 1..width {
        let gab = row[b - a];
        for c in 0..3 {
            fma::<FUSED>(&mut sum[c], r[b][c], gab);
            if START {
                db[b][c] = ZERO;
            }
            fma::<FUSED>(&mut db[b][c], r[a][c], gab);
        }
    }
    for c in 0..3 {
        let before = if START { ZERO } else { db[a][c] };
        db[a][c] = splinerod_core::lanes::add(before, sum[c]);
    }
}

/// Adds \\(c\, \partial b_a \partial b_b^T + \lambda (G_k)_{ab} I\\) at blocks
/// `(first + a, first + b)`, `a ≤ b`, lane by lane ([`LaneBand::row_to_add`]: a block
/// not written yet is written, from zero).
#[inline(always)]
fn add_function_blocks<const FUSED: bool>(
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
        let (row, held) = hessian.row_to_add(first + a, db.len() - a);
        let mut blocks = row.iter_mut().zip(&db[a..]).zip(&g[rows[a]..]);
        for ((block, vb), gab) in blocks.by_ref().take(held) {
            *block = block_sum::<FUSED>(*block, &u, vb, lambda, *gab);
        }
        // Blocks the band holds no value in yet: from zero.
        for ((block, vb), gab) in blocks {
            *block = block_sum::<FUSED>([ZERO; 9], &u, vb, lambda, *gab);
        }
    }
}

/// `sum + u vᵀ + λ g I` for one block, lane by lane (summed in registers and stored
/// once by the caller: a store followed by a partial reload of the same entry stalls
/// the store forwarding).
#[inline(always)]
fn block_sum<const FUSED: bool>(
    mut sum: LaneBlock,
    u: &[Lanes; 3],
    v: &[Lanes; 3],
    lambda: Lanes,
    g: Lanes,
) -> LaneBlock {
    for (col, vc) in v.iter().enumerate() {
        for (r, ur) in u.iter().enumerate() {
            fma::<FUSED>(&mut sum[3 * col + r], *ur, *vc);
        }
    }
    let d = splinerod_core::lanes::mul(lambda, g);
    for e in [0, 4, 8] {
        sum[e] = splinerod_core::lanes::add(sum[e], d);
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{LaneForm, Lifecycle};
    use nalgebra::Vector3;
    use splinerod_core::{BSplineSpace, Material};

    #[test]
    fn the_plain_and_the_fused_kernels_agree_to_round_off() {
        let material = Material {
            rest_length: 1.0,
            linear_density: 0.1,
        };
        let basis = BSplineSpace::clamped_uniform(3, 9, 1.0).expect("basis");
        let end = Vector3::new(1.2, 0.1, 0.0);
        let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
        let mut s = Stretching::new(80.0).expect("stretching");
        s.begin_step(&rod, 1e-3).expect("table");
        let Some(LaneTerm::Moments(term)) = s.lane_term(&rod) else {
            panic!("lane form");
        };
        let n = rod.len();
        let q: Vec<Lanes> = (0..3 * n)
            .map(|k| {
                std::array::from_fn(|l| rod.positions[k / 3][k % 3] * (1.0 + 0.01 * l as Real))
            })
            .collect();
        let run = |fused: bool| {
            let (mut e, mut g, mut h) =
                ([0.0; LANES], vec![[0.0; LANES]; 3 * n], LaneBand::default());
            h.reset(n, 5);
            let d = Derivatives {
                gradient: &mut g,
                hessian: &mut h,
                hessian_scale: 1.0,
            };
            let terms = [&term; LANES];
            with_lane_table(terms, |table| match fused {
                true => moments::<true>(terms, table, &q, &mut e, Some(d)),
                false => moments::<false>(terms, table, &q, &mut e, Some(d)),
            });
            (e, g, h)
        };
        let (a, b) = (run(false), run(true));
        let close = |x: Real, y: Real| (x - y).abs() <= 1e-12 * (1.0 + x.abs());
        assert!(a.0.iter().zip(&b.0).all(|(x, y)| close(*x, *y)));
        assert!(a
            .1
            .iter()
            .flatten()
            .zip(b.1.iter().flatten())
            .all(|(x, y)| close(*x, *y)));
        let (ha, hb) = (a.2.blocks().iter().flatten(), b.2.blocks().iter().flatten());
        assert!(ha.flatten().zip(hb.flatten()).all(|(x, y)| close(*x, *y)));
    }
}
