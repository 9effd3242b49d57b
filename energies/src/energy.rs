//! The [`Energy`] trait and its finite-difference Hessian default.

use nalgebra::{Matrix3, Vector3};
use splinerod_core::{
    BlockBanded, CoreError, HessianKind, KnotMap, Real, Rod, SavedState, StateReader,
};

use crate::ContactSummary;

/// What an energy reports about the rod's current state, for run statistics (see
/// [`Energy::summary`]); every part is optional and summaries of several energies merge.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct EnergySummary {
    /// Contacts the energy sees (self-contact, a floor, obstacles).
    pub contact: Option<ContactSummary>,
    /// The twist between two clamps ([`crate::Twisting`]).
    pub twist: Option<TwistSummary>,
}

/// The twist state of a rod between two clamps.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TwistSummary {
    /// Total twist Tw of the material frame, rad.
    pub twist: Real,
    /// Turn Φ of the end clamp relative to the start clamp, rad.
    pub turn: Real,
    /// Twisting moment \\(GJ\,\mathrm{Tw}/L\\) the clamps hold, N·m.
    pub moment: Real,
    /// Unit clamp axes at the start and the end (the end clamp exerts `+moment` about its
    /// axis on the rod, the start clamp `−moment` about its own).
    pub axes: [[Real; 3]; 2],
    /// The start clamp's director (the material frame at `s = 0` is this director and
    /// `axis × director`, turned by the start clamp's turn, which is absorbed in `turn`).
    pub start_director: [Real; 3],
}

impl EnergySummary {
    /// Folds `other` into this summary (contacts: counts add, closest distances min).
    pub fn merge(&mut self, other: &EnergySummary) {
        if let Some(b) = other.contact {
            self.contact = Some(match self.contact {
                Some(a) => a.merged(&b),
                None => b,
            });
        }
        if other.twist.is_some() {
            self.twist = other.twist;
        }
    }
}

/// A potential energy \\(E(q)\\) of a rod's control points.
///
/// Required: [`energy`](Energy::energy) and [`add_gradient`](Energy::add_gradient).
/// [`add_hessian`](Energy::add_hessian) defaults to central finite differences of the
/// gradient (O(n), slow but correct for energies coupling control points at most
/// `degree` apart, i.e. any integral of the curve and its derivatives); real energies
/// override it. [`on_knot_change`](Energy::on_knot_change) lets an energy with cached
/// per-coefficient data update it locally; the default does nothing.
///
/// **Lifecycle.** Besides the knot changes, an energy with state of its own hears of
/// each integrator step ([`begin_step`](Energy::begin_step)), can name the material
/// points where it acts locally ([`interaction_points`](Energy::interaction_points),
/// read by the adaptivity), forbid states a line search must not enter
/// ([`admissible`](Energy::admissible)) and report statistics
/// ([`summary`](Energy::summary)). All default to doing nothing; contact uses all of
/// them, and any other energy with per-step state plugs in the same way.
///
/// A minimal implementation, a spring holding the rod's first control point at the origin:
/// ```
/// use splinerod_core::{Real, Rod};
/// use splinerod_energies::Energy;
/// use nalgebra::Vector3;
///
/// struct Anchor { k: Real }
/// impl Energy for Anchor {
///     fn energy(&self, rod: &Rod) -> Real { 0.5 * self.k * rod.positions[0].norm_squared() }
///     fn add_gradient(&self, rod: &Rod, g: &mut [Vector3<Real>]) { g[0] += rod.positions[0] * self.k }
/// }
/// ```
pub trait Energy: Send + Sync {
    /// Name used in reports; the type name by default.
    fn name(&self) -> &str {
        std::any::type_name::<Self>()
    }

    /// Energy at the rod's current positions, J.
    fn energy(&self, rod: &Rod) -> Real;

