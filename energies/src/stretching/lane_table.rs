//! The lanes' copy of their tension tables ([`super::lanes`]): each function's place,
//! weights \\(m_k\\), \\(EA/m_k\\) and packed `G_k` entries one vector per entry, gathered
//! from the [`LANES`] tables once and kept while the same tables and stiffnesses come
//! back (a group stepped many times in its lanes, #47, gathers them once instead of at
//! every evaluation). The values are the tables' own, copied; `EA/m_k` is the division
//! the evaluation made, made once.

use super::lanes::MomentTerm;
use splinerod_core::lanes::ZERO;
use splinerod_core::{Lanes, LANES};
use std::cell::RefCell;

/// One function's place in the lanes' table.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct LaneFunction {
    /// First control point touched.
    pub first: usize,
    /// Control points touched.
    pub width: usize,
    /// Where its packed `G_k` starts in [`LaneTable::g`].
    pub offset: usize,
    /// Its packed entries.
    pub len: usize,
    /// \\(m_k\\) per lane.
    pub m: Lanes,
    /// \\(EA/m_k\\) per lane (0 where \\(m_k \le 0\\)).
    pub c: Lanes,
}

/// The gathered tables of the last moment terms evaluated on a thread.
#[derive(Debug, Default)]
pub(super) struct LaneTable {
    /// Per lane: the table's stamp and the stiffness's bits (stamps are never 0, so
    /// an empty key matches no terms).
    key: [(u64, u64); LANES],
    /// Per function, in order.
    pub functions: Vec<LaneFunction>,
    /// Every function's packed `G_k`, one vector per entry.
    pub g: Vec<Lanes>,
}

thread_local! {
    /// This thread's [`LaneTable`] (grown once; no allocation while the sizes hold).
    static LANE_TABLE: RefCell<LaneTable> = RefCell::new(LaneTable::default());
}

/// Runs `f` with this thread's [`LaneTable`] gathered for `terms` (checked compatible:
/// one shape).
pub(super) fn with_lane_table<R>(
    terms: [&MomentTerm<'_>; LANES],
    f: impl FnOnce(&LaneTable) -> R,
) -> R {
    LANE_TABLE.with(|table| {
        let mut table = table.borrow_mut();
        let key = terms.map(|t| (t.table().stamp(), t.stiffness().to_bits()));
        if key != table.key || key.iter().any(|k| k.0 == 0) {
            table.gather(terms);
            table.key = key;
        }
        f(&table)
    })
}

impl LaneTable {
    /// Gathers every function of `terms`' tables, lane by lane.
    fn gather(&mut self, terms: [&MomentTerm<'_>; LANES]) {
        let count = terms[0].table().functions();
        let stride = (0..count)
            .map(|s| terms[0].table().function(s).3.len())
            .max();
        let stride = stride.unwrap_or(0).max(1);
        // Sized in place: no allocation, and no pass, while the shape holds.
        self.functions.resize(count, LaneFunction::default());
        self.g.resize(count * stride, ZERO);
        let rows = self.g.chunks_exact_mut(stride);
        for (slot, (f, g)) in self.functions.iter_mut().zip(rows).enumerate() {
            let tables = terms.map(|t| t.table().function(slot));
            let (first, width, _, packed) = tables[0];
            let len = packed.len();
            let m: Lanes = std::array::from_fn(|l| tables[l].2);
            let c = std::array::from_fn(|l| {
                if m[l] > 0.0 {
                    terms[l].stiffness() / m[l]
                } else {
                    0.0
                }
            });
            // Each lane's G_k entry by entry: one vector per entry.
            let gl = tables.map(|t| &t.3[..len]);
            for (e, entry) in g[..len].iter_mut().enumerate() {
                *entry = std::array::from_fn(|l| gl[l][e]);
            }
            *f = LaneFunction {
                first,
                width,
                offset: slot * stride,
                len,
                m,
                c,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use crate::lanes::{add_lanes, LaneTerm};
    use crate::{LaneForm, Lifecycle, Stretching};
    use nalgebra::Vector3;
    use splinerod_core::{BSplineSpace, Lanes, Material, Real, Rod, LANES};

    fn rod(stretch: Real) -> Rod {
        let material = Material {
            rest_length: 1.0,
            linear_density: 0.1,
        };
        let basis = BSplineSpace::clamped_uniform(3, 9, 1.0).expect("basis");
        let end = Vector3::new(stretch, 0.1, 0.0);
        Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod")
    }

    /// Each lane's energy from `energies` (one per lane) on `rods`.
    fn energies(energies: &[Stretching], rods: &[Rod]) -> Lanes {
        let terms: [LaneTerm<'_>; LANES] =
            std::array::from_fn(|l| energies[l].lane_term(&rods[l]).expect("lane form"));
        let n = rods[0].len();
        let q: Vec<Lanes> = (0..3 * n)
            .map(|k| std::array::from_fn(|l| rods[l].positions[k / 3][k % 3]))
            .collect();
        let mut energy = [0.0; LANES];
        assert_eq!(add_lanes(&terms, &q, &mut energy, None), [true; LANES]);
        energy
    }

    /// The gathered tables follow the terms: another stiffness or a new tabulation is
    /// gathered anew, and coming back to the first terms gives their bits again.
    #[test]
    fn the_gathered_tables_follow_the_tables_and_stiffnesses() {
        let rods: Vec<Rod> = (0..LANES).map(|l| rod(1.1 + 0.01 * l as Real)).collect();
        let make = |ea: Real| -> Vec<Stretching> {
            rods.iter()
                .map(|rod| {
                    let mut s = Stretching::new(ea).expect("stretching");
                    s.begin_step(rod, 1e-3).expect("table");
                    s
                })
                .collect()
        };
        let (soft, stiff) = (make(50.0), make(80.0));
        let first = energies(&soft, &rods);
        let other = energies(&stiff, &rods);
        for l in 0..LANES {
            assert!((other[l] / first[l] - 1.6).abs() < 1e-12, "lane {l}");
        }
        assert_eq!(energies(&soft, &rods), first);
        // A rebuilt table takes a new stamp (so its lanes are gathered again).
        let mut rebuilt = make(50.0);
        let stamp = rebuilt[0].table.stamp();
        rebuilt[0].table.build(&soft[0], &rods[0]);
        assert_ne!(rebuilt[0].table.stamp(), stamp);
        assert_eq!(energies(&rebuilt, &rods), first);
    }
}
