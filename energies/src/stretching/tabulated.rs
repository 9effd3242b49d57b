//! The mixed form's derivatives from its tabulated integrals ([`super::table`]): per
//! tension function `k` with derivatives \\(\\partial b_k\\), stiffness \\(c_k = EA/m_k\\)
//! and tension \\(\\lambda_k\\), the blocks
//!
//! \\[ H_{ab} \\mathrel{+}= c_k\\, \\partial_a b_k\\, \\partial_b b_k^T + \\lambda_k (G_k)_{ab}\\, I,
//! \\qquad g_a \\mathrel{+}= \\lambda_k\\, \\partial_a b_k \\]
//!
//! ([`super::blocks`]). On an open rod one plain pass does it all
//! ([`Stretching::fused_derivatives`]), whatever the tension comes from
//! ([`TensionSource`]): the lumped form's from each function's own moment, computed in
//! the pass; the consistent form's from the Gram solve, after the rows of `B` were
//! computed and kept for the remainder products ([`super::rows`]). On processors with
//! AVX2 and FMA the pass runs with fused multiply-adds (detected at run time), its
//! results equal to round-off (tested in `tests/stretch_table.rs` against the sweep,
//! and below against the plain pass, which is the general pass bit for bit).

use super::blocks::{add_function_blocks, add_scaled, geometric_tension};
use super::rows::Rows;
use super::seam;
use super::table::{add_times, Moment, TensionTable, MAX_WIDTH};
use super::Stretching;
use nalgebra::Vector3;
use splinerod_core::{BlockBanded, HessianKind, Real, Rod};

/// Scratch of a pass: `q − q₀` and `∂b_k` of one function.
type Scratch = [[Vector3<Real>; MAX_WIDTH]; 2];

/// Where [`Stretching::fused_derivatives`] takes each tension function's moment and
/// tension from. Its methods are `#[inline(always)]` in both implementations, so that
/// they compile for the pass's instruction set.
pub(super) trait TensionSource {
    /// Number of tension functions, taken by slot `0..count`.
    fn count(&self) -> usize;
    /// Control points the function at `slot` touches.
    fn width(&self, slot: usize) -> usize;
    /// The [`Moment`] of the function at `slot` (of width `width`, a constant where the
    /// caller can), products fused with `FUSED`.
    fn moment<'a, const FUSED: bool>(
        &'a self,
        slot: usize,
        width: usize,
        scratch: &'a mut Scratch,
    ) -> Moment<'a>;
    /// The tension coefficient \\(\\lambda_k\\) of the function of moment `k`.
    fn tension(&self, k: &Moment<'_>) -> Real;
}

/// The lumped form's source: the moments from the table at the rod's positions, each
/// tension \\(\\hat\\lambda_k + EA\\, b_k/m_k\\) from its own moment.
struct Own<'a> {
    energy: &'a Stretching,
    rod: &'a Rod,
}

impl TensionSource for Own<'_> {
    #[inline(always)]
    fn count(&self) -> usize {
        self.energy.table.functions()
    }

    #[inline(always)]
    fn width(&self, slot: usize) -> usize {
        self.energy.table.width(slot)
    }

    #[inline(always)]
    fn moment<'a, const FUSED: bool>(
        &'a self,
        slot: usize,
        width: usize,
        scratch: &'a mut Scratch,
    ) -> Moment<'a> {
        self.energy
            .table
            .moment_at::<FUSED>(self.rod, (slot, width), scratch)
    }

    #[inline(always)]
    fn tension(&self, k: &Moment<'_>) -> Real {
        self.energy.tension_of(None, k.index, k.b, k.m)
    }
}

/// The consistent form's source: the moments and rows of `B` kept at the rod's
/// positions, the tensions \\(EA\\, G^{-1} b\\) solved from them.
pub(super) struct Solved<'a> {
    table: &'a TensionTable,
    rows: &'a Rows,
    /// Per function index: (λ, b), see [`Stretching::with_tensions`].
    tensions: &'a [(Real, Real)],
}

impl TensionSource for Solved<'_> {
    #[inline(always)]
    fn count(&self) -> usize {
        self.rows.functions.len()
    }

    #[inline(always)]
    fn width(&self, slot: usize) -> usize {
        self.rows.functions[slot].width
    }

    #[inline(always)]
    fn moment<'a, const FUSED: bool>(
        &'a self,
        slot: usize,
        width: usize,
        _scratch: &'a mut Scratch,
    ) -> Moment<'a> {
        let row = &self.rows.functions[slot];
        let db = self.rows.derivatives(slot, width);
        self.table
            .moment((row.index, row.first), (row.b, row.m), db)
    }

    #[inline(always)]
    fn tension(&self, k: &Moment<'_>) -> Real {
        self.tensions[k.index].0
    }
}