    /// Adds \\(\partial E/\partial q_i\\) to `gradient[i]` (one entry per control point).
    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]);

    /// Adds the Hessian \\(\partial^2 E/\partial q_i \partial q_j\\) (or, for
    /// [`HessianKind::Definite`], a positive semi-definite approximation) to `hessian`.
    fn add_hessian(&self, rod: &Rod, kind: HessianKind, hessian: &mut BlockBanded) {
        let _ = kind;
        finite_difference_hessian(self, rod, hessian);
    }

    /// Adds the gradient and the Hessian in one call, as
    /// [`add_gradient`](Energy::add_gradient) then [`add_hessian`](Energy::add_hessian)
    /// (the default). Energies whose two share a pass over the quadrature points override
    /// it; the result must equal the two calls' up to round-off (the conformance harness
    /// checks it). Newton's method calls this once per iteration.
    fn add_gradient_and_hessian(
        &self,
        rod: &Rod,
        kind: HessianKind,
        gradient: &mut [Vector3<Real>],
        hessian: &mut BlockBanded,
    ) {
        self.add_gradient(rod, gradient);
        self.add_hessian(rod, kind, hessian);
    }

    /// Whether the Hessian has a remainder that [`add_hessian`](Energy::add_hessian)
    /// leaves out (see [`add_hessian_remainder`](Energy::add_hessian_remainder)). The
    /// default: none.
    fn has_hessian_remainder(&self, rod: &Rod) -> bool {
        let _ = rod;
        false
    }

    /// Adds `scale · R v` to `out`, where the Hessian is `H + R` with `H` what
    /// [`add_hessian`](Energy::add_hessian) adds (exact kind) and `R` a part that is not
    /// banded — a mixed form's consistent Gram matrix couples every control point with
    /// every other. `R` must be symmetric positive semi-definite and the same for either
    /// [`HessianKind`]: Newton's method factorises the banded `H` and corrects its step
    /// by conjugate gradients preconditioned with it, which converge fast when `H` is
    /// close to `H + R` (for the mixed stretching, within a factor the degree bounds).
    /// O(n) and allocation-free. The default: no remainder.
    fn add_hessian_remainder(
        &self,
        rod: &Rod,
        v: &[Vector3<Real>],
        scale: Real,
        out: &mut [Vector3<Real>],
    ) {
        let _ = (rod, v, scale, out);
    }

    /// Adds the axial tension (force along the centreline, N) this energy carries at the
    /// material coordinates `s` into `out` (same length) and returns true; energies
    /// without a tension (the default) return false.
    fn add_tension(&self, rod: &Rod, s: &[Real], out: &mut [Real]) -> bool {
        let _ = (rod, s, out);
        false
    }

    /// For energies holding constraints by multipliers (the inextensible rod): one
    /// method-of-multipliers update at the current state, `stiffen`ing the penalty if the
    /// violation fell too slowly (for repeated solves of one equilibrium, not for time
    /// steps); returns the violation before it (dimensionless). The default has no
    /// constraints: 0.
    fn update_multipliers(&mut self, rod: &Rod, stiffen: bool) -> Real {
        let _ = (rod, stiffen);
        0.0
    }

    /// Scales the energy's stiffness to `scale` times its own (`1` restores it exactly),
    /// for a static solver's continuation from a soft rod to the real one; returns
    /// whether the energy has such a stiffness (the default: no, and nothing changes).
    fn set_stiffness_scale(&mut self, scale: Real) -> bool {
        let _ = scale;
        false
    }

    /// Block bandwidth of the Hessian: the largest distance between two control points
    /// the energy couples (the degree `d` by default: integrals of the curve and its
    /// derivatives couple control points that share a span).
    fn bandwidth(&self, rod: &Rod) -> usize {
        rod.basis().degree()
    }

    /// Called after the rod's knots changed through `map`; update cached data locally.
    fn on_knot_change(&mut self, rod: &Rod, map: &KnotMap) {
        let _ = (rod, map);
    }

    /// This energy for `fine`, a copy of its rod on a finer basis (the same curve), for
    /// error estimators that evaluate energies there. An energy whose data follow the
    /// rod's coefficients or quadrature points (see
    /// [`on_knot_change`](Energy::on_knot_change)) must return a copy that follows
    /// `fine`; the default `None` says the energy holds no such data and is evaluated on
    /// `fine` as it is.
    fn for_finer_rod(&self, fine: &Rod) -> Option<Box<dyn Energy>> {
        let _ = fine;
        None
    }

    /// Whether the energy can act on `rod`: an error naming what it cannot handle (a
    /// closed rod, for an energy defined by the rod's ends). Systems check it when an
    /// energy is added, and the conformance harness skips the rods it refuses. Default:
    /// every rod.
    fn supports(&self, rod: &Rod) -> Result<(), CoreError> {
        let _ = rod;
        Ok(())
    }

    /// Called before each integrator step (sub-step) of `dt` seconds, at the state it
    /// starts from: freeze per-step data here (contact freezes its friction anchors).
    fn begin_step(&mut self, rod: &Rod, dt: Real) -> Result<(), CoreError> {
        let _ = (rod, dt);
        Ok(())
    }

    /// Appends what this energy keeps between steps that the rod does not determine
    /// (multipliers, a transported frame, a neighbour list whose rounding results depend
    /// on), for a checkpoint ([`splinerod_core::state`]). Default: nothing.
    fn save_state(&self, out: &mut SavedState) {
        let _ = out;
    }

    /// Reads back what [`save_state`](Energy::save_state) wrote, into a copy built like
    /// this one and brought to the same knots; `rod` is the restored rod.
    fn load_state(&mut self, rod: &Rod, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        let _ = (rod, input);
        Ok(())
    }

    /// Called in the drivers stage of every step (sub-step) with the time `t` the step
    /// ends at (a static solve: its end time): time-dependent energies — a turning
    /// clamp, a moving obstacle — set their state for `t` here. Default: nothing.
    fn drive(&mut self, t: Real) {
        let _ = t;
    }

    /// Whether [`drive`](Energy::drive) changes this energy (energy-conserving
    /// integrators then count the work it does). Default false.
    fn time_dependent(&self) -> bool {
        false
    }

    /// Appends the material coordinates (m) where this energy acts locally now (both
    /// sides of every contact), for refinement criteria; the default appends none.
    fn interaction_points(&self, rod: &Rod, out: &mut Vec<Real>) -> Result<(), CoreError> {
        let _ = (rod, out);
        Ok(())
    }

    /// Whether the rod's state is one Newton's line search may move to (a penalty is a
    /// finite barrier; see `System::admissible`). Default: always.
    fn admissible(&self, rod: &Rod) -> bool {
        let _ = rod;
        true
    }

    /// Appends the force (N) the rod exerts on each rigid obstacle this energy holds
    /// (the contact energy); the default holds none.
    fn add_obstacle_forces(
        &self,
        rod: &Rod,
        out: &mut Vec<Vector3<Real>>,
    ) -> Result<(), CoreError> {
        let _ = (rod, out);
        Ok(())
    }

    /// The segment of a joined rod this energy acts on alone ([`crate::OnSegment`]);
    /// `None` (the default) for an energy of the whole rod.
    fn segment(&self) -> Option<usize> {
        None
    }

    /// This energy on `rod` as a term the batched ensemble step evaluates for several
    /// rods at once ([`crate::lanes`]), if it has such a form now; `None` (the default)
    /// steps a rod with this energy on its own, with the same result. The term must
    /// equal [`energy`](Energy::energy) and the exact
    /// [`add_gradient_and_hessian`](Energy::add_gradient_and_hessian) up to round-off,
    /// and [`begin_step`](Energy::begin_step) must be idempotent for an energy that has
    /// one (the batched step calls it before the member's own step does).
    fn lane_term<'a>(&'a self, rod: &'a Rod) -> Option<crate::LaneTerm<'a>> {
        let _ = rod;
        None
    }

    /// Statistics of the current state for reports; the default reports nothing.
    fn summary(&self, rod: &Rod) -> Result<EnergySummary, CoreError> {
        let _ = rod;
        Ok(EnergySummary::default())
    }
}

