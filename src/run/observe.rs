//! Observers of a run: whatever wants to see the state as it evolves (pictures, ParaView
//! files, per-step statistics, a progress bar) implements [`Observer`] and is handed to
//! [`crate::run::runner::run_observed`]. The run loop calls [`Observer::start`] once before the
//! first step, [`Observer::step`] after every step (after adaptivity and cuts), and
//! [`Observer::finish`] with the final result. A static solve is one stage: `start`
//! sees the initial state, `step` (with step count 0) and `finish` the equilibrium.

use crate::run::result::RunResult;
use crate::{Error, RodSystem, Scene, StepReport};
use splinerod_core::Real;

/// The state an observer sees.
#[derive(Debug, Clone, Copy)]
pub struct Frame<'a> {
    /// The scene being run.
    pub scene: &'a Scene,
    /// The mechanical state.
    pub system: &'a RodSystem,
    /// Simulated time, s.
    pub time: Real,
    /// Steps taken so far.
    pub step: usize,
    /// Steps the run will take in all (0 for a static solve).
    pub total_steps: usize,
}

/// Sees a run unfold. Every method defaults to doing nothing.
pub trait Observer {
    /// Before the first step.
    fn start(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        let _ = frame;
        Ok(())
    }

    /// After each step, with what the step did and its wall time (s, integration and
    /// adaptivity).
    fn step(&mut self, frame: &Frame<'_>, report: &StepReport, wall: Real) -> Result<(), Error> {
        let _ = (frame, report, wall);
        Ok(())
    }

    /// Between two steps, for a checkpoint: what this observer needs to continue after a
    /// resume (JSON text), or `None` for nothing. Default `None`.
    fn checkpoint(&mut self) -> Result<Option<String>, Error> {
        Ok(None)
    }

    /// Instead of [`start`](Observer::start), when a run continues from a checkpoint:
    /// `state` is what [`checkpoint`](Observer::checkpoint) returned then, `frame` the
    /// restored state. Default: nothing.
    fn resume(&mut self, frame: &Frame<'_>, state: Option<&str>) -> Result<(), Error> {
        let _ = (frame, state);
        Ok(())
    }

    /// At the end, with the run's result.
    fn finish(&mut self, frame: &Frame<'_>, result: &RunResult) -> Result<(), Error> {
        let _ = (frame, result);
        Ok(())
    }
}
