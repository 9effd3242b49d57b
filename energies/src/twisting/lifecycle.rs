//! The twisting energy's life beside its values ([`Lifecycle`]: cuts, turning and
//! gripped clamps, the branch of ψ kept from step to step, checkpoints) and its report
//! ([`Summary`]).

use super::holonomy::is_cut;
use super::Twisting;
use crate::capabilities::{Lifecycle, Summary};
use crate::{EnergySummary, TwistSummary};
use nalgebra::Matrix3;
use splinerod_core::{CoreError, Keyframes, KnotMap, Real, Rod, SavedState, StateReader};

impl Lifecycle for Twisting {
    fn on_knot_change(&mut self, rod: &Rod, map: &KnotMap) {
        let _ = map;
        self.released |= is_cut(rod);
        if !self.released {
            let branch = self.holonomies(&self.prepared(rod));
            self.branch = branch;
        }
    }

    fn drive(&mut self, t: Real) {
        let [start, end] = &self.schedules;
        if start.is_some() || end.is_some() {
            let angle = |s: &Option<Keyframes<Real>>| s.as_ref().map_or(0.0, |k| k.at(t));
            self.turn = angle(end) - angle(start) + self.rolls[1] - self.rolls[0];
        }
    }

    fn time_dependent(&self) -> bool {
        self.schedules.iter().any(Option::is_some)
    }

    fn grip(&mut self, end: usize, rotation: &Matrix3<Real>, roll: Real) {
        Twisting::grip(self, end, rotation, roll);
    }

    fn save_state(&self, out: &mut SavedState) {
        out.real(self.turn);
        out.reals(&self.branch);
        out.int(u64::from(self.released));
    }

    fn load_state(&mut self, _rod: &Rod, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        self.turn = input.real()?;
        let mut branch = Vec::new();
        input.reals_into(&mut branch)?;
        self.branch = branch
            .try_into()
            .map_err(|_| CoreError::StateMismatch("a twist branch of another length"))?;
        self.released = input.int()? == 1;
        Ok(())
    }

    fn supports(&self, rod: &Rod) -> Result<(), CoreError> {
        match (rod.is_closed(), self.closed) {
            (true, false) => Err(CoreError::InvalidParameter {
                name: "twist",
                value: 0.0,
                reason: "twisting between two clamps needs an open rod (closed rods have no ends)",
            }),
            (false, true) => Err(CoreError::InvalidParameter {
                name: "twist",
                value: 0.0,
                reason: "the twist of a loop needs a closed rod",
            }),
            _ => Ok(()),
        }
    }

    fn begin_step(&mut self, rod: &Rod, dt: Real) -> Result<(), CoreError> {
        let _ = dt;
        self.supports(rod)?;
        if !self.released {
            let branch = self.holonomies(&self.prepared(rod));
            self.branch = branch;
        }
        Ok(())
    }
}

impl Summary for Twisting {
    fn summary(&self, rod: &Rod) -> Result<EnergySummary, CoreError> {
        Ok(EnergySummary {
            twist: Some(TwistSummary {
                twist: self.twist(rod),
                turn: self.turn,
                moment: self.moment(rod),
                axes: [self.start.axis.into(), self.end.axis.into()],
                start_director: self.start.director.into(),
            }),
            ..EnergySummary::default()
        })
    }
}
