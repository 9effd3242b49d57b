//! Parameter identification from observations of a real rod (issue #48): observation
//! files ([`observations`]: markers, unlabelled points, pin forces), the least-squares
//! fit driven by the exact sensitivities ([`least_squares`]) of a static scene
//! ([`scene_fit`]) or of a run ([`run_fit`]), the gradient-free baseline it is measured
//! against ([`gradient_free`]), synthetic data for studies ([`synthetic`]), and the
//! command's report and fitted scene file ([`command`], [`scene_out`]).

pub mod closest;
pub mod command;
pub mod gradient_free;
pub mod least_squares;
pub mod observations;
pub mod run_fit;
pub mod scene_fit;
pub mod scene_out;
pub mod synthetic;

pub use gradient_free::{nelder_mead, GradientFreeFit};
pub use least_squares::{fit, FitReport, Model, ParameterSpace};
pub use observations::{Observation, ObservationFile, ObservationKind};
pub use run_fit::RunFit;
pub use scene_fit::SceneFit;
