//! [`ContactSummary`]: what the detection finds at the rod's positions, for reports and
//! checks (not needed by the energy itself).

use super::Contact;
use splinerod_core::{CoreError, Real, Rod};

/// What the detection found at the rod's current positions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSummary {
    /// Contacts: pairs of contact segments closer than the reach `2r + δ`.
    pub pairs: usize,
    /// Candidate segment pairs of the broad phase.
    pub candidates: usize,
    /// Smallest centre-line distance among the contacts, m (`None` without contacts).
    pub min_distance: Option<Real>,
    /// The smallest clearance ratio (`None` without contacts): centre-line distance
    /// over the diameter `2r` between strands, over the radius `r` from the floor or an
    /// obstacle;
    /// below 1 the rod overlaps.
    pub min_clearance_ratio: Option<Real>,
    /// Points of the rod within the penalty's reach of the floor or an obstacle.
    pub obstacle_contacts: usize,
    /// The smallest gap over the contact's sample pairs and surface points within
    /// reach, m (negative: overlap; `None` without contacts): where the energy holds
    /// the contacts.
    pub min_gap: Option<Real>,
    /// The contact stiffness now (penalty `k` or barrier `κ`, as adapted), N/m.
    pub stiffness: Real,
    /// The gap tolerance, m (`None` for the fixed penalty): see [`Contact::tolerance`].
    pub tolerance: Option<Real>,
}

impl ContactSummary {
    /// The summary of two sets of contacts together (the larger stiffness).
    pub fn merged(&self, other: &ContactSummary) -> ContactSummary {
        let min = |a: Option<Real>, b: Option<Real>| match (a, b) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        ContactSummary {
            pairs: self.pairs + other.pairs,
            candidates: self.candidates + other.candidates,
            min_distance: min(self.min_distance, other.min_distance),
            min_clearance_ratio: min(self.min_clearance_ratio, other.min_clearance_ratio),
            obstacle_contacts: self.obstacle_contacts + other.obstacle_contacts,
            min_gap: min(self.min_gap, other.min_gap),
            stiffness: self.stiffness.max(other.stiffness),
            tolerance: min(self.tolerance, other.tolerance),
        }
    }
}

impl Contact {
    /// Counts and closest distance of the contacts at the rod's positions.
    pub fn summary(&self, rod: &Rod) -> Result<ContactSummary, CoreError> {
        let mut d = self.detected(rod)?;
        d.closest(rod, self.reach())?;
        let min_distance = d.closest.iter().map(|c| c.distance).reduce(Real::min);
        let (pairs, candidates) = (d.closest.len(), d.candidate_count());
        let strands = d
            .closest
            .iter()
            .map(|c| c.distance / (self.radius_at(c.s) + self.radius_at(c.t)))
            .reduce(Real::min);
        drop(d);
        let (obstacle_contacts, obstacles) = self.obstacle_summary(rod)?;
        let min_clearance_ratio = match (strands, obstacles) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        Ok(ContactSummary {
            pairs,
            candidates,
            min_distance,
            min_clearance_ratio,
            obstacle_contacts,
            min_gap: self.smallest_gap(rod)?,
            stiffness: self.stiffness(),
            tolerance: self.tolerance(),
        })
    }
}
