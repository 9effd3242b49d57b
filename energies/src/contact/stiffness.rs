//! How contacts resist ([`ContactLaw`]) and how their stiffness follows the loads, so
//! that at rest every contact sits within a gap tolerance `τ` of touching (issue #46).
//!
//! **The barrier** ([`ContactLaw::Barrier`], the scene default): the `barrier` module's
//! \\(b(g)\\), active below the gap `τ` (the contact's onset) and unbounded as the gap
//! closes. A load `F` on a contact rests at a gap in \\((0, \tau)\\) for any stiffness
//! `κ`; `κ` only sets where in the layer (\\(g \approx \kappa\tau^2/F\\) near contact),
//! and so the conditioning. The default `κ` carries a line load `w` (N per m of rod) at
//! half the tolerance on a surface, whose energy per unit length is \\(b/(2r)\\):
//!
//! \\[ \kappa = \frac{2 r w}{\tau\,(\ln 2 + \tfrac12)} \quad
//! ([`barrier_stiffness_for`]), \\]
//!
//! with `w` the scene's estimate (weight per length plus a tension over the radius,
//! `src/scene/contact.rs`). Overestimating `w` costs little — near the layer's edge the
//! contact's stiffness \\(\sqrt{12 \kappa F/\tau}\\) grows only as \\(\sqrt\kappa\\) —
//! while underestimating it by `n` pushes the gap down to about \\(\tau/n\\), where the
//! stiffness \\(F^2/(\kappa\tau^2)\\) grows as `n`. Hence the update before each step:
//! where the smallest gap `g` over every sample pair and surface point has fallen below
//! [`BARRIER_LOW`]` · τ`, `κ` becomes the stiffness that holds the same force at `τ/4`,
//!
//! \\[ \kappa \leftarrow \kappa \cdot \min\Big(\frac{\tilde b'(g/\tau)}{\tilde b'(1/4)},\
//! 100\Big) \\]
//!
//! (about \\(\tau / 4g\\) inside the barrier, more in its continuation); it never
//! falls, and stops at [`MAX_RATIO`] times the first `κ`.
//!
//! **The adaptive penalty** ([`ContactLaw::AdaptivePenalty`], the scene's choice when
//! both a `stiffness` and a `tolerance` are given; measured against the barrier in
//! ARCHITECTURE.md, #46): the penalty \\(\phi\\) of stiffness `k` with its onset at the
//! tolerance, and before each step, from the deepest penetration \\(p = -\min g\\), the
//! stiffness that would carry the same force at \\(p^* = \tau/2\\): a crossing of
//! overlap `p` pushes with about \\(\pi k f(p)/(2r)\\),
//! \\(f(p) = p^2 + p\delta + \delta^2/3\\), so
//!
//! \\[ k \leftarrow \operatorname{clamp}\Big(k\, \frac{f(\max(p, 0))}{f(p^*)},\
//! [0.8 k,\ 10 k] \cap [k_0,\ 10^4 k_0]\Big) \\]
//!
//! (at most ten times up and a fifth down per step, never below the user's `k_0`, at
//! most [`PENALTY_MAX_RATIO`] times it).
//!
//! **Static solves** adapt between Newton solves instead (`Lifecycle::update_multipliers`,
//! which the static solver repeats until it returns 0): the adaptive penalty raises `k`
//! while the deepest contact is deeper than `τ`; the barrier raises `κ` only if a contact
//! overlaps (a load past its quadratic continuation).
//!
//! **Between updates** the stiffness is constant, so each Newton solve minimises one
//! energy; an update changes the energy between steps (a dissipative scheme absorbs the
//! jump, like a multiplier update). A retried sub-step starts from the same state and
//! does not update again (the measured gap and a fingerprint of the positions are
//! remembered). Friction's frozen normal
//! forces are taken after the update. Checkpoints save the stiffness reached and the
//! last update's state, and the error estimator's finer copy takes the stiffness as it
//! is.

