//! Continuous Green–Lagrange stretching (paper eq. 11–12).
//!
//! The rest state is either the parametrisation itself — `s` is rest arclength,
//! \\(\partial l_0/\partial s = 1\\), the default — or, as in the paper, an initial curve
//! \\(I_0\\) with rest metric \\(g_0(s) = |I_0'(s)|^2\\) ([`Stretching::with_rest_shape`]).
//! With Green–Lagrange strain \\(\varepsilon = (\gamma^2 - g_0)/(2 g_0)\\) and
//! \\(dl_0 = \sqrt{g_0}\, ds\\) the energy is
//! \\(\tfrac{EA}{8}\int (\gamma^2 - g_0)^2 g_0^{-3/2}\, ds\\): the formulas below with
//! `1` replaced by \\(g_0\\) and a factor \\(g_0^{-3/2}\\) on every density. For
//! \\(g_0 = 1\\) and \\(\gamma^2 = |C'|^2\\):
//!
//! \\[ E = \frac{EA}{8} \int_0^L (\gamma^2 - 1)^2\, ds, \qquad
//! \frac{\partial E}{\partial q_i} = \frac{EA}{2} \int_0^L (\gamma^2 - 1)\, b_i'\, C'\, ds, \\]
//!
//! \\[ \frac{\partial^2 E}{\partial q_i \partial q_j} = \int_0^L b_i' b_j'\, H(C')\, ds,
//! \qquad H = \frac{EA}{2}\left[(\gamma^2 - 1) I + 2\, C' C'^T\right]. \\]
//!
//! No square root is needed. The 3×3 density Hessian `H` has eigenvalue
//! \\(\tfrac{EA}{2}(3\gamma^2 - 1)\\) along the tangent and \\(\tfrac{EA}{2}(\gamma^2 - 1)\\)
//! across it, so it is indefinite in compression. [`HessianKind::Definite`] clamps both
//! eigenvalues at zero (the nearest positive semi-definite matrix); forces stay exact.
//! The integrands are polynomials of degree `4(d − 1)`, integrated exactly by the rod's
//! quadrature table (with a rest curve, \\(g_0^{-3/2}\\) is not polynomial: the table
//! integrates it to its own accuracy, and \\(g_0\\) is re-tabulated after every change of
//! knots).
//!
//! These are the formulas of [`StretchFormulation::Pointwise`]. The default,
//! [`StretchFormulation::Mixed`], squares the strain only after projecting it onto the
//! degree-`d − 1` splines ([`mixed`]: free of membrane locking), and
//! [`Stretching::inextensible`] holds that projection at zero ([`multipliers`]).

mod auto;
mod blocks;
mod capabilities;
mod gram;
mod guard;
mod lane_table;
mod lanes;
mod mixed;
mod multipliers;
mod point_batch;
mod rows;
mod seam;
mod table;
mod tabulated;
mod tensions;

pub use auto::{AutoInputs, AUTO_COMPRESSION, AUTO_LUMPING_ERROR, AUTO_RESOLUTION_ERROR};
pub use guard::GUARD_DEVIATION;
pub(crate) use lanes::add_moment_lanes;
pub use lanes::MomentTerm;
pub use multipliers::Multipliers;

use crate::capabilities::{Capabilities, Lifecycle};
use crate::Energy;
use guard::GuardSums;
use nalgebra::{Matrix3, Vector3};
use point_batch::{PointBatch, Sums};
use splinerod_core::{
    BasisSpace, BasisValues, BlockBanded, CoreError, HessianKind, QuadPoint, Real, Rod,
};
use std::sync::Arc;

