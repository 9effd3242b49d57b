//! Why an ensemble member's step was not solved in the lanes of the batched step
//! ([`Unbatched`], decided by `world/lanes.rs`), and the counts of such steps per reason
//! that a run reports (JSON `solver.unbatched`, [`UnbatchedCounts`]).

use serde::de::Error as _;
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::collections::BTreeMap;
use std::ops::AddAssign;

/// Why a member of an ensemble took its step alone (its own solver) instead of through
/// the lanes of the batched step (`world/lanes.rs`). Every reason is the
/// member's own: none depends on which members share its group or shard.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Unbatched {
    /// Batching is off (`[ensemble] batched = false`, [`crate::Ensemble::batched`]).
    Off,
    /// The integrator has no batched form (only implicit Euler has one).
    Scheme,
    /// A sub-step shorter than the step is pending (the sub-stepper split a step).
    SubStep,
    /// The member adapts its knots (a round-off difference could flip a decision).
    Adaptive,
    /// Driven pins or an energy that depends on time.
    Driven,
    /// An energy's per-step setup failed (the member's own step reports the error).
    Setup,
    /// The stretching has no lane form now: a form other than the lumped `"mixed"` one
    /// (`"mixed-consistent"`, also what `"auto"` may choose, or `"pointwise"`), a closed
    /// rod or a rest curve.
    StretchingForm,
    /// Another energy acting now has no lane form (contact, grabs, loads, clamps, twist).
    Energy,
    /// More energies than the lanes take, or lane terms that do not fit the shape.
    Terms,
    /// The batched solver does not take the member's settings or shape (the sparse
    /// solver, a Newton step limit, pins that do not hold single control points).
    Solver,
    /// The lane's matrix was not positive definite (the scalar solver switches
    /// factorisation).
    Indefinite,
    /// The lane's step would have been shortened by the line search.
    LineSearch,
    /// The lane did not converge in the iterations allowed.
    NotConverged,
    /// The stretching's projection guard acts on the lane's rod.
    Guard,
    /// Per-point (not uniform) damping.
    Damping,
    /// A non-finite or diverging value in the lane.
    NonFinite,
    /// The batched result was ready but the member's step was not the one it was
    /// computed for (the step was split into sub-steps).
    NotTaken,
}

impl Unbatched {
    /// Every reason, in the order of [`UnbatchedCounts`].
    pub const ALL: [Unbatched; 17] = [
        Unbatched::Off,
        Unbatched::Scheme,
        Unbatched::SubStep,
        Unbatched::Adaptive,
        Unbatched::Driven,
        Unbatched::Setup,
        Unbatched::StretchingForm,
        Unbatched::Energy,
        Unbatched::Terms,
        Unbatched::Solver,
        Unbatched::Indefinite,
        Unbatched::LineSearch,
        Unbatched::NotConverged,
        Unbatched::Guard,
        Unbatched::Damping,
        Unbatched::NonFinite,
        Unbatched::NotTaken,
    ];

    /// Its key in JSON `solver.unbatched`.
    pub fn name(self) -> &'static str {
        match self {
            Unbatched::Off => "off",
            Unbatched::Scheme => "scheme",
            Unbatched::SubStep => "sub-step",
            Unbatched::Adaptive => "adaptive",
            Unbatched::Driven => "driven",
            Unbatched::Setup => "setup",
            Unbatched::StretchingForm => "stretching-form",
            Unbatched::Energy => "energy",
            Unbatched::Terms => "terms",
            Unbatched::Solver => "solver",
            Unbatched::Indefinite => "indefinite",
            Unbatched::LineSearch => "line-search",
            Unbatched::NotConverged => "not-converged",
            Unbatched::Guard => "guard",
            Unbatched::Damping => "damping",
            Unbatched::NonFinite => "non-finite",
            Unbatched::NotTaken => "not-taken",
        }
    }

    /// Why a member's step was solved alone, recorded after the step: `decided`, the
    /// reason [`crate::world::lanes`] gave before or during the batched solve (`None`:
    /// its step was preloaded), and whether the step `taken` was the batched one. A
    /// preloaded step the member did not take (another `dt`, another start) is
    /// [`Unbatched::NotTaken`]; a batched step is `None`.
    pub(crate) fn of_step(decided: Option<Unbatched>, taken: bool) -> Option<Unbatched> {
        (!taken).then_some(decided.unwrap_or(Unbatched::NotTaken))
    }

    /// The reason of a lane the batched solver failed with `why`
    /// ([`splinerod_integrators::lane_euler::LaneFallback`]).
    pub(crate) fn of_lane(why: &str) -> Unbatched {
        match why {
            "not positive definite" => Unbatched::Indefinite,
            "line search" => Unbatched::LineSearch,
            "not converged" => Unbatched::NotConverged,
            "potential" => Unbatched::Guard,
            "damping" => Unbatched::Damping,
            _ => Unbatched::NonFinite,
        }
    }

    fn index(self) -> usize {
        self as usize
    }
}

