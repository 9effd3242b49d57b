//! Running a scene to its end: the entry points ([`run`], [`run_observed`],
//! [`run_controlled`], [`resume`], [`run_shard`]) that set a run up (a scene, a
//! checkpoint to continue, a shard's members) and hand it to the one run loop
//! (`main_loop.rs`); and, re-exported here where they have always been, the
//! result's types.

use crate::run::main_loop;
use crate::run::observe::Observer;
use crate::run::shard::Shard;
use crate::scene::Scene;
use crate::Error;

pub use crate::run::control::RunControl;
pub use crate::run::result::{RodModel, RunResult};
pub use crate::run::rods::Samples;
pub use crate::run::tally::Probe;
pub use crate::run::totals::{ContactStats, SolverTotals};
pub use crate::run::twist::TwistOutput;

/// Runs `scene` to its end.
pub fn run(scene: &Scene) -> Result<RunResult, Error> {
    run_observed(scene, &mut [])
}

/// Runs `scene` to its end, showing every step to `observers` (in order).
pub fn run_observed(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
) -> Result<RunResult, Error> {
    run_controlled(scene, observers, &RunControl::default())
}

/// [`run_observed`], stopping early as `control` says.
pub fn run_controlled(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
    control: &RunControl,
) -> Result<RunResult, Error> {
    main_loop::run_scene(scene, observers, None, control)
}

/// Continues the run checkpointed in `dir` (see [`crate::run::checkpoint`]) to its end,
/// showing every step to `observers` (built from the checkpoint's command line, in the
/// same order) and stopping early as `control` says. The result equals, bit for bit but
/// for wall-clock times, that of the run never stopped.
pub fn resume(
    dir: &std::path::Path,
    observers: &mut [&mut dyn Observer],
    control: &RunControl,
) -> Result<RunResult, Error> {
    let checkpoint = crate::run::checkpoint::read(dir)?;
    let scene = Scene::from_toml_cancellable(&checkpoint.scene, &control.cancel)?;
    let (only, shard) = (checkpoint.only, checkpoint.shard);
    let mut result = main_loop::resume_scene(&scene, checkpoint, observers, control)?;
    if let (Some((a, b)), Some((index, count))) = (only, shard) {
        result.shard = Some(Shard { index, count }.info(&scene, &(a..b)));
    }
    Ok(result)
}

/// Runs shard `shard` of the `[ensemble]` of `scene` (see [`crate::run::shard`]): its
/// members only, the result recording which.
pub fn run_shard(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
    shard: Shard,
    control: &RunControl,
) -> Result<RunResult, Error> {
    let members = shard.members(scene)?;
    let mut result = main_loop::run_scene(scene, observers, Some(&members), control)?;
    result.shard = Some(shard.info(scene, &members));
    Ok(result)
}