/// How the strain enters the energy (see the module docs for the trade-off).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum StretchFormulation {
    /// Mixed (assumed strain): the strain is projected onto the degree-`d − 1`
    /// B-splines on the rod's knots before it is squared (`stretching/mixed.rs`). Free
    /// of membrane locking at any `EA`; the default.
    #[default]
    Mixed,
    /// The paper's eq. 12: the strain squared at every quadrature point. Converges at
    /// order `d + 1` on stretchy rods, locks on stiff ones (`EA` ≫ the loads).
    Pointwise,
    /// Mixed, with the tension coefficients from the consistent Gram matrix instead of
    /// the lumped one (`stretching/tensions.rs`): locking-free and of order `d + 1` on
    /// stretchy rods too. Its Hessian has a remainder that is not banded
    /// ([`crate::HessianRemainder::add_remainder`]), which Newton's method handles by
    /// preconditioned conjugate gradients.
    MixedConsistent,
}

impl StretchFormulation {
    /// The scene name of the form (`"mixed"`, `"pointwise"`, `"mixed-consistent"`).
    pub fn name(self) -> &'static str {
        match self {
            Self::Mixed => "mixed",
            Self::Pointwise => "pointwise",
            Self::MixedConsistent => "mixed-consistent",
        }
    }

    /// Gauss points per knot span that integrate this form's integrands (constant rest
    /// metric) and the mass matrix exactly for degree `d`: the mixed form's are
    /// polynomials of degree `3(d − 1)`, the pointwise form's of degree `4(d − 1)`.
    /// Cubic: 4 and 5.
    pub fn points_per_span(self, d: usize) -> usize {
        let integrand = match self {
            Self::Mixed | Self::MixedConsistent => 3 * d.saturating_sub(1),
            Self::Pointwise => 4 * d.saturating_sub(1),
        };
        (d + 1).max(integrand / 2 + 1)
    }
}

/// Green–Lagrange stretching with axial stiffness `EA = Y·r` (N).
#[derive(Debug, Clone)]
pub struct Stretching {
    /// Axial stiffness `EA`, N.
    pub stiffness: Real,
    /// How the strain enters the energy.
    pub formulation: StretchFormulation,
    /// For an inextensible rod ([`Stretching::inextensible`]): the constraints'
    /// multipliers; their penalty then takes the place of `stiffness`.
    pub multipliers: Option<Multipliers>,
    /// The projection guard of the mixed forms (`stretching/guard.rs`): stiffen where the strain
    /// varies inside a knot span by more than [`GUARD_DEVIATION`]. Off by default;
    /// scenes with contact turn it on.
    pub guard: bool,
    rest: Option<RestMetric>,
    /// `stiffness` before [`crate::Lifecycle::set_stiffness_scale`] scaled it (`None`: unscaled).
    unscaled: Option<Real>,
    /// The mixed form's integrals for the rod's current basis ([`table`]).
    table: table::TensionTable,
    /// The tension functions' Gram matrix for the rod's current basis ([`gram`]).
    gram: gram::TensionGram,
}

/// A rest curve: its basis and control points.
type RestCurve = (Box<dyn BasisSpace>, Vec<Vector3<Real>>);

/// A rest curve \\(I_0\\) and its metric \\(g_0 = |I_0'|^2\\) at the rod's quadrature points,
/// with \\(g_0^{-3/2}\\) (see [`rest_scale`]).
#[derive(Debug, Clone)]
struct RestMetric {
    curve: Arc<RestCurve>,
    /// Per quadrature point, \\(g_0\\) and \\(g_0^{-3/2}\\) (one buffer: a smaller energy
    /// object, which an ensemble of thousands of rods feels).
    g0: Vec<[Real; 2]>,
}

impl RestMetric {
    /// Tabulates \\(g_0\\) at the quadrature points of `rod`; errors where it vanishes.
    fn tabulate(&mut self, rod: &Rod) -> Result<(), CoreError> {
        let (basis, points) = &*self.curve;
        let mut b = BasisValues::default();
        self.g0.clear();
        for qp in rod.quadrature().walk() {
            basis.evaluate(qp.s, &mut b)?;
            let g0 = b.combine(&b.d1, points).norm_squared();
            if !(g0.is_finite() && g0 > 0.0) {
                return Err(CoreError::InvalidParameter {
                    name: "rest shape",
                    value: qp.s,
                    reason: "the rest curve has zero speed at this material coordinate",
                });
            }
            self.g0.push([g0, rest_scale(g0)]);
        }
        Ok(())
    }
}

