//! # splinerod-core
//!
//! The foundation of splinerod: B-spline basis spaces with exact knot maps, the [`Rod`]
//! (control points, velocities, mass), [`Pin`] constraints, Gauss–Legendre quadrature and
//! banded storage for the Newton matrices. Energies, integrators and adaptivity build on
//! this crate and never on each other.
//!
//! A rod's centreline is a B-spline in its rest arclength `s ∈ [0, L]`
//! (Lenoir et al. 2005, eq. 1):
//!
//! \\[ C(s, t) = \sum_{i=0}^{n-1} q_i(t)\, b_{i,d}(s). \\]
//!
//! Knot insertion (eq. 3–6) rewrites old basis functions exactly in the new ones,
//! \\(F^0 = \beta^T F^1\\), so control points map as \\(q^1 = \beta q^0\\) and the curve does
//! not move. Mass (eq. 10) and all energies are integrals over `s`, so they do not change
//! either: this is the invariant that makes adaptivity exact.
//!
//! ```
//! use splinerod_core::{BSplineSpace, Material, Rod};
//! use nalgebra::Vector3;
//!
//! let material = Material { rest_length: 2.0, linear_density: 0.1 };
//! let basis = BSplineSpace::clamped_uniform(3, 8, 2.0)?;
//! let mut rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), Vector3::new(1.5, 0.0, 0.0))?;
//! rod.positions[3].y += 0.2; // bend it
//! let before = rod.point(0.7)?;
//! rod.insert_knot(0.9)?;
//! assert_eq!(rod.len(), 9);
//! assert!((rod.point(0.7)? - before).norm() < 1e-14);
//! assert!((rod.total_mass() - 0.2).abs() < 1e-14);
//! # Ok::<(), splinerod_core::CoreError>(())
//! ```
#![warn(missing_docs)]

pub mod banded;
pub mod basis;
pub mod block_banded;
pub mod body;
pub mod bspline;
pub mod cancel;
pub mod check;
mod cutting;
mod error;
pub mod kernels;
pub mod keyframes;
pub mod knot_map;
pub mod lanes;
pub mod local_update;
pub mod periodic;
pub mod pins;
pub mod proximity;
pub mod quadrature;
pub mod refine;
mod ring;
pub mod rod;
pub mod segments;
#[cfg(target_arch = "x86_64")]
pub mod simd;
pub mod state;

/// The scalar type of every physical quantity.
pub type Real = f64;

pub use banded::SymBanded;
pub use basis::{BasisSpace, BasisValues, Span, MAX_BASIS_FUNCTIONS, MAX_DEGREE};
pub use block_banded::{add_operator_columns, BlockBanded, FarBlock, LowRank};
pub use body::{Attachment, RigidBody};
pub use bspline::BSplineSpace;
pub use cancel::Cancel;
pub use check::Requirement;
pub use error::CoreError;
pub use keyframes::{Interpolation, Keyframes};
pub use knot_map::{Coefficient, KnotMap, KnotOperation};
pub use lanes::{Derivatives, LaneBand, LaneBlock, Lanes, LANES};
pub use periodic::PeriodicBSplineSpace;
pub use pins::Pin;
pub use proximity::{closest_points, Closest, SpanBoxes};
pub use quadrature::{GaussLegendre, QuadPoint, QuadratureTable};
pub use refine::RefinementOperator;
pub use rod::{Material, Rod};
pub use segments::Segment;
pub use state::{SavedState, StateReader};

/// Which second derivative an energy adds to a Newton matrix.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum HessianKind {
    /// The exact Hessian, possibly indefinite (modal and buckling analyses).
    Exact,
    /// A positive semi-definite approximation for Newton steps: indefinite parts are
    /// dropped or clamped (each energy documents how). Equal to the exact Hessian where
    /// the energy is locally convex.
    #[default]
    Definite,
}

#[cfg(test)]
mod tests;
