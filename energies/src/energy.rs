//! The [`Energy`] trait and its finite-difference Hessian default.

use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, HessianKind, Real, Rod};

use crate::capabilities::{Capabilities, Lifecycle};
#[cfg(doc)]
use crate::capabilities::{HessianRemainder, Interaction, LaneForm, Summary, Tension};
use crate::ContactSummary;

/// What an energy reports about the rod's current state, for run statistics (see
/// [`crate::capabilities::Summary`]); every part is optional and summaries of several
/// energies merge.
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
/// override it.
///
/// **Capabilities.** Everything else an energy may do is a small trait of its own
/// ([`crate::capabilities`]), reached through [`capabilities`](Energy::capabilities)
/// and, for the one with state to change, [`lifecycle_mut`](Energy::lifecycle_mut): its
/// [`Lifecycle`] (per-step hooks, knot changes, driving, checkpoints), [`Interaction`]
/// points and barrier, a [`HessianRemainder`], a [`Tension`], a [`LaneForm`] for the
/// batched step, a [`Summary`]. An energy has none of them unless it says so;
/// decorators such as [`crate::OnSegment`] pass all of them on
/// ([`crate::decorate`]).
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

    /// Block bandwidth of the Hessian: the largest distance between two control points
    /// the energy couples (the degree `d` by default: integrals of the curve and its
    /// derivatives couple control points that share a span).
    fn bandwidth(&self, rod: &Rod) -> usize {
        rod.basis().degree()
    }

    /// The capabilities this energy has besides the core ([`crate::capabilities`]):
    /// by default none.
    fn capabilities(&self) -> Capabilities<'_> {
        Capabilities::default()
    }

    /// Its [`Lifecycle`], mutably, if it has one (then also in
    /// [`capabilities`](Energy::capabilities)); by default none.
    fn lifecycle_mut(&mut self) -> Option<&mut dyn Lifecycle> {
        None
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