impl Stretching {
    /// [`Self::mixed_hessian`] from the tabulated integrals ([`super::table`]): per tension
    /// function, the material term \\(\\tfrac{EA}{m_k} \\partial b_k \\partial b_k^T\\), the
    /// geometric term \\(\\lambda_k G_k \\otimes I\\) and the gradient \\(\\lambda_k \\partial b_k\\).
    pub(super) fn tabulated_derivatives(
        &self,
        rod: &Rod,
        kind: HessianKind,
        gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        if self.lumped_open(rod) {
            let source = Own { energy: self, rod };
            return self.fused_derivatives_any(&source, kind, gradient, hessian);
        }
        if self.consistent_open(rod) {
            let mut gradient = gradient;
            let done = self.with_solved(rod, |source| {
                let g = gradient.as_deref_mut();
                self.fused_derivatives_any(source, kind, g, hessian)
            });
            if done.is_some() {
                return;
            }
            return self.general_derivatives(rod, kind, gradient, hessian);
        }
        self.general_derivatives(rod, kind, gradient, hessian);
    }

    /// Calls `f` with the consistent form's [`Solved`] source at `rod`'s positions
    /// (the tensions solved, the rows of `B` kept); `None` if the rows are not held
    /// (they are: the solve fills them).
    pub(super) fn with_solved<R>(&self, rod: &Rod, f: impl FnOnce(&Solved<'_>) -> R) -> Option<R> {
        self.with_tensions(rod, |tensions| {
            self.with_held_rows(rod, |rows| {
                let table = &self.table;
                f(&Solved {
                    table,
                    rows,
                    tensions,
                })
            })
        })
    }

    /// [`Self::tabulated_derivatives`] in every case: the consistent form's tensions,
    /// a closed rod's merged pairs and seam.
    fn general_derivatives(
        &self,
        rod: &Rod,
        kind: HessianKind,
        mut gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
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

    /// Whether `rod` takes the consistent form's tabulated derivatives on an open rod
    /// (no seam), the energy's own table matching it.
    #[inline]
    fn consistent_open(&self, rod: &Rod) -> bool {
        self.consistent() && !rod.is_closed() && self.table.matches(rod)
    }

    /// [`Self::fused_derivatives`], fused where the processor has AVX2 and FMA.
    fn fused_derivatives_any<S: TensionSource>(
        &self,
        source: &S,
        kind: HessianKind,
        gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        #[cfg(target_arch = "x86_64")]
        if splinerod_core::lanes::wide() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            return unsafe { self.fused_derivatives_wide(source, kind, gradient, hessian) };
        }
        // The same operations as the general pass, in the same order (no merged pairs
        // on an open rod).
        self.fused_derivatives::<false, S>(source, kind, gradient, hessian);
    }

    /// [`Self::fused_derivatives`] with fused products, compiled for AVX2 and FMA (the
    /// same sums as [`Self::tabulated_derivatives`], each product rounded once).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn fused_derivatives_wide<S: TensionSource>(
        &self,
        source: &S,
        kind: HessianKind,
        gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        self.fused_derivatives::<true, S>(source, kind, gradient, hessian);
    }

    /// [`Self::tabulated_derivatives`] on an open rod, one pass over the functions of
    /// `source`. Plain loops and `#[inline(always)]` callees only, so that all of it is
    /// compiled for the caller's instruction set (fused multiply-add where `FUSED`).
    #[inline(always)]
    fn fused_derivatives<const FUSED: bool, S: TensionSource>(
        &self,
        source: &S,
        kind: HessianKind,
        mut gradient: Option<&mut [Vector3<Real>]>,
        hessian: &mut BlockBanded,
    ) {
        let mut scratch = [[Vector3::zeros(); MAX_WIDTH]; 2];
        for slot in 0..source.count() {
            let g = gradient.as_deref_mut();
            let terms = (kind, slot, &mut scratch);
            match source.width(slot) {
                // A cubic's interior functions touch 6 points: with the width a
                // constant, every loop of their sums unrolls.
                6 => self.function_terms::<FUSED, 6, S>(source, terms, (g, hessian)),
                _ => self.function_terms::<FUSED, 0, S>(source, terms, (g, hessian)),
            }
        }
    }

