//! Parameter identification from observations of a real rod (issue #48): the
//! observation files ([`observations`]). The least-squares fit driven by the
//! sensitivities builds on them.

pub mod closest;
pub mod command;
pub mod gradient_free;
pub mod least_squares;
pub mod observations;
pub mod scene_fit;
pub mod scene_out;
pub mod synthetic;

pub use gradient_free::{nelder_mead, GradientFreeFit};
pub use least_squares::{fit, FitReport, Model, ParameterSpace};
pub use observations::{Observation, ObservationFile, ObservationKind};
pub use scene_fit::SceneFit;
