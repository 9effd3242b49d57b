//! # splinerod
//!
//! Thin elastic objects — threads, sutures, cables, hair — simulated as B-spline curves
//! whose control points are the degrees of freedom (Lenoir et al. 2005). This facade
//! wires the extension crates together:
//!
//! * [`core`] — basis spaces with exact knot maps, the [`Rod`], pins, quadrature;
//! * [`energies`] — the [`Energy`] trait, Green–Lagrange [`Stretching`], [`Gravity`];
//! * [`integrators`] — the [`Integrator`] trait, [`ImplicitEuler`], [`StaticSolver`],
//!   modal analysis;
//! * [`adaptivity`] — the [`RefinementCriterion`] trait.
//!
//! A [`RodSystem`] holds a rod, its pins and energies; a [`Simulation`] advances it with
//! a boxed integrator; a [`Scene`] builds both from TOML and [`run`] executes it.
//!
//! ```
//! use splinerod::prelude::*;
//!
//! // A 1 m cable, 16 control points, hanging between pins 0.8 m apart.
//! let material = Material { rest_length: 1.0, linear_density: 0.1 };
//! let basis = BSplineSpace::clamped_uniform(3, 16, 1.0)?;
//! let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), Vector3::new(0.8, 0.0, 0.0))?;
//! let ends = [Pin::here(&rod, 0.0)?, Pin::here(&rod, 1.0)?];
//! let mut system = RodSystem::new(rod)
//!     .with_energy(Stretching::new(100.0)?)
//!     .with_energy(Gravity::new(Vector3::new(0.0, -9.81, 0.0))?)
//!     .with_pin(ends[0])
//!     .with_pin(ends[1]);
//! StaticSolver::new(StaticParams::default())?.solve(&mut system)?;
//! let sag = -system.rod.point(0.5)?.y;
//! assert!((sag - 0.268663).abs() < 1e-4); // the elastic catenary's midpoint sag
//! # Ok::<(), splinerod::Error>(())
//! ```
#![warn(missing_docs)]

pub mod adaptive_study;
#[cfg(feature = "parallel")]
pub mod bench;
#[cfg(feature = "parallel")]
pub mod bench_adapt;
pub mod bench_twist;
#[cfg(feature = "parallel")]
pub mod bench_world;
mod build;
pub mod elastic_catenary;
mod ensemble;
mod error;
pub mod estimate;
mod grab;
pub mod hard_cases;
pub mod knot;
mod knot_track;
pub mod locking;
pub mod observe;
pub mod output;
pub mod path;
pub mod problems;
pub mod report;
pub mod report_adaptive;
mod report_md;
pub mod rods_output;
mod run_loop;
mod run_summary;
pub mod runner;
pub mod scene;
mod scene_adapt;
mod scene_contact;
mod scene_ensemble;
mod scene_loads;
mod scene_obstacles;
mod scene_pins;
mod scene_rods;
mod scene_shape;
mod scene_solver;
mod simulation;
pub mod step_report;
pub mod substep;
mod system;
mod twist_output;
pub mod writhe;

pub use ensemble::Ensemble;
pub use error::Error;
pub use grab::Grab;
pub use knot_track::KnotTrack;
pub use observe::{Frame, Observer};
pub use runner::{run, run_observed, RunResult};
pub use scene::Scene;
pub use simulation::Simulation;
pub use step_report::{StageTimes, StepReport};
pub use system::{Load, PinDriver, RodSystem};

pub use splinerod_adaptivity as adaptivity;
pub use splinerod_core as core;
pub use splinerod_energies as energies;
pub use splinerod_integrators as integrators;

pub use splinerod_adaptivity::RefinementCriterion;
pub use splinerod_core::{BSplineSpace, BasisSpace, Material, Pin, Real, Rod};
pub use splinerod_energies::{
    Bending, Clamp, Energy, Gravity, PointSpring, StretchFormulation, Stretching,
};
pub use splinerod_integrators::{
    Bdf2, ImplicitEuler, ImplicitMidpoint, Integrator, NewtonParams, StaticParams, StaticSolver,
    System,
};

/// Everything needed to build and run a rod, in one import.
pub mod prelude {
    pub use crate::{
        BSplineSpace, BasisSpace, Bdf2, Bending, Clamp, Energy, Error, Grab, Gravity,
        ImplicitEuler, ImplicitMidpoint, Integrator, Material, NewtonParams, Pin, Real, Rod,
        RodSystem, Scene, Simulation, StaticParams, StaticSolver, StretchFormulation, Stretching,
        System,
    };
    pub use nalgebra::Vector3;
}

#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
