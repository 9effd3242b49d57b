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
//! a boxed integrator; a [`Scene`] builds both from TOML and [`run`](fn@run) executes it.
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

//! ## Layout
//!
//! * [`scene`] — the TOML format, one file per table (parse + validate), and building
//!   the world from it;
//! * [`world`] — the system of rods, pins, energies, grabs and loads, the simulation
//!   that steps it, ensembles;
//! * [`run`](mod@run) — the run loop, the observer interface and the result of a run (with its
//!   twist, per-rod and ensemble parts);
//! * [`output`] — observers writing pictures, plots, VTK, statistics and progress;
//! * [`report`], [`problems`], [`bench`](mod@bench) — the accuracy report, its known-answer
//!   problems, and the speed figures;
//! * [`knot`] — knot shapes and curve invariants (crossings, writhe);
//! * [`bundled`] — the scenes of `scenes/`, compiled in.
//!
//! Imports run one way: `world` uses none of the others; `scene` → `world`, `knot`;
//! `run` → `scene`, `world`, `knot`; `output` → `run` (and the scene and world a frame
//! carries: obstacles, their paths); `bundled` → `scene`; `problems` → `run`; `report`
//! and `bench` → all of these. `knot` uses none.

#[cfg(feature = "parallel")]
pub mod bench;
pub mod bundled;
mod error;
pub mod fit;
pub mod knot;
pub mod output;
pub mod problems;
pub mod report;
pub mod run;
pub mod scene;
pub mod sensitivity;
pub mod sensitivity_at;
pub mod world;

// The paths of the flat layout before the modules above, kept so code written against
// them still compiles.
#[cfg(feature = "parallel")]
pub use bench::{adapt as bench_adapt, twist as bench_twist, world as bench_world};
pub use knot::writhe;
pub use problems::{elastic_catenary, hard_cases, locking};
pub use report::{adaptive as report_adaptive, adaptive_study};
pub use run::rods as rods_output;
pub use run::{observe, runner};
pub use world::{estimate, path, sliver, step_report, substep};

pub use error::Error;
pub use run::knot_track::KnotTrack;
pub use run::observe::{Frame, Observer};
pub use run::result::RunResult;
pub use run::runner::{run, run_observed};
pub use run::session::SceneRun;
pub use scene::Scene;
pub use world::ensemble::Ensemble;
pub use world::grab::Grab;
pub use world::simulation::Simulation;
pub use world::step_report::{StageTimes, StepReport};
pub use world::system::{Load, PinDriver, RodSystem};
pub use world::unbatched::{Unbatched, UnbatchedCounts};

pub use splinerod_adaptivity as adaptivity;
pub use splinerod_core as core;
pub use splinerod_core::kernels;
pub use splinerod_energies as energies;
pub use splinerod_integrators as integrators;

pub use splinerod_adaptivity::RefinementCriterion;
pub use splinerod_core::{
    BSplineSpace, BasisSpace, Material, PeriodicBSplineSpace, Pin, Real, Rod,
};
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
        ImplicitEuler, ImplicitMidpoint, Integrator, Material, NewtonParams, PeriodicBSplineSpace,
        Pin, Real, Rod, RodSystem, Scene, Simulation, StaticParams, StaticSolver,
        StretchFormulation, Stretching, System,
    };
    pub use nalgebra::Vector3;
}

#[cfg(doctest)]
#[doc = include_str!("../README.md")]
struct ReadmeDoctests;
