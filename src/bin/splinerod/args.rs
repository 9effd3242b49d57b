//! The command line's arguments (clap's derive): the subcommands and `run`'s options.

use clap::{Args, Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser)]
#[command(
    name = "splinerod",
    version,
    about = "Adaptive mechanical B-spline rods"
)]
pub(crate) struct Cli {
    #[command(subcommand)]
    pub(crate) command: Command,
}

#[derive(Subcommand)]
pub(crate) enum Command {
    /// Runs a scene to its end, prints a summary and optionally writes outputs.
    Run(Box<RunArgs>),
    /// Continues a run from its checkpoint (`run --checkpoint DIR`), with the same
    /// outputs, to the end of its scene (or --max-steps).
    Resume {
        /// The checkpoint directory.
        dir: PathBuf,
        /// Stops after N steps in all (counted from the run's start).
        #[arg(long, value_name = "N")]
        max_steps: Option<usize>,
    },
    /// Combines the JSON results of `run --shard K/N` (all N shards) into the result of
    /// one run of the whole ensemble.
    Merge {
        /// Where to write the merged JSON.
        out: PathBuf,
        /// The shards' JSON files, any order.
        #[arg(required = true)]
        shards: Vec<PathBuf>,
    },
    /// Measures speed against error on the problems with known answers.
    Report {
        /// A few points per sweep (under 30 s).
        #[arg(long)]
        quick: bool,
        /// Directory for report.md and its plots.
        #[arg(long)]
        out: PathBuf,
    },
    /// Exact sensitivities of a static scene's equilibrium, or of an implicit Euler or
    /// BDF2 run (at its end and every recorded time), to scalar parameters: the
    /// derivatives of the output samples' positions (#48).
    Sensitivities {
        /// The scene (`method = "static"`, `"implicit-euler"` or `"bdf2"`).
        scene: PathBuf,
        /// Parameters by scene path, comma-separated: rod.stretch_stiffness,
        /// rod.bending_stiffness, rod.twist_stiffness, rod.linear_density, rod.rest_length
        /// (the domain scales, material coordinates at their fractions), rod.damping
        /// (runs), rods[k].…, world.gravity[c], loads[i].force[c], pins[i].position[c],
        /// contact.friction (runs).
        #[arg(long, value_name = "P1,P2,…")]
        params: String,
        /// Where to write the sensitivities as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
    },
    /// Fits scene parameters to observations of a static scene or a run.
    Fit {
        /// The scene (static, or an implicit Euler or BDF2 run), its values the start.
        scene: PathBuf,
        /// Observation files (CSV t,s,x,y,z; t,x,y,z; t,pin,fx,fy,fz; optional sigma); repeatable.
        #[arg(long, required = true)]
        observations: Vec<PathBuf>,
        /// Parameters by scene path, comma-separated (as for `sensitivities`).
        #[arg(long, value_name = "P1,P2,…")]
        params: String,
        /// Where to write the fit as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
        /// Where to write the scene with the fitted values (comments and layout kept).
        #[arg(long)]
        scene_out: Option<PathBuf>,
    },
    /// Measures step times, O(n) scaling, ensemble throughput and memory on this machine.
    Bench {
        /// Fewer repetitions and a smaller ensemble (under 15 s).
        #[arg(long)]
        quick: bool,
        /// Where to write the figures as JSON.
        #[arg(long)]
        json: Option<PathBuf>,
    },
}

#[derive(Args)]
pub(crate) struct RunArgs {
    /// The scene file (TOML; see scenes/README.md).
    pub(crate) scene: PathBuf,
    /// Where to write the JSON result.
    #[arg(long)]
    pub(crate) json: Option<PathBuf>,
    /// Per-step statistics as CSV.
    #[arg(long)]
    pub(crate) stats: Option<PathBuf>,
    /// Directory for PNG pictures of the rod.
    #[arg(long)]
    pub(crate) frames: Option<PathBuf>,
    /// Record every K-th step (pictures, VTK and USD).
    #[arg(long, default_value_t = 1)]
    pub(crate) every: usize,
    /// Camera of the pictures: xy, xz, yz or oblique.
    #[arg(long, default_value = "xy")]
    pub(crate) camera: String,
    /// Also write SVG pictures.
    #[arg(long)]
    pub(crate) svg: bool,
    /// Draw the control polygon in the pictures.
    #[arg(long)]
    pub(crate) polygon: bool,
    /// Assemble the pictures into an animated GIF (needs --frames).
    #[arg(long)]
    pub(crate) gif: Option<PathBuf>,
    /// Directory for ParaView files (VTK PolyData and a PVD collection).
    #[arg(long)]
    pub(crate) vtk: Option<PathBuf>,
    /// A USD layer (.usda): rods as time-sampled BasisCurves with their exact control
    /// points and knots, obstacles as transformed primitives.
    #[arg(long, value_name = "OUT.usda")]
    pub(crate) usd: Option<PathBuf>,
    /// Runs only shard K of N of the `[ensemble]` (a contiguous block of members);
    /// merge the shards' `--json` files with `splinerod merge`.
    #[arg(long)]
    pub(crate) shard: Option<String>,
    /// Stops after N steps (outputs complete, JSON `"interrupted": true` if the scene
    /// had more).
    #[arg(long, value_name = "N")]
    pub(crate) max_steps: Option<usize>,
    /// Runs a scene past the resource limits of `scenes/README.md` (steps, control
    /// points, samples, memory, work) instead of refusing it.
    #[arg(long)]
    pub(crate) allow_large: bool,
    /// Writes checkpoints into DIR (every --checkpoint-every seconds of wall-clock time,
    /// and where the run stops); `splinerod resume DIR` continues the run.
    #[arg(long, value_name = "DIR")]
    pub(crate) checkpoint: Option<PathBuf>,
    /// Wall-clock seconds between checkpoints.
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 300.0,
        requires = "checkpoint"
    )]
    pub(crate) checkpoint_every: f64,
}

/// A `run` command line on its own (how `resume` reads the checkpointed one).
#[derive(Parser)]
#[command(name = "run")]
pub(crate) struct RunLine {
    #[command(flatten)]
    pub(crate) args: RunArgs,
}
