//! The `splinerod` command line:
//!
//! * `splinerod run SCENE.toml [--json OUT] [--stats OUT.csv] [--frames DIR [--every K]
//!   [--camera xy|xz|yz|oblique] [--svg] [--polygon] [--gif OUT.gif]] [--vtk DIR]`
//!   [--shard K/N] [--max-steps N] [--allow-large]
//! * `splinerod merge OUT.json SHARD.json…` (the shards of a `--shard` ensemble run)
//! * `splinerod report [--quick] --out DIR`
//! * `splinerod bench [--quick] [--json OUT]`
//!
//! Errors print one line naming the field or file and exit with code 2; so does a
//! `SPLINEROD_KERNELS` value that is not understood, before any command runs (see
//! `splinerod_core::kernels`: `auto`, `portable` or `avx2-fma`). SIGINT or SIGTERM
//! stops a run (also inside a long step or solve, and during the scene's setup) with
//! exit code 130. A closed standard output (`| head`) is not an error: what is left to
//! print is dropped, the files are still written.

use clap::{Args, Parser, Subcommand};
use splinerod::core::Cancel;
use splinerod::output::{picture, progress::Progress, stats::StatsWriter, vtk::VtkWriter};
use splinerod::run::checkpoint::CheckpointPlan;
use splinerod::run::control::{RunControl, STOP_GRACE};
use splinerod::run::shard::Shard;
use splinerod::{Error, Observer};
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

#[derive(Parser)]
#[command(
    name = "splinerod",
    version,
    about = "Adaptive mechanical B-spline rods"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
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
        /// rod.bending_stiffness, rod.twist_stiffness, rod.linear_density, rod.damping
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
struct RunArgs {
    /// The scene file (TOML; see scenes/README.md).
    scene: PathBuf,
    /// Where to write the JSON result.
    #[arg(long)]
    json: Option<PathBuf>,
    /// Per-step statistics as CSV.
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Directory for PNG pictures of the rod.
    #[arg(long)]
    frames: Option<PathBuf>,
    /// Record every K-th step (pictures and VTK).
    #[arg(long, default_value_t = 1)]
    every: usize,
    /// Camera of the pictures: xy, xz, yz or oblique.
    #[arg(long, default_value = "xy")]
    camera: String,
    /// Also write SVG pictures.
    #[arg(long)]
    svg: bool,
    /// Draw the control polygon in the pictures.
    #[arg(long)]
    polygon: bool,
    /// Assemble the pictures into an animated GIF (needs --frames).
    #[arg(long)]
    gif: Option<PathBuf>,
    /// Directory for ParaView files (VTK PolyData and a PVD collection).
    #[arg(long)]
    vtk: Option<PathBuf>,
    /// Runs only shard K of N of the `[ensemble]` (a contiguous block of members);
    /// merge the shards' `--json` files with `splinerod merge`.
    #[arg(long)]
    shard: Option<String>,
    /// Stops after N steps (outputs complete, JSON `"interrupted": true` if the scene
    /// had more).
    #[arg(long, value_name = "N")]
    max_steps: Option<usize>,
    /// Runs a scene past the resource limits of `scenes/README.md` (steps, control
    /// points, samples, memory, work) instead of refusing it.
    #[arg(long)]
    allow_large: bool,
    /// Writes checkpoints into DIR (every --checkpoint-every seconds of wall-clock time,
    /// and where the run stops); `splinerod resume DIR` continues the run.
    #[arg(long, value_name = "DIR")]
    checkpoint: Option<PathBuf>,
    /// Wall-clock seconds between checkpoints.
    #[arg(
        long,
        value_name = "SECONDS",
        default_value_t = 300.0,
        requires = "checkpoint"
    )]
    checkpoint_every: f64,
}

/// A `run` command line on its own (how `resume` reads the checkpointed one).
#[derive(Parser)]
#[command(name = "run")]
struct RunLine {
    #[command(flatten)]
    args: RunArgs,
}