impl Stretching {
    /// Stretching energy with stiffness `EA > 0`, at rest when `s` is arclength.
    pub fn new(stiffness: Real) -> Result<Self, CoreError> {
        splinerod_core::rod::positive("stretch_stiffness", stiffness)?;
        Ok(Self {
            stiffness,
            formulation: StretchFormulation::default(),
            multipliers: None,
            guard: false,
            rest: None,
            unscaled: None,
            table: table::TensionTable::default(),
            gram: gram::TensionGram::default(),
        })
    }

    /// An inextensible rod: the mixed form's constraints (every tension function's mean
    /// strain zero) held by an augmented Lagrangian ([`Multipliers`]); call
    /// [`crate::Lifecycle::update_multipliers`] after each solve or step.
    pub fn inextensible(rod: &Rod) -> Self {
        let mut s = Self {
            stiffness: 1.0,
            formulation: StretchFormulation::Mixed,
            multipliers: None,
            guard: false,
            rest: None,
            unscaled: None,
            table: table::TensionTable::default(),
            gram: gram::TensionGram::default(),
        };
        s.make_inextensible(rod);
        s
    }

    /// Turns this energy (with its rest state) into the inextensible rod's: mixed form,
    /// zero multipliers.
    pub fn make_inextensible(&mut self, rod: &Rod) {
        self.formulation = StretchFormulation::Mixed;
        self.multipliers = Some(Multipliers::new(rod));
        self.tabulate(rod);
    }

    /// The stiffness the mixed form's tension uses: `EA`, or an inextensible rod's
    /// current penalty.
    #[inline]
    fn axial_stiffness(&self) -> Real {
        self.multipliers
            .as_ref()
            .map_or(self.stiffness, |m| m.penalty)
    }

    /// The multiplier \\(\\hat\\lambda_j\\) of tension function `j` (0 without multipliers).
    #[inline]
    fn multiplier(&self, j: usize) -> Real {
        self.multipliers
            .as_ref()
            .map_or(0.0, |m| m.values.get(j).copied().unwrap_or(0.0))
    }

    /// Stretching energy with stiffness `EA > 0` whose rest state is the current shape of
    /// `rod` (the paper's \\(I_0\\)): a rod not parametrised by arclength starts unstrained.
    /// Errors if the curve has zero speed somewhere.
    pub fn with_rest_shape(stiffness: Real, rod: &Rod) -> Result<Self, CoreError> {
        let mut s = Self::new(stiffness)?;
        let curve = Arc::new((rod.basis().clone_box(), rod.positions.clone()));
        let mut rest = RestMetric {
            curve,
            g0: Vec::new(),
        };
        rest.tabulate(rod)?;
        s.rest = Some(rest);
        s.tabulate(rod);
        Ok(s)
    }

    /// Makes the cached data (rest metric, multipliers) follow `rod`'s current basis.
    fn follow(&mut self, rod: &Rod) {
        if let Some(rest) = &mut self.rest {
            // The rest curve was regular where tabulated first; it stays so at any s.
            if rest.tabulate(rod).is_err() {
                rest.g0.iter_mut().for_each(|g| *g = [Real::NAN; 2]);
            }
        }
        let rest = &self.rest;
        if let Some(m) = &mut self.multipliers {
            m.remap(rod, |p| rest.as_ref().map_or(1.0, |r| r.g0[p][0]));
        }
        self.tabulate(rod);
    }

