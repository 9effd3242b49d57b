//! How a run stops early: [`RunControl`] (a step limit, a [`Cancel`] that signals raise,
//! a checkpoint plan) and what the run loop keeps so that a stop inside a step leaves
//! a clean state.
//!
//! **Stopping between steps.** The loop checks [`RunControl::stops_before`] before each
//! stage; a stop there loses nothing (the checkpoint written there resumes bit for bit).
//!
//! **Stopping inside a step.** The solvers poll the members' [`Cancel`]
//! ([`Cancel::abandon`]: once the handle's grace has passed after the request, so that a
//! short step still finishes and the run stops between steps). An abandoned stage
//! returns an interrupted error ([`crate::Error::is_interrupted`]) and each member that
//! was abandoned is rolled back by its [`crate::Simulation`]: positions, velocities and
//! time, not what its energies and integrator keep between sub-steps (friction anchors,
//! contact lists, BDF2's history), nor members of an ensemble that had finished the
//! stage. So `Undo` keeps the members' saved states from before each stage that is
//! slow enough for the copy to cost little (at most 1/[`UNDO_RATIO`] of the stage
//! before, measured; always before the first) and rebuilds the run from them, exactly
//! as a resume does. A stage abandoned without such a copy (a fast stage followed by
//! one that ran past the grace) ends an ensemble's run with
//! [`crate::Error::Interrupted`]; one simulation keeps its rolled-back state for the
//! outputs but writes no checkpoint at the stop
//! ([`crate::RunResult::checkpoint_at_stop`]).

use crate::run::state::{restored_run, Run};
use crate::scene::Scene;
use crate::world::saved::SimulationState;
use crate::Error;
use splinerod_core::{Cancel, Real};
use std::time::{Duration, Instant};

/// How long the solvers let a step under way go on after the command line's first
/// SIGINT or SIGTERM before they abandon it ([`Cancel::with_grace`]): a step that ends
/// sooner stops the run between steps, losing nothing.
pub const STOP_GRACE: Duration = Duration::from_millis(250);

/// `Undo` copies the members' states before a stage only when the stage before took
/// at least this many times as long as the last copy.
pub const UNDO_RATIO: Real = 50.0;

/// How a run may end before its duration: after a number of steps, or when a stop is
/// asked ([`Cancel`], raised by a signal handler or another thread). A stop seen between
/// steps ends the run there; inside a step, the step is abandoned and rolled back (see
/// the module docs). Either way the result, observers and outputs are complete up to
/// the last completed step, with [`crate::RunResult::interrupted`] set. The default
/// runs to the end.
#[derive(Debug, Clone, Default)]
pub struct RunControl {
    /// Take at most this many steps (counted from the run's start, also when resumed).
    pub max_steps: Option<usize>,
    /// Stop once this asks to (checked before each step; polled inside steps by the
    /// solvers, and during setup).
    pub cancel: Cancel,
    /// Write checkpoints (see [`crate::run::checkpoint`]), and one where the run stops.
    pub checkpoint: Option<crate::run::checkpoint::CheckpointPlan>,
}

impl RunControl {
    /// Whether the run must stop before taking step `step` (0-based).
    pub fn stops_before(&self, step: usize) -> bool {
        self.cancel.check() || self.max_steps.is_some_and(|m| step >= m)
    }
}

/// What the run loop keeps to undo a stage abandoned part-way (module docs).
#[derive(Debug, Default)]
pub(crate) struct Undo {
    /// Whether copies are needed at all: the run can be cancelled.
    wanted: bool,
    /// The members' states before the stage under way, and that stage's number.
    states: Option<(usize, Vec<SimulationState>)>,
    /// Wall time of the last copy, s.
    cost: Option<Real>,
}

impl Undo {
    /// The undo of a run under `cancel` (none is kept without one).
    pub(crate) fn new(cancel: &Cancel) -> Self {
        Self {
            wanted: cancel.is_active(),
            ..Self::default()
        }
    }

    /// Copies from now on if `cancel` can ask to stop (the cost measured so far kept).
    pub(crate) fn follow(&mut self, cancel: &Cancel) {
        self.wanted = cancel.is_active();
    }

    /// Before stage `run.stage`: copies the members' states if wanted and cheap
    /// against the last stage (or none was copied yet).
    pub(crate) fn before(&mut self, run: &Run) {
        self.states = None;
        if !self.wanted {
            return;
        }
        let last = run.step_seconds.last().copied();
        let due = match (self.cost, last) {
            (Some(cost), Some(stage)) => stage >= UNDO_RATIO * cost,
            _ => true,
        };
        if !due {
            return;
        }
        let start = Instant::now();
        let states = run
            .ensemble
            .members
            .iter()
            .map(|s| s.save_state())
            .collect();
        self.states = Some((run.stage, states));
        self.cost = Some(start.elapsed().as_secs_f64());
    }

    /// After stage `run.stage` of `scene` was abandoned (each member it abandoned
    /// rolled back in place): puts `run` back as it stood before that stage, its
    /// members polling `cancel`. Whether that is exact (rebuilt from the copies); an
    /// ensemble that cannot be put back is an error.
    pub(crate) fn restore(
        &mut self,
        scene: &Scene,
        run: &mut Run,
        cancel: &Cancel,
    ) -> Result<bool, Error> {
        match self.states.take() {
            Some((stage, states)) if stage == run.stage => {
                let tallies = run.members.iter().map(|m| m.tally.clone());
                let states: Vec<_> = states.into_iter().zip(tallies).collect();
                let mut rebuilt = restored_run(scene, run.only.clone(), states.into_iter(), stage)?;
                rebuilt.step_seconds = std::mem::take(&mut run.step_seconds);
                rebuilt.wall_before = run.wall_before;
                rebuilt.set_cancel(cancel);
                *run = rebuilt;
                Ok(true)
            }
            _ if run.members.len() > 1 => Err(Error::Interrupted(
                "inside a step of the ensemble, before its members' states were copied: they stand at different steps, so no result is written",
            )),
            _ => Ok(false),
        }
    }
}
