//! # splinerod-energies
//!
//! Potential energies of a rod, as functions of its control points, through one small
//! trait, [`Energy`], and small [`capabilities`] beside it. Provided: continuous
//! Green–Lagrange [`Stretching`] (paper eq. 11–12),
//! [`Bending`] with the exact nonlinear curvature, a penalty [`Clamp`] on the tangent
//! direction at a material point, uniform [`Gravity`], the [`PointSpring`] of a grab and the [`Contact`] penalty (self-contact,
//! cut pieces, floor). [`OnSegment`] puts any energy on one rod of a joined rod
//! (several rods in one system).
//! The [`conformance`] module checks any energy (gradient and
//! Hessian against finite differences, symmetry, definiteness, invariances).
//!
//! Energies are integrals over the rest arclength `s`, evaluated with the rod's cached
//! quadrature table; their cost is O(n) in control points and they do not depend on the
//! knots, so knot insertion leaves them unchanged (exactly for polynomial integrands, up
//! to the quadrature error for bending's rational κ²).
//!
//! ```
//! use splinerod_core::{BSplineSpace, Material, Rod};
//! use splinerod_energies::{Energy, Gravity, Stretching};
//! use nalgebra::Vector3;
//!
//! let material = Material { rest_length: 1.0, linear_density: 0.1 };
//! let basis = BSplineSpace::clamped_uniform(3, 10, 1.0)?;
//! // Stretched to 1.2 times its rest length along x.
//! let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), Vector3::new(1.2, 0.0, 0.0))?;
//! let stretching = Stretching::new(100.0)?;
//! // W = (EA/8)(γ² − 1)² L with γ = 1.2.
//! assert!((stretching.energy(&rod) - 100.0 / 8.0 * (1.44f64 - 1.0).powi(2)).abs() < 1e-12);
//! let gravity = Gravity::new(Vector3::new(0.0, -9.81, 0.0))?;
//! assert!(gravity.energy(&rod).abs() < 1e-15); // on the line y = 0
//! # Ok::<(), splinerod_core::CoreError>(())
//! ```
#![warn(missing_docs)]

mod bending;
pub mod capabilities;
mod clamp;
pub mod conformance;
pub mod contact;
pub mod decorate;
mod energy;
mod gravity;
pub mod lanes;
mod on_segment;
pub mod parameters;
mod point_force;
mod point_spring;
pub mod rest_length;
mod stretching;
#[cfg(test)]
mod test_rods;
pub mod twisting;

pub use bending::{Bending, BendingTerm, STRETCH_FLOOR};
pub use capabilities::{
    Capabilities, HessianRemainder, Interaction, LaneForm, Lifecycle, Summary, Tension,
};
pub use clamp::Clamp;
pub use contact::{Contact, ContactLaw, ContactParams, ContactSummary, Obstacle};
pub use decorate::{Decorator, Placement};
pub use energy::{finite_difference_hessian, Energy, EnergySummary, TwistSummary};
pub use gravity::Gravity;
pub use lanes::LaneTerm;
pub use on_segment::OnSegment;
pub use parameters::Parameters;
pub use point_force::PointForce;
pub use point_spring::PointSpring;
pub use stretching::{
    AutoInputs, Multipliers, StretchFormulation, Stretching, AUTO_COMPRESSION, AUTO_LUMPING_ERROR,
    AUTO_RESOLUTION_ERROR, GUARD_DEVIATION,
};
pub use twisting::holonomy::transport as parallel_transport;
pub use twisting::{Frame, Twisting};