/// Exit code of a run stopped by SIGINT or SIGTERM (128 + SIGINT, as shells report).
const INTERRUPTED: u8 = 130;

fn main() -> ExitCode {
    let cli = Cli::parse();
    if let Some(message) = splinerod::kernels::setting_error() {
        eprintln!("error: {message}");
        return ExitCode::from(2);
    }
    match execute(cli) {
        Ok(code) => code,
        Err(e) => {
            complain(format_args!("error: {e}\n"));
            ExitCode::from(2)
        }
    }
}

/// Prints `text` on standard output; a closed pipe (`splinerod run … | head -1`) drops
/// it silently, other failures are reported on standard error. The run goes on.
fn say(text: std::fmt::Arguments<'_>) {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_fmt(text).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => {
            complain(format_args!("warning: standard output: {e}\n"));
        }
        _ => {}
    }
}

/// Prints `text` on standard error, ignoring failures (a closed pipe).
fn complain(text: std::fmt::Arguments<'_>) {
    use std::io::Write;
    let _ = std::io::stderr().lock().write_fmt(text);
}

/// `println!` through [`say`].
macro_rules! say {
    ($($t:tt)*) => { say(format_args!("{}\n", format_args!($($t)*))) };
}

fn execute(cli: Cli) -> Result<ExitCode, Error> {
    match cli.command {
        Command::Run(args) => run(*args, run_arguments()),
        Command::Resume { dir, max_steps } => resume(&dir, max_steps),
        Command::Report { quick, out } => {
            let report = splinerod::report::write_report(&out, quick)?;
            say!(
                "static catenary order {:.2}; wrote {}",
                report.order,
                out.join("report.md").display()
            );
            Ok(ExitCode::SUCCESS)
        }
        Command::Bench { quick, json } => bench(quick, json).map(|()| ExitCode::SUCCESS),
        Command::Merge { out, shards } => merge(&out, &shards).map(|()| ExitCode::SUCCESS),
        Command::Fit {
            scene,
            observations,
            params,
            json,
            scene_out,
        } => {
            let fitted = splinerod::fit::command::fit_files(&scene, &observations, &params)?;
            fitted.summary().iter().for_each(|line| say!("{line}"));
            json.map_or(Ok(()), |path| write_json(&path, &fitted.json()))?;
            scene_out.map_or(Ok(()), |out| fitted.write_scene(&scene, &out))?;
            Ok(ExitCode::SUCCESS)
        }
        Command::Sensitivities {
            scene,
            params,
            json,
        } => {
            let params: Vec<&str> = params.split(',').map(str::trim).collect();
            let scene = splinerod::Scene::load(&scene)?;
            let (summary, found) = splinerod::sensitivity::report(&scene, &params)?;
            for line in summary {
                say!("{line}");
            }
            json.map_or(Ok(()), |path| write_json(&path, &found))?;
            Ok(ExitCode::SUCCESS)
        }
    }
}

/// `splinerod merge`: reads every shard, merges, writes `out`.
fn merge(out: &PathBuf, shards: &[PathBuf]) -> Result<(), Error> {
    write_json(out, &splinerod::run::shard::merge_files(shards)?)
}

/// Writes `value` as pretty JSON to `path`.
fn write_json(path: &PathBuf, value: &impl serde::Serialize) -> Result<(), Error> {
    let text = serde_json::to_string_pretty(value)?;
    std::fs::write(path, text).map_err(|source| Error::Io {
        path: path.display().to_string(),
        source,
    })?;
    say!("wrote {}", path.display());
    Ok(())
}

#[cfg(feature = "parallel")]
fn bench(quick: bool, json: Option<PathBuf>) -> Result<(), Error> {
    let b = splinerod::bench::measure(quick)?;
    for line in b.summary() {
        say!("{line}");
    }
    match json {
        Some(path) => write_json(&path, &b),
        None => Ok(()),
    }
}

