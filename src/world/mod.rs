//! The mechanical world a scene builds and a run advances: the [`RodSystem`] (rods —
//! several joined into one — with pins, energies, grabs, drivers and loads), the
//! [`Simulation`] that steps it (sub-stepping, step reports, the error estimate) and
//! the [`Ensemble`] of many simulations. It knows nothing of scene files or outputs.
//!
//! [`RodSystem`]: crate::RodSystem
//! [`Simulation`]: crate::Simulation
//! [`Ensemble`]: crate::Ensemble

pub mod bodies;
pub mod body_contact;
pub mod body_friction;
pub(crate) mod ensemble;
pub mod estimate;
pub(crate) mod grab;
pub mod gripper;
pub(crate) mod kept;
pub(crate) mod lanes;
pub mod path;
pub mod saved;
pub(crate) mod simulation;
pub mod sliver;
pub use simulation::MAX_SETTLE_ROUNDS;
pub mod step_report;
pub mod substep;
pub(crate) mod system;
pub mod unbatched;
