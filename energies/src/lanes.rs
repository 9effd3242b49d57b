//! Energies of [`LANES`] rods of one shape evaluated at once, structure of arrays (the
//! batched ensemble step, #17; storage in [`splinerod_core::lanes`]).
//!
//! An energy joins the batched step by describing itself as a [`LaneTerm`]
//! ([`crate::LaneForm::lane_term`]): a form whose evaluation is written once for all lanes.
//! The forms are
//!
//! - **gravity** on the lumped masses, \\(E = -\sum_i m_i\, g \cdot q_i\\) (gradient
//!   \\(-m_i g\\), no Hessian);
//! - the **lumped mixed stretching** from its tabulated moments ([`crate::Stretching`]
//!   with [`crate::StretchFormulation::Mixed`]): per tension function `k`,
//!   \\(b_k = \tfrac12 q^T G_k q - \tfrac12 m_k\\), tension
//!   \\(\lambda_k = \hat\lambda_k + \tfrac{EA}{m_k} b_k\\),
//!   \\(E = \sum_k \tfrac12(\lambda_k + \hat\lambda_k) b_k\\), gradient
//!   \\(\sum_k \lambda_k \partial b_k\\) and Hessian
//!   \\(\sum_k \tfrac{EA}{m_k} \partial b_k \partial b_k^T + \lambda_k G_k \otimes I\\)
//!   (each lane with its own table, stiffness and multipliers).
//!
//! - **bending** ([`crate::Bending`]), from the rods' common quadrature table: per point
//!   the exact curvature density, its gradient and its exact Hessian (each lane with its
//!   own `EI`).
//!
//! Each lane's result equals the energy's own evaluation up to round-off (the same sums,
//! associated alike; the tests compare them). An energy that is not one of these forms
//! returns `None` and its rod is stepped on its own, with the same result.

use crate::bending::BendingTerm;
use crate::stretching::MomentTerm;
use nalgebra::Vector3;
use splinerod_core::{Derivatives, Lanes, Real, LANES};

