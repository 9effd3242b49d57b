//! The cost of a checkpoint (`bench` keys `checkpoint_us_16`, `checkpoint_bytes_16`):
//! the default scene (the 16-point hanging cable, one probe) after 100 steps, its
//! checkpoint written (encoded, written, flushed to disk, renamed) into a temporary
//! directory.

use crate::run::checkpoint::CheckpointPlan;
use crate::{Error, Scene};
use splinerod_core::Real;

/// Steps taken before the checkpoint (its probe then holds 101 points).
const STEPS: usize = 100;

/// Median wall time of writing the checkpoint (s) and its size (bytes).
pub fn checkpoint_cost(repeats: usize) -> Result<(Real, u64), Error> {
    let text = include_str!("../../scenes/hanging_cable.toml");
    let scene = Scene::from_toml(text)?;
    let dir = std::env::temp_dir().join(format!("splinerod-bench-ck-{}", std::process::id()));
    let plan = CheckpointPlan {
        dir: dir.clone(),
        every_seconds: 0.0,
        scene: text.to_string(),
        args: Vec::new(),
        shard: None,
    };
    let cost = crate::run::main_loop::checkpoint_cost(&scene, STEPS, &plan, repeats);
    let _ = std::fs::remove_dir_all(&dir);
    cost
}
