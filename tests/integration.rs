//! The integration tests, one module per file of `tests/`, built as one binary: one link
//! instead of fifty, and one test harness that keeps both cores busy to the end (separate
//! binaries run one after another, each ending on its slowest test). Run one file's tests
//! with its module path, `cargo test --release --test integration snapshots::`.
//!
//! Two files stay binaries of their own: `allocations` (its global allocator counts
//! every allocation of the process) and `interrupts` (it times how fast a signalled run
//! stops, which other tests running beside it would slow).

mod common;

mod adaptivity;
mod bad_input;
mod bad_input_cli;
mod bad_input_contact;
mod bad_input_extensions;
mod bad_input_overhand;
mod batched;
mod bench;
mod bending;
mod bodies;
mod body_contact;
mod bundled;
mod capstan_turn;
mod catenary;
mod checkpoints;
mod clamps;
mod closed_rings;
mod closed_scenes;
mod conservation;
mod consistent_gram;
mod contact_scenes;
mod contact_tolerance;
mod cutting;
mod driven;
mod ensemble;
mod fit_least_squares;
mod fit_run;
mod fit_scene;
mod friction;
mod fuzz_scenes;
mod grippers;
mod hard_cases;
mod integrator_energy;
mod kept_lanes;
mod kernels;
mod knot_changes;
mod knot_geometry;
mod knot_pulled;
mod lifecycle;
mod loads;
mod locking;
mod long_runs;
mod michell;
mod moving_obstacles;
mod observations;
mod obstacles;
mod outputs;
mod pictures;
mod pileup;
mod refinement;
mod refused_up_front;
mod resume;
mod robustness;
mod run_imports;
mod scene_errors;
mod scenes;
mod sensitivities;
mod sensitivities_dynamic;
mod session;
mod several_rods;
mod shards;
mod snapshots;
mod string_modes;
mod tolerance;
mod twist;
mod usd;
mod vtk;
