//! What differs between the surfaces a [`Contact`] keeps apart: the radius of each
//! segment of a joined rod, and the friction coefficient of each surface — each segment
//! of the rod, each obstacle, the floor.
//!
//! **Friction of a contact.** Every surface has a coefficient; a contact between two
//! surfaces takes the smaller of their two,
//!
//! \\[ \mu_{ab} = \min(\mu_a, \mu_b), \\]
//!
//! so a slippery surface is slippery whatever touches it, and one coefficient for every
//! surface (the default: `ContactParams::friction` for all) gives that coefficient. The
//! floor's coefficient is `ContactParams::friction`; a segment's or an obstacle's is
//! its own if given ([`Contact::with_segment_friction`],
//! [`Contact::with_obstacle_friction`]), else that one.

use super::Contact;
use splinerod_core::rod::non_negative;
use splinerod_core::{CoreError, Real};

/// A value per segment of a joined rod: `starts[k]` is where segment `k` starts in the
/// parameter; empty for one value everywhere (the caller's default).
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct SegmentValues {
    starts: Vec<Real>,
    pub(super) values: Vec<Real>,
}

impl SegmentValues {
    /// `values[k]` from `starts[k]` on (increasing, the first 0), checked.
    pub(super) fn new(starts: &[Real], values: &[Real]) -> Result<Self, CoreError> {
        let increasing = starts.windows(2).all(|w| w[0] < w[1]);
        if starts.len() != values.len() || !increasing || starts.first() != Some(&0.0) {
            return Err(CoreError::InvalidParameter {
                name: "segment starts",
                value: starts.len() as Real,
                reason: "one increasing start per value, the first at 0",
            });
        }
        Ok(Self {
            starts: starts.to_vec(),
            values: values.to_vec(),
        })
    }

    /// The value at material coordinate `s`, `default` if there is none per segment.
    pub(super) fn at(&self, s: Real, default: Real) -> Real {
        if self.values.is_empty() {
            return default;
        }
        let k = self.starts.partition_point(|&t| t <= s).saturating_sub(1);
        self.values[k]
    }
}

impl Contact {
    /// Friction per segment of a joined rod (builder style): `mu[k]` (≥ 0) for the
    /// segment starting at parameter `starts[k]` (increasing, the first 0). See the
    /// module docs for the coefficient of a contact.
    pub fn with_segment_friction(
        mut self,
        starts: &[Real],
        mu: &[Real],
    ) -> Result<Self, CoreError> {
        for &m in mu {
            non_negative("friction", m)?;
        }
        self.frictions = SegmentValues::new(starts, mu)?;
        Ok(self)
    }

    /// Friction per obstacle (builder style, after the obstacles): `mu[i]` (≥ 0) for
    /// obstacle `i`, one per obstacle.
    pub fn with_obstacle_friction(mut self, mu: &[Real]) -> Result<Self, CoreError> {
        for &m in mu {
            non_negative("friction", m)?;
        }
        if mu.len() != self.obstacles.len() {
            return Err(CoreError::InvalidParameter {
                name: "obstacle friction",
                value: mu.len() as Real,
                reason: "one coefficient per obstacle",
            });
        }
        self.obstacle_friction = mu.to_vec();
        Ok(self)
    }

    /// The friction coefficient of the rod's surface at material coordinate `s`.
    pub fn friction_at(&self, s: Real) -> Real {
        self.frictions.at(s, self.params.friction)
    }

    /// The friction coefficient of obstacle `i`'s surface (`None`: the floor).
    pub fn surface_friction(&self, obstacle: Option<usize>) -> Real {
        let own = obstacle.and_then(|i| self.obstacle_friction.get(i));
        own.copied().unwrap_or(self.params.friction)
    }

    /// Whether any contact can have friction.
    pub(super) fn has_friction(&self) -> bool {
        let any = |v: &[Real]| v.iter().any(|&m| m > 0.0);
        self.params.friction > 0.0 || any(&self.frictions.values) || any(&self.obstacle_friction)
    }

    /// The radius of the rod at material coordinate `s`.
    pub fn radius_at(&self, s: Real) -> Real {
        self.radii.at(s, self.params.radius)
    }

    /// The largest radius.
    pub(super) fn max_radius(&self) -> Real {
        self.radii
            .values
            .iter()
            .fold(self.params.radius, |a, &b| a.max(b))
    }
}
