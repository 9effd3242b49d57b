//! A scene's run driven from outside, one stage at a time: [`SceneRun`].
//!
//! `splinerod run` hands a scene to the run loop and gets its result at the end. A
//! program that wants to look at the state between steps, change it (move a pin, set
//! velocities) or stop when it likes — the Python package, a notebook, an optimiser —
//! drives the same loop stage by stage instead. The stages, the records made after each
//! (probes, counters, knot tracking, cuts, error estimates) and the result are the run
//! loop's own, so a scene driven to its end this way reports what `splinerod run`
//! reports, bit for bit but the wall-clock fields.

use crate::run::control::Undo;
use crate::run::main_loop;
use crate::run::result::RunResult;
use crate::run::state::{self, Run};
use crate::scene::{Method, Scene};
use crate::{Error, Simulation};
use nalgebra::Vector3;
use splinerod_core::{Cancel, Real};
use std::time::Instant;

/// A scene's run under way, advanced by the caller (see the module docs).
pub struct SceneRun {
    scene: Scene,
    run: Run,
    /// The stop the stages poll ([`SceneRun::set_cancel`]).
    cancel: Cancel,
    /// Copies to undo an abandoned stage ([`crate::run::control`]).
    undo: Undo,
}

impl std::fmt::Debug for SceneRun {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneRun")
            .field("members", &self.run.members.len())
            .field("stages_done", &self.run.stage)
            .finish_non_exhaustive()
    }
}

impl SceneRun {
    /// The run of `scene` at its start: every member built, the cuts due at time zero
    /// made (a static scene: at the grabs' and paths' final time, with every cut).
    pub fn new(scene: &Scene) -> Result<Self, Error> {
        state::check_memory(scene, None)?;
        Ok(Self {
            scene: scene.clone(),
            run: state::fresh_run(scene, None, &Cancel::none())?,
            cancel: Cancel::none(),
            undo: Undo::default(),
        })
    }

    /// Makes the stages poll `cancel` from now on: [`SceneRun::advance`] stops between
    /// stages when it asks to, and the solvers abandon a stage under way
    /// ([`Cancel::abandon`]), which is then undone (see [`crate::run::control`]).
    pub fn set_cancel(&mut self, cancel: Cancel) {
        self.run.set_cancel(&cancel);
        self.undo.follow(&cancel);
        self.cancel = cancel;
    }

    /// The scene being run.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Whether the scene is a static solve (one stage: the equilibrium).
    pub fn is_static(&self) -> bool {
        self.scene.solver.method == Method::Static
    }

    /// The time step of a dynamic scene, s (0 for a static one).
    pub fn dt(&self) -> Real {
        match self.is_static() {
            true => 0.0,
            false => self.scene.solver.dt.unwrap_or_default(),
        }
    }

    /// The stages `splinerod run` makes: the scene's step count, or 1 for a static solve.
    pub fn stage_count(&self) -> usize {
        match self.is_static() {
            true => 1,
            false => self.scene.step_count(),
        }
    }

    /// Stages made so far.
    pub fn stages_done(&self) -> usize {
        self.run.stage
    }

    /// Makes `stages` more stages (time steps of [`SceneRun::dt`], or static solves),
    /// also past the scene's duration. A failing step leaves its member as it was before
    /// that step and returns the error; the stages made before it stay made. A stop
    /// asked through [`SceneRun::set_cancel`] ends it with an interrupted error
    /// ([`Error::is_interrupted`]), every member as it was after the last stage made.
    pub fn advance(&mut self, stages: usize) -> Result<(), Error> {
        let (statics, dt) = (self.is_static(), self.dt());
        for _ in 0..stages {
            if self.cancel.check() {
                return Err(Error::Interrupted("between steps"));
            }
            let start = Instant::now();
            self.undo.before(&self.run);
            let made = main_loop::stage(&self.scene, &mut self.run, &mut [], statics, dt);
            self.run.wall_before += start.elapsed().as_secs_f64();
            if let Err(e) = made {
                if e.is_interrupted() {
                    self.undo
                        .restore(&self.scene, &mut self.run, &self.cancel)?;
                }
                return Err(e);
            }
        }
        Ok(())
    }

    /// The simulations: one, or the `[ensemble]`'s members in order.
    pub fn members(&self) -> &[Simulation] {
        &self.run.ensemble.members
    }

    /// Member `index`'s simulation, to change its state between stages (velocities,
    /// pin positions); `None` past the last member.
    pub fn member_mut(&mut self, index: usize) -> Option<&mut Simulation> {
        self.run.ensemble.members.get_mut(index)
    }

    /// The force member `index`'s rod puts on each `[[pins]]` entry's support after the
    /// last stage, N (as the JSON's `pin_forces`); `None` past the last member.
    pub fn pin_forces(&self, index: usize) -> Option<Vec<Vector3<Real>>> {
        let sim = self.members().get(index)?;
        let forces = crate::run::pins::scene_pin_forces(&self.scene, sim);
        Some(forces.into_iter().map(Vector3::from).collect())
    }

    /// The torque member `index`'s rod puts on each `[[pins]]` entry's support about its
    /// point after the last stage, N·m (as the JSON's `pin_torques`, but one per entry
    /// even when all are zero); `None` past the last member.
    pub fn pin_torques(&self, index: usize) -> Option<Result<Vec<Vector3<Real>>, Error>> {
        let sim = self.members().get(index)?;
        let torques = crate::run::pins::pin_torques(&self.scene, sim).map(|mut t| {
            t.resize(self.scene.pins.len(), [0.0; 3]);
            t.into_iter().map(Vector3::from).collect()
        });
        Some(torques)
    }

    /// What `splinerod run` would report had the run ended after the stages made so far
    /// (marked interrupted before the scene's duration). The final records (error
    /// estimate, knot) are made on a copy of the members restored from their saved
    /// states, so the run goes on unchanged; the rest is read from the members.
    pub fn result(&self) -> Result<RunResult, Error> {
        let states = self.run.members.iter().zip(&self.run.ensemble.members);
        let states = states.map(|(m, sim)| (sim.save_state(), m.tally.clone()));
        let states: Vec<_> = states.collect();
        let only = self.run.only.clone();
        let first_index = only.as_ref().map_or(0, |r| r.start);
        let copy = state::restored_run(&self.scene, only, states.into_iter(), 0)?;
        let (mut members, mut sims) = (copy.members, copy.ensemble.members);
        main_loop::close(&mut members, &mut sims)?;
        let mut step_seconds = self.run.step_seconds.clone();
        let live = &self.run.ensemble.members;
        let wall = self.run.wall_before;
        let result = main_loop::report(
            &self.scene,
            members,
            live,
            first_index,
            wall,
            &mut step_seconds,
        )?;
        Ok(RunResult {
            interrupted: self.run.stage < self.stage_count(),
            ..result
        })
    }
}
