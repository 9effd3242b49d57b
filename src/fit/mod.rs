//! Parameter identification from observations of a real rod (issue #48): the
//! observation files ([`observations`]). The least-squares fit driven by the
//! sensitivities builds on them.

pub mod observations;

pub use observations::{Observation, ObservationFile, ObservationKind};
