//! How far adaptivity may lower the continuity of the curve: the highest interior knot
//! multiplicity a criterion may reach, by where on the rod the knot lies.
//!
//! A knot of multiplicity `m` in a degree-`d` spline leaves the curve `C^{d−m}` there.
//!
//! * **A corner (`m = d`, `C⁰`) only where nothing resists bending or twist** — a
//!   string, or a segment of `[[rods]]` without bending and twist stiffness. A point
//!   force on a string makes a kink, which only a corner represents; on a rod with
//!   bending stiffness `EI > 0` the same corner is a free hinge: the bending energy,
//!   integrated per span, no longer sees the turn of the tangent across the knot, so
//!   the rod there carries no moment (measured: a 37° hinge at a contact of two crossing
//!   ropes, the upper rope's lift 6.3 % off).
//! * **Elsewhere at most `m = d − 1` (`C¹`)**: the tangent stays continuous, the
//!   curvature stays bounded (it may jump), so the bending and twist energies stay
//!   finite and see every turn. A point load on an Euler–Bernoulli beam needs less: its
//!   deflection is a `C²` piecewise cubic, which one simple knot at the load represents
//!   exactly; the second knot is allowed because it costs nothing in accuracy and lets a
//!   thread of small `EI` (a boundary layer of length `√(EI/T)` under tension `T`)
//!   turn sharply without a hinge.
//!
//! Multiplicity `d + 1` (a break: a cut, the junction of two rods) is never made by a
//! criterion. Degree 1 has no bending to keep (its spans are straight); there the limit
//! is 1 everywhere.

use splinerod_core::{Real, Rod};

/// Where corners (`C⁰` knots) may be made: the material ranges of the rod's
/// segments that have neither bending nor twist stiffness. Elsewhere the adapter
/// stops at multiplicity `d − 1`.
///
/// The default allows corners nowhere, the safe choice for a rod whose energies the
/// adapter cannot see; a scene opens the ranges of its strings.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Continuity {
    /// Closed material-coordinate ranges `[a, b]` (m) where corners are allowed.
    pub corners_allowed: Vec<(Real, Real)>,
}

impl Continuity {
    /// Corners allowed on the whole rod `[0, length]` (a string).
    pub fn corners_everywhere(length: Real) -> Self {
        Self {
            corners_allowed: vec![(0.0, length)],
        }
    }

    /// Whether a corner may be made at material coordinate `at`.
    pub fn allows_corner(&self, at: Real) -> bool {
        self.corners_allowed
            .iter()
            .any(|&(a, b)| a <= at && at <= b)
    }

    /// The highest multiplicity a criterion may give a knot at `at` on a rod of
    /// `degree`: the degree where corners are allowed, one less elsewhere (at least 1).
    pub fn max_multiplicity(&self, degree: usize, at: Real) -> usize {
        if self.allows_corner(at) {
            degree
        } else {
            degree.saturating_sub(1).max(1)
        }
    }
}

impl Continuity {
    /// The interior knots of `rod` that are hinges: multiplicity exactly the degree
    /// (`C⁰`, not a break) where corners are not allowed. Degree 1 has none (its knots
    /// are all corners; it has no bending). One pass over the knots, no allocation.
    pub fn hinges(&self, rod: &Rod) -> usize {
        let d = rod.basis().degree();
        if d < 2 {
            return 0;
        }
        let knots = rod.basis().knots();
        let (start, end) = rod.basis().domain();
        let mut count = 0;
        let mut k = 0;
        while k < knots.len() {
            let t = knots[k];
            let run = knots[k..].iter().take_while(|&&x| x == t).count();
            if t > start && t < end && run == d && !self.allows_corner(t) {
                count += 1;
            }
            k += run;
        }
        count
    }
}

#[cfg(test)]
mod tests {
    use super::Continuity;

    #[test]
    fn corners_only_inside_the_ranges() {
        let c = Continuity {
            corners_allowed: vec![(0.0, 1.0)],
        };
        assert_eq!(c.max_multiplicity(3, 0.5), 3);
        assert_eq!(c.max_multiplicity(3, 1.0), 3);
        assert_eq!(c.max_multiplicity(3, 1.5), 2);
        assert_eq!(Continuity::default().max_multiplicity(3, 0.5), 2);
        assert_eq!(Continuity::default().max_multiplicity(1, 0.5), 1);
        assert!(Continuity::corners_everywhere(2.0).allows_corner(2.0));
    }
}
