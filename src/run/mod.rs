//! Running a scene: [`runner`] sets a run up and hands it to the one run loop
//! (`main_loop`), which steps it, shows it to the [`observe`] observers (the outputs:
//! pictures, VTK, statistics), records each member's tally, writes the checkpoints and
//! reads the [`result::RunResult`] off the end.
//!
//! **A scene followed from [`runner::run`].** `runner::run_controlled` (or `resume`,
//! `run_shard`: a checkpoint read, a shard's members chosen) calls
//! `main_loop::run_scene`, which builds the members (`state::fresh_run`: each member's
//! simulation prepared, its `tally::Tally` started) and loops over the stages: the
//! ensemble steps, each member's tally records the stage (counters, probes, cuts, knot
//! tracking, estimates), the observers see member 0, a due [`checkpoint`] is written; a
//! stop ([`control::RunControl`]) ends the loop, putting back an abandoned stage
//! (`control::Undo`, through `state::restored_run`). At the end the loop closes the
//! tallies, builds the result (`result::finish`: the per-rod parts of [`rods`], the
//! pins' forces and torques of `pins`, the twist; plus the [`ensemble`] summaries) and
//! hands it to the observers' `finish`. [`session::SceneRun`] drives the same stages
//! one call at a time.
//!
//! **Imports run one way** (kept by `tests/run_imports.rs`): `runner` → `main_loop` →
//! `state`, `control`, `checkpoint`, `observe`, `result`, `ensemble`; `state` → `tally`;
//! `session` → `main_loop`; `result` → `rods`, `pins`, `tally`, `totals`, `twist`,
//! `shard`, `ensemble`, `knot_track`; the leaves (`totals`, `twist`, `knot_track`, `bodies`) import
//! no other file of `run/`. Nothing calls back up: the loop calls the outputs, the
//! tallies and the checkpoint, never the other way round.

pub mod bodies;
pub mod checkpoint;
pub mod control;
pub mod ensemble;
pub(crate) mod knot_track;
pub(crate) mod main_loop;
pub mod observe;
pub(crate) mod pins;
pub mod result;
pub mod rods;
pub mod runner;
pub mod session;
pub mod shard;
pub(crate) mod state;
pub(crate) mod summary;
pub(crate) mod tally;
pub(crate) mod totals;
pub(crate) mod twist;