    /// Tabulates the mixed form's integrals for `rod` ([`table`]); nothing for the
    /// pointwise form.
    fn tabulate(&mut self, rod: &Rod) {
        if self.formulation != StretchFormulation::Pointwise {
            let mut table = std::mem::take(&mut self.table);
            table.build(self, rod);
            self.table = table;
            if self.consistent() {
                let mut gram = std::mem::take(&mut self.gram);
                gram.build(self, rod);
                self.gram = gram;
            }
        }
    }

    /// Rest metric at quadrature point `p` (1 without a rest curve).
    #[inline]
    fn g0(&self, p: usize) -> Real {
        self.rest.as_ref().map_or(1.0, |r| r.g0[p][0])
    }

    /// Rest metric at quadrature point `p` and its [`rest_scale`], tabulated (1 and 1
    /// without a rest curve).
    #[inline]
    fn metric(&self, p: usize) -> (Real, Real) {
        self.rest
            .as_ref()
            .map_or((1.0, 1.0), |r| (r.g0[p][0], r.g0[p][1]))
    }

    /// \\(g_0(s)\\) of the rest curve at any parameter (1 without one, or where the rest
    /// curve cannot be evaluated).
    fn rest_metric_at(&self, s: Real) -> Real {
        let Some(rest) = &self.rest else { return 1.0 };
        let (basis, points) = &*rest.curve;
        let mut b = BasisValues::default();
        match basis.evaluate(s, &mut b) {
            Ok(()) => b.combine(&b.d1, points).norm_squared(),
            Err(_) => 1.0,
        }
    }

    /// Tension \\(T(\gamma) = \tfrac{EA}{2}\gamma(\gamma^2 - 1)\\) at stretch `γ`.
    pub fn tension(&self, gamma: Real) -> Real {
        0.5 * self.stiffness * gamma * (gamma * gamma - 1.0)
    }

    /// The 3×3 density Hessian `H(C')` for rest metric `g0`, clamped to PSD for
    /// [`HessianKind::Definite`].
    fn density_hessian(
        &self,
        c1: &Vector3<Real>,
        (g0, scale): (Real, Real),
        kind: HessianKind,
    ) -> Matrix3<Real> {
        let ea = self.stiffness * scale;
        let g2 = c1.norm_squared();
        // H = across·I + β C'C'ᵀ with across = EA(γ²−g₀)/2 and β = (along − across)/γ² = EA.
        let (across, beta) = match kind {
            HessianKind::Exact => (0.5 * ea * (g2 - g0), ea),
            _ if g2 >= g0 => (0.5 * ea * (g2 - g0), ea),
            // Compression: the transverse eigenvalue is clamped to 0, the axial one too
            // below γ² = g₀/3.
            _ if 3.0 * g2 > g0 => (0.0, 0.5 * ea * (3.0 * g2 - g0) / g2),
            _ => (0.0, 0.0),
        };
        let mut h = c1 * c1.transpose() * beta;
        for k in 0..3 {
            h[(k, k)] += across;
        }
        h
    }
}

/// \\(g_0^{-3/2}\\), exactly 1 for the default rest state.
#[inline]
fn rest_scale(g0: Real) -> Real {
    if g0 == 1.0 {
        1.0
    } else {
        1.0 / (g0 * g0.sqrt())
    }
}

impl Stretching {
    /// The energy of the form (without the compression guard, [`guard`]).
    fn form_energy(&self, rod: &Rod) -> Real {
        if self.formulation != StretchFormulation::Pointwise {
            return self.mixed_energy(rod);
        }
        let k = self.stiffness / 8.0;
        rod.quadrature()
            .walk()
            .enumerate()
            .map(|(p, qp)| {
                let (g0, scale) = self.metric(p);
                let e = tangent(&qp, &rod.positions).norm_squared() - g0;
                qp.weight * k * e * e * scale
            })
            .sum()
    }