#[cfg(not(feature = "parallel"))]
fn bench(_quick: bool, _json: Option<PathBuf>) -> Result<(), Error> {
    Err(Error::FeatureMissing("parallel"))
}

/// The observers the flags ask for, all checked before anything runs.
fn observers(args: &RunArgs) -> Result<Vec<Box<dyn Observer>>, Error> {
    if args.every == 0 {
        return Err(Error::field("--every", 0, "must be at least 1"));
    }
    let camera = picture::Camera::from_name(&args.camera)?;
    if args.gif.is_some() && args.frames.is_none() {
        return Err(Error::Options {
            option: "--gif",
            message: "--gif needs --frames DIR: the GIF is assembled from the PNG pictures \
                      written there"
                .into(),
        });
    }
    let mut list: Vec<Box<dyn Observer>> = vec![Box::new(Progress::new())];
    if let Some(path) = &args.stats {
        list.push(Box::new(StatsWriter::new(path)?));
    }
    if let Some(dir) = &args.frames {
        let mut pictures = picture::Pictures::new(dir, args.every, camera, args.svg, args.polygon)?;
        if let Some(gif) = &args.gif {
            pictures = pictures.with_gif(gif.clone());
        }
        list.push(Box::new(pictures));
    }
    if let Some(dir) = &args.vtk {
        list.push(Box::new(VtkWriter::new(dir, args.every)?));
    }
    Ok(list)
}

/// The command line after `run`, as given.
fn run_arguments() -> Vec<String> {
    std::env::args()
        .skip_while(|a| a != "run")
        .skip(1)
        .collect()
}

fn run(args: RunArgs, line: Vec<String>) -> Result<ExitCode, Error> {
    let signals = stop_on_signals()?;
    let text = std::fs::read_to_string(&args.scene).map_err(|source| Error::Io {
        path: args.scene.display().to_string(),
        source,
    })?;
    let scene = match splinerod::Scene::load_cancellable(&args.scene, &signals) {
        Err(e) if e.is_interrupted() => return Ok(stopped_without_state(&e)),
        loaded => loaded?,
    };
    let shard = match &args.shard {
        Some(text) => Some(Shard::parse(text)?),
        None => None,
    };
    if !args.allow_large {
        let limits = splinerod::scene::Limits::default();
        match &shard {
            Some(s) => scene.with_member_count(s.members(&scene)?.len()),
            None => scene.clone(),
        }
        .check_limits(&limits)?;
    }
    let plan = checkpoint_plan(&args, text, line, shard.as_ref())?;
    execute_run(
        &args,
        |observers, control| match shard {
            Some(shard) => splinerod::run::runner::run_shard(&scene, observers, shard, control),
            None => splinerod::run::runner::run_controlled(&scene, observers, control),
        },
        plan,
        args.max_steps,
        signals,
    )
}

/// `splinerod resume DIR`: the checkpointed command line's outputs, continued.
fn resume(dir: &std::path::Path, max_steps: Option<usize>) -> Result<ExitCode, Error> {
    let signals = stop_on_signals()?;
    let saved = splinerod::run::checkpoint::resumable(dir)?;
    let line = std::iter::once("run".to_string()).chain(saved.args.iter().cloned());
    let parsed = RunLine::try_parse_from(line).map_err(|e| {
        Error::field(
            "checkpoint",
            dir.display(),
            format!("its command line: {e}"),
        )
    })?;
    let args = parsed.args;
    let shard = saved.shard.map(|(index, count)| Shard { index, count });
    let plan = checkpoint_plan(&args, saved.scene, saved.args, shard.as_ref())?;
    // The checkpointed run's own --max-steps ended that invocation, not the run.
    execute_run(
        &args,
        |observers, control| splinerod::run::runner::resume(dir, observers, control),
        plan,
        max_steps,
        signals,
    )
}

