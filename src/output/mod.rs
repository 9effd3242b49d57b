//! Outputs of a run, each an [`Observer`](crate::Observer): pictures (PNG/SVG frames
//! and a GIF, with the floor, obstacles and rod names), ParaView files (VTK PolyData and a PVD collection), a USD layer
//! (rods as time-sampled `BasisCurves`, obstacles as transformed primitives), per-step
//! statistics (CSV), a progress bar, and the plotting used by the speed-vs-error report.

pub mod camera;
pub mod picture;
pub mod plot;
pub mod progress;
pub mod ribbon;
mod scenery;
pub mod stats;
pub mod usd;
pub mod vtk;
