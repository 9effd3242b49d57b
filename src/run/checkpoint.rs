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
//! format version [`VERSION`], the splinerod version that wrote it), the checkpoint
//! (postcard, through serde; it holds the scene's text and the [`fnv1a64`] hash of that
//! text), then 8 bytes: the [`fnv1a64`] checksum of every byte before them,
//! little-endian. A file of another format or version is refused with a message saying
//! so (one of an older format, which has no checksum, says that); so is one written by
//! another splinerod version (the results would not be bit-identical across builds that
//! change the numerics). Then the file's integrity is checked, and a failure refused
//! naming it: a scene text that does not match its hash (edited or damaged), a checksum
//! mismatch (any other damage: the checksum covers the whole file, so a field added to
//! the format later is covered too), or content that does not decode (malformed) under
//! a checksum that matches. FNV-1a changes its hash at every single-byte change, so any
//! one damaged byte is refused. Writing is atomic: a temporary file is written, flushed
//! to disk (`fsync`) and renamed over the previous checkpoint, so a crash while writing
//! leaves the previous one intact.
//! A checkpoint written under another kernel set ([`splinerod_core::kernels`]: the
//! fused and the plain kernels round differently) is refused too, naming both sets.

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
/// final error estimate; 4: the checksum over the file and the scene text's hash, the
/// kernel set, and the solver totals' steps solved alone per reason; 5: the count of
/// steps with a hinge and the estimate's spread; 6: each probe's rod; 7: the grippers'
/// poses; 8: the rigid bodies' states and tracks; 9: BDF2's history of the rigid
/// bodies' motion).
pub const VERSION: u32 = 9;
/// The first format version with a checksum; older files are refused as such.
const FIRST_CHECKSUMMED: u32 = 4;
/// Bytes of the checksum at the end of the file.
const CHECKSUM_BYTES: usize = 8;
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
    /// [`fnv1a64`] of `scene`'s bytes.
    pub scene_hash: u64,
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
    let checksum = fnv1a64(&bytes);
    bytes.extend(checksum.to_le_bytes());
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

/// Reads the checkpoint in `dir`, refusing a foreign, old, damaged or edited one
/// (module docs).
pub(crate) fn read(dir: &Path) -> Result<Checkpoint, Error> {
    let path = dir.join(FILE);
    let bytes = std::fs::read(&path).map_err(io(&path))?;
    let foreign = || refused(&path, "not a splinerod checkpoint");
    let (header, rest) = postcard::take_from_bytes::<Header>(&bytes).map_err(|_| foreign())?;
    if header.format != FORMAT {
        return Err(foreign());
    }
    let this = env!("CARGO_PKG_VERSION");
    if header.version < FIRST_CHECKSUMMED {
        let reason = format!(
            "no checksum (older format): written by splinerod {} in checkpoint format {}; this is splinerod {this} (format {VERSION}), which resumes only checksummed checkpoints: resume it with the version that wrote it",
            header.build, header.version
        );
        return Err(refused(&path, reason));
    }
    if header.version != VERSION || header.build != this {
        let reason = format!(
            "written by splinerod {} (checkpoint format {}); this is splinerod {this} (format {VERSION}): resume it with the version that wrote it",
            header.build, header.version
        );
        return Err(refused(&path, reason));
    }
    let Some(body_len) = rest.len().checked_sub(CHECKSUM_BYTES) else {
        return Err(refused(&path, "damaged: too short to hold its checksum"));
    };
    let (body, trailer) = rest.split_at(body_len);
    let mut stored = [0; CHECKSUM_BYTES];
    stored.copy_from_slice(trailer);
    let content = &bytes[..bytes.len() - CHECKSUM_BYTES];
    let (stored, computed) = (u64::from_le_bytes(stored), fnv1a64(content));
    let decoded = match postcard::take_from_bytes::<Checkpoint>(body) {
        Ok((c, [])) => Ok(c),
        Ok((_, extra)) => Err(format!("{} bytes past its end", extra.len())),
        Err(e) => Err(e.to_string()),
    };
    match decoded {
        Ok(c) if fnv1a64(c.scene.as_bytes()) != c.scene_hash => {
            let reason = format!(
                "scene hash mismatch: the scene text it holds hashes to {:016x}, not to the {:016x} it was written with (edited or damaged)",
                fnv1a64(c.scene.as_bytes()),
                c.scene_hash
            );
            Err(refused(&path, reason))
        }
        _ if stored != computed => {
            let reason = format!(
                "damaged: checksum mismatch (the file's content hashes to {computed:016x}, its checksum says {stored:016x})"
            );
            Err(refused(&path, reason))
        }
        Ok(c) => check_kernels(&path, c),
        Err(e) => Err(refused(
            &path,
            format!("malformed field under a matching checksum: {e}"),
        )),
    }
}

/// The 64-bit FNV-1a hash of `bytes` (Fowler–Noll–Vo; offset basis
/// `0xcbf29ce484222325`, prime `0x100000001b3`): the checkpoint's checksum and scene
/// hash. Every step `h ← (h ⊕ byte) · prime` is a bijection of `h` for each byte and
/// of the byte for each `h`, so changing any one byte changes the hash.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    const BASIS: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0000_0100_0000_01b3;
    bytes
        .iter()
        .fold(BASIS, |h, &b| (h ^ u64::from(b)).wrapping_mul(PRIME))
}

/// `checkpoint` if it was written under the kernel set this process runs; else refused
/// naming both.
fn check_kernels(path: &Path, checkpoint: Checkpoint) -> Result<Checkpoint, Error> {
    let running = splinerod_core::kernels::name();
    if checkpoint.kernels != running {
        let reason = format!(
            "written under the \"{}\" kernel set; this process runs \"{running}\" \
             ({}), whose results differ at round-off: resume it under the set that wrote it",
            checkpoint.kernels,
            splinerod_core::kernels::ENV
        );
        return Err(refused(path, reason));
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

#[cfg(test)]
mod tests {
    use super::fnv1a64;

    #[test]
    fn fnv1a64_matches_the_reference_vectors() {
        // From the FNV reference test suite (isthe.com/chongo/tech/comp/fnv).
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }
}