/// The checkpoints `args` ask for (`scene`: the scene's text; `line`: the command line).
fn checkpoint_plan(
    args: &RunArgs,
    scene: String,
    line: Vec<String>,
    shard: Option<&Shard>,
) -> Result<Option<CheckpointPlan>, Error> {
    let Some(dir) = &args.checkpoint else {
        return Ok(None);
    };
    if !(args.checkpoint_every.is_finite() && args.checkpoint_every >= 0.0) {
        let reason = "must be a finite number of seconds, at least 0";
        return Err(Error::field(
            "--checkpoint-every",
            args.checkpoint_every,
            reason,
        ));
    }
    if args.gif.is_some() {
        return Err(Error::Options {
            option: "--gif",
            message: "--gif cannot go with --checkpoint: a GIF cannot be continued after a \
                      resume (write --frames and assemble the pictures afterwards)"
                .into(),
        });
    }
    Ok(Some(CheckpointPlan {
        dir: dir.clone(),
        every_seconds: args.checkpoint_every,
        scene,
        args: line,
        shard: shard.map(|s| (s.index, s.count)),
    }))
}

/// Runs `go` with the outputs `args` ask for, stopping on `signals` and after
/// `max_steps`; prints the summary, writes the JSON; exit 130 if a signal stopped it.
fn execute_run(
    args: &RunArgs,
    go: impl FnOnce(&mut [&mut dyn Observer], &RunControl) -> Result<splinerod::RunResult, Error>,
    plan: Option<CheckpointPlan>,
    max_steps: Option<usize>,
    signals: Cancel,
) -> Result<ExitCode, Error> {
    let mut boxed = observers(args)?;
    let mut refs: Vec<&mut dyn Observer> = Vec::with_capacity(boxed.len());
    for b in boxed.iter_mut() {
        refs.push(b.as_mut());
    }
    let dir = plan.as_ref().map(|p| p.dir.display().to_string());
    let control = RunControl {
        max_steps,
        cancel: signals.clone(),
        checkpoint: plan,
    };
    let result = match go(&mut refs, &control) {
        Err(e) if e.is_interrupted() => return Ok(stopped_without_state(&e)),
        result => result?,
    };
    say(format_args!("{}", result.summary()));
    if let Some(path) = &args.json {
        write_json(path, &result)?;
    }
    if !signals.requested() {
        return Ok(ExitCode::SUCCESS);
    }
    let abandoned = "abandoned the step under way (rolled back) and ";
    let how = if result.abandoned_step { abandoned } else { "" };
    complain(format_args!(
        "interrupted: {how}stopped at t = {} s after {} steps\n",
        result.time, result.steps
    ));
    if let (Some(dir), false) = (dir, result.checkpoint_at_stop) {
        complain(format_args!(
            "the checkpoint in {dir} was not updated at the stop (the abandoned step could not be undone exactly): it holds the last one written, if any\n"
        ));
    }
    Ok(ExitCode::from(INTERRUPTED))
}

/// The exit of a run a signal stopped before it had a state to write.
fn stopped_without_state(e: &Error) -> ExitCode {
    complain(format_args!("{e}: nothing written\n"));
    ExitCode::from(INTERRUPTED)
}

/// SIGINT and SIGTERM raise the returned request: the run stops at the end of its step,
/// or abandons a step still running [`STOP_GRACE`] later, and writes its outputs; a
/// second signal ends the process at once with the interrupted code.
fn stop_on_signals() -> Result<Cancel, Error> {
    use signal_hook::consts::{SIGINT, SIGTERM};
    let flag = Arc::new(AtomicBool::new(false));
    for signal in [SIGINT, SIGTERM] {
        let installed = signal_hook::flag::register_conditional_shutdown(
            signal,
            INTERRUPTED.into(),
            flag.clone(),
        )
        .and_then(|_| signal_hook::flag::register(signal, flag.clone()));
        installed.map_err(|source| Error::Io {
            path: "signal handler".into(),
            source,
        })?;
    }
    Ok(Cancel::from_flag(flag).with_grace(STOP_GRACE))
}