/// Central finite differences of the gradient, assembled with a colouring of the control
/// points: points `2w + 1` apart (`w` the energy's [`Energy::bandwidth`]) are never
/// coupled, so one pair of gradient evaluations
/// per colour and coordinate gives all their columns. Cost: `6(2d + 1)` gradients.
/// Exact up to O(h²) truncation (h ≈ ε^{1/3} · L) for energies local to the B-spline band.
pub fn finite_difference_hessian<E: Energy + ?Sized>(
    energy: &E,
    rod: &Rod,
    hessian: &mut BlockBanded,
) {
    let n = rod.len();
    let d = energy.bandwidth(rod);
    let colours = 2 * d + 1;
    let h = 6e-6 * rod.material().rest_length;
    let mut probe = rod.clone();
    let mut plus = vec![Vector3::zeros(); n];
    let mut minus = vec![Vector3::zeros(); n];
    // columns[α][j] = ∂g_j/∂q_i[α] for the perturbed i of j's colour class.
    let mut columns = [
        vec![Vector3::zeros(); n],
        vec![Vector3::zeros(); n],
        vec![Vector3::zeros(); n],
    ];
    for colour in 0..colours {
        for (alpha, column) in columns.iter_mut().enumerate() {
            for (sign, g) in [(1.0, &mut plus), (-1.0, &mut minus)] {
                probe.positions.copy_from_slice(&rod.positions);
                for i in (colour..n).step_by(colours) {
                    probe.positions[i][alpha] += sign * h;
                }
                g.iter_mut().for_each(|x| *x = Vector3::zeros());
                energy.add_gradient(&probe, g);
            }
            for j in 0..n {
                column[j] = (plus[j] - minus[j]) / (2.0 * h);
            }
        }
        for j in 0..n {
            // The perturbed point of this colour within the band of j, if any, with i ≥ j.
            let i = j + (colour + colours - j % colours) % colours;
            if i >= n || i - j > d {
                continue;
            }
            // block[β][α] = ∂g_j[β]/∂q_i[α]
            let mut block = Matrix3::from_columns(&[columns[0][j], columns[1][j], columns[2][j]]);
            if i == j {
                block = 0.5 * (block + block.transpose());
            }
            hessian.add_coupling(j, i, &block);
        }
    }
}