/// An energy in a form the batched step evaluates for several rods at once.
#[derive(Debug, Clone, Copy)]
pub enum LaneTerm<'a> {
    /// \\(E = -\sum_i m_i\, g \cdot q_i\\).
    Gravity {
        /// Acceleration, m/s².
        g: Vector3<Real>,
        /// The rod's lumped masses, kg.
        masses: &'a [Real],
    },
    /// The lumped mixed stretching's tabulated moments.
    Moments(MomentTerm<'a>),
    /// Bending, from the rod's quadrature table.
    Bending(BendingTerm<'a>),
}

impl LaneTerm<'_> {
    /// Whether the term stays what it is from one step to the next while its rod's knots
    /// do: not the stretching of an inextensible rod, whose multipliers are updated
    /// after every step (a run of steps kept in the lanes must not skip that update).
    pub fn holds_across_steps(&self) -> bool {
        match self {
            LaneTerm::Moments(m) => !m.has_multipliers(),
            LaneTerm::Gravity { .. } | LaneTerm::Bending(_) => true,
        }
    }

    /// Whether `other` is the same form (variant).
    pub fn same_form(&self, other: &LaneTerm<'_>) -> bool {
        std::mem::discriminant(self) == std::mem::discriminant(other)
    }

    /// Whether `terms` (one per lane) are one form on one shape: `n` control points and
    /// a Hessian within block bandwidth `bw`.
    pub fn compatible(terms: &[LaneTerm<'_>; LANES], n: usize, bw: usize) -> bool {
        terms.iter().all(|t| match (t, &terms[0]) {
            (LaneTerm::Gravity { masses, .. }, LaneTerm::Gravity { .. }) => masses.len() == n,
            (LaneTerm::Moments(a), LaneTerm::Moments(b)) => a.fits(n, bw) && a.same_shape(b),
            (LaneTerm::Bending(a), LaneTerm::Bending(b)) => a.fits(n, bw) && a.same_shape(b),
            _ => false,
        })
    }
}

/// Positions, or any field of 3-vectors, in lane form: coordinate `c` of point `i` at
/// `3i + c`.
pub type LaneField = [Lanes];

/// Adds to `energy` each lane's energy of `terms` at the positions `q`, and with
/// `derivatives` its gradient and exact Hessian. No allocation. Returns per lane whether
/// it was evaluated: every lane false, adding nothing, if the terms are not one form on
/// one shape fitting `q` and the derivatives' sizes ([`LaneTerm::compatible`]); a lane
/// false where its stretching's projection guard acts (the lanes do not replicate it;
/// each lane tested alone).
pub fn add_lanes(
    terms: &[LaneTerm<'_>; LANES],
    q: &LaneField,
    energy: &mut Lanes,
    derivatives: Option<Derivatives<'_>>,
) -> [bool; LANES] {
    let n = q.len() / 3;
    let (bw, sized) = derivatives.as_ref().map_or((usize::MAX - 1, true), |d| {
        let h = &d.hessian;
        (h.bandwidth(), h.dim() == n && d.gradient.len() == q.len())
    });
    if !(sized && q.len() == 3 * n && LaneTerm::compatible(terms, n, bw)) {
        return [false; LANES];
    }
    match &terms[0] {
        LaneTerm::Gravity { .. } => add_gravity(terms, q, energy, derivatives.map(|d| d.gradient)),
        LaneTerm::Moments(first) => {
            let mut moments = [first; LANES];
            for (slot, term) in moments.iter_mut().zip(terms) {
                if let LaneTerm::Moments(m) = term {
                    *slot = m;
                }
            }
            return crate::stretching::add_moment_lanes(moments, q, energy, derivatives);
        }
        LaneTerm::Bending(first) => {
            let mut bending = [first; LANES];
            for (slot, term) in bending.iter_mut().zip(terms) {
                if let LaneTerm::Bending(b) = term {
                    *slot = b;
                }
            }
            crate::bending::add_bending_lanes(bending, q, energy, derivatives);
        }
    }
    [true; LANES]
}

/// Gravity's energy and gradient, lane by lane.
fn add_gravity(
    terms: &[LaneTerm<'_>; LANES],
    q: &LaneField,
    energy: &mut Lanes,
    gradient: Option<&mut LaneField>,
) {
    let mut gravity = [(Vector3::zeros(), &[][..]); LANES];
    for (slot, term) in gravity.iter_mut().zip(terms) {
        if let LaneTerm::Gravity { g, masses } = term {
            *slot = (*g, masses);
        }
    }
    // Each lane's arithmetic as before (Σᵢ mᵢ (g·qᵢ), gradient −g mᵢ), over the lanes
    // at once.
    let n = gravity.iter().map(|(_, m)| m.len()).min().unwrap_or(0);
    let g: [Lanes; 3] = std::array::from_fn(|c| std::array::from_fn(|l| gravity[l].0[c]));
    let mut sum = [0.0; LANES];
    for i in 0..n {
        let m: Lanes = std::array::from_fn(|l| gravity[l].1[i]);
        for l in 0..LANES {
            let dot = g[0][l] * q[3 * i][l] + g[1][l] * q[3 * i + 1][l] + g[2][l] * q[3 * i + 2][l];
            sum[l] += m[l] * dot;
        }
    }
    for l in 0..LANES {
        energy[l] -= sum[l];
    }
    if let Some(gradient) = gradient {
        for i in 0..n {
            let m: Lanes = std::array::from_fn(|l| gravity[l].1[i]);
            for c in 0..3 {
                for l in 0..LANES {
                    gradient[3 * i + c][l] -= g[c][l] * m[l];
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Bending, Energy, Gravity, LaneForm, Lifecycle, Stretching};
    use splinerod_core::{BSplineSpace, BlockBanded, HessianKind, LaneBand, Material, Rod};

    /// Four rods of one basis, bent and stretched differently (`wiggle` scales the
    /// bends: at 1 the strain varies inside the spans by more than the mixed forms'
    /// projection guard allows, at 0.05 it does not).
    fn wiggly_rods(degree: usize, wiggle: Real) -> Vec<Rod> {
        (0..LANES)
            .map(|l| {
                let material = Material {
                    rest_length: 1.0,
                    linear_density: 0.1 + 0.02 * l as Real,
                };
                let basis = BSplineSpace::clamped_uniform(degree, 11, 1.0).expect("basis");
                let end = Vector3::new(1.0, 0.0, 0.0);
                let mut rod =
                    Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
                for (i, p) in rod.positions.iter_mut().enumerate() {
                    let t = (i * 7 + l * 3) as Real;
                    *p = *p * (1.1 + 0.05 * l as Real)
                        + Vector3::new(0.01 * t.sin(), 0.05 * (0.3 * t).cos(), 0.02 * t.cos())
                            * wiggle;
                }
                rod
            })
            .collect()
    }

    /// The rods of [`wiggly_rods`].
    fn rods(degree: usize) -> Vec<Rod> {
        wiggly_rods(degree, 1.0)
    }

    /// The lane term of a boxed energy (which must have one).
    fn lane_term<'a>(energy: &'a dyn Energy, rod: &'a Rod) -> LaneTerm<'a> {
        let form = energy.capabilities().lanes.expect("a lane form");
        form.lane_term(rod).expect("lane form")
    }

    /// Lane evaluation of one energy per rod against each energy's own.
    fn check(rods: &[Rod], energies: &[Box<dyn Energy>]) {
        let n = rods[0].len();
        let bw = energies[0].bandwidth(&rods[0]);
        let terms: [LaneTerm<'_>; LANES] =
            std::array::from_fn(|l| lane_term(energies[l].as_ref(), &rods[l]));
        assert!(LaneTerm::compatible(&terms, n, bw));
        let q: Vec<Lanes> = (0..3 * n)
            .map(|k| std::array::from_fn(|l| rods[l].positions[k / 3][k % 3]))
            .collect();
        let (mut energy, mut gradient, mut band) =
            ([0.0; LANES], vec![[0.0; LANES]; 3 * n], LaneBand::default());
        band.reset(n, bw);
        let derivatives = Derivatives {
            gradient: &mut gradient,
            hessian: &mut band,
            hessian_scale: 1.0,
        };
        assert_eq!(
            add_lanes(&terms, &q, &mut energy, Some(derivatives)),
            [true; LANES]
        );
        for (l, (rod, e)) in rods.iter().zip(energies).enumerate() {
            let close = |a: Real, b: Real, scale: Real| (a - b).abs() <= 1e-12 * scale;
            assert!(
                close(energy[l], e.energy(rod), e.energy(rod).abs()),
                "lane {l} energy"
            );
            let mut g = vec![Vector3::zeros(); n];
            let mut h = BlockBanded::zeros(n, bw);
            e.add_gradient_and_hessian(rod, HessianKind::Exact, &mut g, &mut h);
            let gscale = g.iter().map(|v| v.amax()).fold(1e-300, Real::max);
            for (k, lanes) in gradient.iter().enumerate() {
                assert!(
                    close(lanes[l], g[k / 3][k % 3], gscale),
                    "lane {l} gradient {k}"
                );
            }
            let hscale = h
                .band_blocks()
                .iter()
                .map(|b| b.amax())
                .fold(1e-300, Real::max);
            for i in 0..n {
                for j in i..(i + bw + 1).min(n) {
                    let (lane, own) = (band.block(i, j), h.block(i, j));
                    for e in 0..9 {
                        let (r, c) = (e % 3, e / 3);
                        assert!(
                            close(lane[e][l], own[(r, c)], hscale),
                            "lane {l} block ({i}, {j})"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn lane_terms_equal_each_energys_own_evaluation() {
        for degree in 2..=5 {
            let rods = rods(degree);
            let stretching: Vec<Box<dyn Energy>> = rods
                .iter()
                .enumerate()
                .map(|(l, rod)| {
                    let mut s = Stretching::new(50.0 + 30.0 * l as Real).expect("stretching");
                    s.begin_step(rod, 1e-3).expect("table");
                    Box::new(s) as Box<dyn Energy>
                })
                .collect();
            check(&rods, &stretching);
            let gravity: Vec<Box<dyn Energy>> = (0..LANES)
                .map(|l| {
                    let g = Vector3::new(0.1 * l as Real, -9.81, 0.5);
                    Box::new(Gravity::new(g).expect("gravity")) as Box<dyn Energy>
                })
                .collect();
            check(&rods, &gravity);
            let bending: Vec<Box<dyn Energy>> = (0..LANES)
                .map(|l| {
                    let ei = 1e-3 * (1.0 + l as Real);
                    Box::new(Bending::for_rod(ei, &rods[l]).expect("bending")) as Box<dyn Energy>
                })
                .collect();
            check(&rods, &bending);
        }
    }

    /// Where the projection guard acts on a lane's rod, the lanes refuse (the member
    /// is stepped alone) instead of leaving it out.
    #[test]
    fn the_lanes_refuse_rods_where_the_projection_guard_acts() {
        let rods = wiggly_rods(3, 1.0);
        let energies: Vec<Stretching> = rods
            .iter()
            .map(|rod| {
                let mut s = Stretching::new(80.0).expect("stretching");
                s.guard = true;
                s.begin_step(rod, 1e-3).expect("table");
                s
            })
            .collect();
        let terms: [LaneTerm<'_>; LANES] =
            std::array::from_fn(|l| lane_term(&energies[l], &rods[l]));
        let n = rods[0].len();
        let q: Vec<Lanes> = (0..3 * n)
            .map(|k| std::array::from_fn(|l| rods[l].positions[k / 3][k % 3]))
            .collect();
        let mut energy = [0.0; LANES];
        assert_eq!(add_lanes(&terms, &q, &mut energy, None), [false; LANES]);
        assert_eq!(energy, [0.0; LANES], "nothing added");
        // With gentler bends the guard is idle and the lanes take the rods.
        let rods = wiggly_rods(3, 0.05);
        let energies: Vec<Box<dyn Energy>> = rods
            .iter()
            .map(|rod| {
                let mut s = Stretching::new(80.0).expect("stretching");
                s.guard = true;
                s.begin_step(rod, 1e-3).expect("table");
                Box::new(s) as Box<dyn Energy>
            })
            .collect();
        check(&rods, &energies);
    }

    /// The guard refuses a lane on its own: lanes whose guard is idle are evaluated,
    /// with the same bits as beside other lane-mates.
    #[test]
    fn the_guard_refuses_lanes_one_by_one() {
        let (bent, gentle) = (wiggly_rods(3, 1.0), wiggly_rods(3, 0.05));
        let energy_of = |rods: &[&Rod]| {
            let energies: Vec<Stretching> = rods
                .iter()
                .map(|rod| {
                    let mut s = Stretching::new(80.0).expect("stretching");
                    s.guard = true;
                    s.begin_step(rod, 1e-3).expect("table");
                    s
                })
                .collect();
            let terms: [LaneTerm<'_>; LANES] =
                std::array::from_fn(|l| lane_term(&energies[l], rods[l]));
            let n = rods[0].len();
            let q: Vec<Lanes> = (0..3 * n)
                .map(|k| std::array::from_fn(|l| rods[l].positions[k / 3][k % 3]))
                .collect();
            let mut energy = [0.0; LANES];
            let evaluated = add_lanes(&terms, &q, &mut energy, None);
            (evaluated, energy)
        };
        let mixed: Vec<&Rod> = (0..LANES)
            .map(|l| if l % 2 == 0 { &bent[l] } else { &gentle[l] })
            .collect();
        let (evaluated, energy) = energy_of(&mixed);
        assert_eq!(evaluated, [false, true, false, true]);
        let (all, alone) = energy_of(&gentle.iter().collect::<Vec<_>>());
        assert_eq!(all, [true; LANES]);
        for l in [1, 3] {
            assert_eq!(energy[l].to_bits(), alone[l].to_bits(), "lane {l}");
        }
    }

    #[test]
    fn the_lumped_mixed_stretching_has_a_lane_form_on_a_current_table_only() {
        let rod = &rods(3)[0];
        let mut s = Stretching::new(100.0).expect("stretching");
        assert!(s.lane_term(rod).is_none(), "no table yet");
        s.begin_step(rod, 1e-3).expect("table");
        assert!(s.lane_term(rod).is_some());
        s.formulation = crate::StretchFormulation::Pointwise;
        assert!(s.lane_term(rod).is_none());
        let bending = crate::Bending::new(1e-3).expect("bending");
        assert!(bending.lane_term(rod).is_some());
        let lean = rod.clone().without_second_derivatives();
        assert!(bending.lane_term(&lean).is_none(), "no second derivatives");
    }

    #[test]
    fn bending_lanes_need_one_quadrature_table() {
        let rods = rods(3);
        let other = rods[1]
            .clone()
            .with_quadrature_points(6)
            .expect("quadrature");
        let bending = crate::Bending::new(1e-3).expect("bending");
        let terms: [LaneTerm<'_>; LANES] = std::array::from_fn(|l| {
            let rod = if l == 1 { &other } else { &rods[l] };
            bending.lane_term(rod).expect("lane form")
        });
        assert!(!LaneTerm::compatible(&terms, rods[0].len(), 5));
    }
}