    /// [`Self::fused_derivatives`]' terms of the function at `slot`, whose width is `W`
    /// (if not 0; else the source's), added to the gradient (if any) and the Hessian.
    #[inline(always)]
    fn function_terms<const FUSED: bool, const W: usize, S: TensionSource>(
        &self,
        source: &S,
        (kind, slot, scratch): (HessianKind, usize, &mut Scratch),
        (gradient, hessian): (Option<&mut [Vector3<Real>]>, &mut BlockBanded),
    ) {
        let width = if W > 0 { W } else { source.width(slot) };
        let k = source.moment::<FUSED>(slot, width, scratch);
        let c = self.lumped_stiffness(k.m);
        let tension = source.tension(&k);
        if let Some(g) = gradient {
            for (g, v) in g[k.first..].iter_mut().zip(k.db) {
                add_times::<FUSED>(g, v, tension);
            }
        }
        add_function_blocks::<FUSED>(hessian, &k, c, geometric_tension(kind, tension));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Energy;
    use crate::Lifecycle;
    use splinerod_core::{BSplineSpace, Material};

    /// Gradient and Hessian (dense) of `e` on `rod` by `pass`.
    fn derivatives(
        e: &Stretching,
        rod: &Rod,
        pass: impl Fn(&Stretching, &Rod, Option<&mut [Vector3<Real>]>, &mut BlockBanded),
    ) -> (Vec<Vector3<Real>>, nalgebra::DMatrix<Real>) {
        let mut g = vec![Vector3::zeros(); rod.len()];
        let mut h = BlockBanded::zeros(rod.len(), e.bandwidth(rod));
        pass(e, rod, Some(&mut g), &mut h);
        (g, h.to_dense())
    }

    /// Wiggly rods of degrees 2–4, with an energy of stiffness 250 N tabulated for them.
    fn cases(formulation: super::super::StretchFormulation) -> Vec<(Stretching, Rod)> {
        let material = Material {
            rest_length: 1.0,
            linear_density: 0.1,
        };
        let mut out = Vec::new();
        for (degree, points) in [(2, 7), (3, 5), (3, 16), (4, 11)] {
            let basis = BSplineSpace::clamped_uniform(degree, points, 1.0).expect("basis");
            let end = Vector3::new(1.1, 0.2, -0.1);
            let mut rod =
                Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
            for (i, q) in rod.positions.iter_mut().enumerate() {
                *q += Vector3::new(0.0, 0.03 * (i as Real).sin(), 0.02 * (i as Real).cos());
            }
            let mut e = Stretching::new(250.0).expect("stretching");
            e.formulation = formulation;
            e.begin_step(&rod, 1e-3).expect("table");
            out.push((e, rod));
        }
        out
    }

    /// Checks that `pass` (`true`: fused) gives the general pass's gradient and
    /// Hessian, bit for bit when plain and to round-off (but not bit for bit) fused.
    fn check_pass(
        e: &Stretching,
        rod: &Rod,
        pass: impl Fn(bool, HessianKind, Option<&mut [Vector3<Real>]>, &mut BlockBanded),
    ) {
        for kind in [HessianKind::Exact, HessianKind::Definite] {
            let general = derivatives(e, rod, |e, r, g, h| e.general_derivatives(r, kind, g, h));
            let plain = derivatives(e, rod, |_, _, g, h| pass(false, kind, g, h));
            assert_eq!(general, plain, "{} points", rod.len());
            #[cfg(target_arch = "x86_64")]
            if splinerod_core::lanes::wide() {
                let fused = derivatives(e, rod, |_, _, g, h| pass(true, kind, g, h));
                let scale_h = general.1.amax();
                assert!((&fused.1 - &general.1).amax() <= 1e-12 * scale_h);
                let scale_g = general.0.iter().map(|v| v.amax()).fold(0.0, Real::max);
                let gap = fused.0.iter().zip(&general.0).map(|(a, b)| (a - b).amax());
                assert!(gap.fold(0.0, Real::max) <= 1e-12 * scale_g);
                assert_ne!(fused.1, general.1, "the fused pass rounds differently");
            }
        }
    }

    /// The pass over `source`, fused or plain.
    fn run<S: TensionSource>(
        e: &Stretching,
        source: &S,
        fused: bool,
        (kind, g, h): (HessianKind, Option<&mut [Vector3<Real>]>, &mut BlockBanded),
    ) {
        #[cfg(target_arch = "x86_64")]
        if fused {
            // SAFETY: only called fused where the processor has AVX2 and FMA.
            return unsafe { e.fused_derivatives_wide(source, kind, g, h) };
        }
        assert!(!fused);
        e.fused_derivatives::<false, S>(source, kind, g, h);
    }

    #[test]
    fn the_lumped_pass_is_the_general_one_bit_for_bit_and_fused_to_round_off() {
        for (e, rod) in cases(super::super::StretchFormulation::Mixed) {
            assert!(e.lumped_open(&rod));
            check_pass(&e, &rod, |fused, kind, g, h| {
                let source = Own {
                    energy: &e,
                    rod: &rod,
                };
                run(&e, &source, fused, (kind, g, h));
            });
        }
    }

    #[test]
    fn the_consistent_pass_is_the_general_one_bit_for_bit_and_fused_to_round_off() {
        for (e, rod) in cases(super::super::StretchFormulation::MixedConsistent) {
            assert!(e.consistent_open(&rod));
            check_pass(&e, &rod, |fused, kind, g, h| {
                e.with_solved(&rod, |source| run(&e, source, fused, (kind, g, h)))
                    .expect("rows held");
            });
        }
    }
}