    /// Adds the gradient of the form (without the compression guard).
    fn add_form_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        if self.formulation != StretchFormulation::Pointwise {
            return self.mixed_gradient(rod, gradient);
        }
        let half = 0.5 * self.stiffness;
        for (p, qp) in rod.quadrature().walk().enumerate() {
            let (c1, (g0, scale)) = (tangent(&qp, &rod.positions), self.metric(p));
            let f = c1 * (qp.weight * half * (c1.norm_squared() - g0) * scale);
            for (a, &da) in qp.d1.iter().enumerate() {
                gradient[qp.first + a] += f * da;
            }
        }
    }

    /// The pointwise gradient (with `sums.gradient`) and Hessian, point by point in
    /// batches ([`point_batch`]).
    fn add_point_terms(&self, rod: &Rod, kind: HessianKind, mut sums: Sums<'_>) {
        let half = 0.5 * self.stiffness;
        let mut batch = PointBatch::default();
        for (p, qp) in rod.quadrature().walk().enumerate() {
            let (c1, (g0, scale)) = (tangent(&qp, &rod.positions), self.metric(p));
            let f = c1 * (qp.weight * half * (c1.norm_squared() - g0) * scale);
            let h = self.density_hessian(&c1, (g0, scale), kind) * qp.weight;
            batch.push(&qp, (h, f), &mut sums);
        }
        batch.flush(&mut sums);
    }
}

/// \\(C'(s)\\) at a quadrature point.
#[inline]
fn tangent(qp: &QuadPoint<'_>, positions: &[Vector3<Real>]) -> Vector3<Real> {
    qp.d1
        .iter()
        .enumerate()
        .fold(Vector3::zeros(), |acc, (a, &w)| {
            acc + positions[qp.first + a] * w
        })
}

impl Energy for Stretching {
    fn name(&self) -> &str {
        "stretch"
    }

    fn energy(&self, rod: &Rod) -> Real {
        self.form_energy(rod) + self.guard_energy(rod)
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        self.add_form_gradient(rod, gradient);
        let gradient = Some(gradient);
        self.add_guard_terms(
            rod,
            GuardSums {
                hessian: None,
                gradient,
            },
        );
    }

    fn add_hessian(&self, rod: &Rod, kind: HessianKind, hessian: &mut BlockBanded) {
        if self.formulation != StretchFormulation::Pointwise {
            self.mixed_hessian(rod, kind, None, hessian);
        } else {
            let gradient = None;
            self.add_point_terms(rod, kind, Sums { hessian, gradient });
        }
        let hessian = Some((kind, hessian));
        self.add_guard_terms(
            rod,
            GuardSums {
                hessian,
                gradient: None,
            },
        );
    }

    fn add_gradient_and_hessian(
        &self,
        rod: &Rod,
        kind: HessianKind,
        gradient: &mut [Vector3<Real>],
        hessian: &mut BlockBanded,
    ) {
        if self.formulation != StretchFormulation::Pointwise {
            self.mixed_hessian(rod, kind, Some(gradient), hessian);
        } else {
            let gradient = Some(&mut *gradient);
            self.add_point_terms(rod, kind, Sums { hessian, gradient });
        }
        let (hessian, gradient) = (Some((kind, hessian)), Some(gradient));
        self.add_guard_terms(rod, GuardSums { hessian, gradient });
    }

    fn bandwidth(&self, rod: &Rod) -> usize {
        let d = rod.basis().degree();
        match self.formulation {
            StretchFormulation::Pointwise => d,
            _ => 2 * d - 1,
        }
    }

    fn capabilities(&self) -> Capabilities<'_> {
        Capabilities {
            lifecycle: Some(self),
            remainder: Some(self),
            tension: Some(self),
            lanes: Some(self),
            parameters: Some(self),
            ..Capabilities::default()
        }
    }

    fn lifecycle_mut(&mut self) -> Option<&mut dyn Lifecycle> {
        Some(self)
    }
}
