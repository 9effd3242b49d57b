//! Checkpoints: the whole state of a run between two steps, in one file, so that a run
//! stopped (Ctrl-C, `--max-steps`, a crash, a time limit) continues with `splinerod
//! resume DIR` to bit-identical results.
//!
//! A checkpoint holds the scene's text and the run's command line, the stages done, and
//! per ensemble member its [`SimulationState`] and tally (probe trajectories,
//! histories, counters, knot records, cut schedule), the wall time so far, and each
//! observer's state (the stats CSV's length, the ParaView frames, the pictures'
//! framing). Resuming rebuilds every member from the scene, restores those states (the
//! knot changes are replayed, see [`crate::world::saved`]) and goes on with the stage
//! after the checkpoint.
//!
//! **Format.** `DIR/checkpoint.bin`: a [postcard] header (`"splinerod-checkpoint"`, the
//! format version [`VERSION`], the splinerod version that wrote it) followed by the
//! checkpoint, both through serde. A file of another format or version is refused with
//! a message saying so; so is one written by another splinerod version (the results
//! would not be bit-identical across builds that change the numerics), and one written
//! under another kernel set ([`splinerod_core::kernels`]: the fused and the plain
//! kernels round differently), the message naming both sets. Writing is
//! atomic: a temporary file is written, flushed to disk (`fsync`) and renamed over the
//! previous checkpoint, so a crash while writing leaves the previous one intact.

use crate::run::tally::Tally;
use crate::world::saved::SimulationState;
use crate::Error;
use serde::{Deserialize, Serialize};
use splinerod_core::Real;
use std::io::Write;
use std::path::{Path, PathBuf};

/// Format version of checkpoint files; a file of another version is refused (2: the
/// solver totals count the remainder's conjugate-gradient iterations; 3: the velocities
/// at the start of the last step, so that a run resumed at its end reports the same
/// final error estimate; 4: the kernel set, and the solver totals' steps solved alone
/// per reason).
pub const VERSION: u32 = 4;
/// The checkpoint's file name inside its directory.
pub const FILE: &str = "checkpoint.bin";
const FORMAT: &str = "splinerod-checkpoint";

/// Where and how often a run writes checkpoints.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckpointPlan {
    /// The directory (created if missing).
    pub dir: PathBuf,
    /// Wall-clock seconds between checkpoints; a stopped run (signal, `--max-steps`)
    /// always writes one where it stops.
    pub every_seconds: Real,
    /// The scene file's text (a resumed run parses it again).
    pub scene: String,
    /// The command line after `run` (a resumed run rebuilds its outputs from it).
    pub args: Vec<String>,
    /// For a `--shard K/N` run: (K, N).
    pub shard: Option<(usize, usize)>,
}

#[derive(Debug, Serialize, Deserialize)]
struct Header {
    format: String,
    version: u32,
    build: String,
}

/// One member's state.
#[derive(Debug, Serialize, Deserialize)]
pub(crate) struct MemberState {
    pub simulation: SimulationState,
    pub tally: Tally,
}

/// The whole run between two stages (module docs).
#[derive(Debug, Serialize, Deserialize)]
pub(crate) struct Checkpoint {
    /// The kernel set of the process that wrote it ([`splinerod_core::kernels::name`]).
    pub kernels: String,
    pub scene: String,
    pub args: Vec<String>,
    /// The ensemble members run, if a shard's, and the shard (K, N).
    pub only: Option<(usize, usize)>,
    pub shard: Option<(usize, usize)>,
    /// Stages done.
    pub stage: usize,
    pub members: Vec<MemberState>,
    /// Wall time so far, s (the step times are not kept: a resumed run's median step
    /// is of its own steps).
    pub wall_seconds: Real,
    /// Each observer's state (JSON), in order; `None` for an observer without one.
    pub observers: Vec<Option<String>>,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.display().to_string(),
        source,
    }
}

fn refused(path: &Path, reason: impl Into<String>) -> Error {
    Error::field("checkpoint", path.display(), reason)
}

/// Writes `checkpoint` into `dir` atomically (module docs).
pub(crate) fn write(dir: &Path, checkpoint: &Checkpoint) -> Result<(), Error> {
    std::fs::create_dir_all(dir).map_err(io(dir))?;
    let header = Header {
        format: FORMAT.into(),
        version: VERSION,
        build: env!("CARGO_PKG_VERSION").into(),
    };
    let encode = |e: postcard::Error| refused(dir, format!("could not encode: {e}"));
    let mut bytes = postcard::to_stdvec(&header).map_err(encode)?;
    bytes.extend(postcard::to_stdvec(checkpoint).map_err(encode)?);
    let path = dir.join(FILE);
    let temporary = dir.join(format!("{FILE}.tmp"));
    let mut file = std::fs::File::create(&temporary).map_err(io(&temporary))?;
    file.write_all(&bytes).map_err(io(&temporary))?;
    file.sync_all().map_err(io(&temporary))?;
    drop(file);
    std::fs::rename(&temporary, &path).map_err(io(&path))?;
    // The rename itself is durable once the directory is synced (where the OS allows).
    if let Ok(d) = std::fs::File::open(dir) {
        let _ = d.sync_all();
    }
    Ok(())
}

/// Reads the checkpoint in `dir`, refusing a foreign or old one.
pub(crate) fn read(dir: &Path) -> Result<Checkpoint, Error> {
    let path = dir.join(FILE);
    let bytes = std::fs::read(&path).map_err(io(&path))?;
    let foreign = || refused(&path, "not a splinerod checkpoint");
    let (header, rest) = postcard::take_from_bytes::<Header>(&bytes).map_err(|_| foreign())?;
    if header.format != FORMAT {
        return Err(foreign());
    }
    if header.version != VERSION || header.build != env!("CARGO_PKG_VERSION") {
        let reason = format!(
            "written by splinerod {} (checkpoint format {}); this is splinerod {} (format {VERSION}): resume it with the version that wrote it",
            header.build,
            header.version,
            env!("CARGO_PKG_VERSION")
        );
        return Err(refused(&path, reason));
    }
    let checkpoint: Checkpoint =
        postcard::from_bytes(rest).map_err(|e| refused(&path, format!("damaged: {e}")))?;
    let running = splinerod_core::kernels::name();
    if checkpoint.kernels != running {
        let reason = format!(
            "written under the \"{}\" kernel set; this process runs \"{running}\" \
             ({}), whose results differ at round-off: resume it under the set that wrote it",
            checkpoint.kernels,
            splinerod_core::kernels::ENV
        );
        return Err(refused(&path, reason));
    }
    Ok(checkpoint)
}

/// What `splinerod resume` needs to know of the run checkpointed in a directory.
#[derive(Debug, Clone, PartialEq)]
pub struct Resumable {
    /// The scene's text.
    pub scene: String,
    /// The command line after `run`.
    pub args: Vec<String>,
    /// For a shard's run: (K, N).
    pub shard: Option<(usize, usize)>,
}

/// The scene and command line of the run checkpointed in `dir`.
pub fn resumable(dir: &Path) -> Result<Resumable, Error> {
    read(dir).map(|c| Resumable {
        scene: c.scene,
        args: c.args,
        shard: c.shard,
    })
}