use super::barrier::unit_slope;
use super::Contact;
use splinerod_core::{CoreError, Real, Rod};

/// How contacts resist (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactLaw {
    /// The penalty \\(\phi\\) of stiffness `k`, starting at the gap `onset`: fixed.
    Penalty,
    /// The penalty, its stiffness raised where the deepest contact passes half the
    /// tolerance (the onset should not exceed it).
    AdaptivePenalty {
        /// Gap tolerance `τ`, m (> 0).
        tolerance: Real,
    },
    /// The barrier of the `barrier` module, acting below the gap `onset` (the tolerance
    /// `τ`), its stiffness raised where a contact comes closer than a tenth of it.
    Barrier,
}

/// The barrier's stiffness is raised where a gap falls below this fraction of `τ`.
pub const BARRIER_LOW: Real = 0.1;
/// Largest stiffness an update reaches, in multiples of the first.
pub const MAX_RATIO: Real = 1e6;
/// Largest growth of the adaptive penalty's stiffness in one update.
pub const GROWTH: Real = 10.0;
/// Largest growth of the barrier's stiffness in one update.
pub const BARRIER_GROWTH: Real = 100.0;
/// Largest stiffness the adaptive penalty reaches, in multiples of the user's.
pub const PENALTY_MAX_RATIO: Real = 1e4;
/// Largest fall of the adaptive penalty's stiffness in one update (to this fraction).
pub const RELAX: Real = 0.8;

/// The barrier stiffness `κ` (N/m) that carries a line load `w` (N/m) on a surface at
/// half the tolerance `tau` (m), for a rod of radius `r` (m): \\(2 r w /
/// (\tau (\ln 2 + 1/2))\\).
pub fn barrier_stiffness_for(w: Real, r: Real, tau: Real) -> Real {
    2.0 * r * w / (tau * super::barrier::HALF_TOLERANCE_FORCE)
}

/// \\(f(p) = p^2 + p\delta + \delta^2/3\\) for a penetration `p ≥ 0` and onset `delta`:
/// a crossing's force over \\(\pi k / 2r\\).
fn crossing_force(p: Real, delta: Real) -> Real {
    p * p + p * delta + delta * delta / 3.0
}

/// The adaptive penalty's stiffness after one update from `k` (first `k0`), for the
/// deepest penetration `p` (`None`: no contact), the aim `aim` and the onset `delta`.
fn penalty_update(k: Real, k0: Real, p: Option<Real>, aim: Real, delta: Real) -> Real {
    let p = p.unwrap_or(0.0).max(0.0);
    let wanted = k * crossing_force(p, delta) / crossing_force(aim, delta);
    let stepped = wanted.clamp(RELAX * k, GROWTH * k);
    stepped.clamp(k0, PENALTY_MAX_RATIO * k0)
}

/// The barrier's stiffness after one update from `kappa` (first `k0`), for the smallest
/// gap `g` (`None`: no contact) and the tolerance `tau`.
fn barrier_update(kappa: Real, k0: Real, g: Option<Real>, tau: Real) -> Real {
    match g {
        Some(g) if g < BARRIER_LOW * tau => {
            let factor = unit_slope(g / tau) / unit_slope(0.25);
            (kappa * factor.min(BARRIER_GROWTH)).min(MAX_RATIO * k0)
        }
        _ => kappa,
    }
}

/// A fingerprint of the rod's positions: equal for a step retried from the same state
/// (bit for bit), different once the rod has moved.
fn fingerprint(rod: &Rod) -> Real {
    let sum = |(i, q): (usize, &nalgebra::Vector3<Real>)| {
        (q.x + 1.7 * q.y + 2.9 * q.z) * (1.0 + 1e-3 * i as Real)
    };
    rod.positions.iter().enumerate().map(sum).sum()
}

