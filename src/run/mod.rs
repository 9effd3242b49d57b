//! Running a scene: [`runner`] builds the world from a [`crate::Scene`], steps it in the
//! one run loop (`main_loop`: drivers, grabs, cuts, adaptivity, observers), tracks the
//! knot of knot scenes and gathers the [`runner::RunResult`]; [`observe`] is the
//! interface outputs (pictures, VTK, statistics) plug into.

pub mod checkpoint;
pub mod control;
pub mod ensemble;
pub(crate) mod knot_track;
pub(crate) mod main_loop;
pub mod observe;
pub mod rods;
pub mod runner;
pub mod session;
pub mod shard;
pub(crate) mod summary;
pub(crate) mod tally;
pub(crate) mod totals;
pub(crate) mod twist;