/// Steps taken alone, per [`Unbatched`] reason (JSON `solver.unbatched`: an object of
/// the nonzero counts, keyed by [`Unbatched::name`]). No allocation to count.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct UnbatchedCounts([usize; Unbatched::ALL.len()]);

impl UnbatchedCounts {
    /// Counts one step taken alone for `reason`.
    pub fn add(&mut self, reason: Unbatched) {
        self.0[reason.index()] += 1;
    }

    /// The steps counted for `reason`.
    pub fn get(&self, reason: Unbatched) -> usize {
        self.0[reason.index()]
    }

    /// Whether no step was counted.
    pub fn is_empty(&self) -> bool {
        self.0.iter().all(|&c| c == 0)
    }

    /// All steps counted, whatever the reason.
    pub fn total(&self) -> usize {
        self.0.iter().sum()
    }
}

impl AddAssign for UnbatchedCounts {
    fn add_assign(&mut self, other: UnbatchedCounts) {
        for (a, b) in self.0.iter_mut().zip(other.0) {
            *a += b;
        }
    }
}

impl Serialize for UnbatchedCounts {
    fn serialize<S: Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        // The length up front: postcard (checkpoints) needs it.
        let nonzero = self.0.iter().filter(|&&c| c > 0).count();
        let mut map = serializer.serialize_map(Some(nonzero))?;
        for reason in Unbatched::ALL.iter().filter(|r| self.get(**r) > 0) {
            map.serialize_entry(reason.name(), &self.get(*reason))?;
        }
        map.end()
    }
}

impl<'de> Deserialize<'de> for UnbatchedCounts {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        let map = BTreeMap::<String, usize>::deserialize(deserializer)?;
        let mut counts = UnbatchedCounts::default();
        for (key, count) in map {
            let reason = Unbatched::ALL
                .into_iter()
                .find(|r| r.name() == key)
                .ok_or_else(|| D::Error::custom(format!("unknown unbatched reason {key:?}")))?;
            counts.0[reason.index()] += count;
        }
        Ok(counts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_go_to_json_by_name_and_back() {
        for (i, r) in Unbatched::ALL.iter().enumerate() {
            assert_eq!(r.index(), i);
        }
        let mut counts = UnbatchedCounts::default();
        assert!(counts.is_empty());
        counts.add(Unbatched::Energy);
        counts.add(Unbatched::Energy);
        counts.add(Unbatched::LineSearch);
        let json = serde_json::to_value(counts).expect("json");
        assert_eq!(json, serde_json::json!({"energy": 2, "line-search": 1}));
        let back: UnbatchedCounts = serde_json::from_value(json).expect("back");
        assert_eq!(back, counts);
        assert_eq!(back.total(), 3);
        let bytes = postcard::to_stdvec(&counts).expect("postcard");
        assert_eq!(
            postcard::from_bytes::<UnbatchedCounts>(&bytes).ok(),
            Some(counts)
        );
        assert!(serde_json::from_value::<UnbatchedCounts>(serde_json::json!({"x": 1})).is_err());
    }
}