impl Contact {
    /// The smallest gap (m, negative: overlap) over every sample pair and surface point
    /// within reach at the rod's positions; `None` without contacts.
    pub fn smallest_gap(&self, rod: &Rod) -> Result<Option<Real>, CoreError> {
        let d = self.detected(rod)?;
        let least = |a: Option<Real>, g: Real| Some(a.map_or(g, |a: Real| a.min(g)));
        let mut g = d.pairs.iter().map(|c| self.gap(&d, c)).fold(None, least);
        drop(d);
        self.for_each_surface_point(rod, |s| g = least(g, s.gap))?;
        Ok(g)
    }

    /// The contact stiffness now, N/m: `params.stiffness` as the updates left it.
    pub fn stiffness(&self) -> Real {
        self.penalty.k
    }

    /// The gap tolerance, m: the barrier's onset or the adaptive penalty's tolerance;
    /// `None` for the fixed penalty.
    pub fn tolerance(&self) -> Option<Real> {
        match self.params.law {
            ContactLaw::Penalty => None,
            ContactLaw::AdaptivePenalty { tolerance } => Some(tolerance),
            ContactLaw::Barrier => Some(self.params.onset),
        }
    }

    /// One update of the stiffness at the rod's positions (module docs), unless the
    /// last one was made at the same state (a retried step). Returns the stiffness.
    pub fn adapt_stiffness(&mut self, rod: &Rod) -> Result<Real, CoreError> {
        if self.params.law == ContactLaw::Penalty {
            return Ok(self.penalty.k);
        }
        let g = self.smallest_gap(rod)?;
        let state = [g.unwrap_or(Real::INFINITY), fingerprint(rod)];
        if self.adapted_at == Some(state) || state[0].is_nan() {
            return Ok(self.penalty.k);
        }
        self.adapted_at = Some(state);
        let (k, k0, delta) = (self.penalty.k, self.params.stiffness, self.params.onset);
        self.penalty.k = match self.params.law {
            ContactLaw::AdaptivePenalty { tolerance } => {
                penalty_update(k, k0, g.map(|g| -g), 0.5 * tolerance, delta)
            }
            _ => barrier_update(k, k0, g, delta),
        };
        Ok(self.penalty.k)
    }

    /// The static solver's update (module docs): raises the stiffness where the
    /// tolerance is not met and returns by how much it was missed, in tolerances (0:
    /// met, nothing changed).
    pub(crate) fn stiffen_for_statics(&mut self, rod: &Rod) -> Real {
        let Ok(Some(g)) = self.smallest_gap(rod) else {
            return 0.0;
        };
        let (k, k0, delta) = (self.penalty.k, self.params.stiffness, self.params.onset);
        let (missed, updated) = match self.params.law {
            ContactLaw::AdaptivePenalty { tolerance } if -g > tolerance => (
                -g / tolerance - 1.0,
                penalty_update(k, k0, Some(-g), 0.5 * tolerance, delta).max(k),
            ),
            ContactLaw::Barrier if g < 0.0 => (-g / delta, barrier_update(k, k0, Some(g), delta)),
            _ => return 0.0,
        };
        if updated == k {
            return 0.0;
        }
        self.penalty.k = updated;
        missed
    }

    /// Sets the stiffness (N/m, > 0), e.g. to carry an adapted one over to a copy.
    pub fn set_stiffness(&mut self, k: Real) -> Result<(), CoreError> {
        splinerod_core::rod::positive("stiffness", k)?;
        self.penalty.k = k;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::{barrier_update, crossing_force, penalty_update, unit_slope};
    use super::{BARRIER_GROWTH, GROWTH, MAX_RATIO, PENALTY_MAX_RATIO, RELAX};

    const DELTA: f64 = 3e-4;
    const AIM: f64 = 1.5e-4;

    #[test]
    fn the_adaptive_penalty_carries_a_deep_contacts_force_at_the_aim() {
        assert_eq!(penalty_update(1e4, 1e4, Some(1e-4), AIM, DELTA), 1e4);
        assert_eq!(penalty_update(1e4, 1e4, None, AIM, DELTA), 1e4);
        let p = 4e-4;
        let k = penalty_update(1e4, 1e4, Some(p), AIM, DELTA);
        let force = |k: f64, p: f64| k * crossing_force(p, DELTA);
        assert!((force(k, AIM) - force(1e4, p)).abs() < 1e-9 * force(1e4, p));
        assert_eq!(
            penalty_update(1e4, 1e4, Some(1.0), AIM, DELTA),
            GROWTH * 1e4
        );
        let top = PENALTY_MAX_RATIO * 1e4;
        assert_eq!(penalty_update(top, 1e4, Some(1.0), AIM, DELTA), top);
        // Without contacts it relaxes to the user's stiffness, at most by RELAX a step.
        let mut k = 1e6;
        for _ in 0..100 {
            let next = penalty_update(k, 1e4, None, AIM, DELTA);
            assert!(next >= RELAX * k && next <= k);
            k = next;
        }
        assert_eq!(k, 1e4);
    }

    /// A straight 1 m rod of radius 1 cm lying `depth` m into the floor `y = 0`.
    fn sunk_rod(depth: f64) -> splinerod_core::Rod {
        use nalgebra::Vector3;
        use splinerod_core::{BSplineSpace, Material, Rod};
        let material = Material {
            rest_length: 1.0,
            linear_density: 0.1,
        };
        let basis = BSplineSpace::clamped_uniform(3, 8, 1.0).expect("basis");
        let y = 0.01 - depth;
        let (a, b) = (Vector3::new(0.0, y, 0.0), Vector3::new(1.0, y, 0.0));
        Rod::straight(material, Box::new(basis), a, b).expect("rod")
    }

    #[test]
    fn a_retried_step_does_not_update_again_and_a_free_rod_relaxes() {
        use crate::{Contact, ContactParams};
        let params = ContactParams::adaptive(0.01, 1e3, 5e-4).expect("params");
        let mut c = Contact::new(params.with_floor(0.0).expect("floor")).expect("contact");
        let deep = sunk_rod(2e-3);
        let once = c.adapt_stiffness(&deep).expect("update");
        assert!(once > 1e3, "{once}");
        // The same state again (a retried sub-step): no second update.
        assert_eq!(c.adapt_stiffness(&deep).expect("update"), once);
        // Lifted off the floor, it relaxes at every step, by at most RELAX.
        let (mut k, mut free) = (once, sunk_rod(-0.1));
        for step in 0..3 {
            free.positions[0].x = 1e-6 * step as f64;
            let next = c.adapt_stiffness(&free).expect("update");
            assert!(next < k && next >= RELAX * k, "{next} after {k}");
            k = next;
        }
    }

    #[test]
    fn the_barrier_stiffens_only_below_a_tenth_of_the_tolerance() {
        let tau = 1e-4;
        assert_eq!(barrier_update(5.0, 5.0, None, tau), 5.0);
        assert_eq!(barrier_update(5.0, 5.0, Some(0.2 * tau), tau), 5.0);
        // The force of a contact at τ/20 is held at τ/4 (about 5 κ).
        let k = barrier_update(5.0, 5.0, Some(0.05 * tau), tau);
        let force = |k: f64, x: f64| -k * unit_slope(x);
        assert!((force(k, 0.25) - force(5.0, 0.05)).abs() < 1e-12 * force(k, 0.25));
        assert!(k > 5.0 * 5.0 && k < 6.0 * 5.0, "{k}");
        // Deep in the continuation: at most BARRIER_GROWTH a step, MAX_RATIO in all.
        assert_eq!(
            barrier_update(5.0, 5.0, Some(-tau), tau),
            5.0 * BARRIER_GROWTH
        );
        assert_eq!(
            barrier_update(5.0 * MAX_RATIO, 5.0, Some(-tau), tau),
            5.0 * MAX_RATIO
        );
    }
}
