//! Checkpoints through the library, with no outputs (so nothing but the run itself
//! detects contact between steps): a checkpoint taken on any step — that of a cut, of an
//! adaptive knot insertion or removal — resumes to the uninterrupted run's result, bit
//! for bit but for wall-clock times; and a damaged or edited checkpoint is refused,
//! naming what failed, or (never, with a checksum that sees every byte) resumes to that
//! same result.

use splinerod::run::checkpoint::{fnv1a64, CheckpointPlan, FILE};
use splinerod::runner::{resume, run_controlled, RunControl};
use splinerod::{run, RunResult, Scene, SceneRun};
use std::path::{Path, PathBuf};

/// A free rod with contact and a floor, cut at 0.883 at t = 0.05 s (after step 50):
/// the cut changes the contact samples' layout (issue #45: a checkpoint on that step
/// could not be resumed, "contact samples of another rod").
const FREE_CUT: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 0.5
control_points = 10
start = [0.0, 0.0, 0.0]
end = [1.0, 0.0, 0.2]
radius = 0.01

[[cuts]]
at = 0.883
time = 0.05

[contact]
stiffness = 1e5
floor = -0.05

[solver]
method = "implicit-euler"
dt = 0.001
duration = 0.2
"#;

/// `result` as JSON (exact: floats round-trip), without the wall-clock fields and the
/// count of symbolic analyses (a resumed run analyses the sparse pattern once more:
/// work, not results).
fn timeless(mut result: RunResult) -> String {
    result.wall_seconds = 0.0;
    result.median_step_seconds = 0.0;
    result.stage_seconds = Default::default();
    result.solver.symbolic_analyses = 0;
    serde_json::to_string(&result).expect("JSON")
}

/// A fresh, empty temporary directory for `test`.
fn fresh_dir(test: &str) -> PathBuf {
    let name = format!("splinerod-{}-checkpoints-{test}", std::process::id());
    let d = std::env::temp_dir().join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// The scene file `name` with each `(from, to)` replaced (each must occur).
fn variant(name: &str, edits: &[(&str, &str)]) -> String {
    let mut text = std::fs::read_to_string(Path::new("scenes").join(name)).expect("scene");
    for (from, to) in edits {
        assert!(text.contains(from), "{name} has no `{from}`");
        text = text.replace(from, to);
    }
    text
}

/// Runs the scene of `text` for `steps` steps, writing its checkpoint into `dir`.
fn checkpoint_at(text: &str, dir: &Path, steps: usize) {
    let scene = Scene::from_toml(text).expect("scene");
    let control = RunControl {
        max_steps: Some(steps),
        checkpoint: Some(CheckpointPlan {
            dir: dir.to_path_buf(),
            every_seconds: f64::INFINITY,
            scene: text.to_string(),
            args: Vec::new(),
            shard: None,
        }),
        ..RunControl::default()
    };
    let stopped = run_controlled(&scene, &mut [], &control).expect("run until the stop");
    assert!(stopped.interrupted && stopped.steps == steps);
}

/// The checkpoint in `dir`, resumed to the end.
fn resumed(dir: &Path) -> Result<String, splinerod::Error> {
    resume(dir, &mut [], &RunControl::default()).map(timeless)
}

/// Checkpoints the scene of `text` after each of `stops` steps and resumes each: every
/// resumed run must end as the uninterrupted one.
fn resumes_exactly(test: &str, text: &str, stops: &[usize]) {
    let whole = timeless(run(&Scene::from_toml(text).expect("scene")).expect("run"));
    let d = fresh_dir(test);
    for &stop in stops {
        checkpoint_at(text, &d, stop);
        let resumed = resumed(&d).unwrap_or_else(|e| panic!("{test}: step {stop}: {e}"));
        assert!(
            resumed == whole,
            "{test}: resumed after step {stop} differs"
        );
    }
    std::fs::remove_dir_all(&d).ok();
}

/// The steps (1-based) after which the count of control points changed, the first
/// `count` of them.
fn knot_change_steps(text: &str, count: usize) -> Vec<usize> {
    let scene = Scene::from_toml(text).expect("scene");
    let mut driven = SceneRun::new(&scene).expect("scene run");
    let points = |r: &SceneRun| r.members()[0].system.rod.len();
    let mut steps = Vec::new();
    while steps.len() < count && driven.stages_done() < driven.stage_count() {
        let before = points(&driven);
        driven.advance(1).expect("step");
        if points(&driven) != before {
            steps.push(driven.stages_done());
        }
    }
    assert_eq!(steps.len(), count, "too few knot changes");
    steps
}

#[test]
fn a_checkpoint_on_the_step_of_a_cut_resumes_exactly() {
    resumes_exactly("free-cut", FREE_CUT, &[49, 50, 51, 120]);
    let contact = variant("cut_contact.toml", &[("duration = 2.0", "duration = 0.7")]);
    resumes_exactly("cut-contact", &contact, &[200, 400, 600]);
}

#[test]
fn a_checkpoint_on_the_step_of_a_knot_change_resumes_exactly() {
    // Insertions and removals.
    let grab = variant("grab_adaptive.toml", &[]);
    let steps = knot_change_steps(&grab, 8);
    println!("grab_adaptive: knot changes after steps {steps:?}");
    resumes_exactly("grab", &grab, &steps);
    // Insertions with self-contact.
    let knot = variant(
        "knot_tying_adaptive.toml",
        &[("duration = 3.0", "duration = 0.3")],
    );
    let steps = knot_change_steps(&knot, 4);
    println!("knot_tying_adaptive: knot changes after steps {steps:?}");
    resumes_exactly("knot", &knot, &steps);
}

/// A small deterministic generator (SplitMix64) for the corruptions.
struct SplitMix(u64);

impl SplitMix {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (`n > 0`; the modulo bias is immaterial here).
    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }
}

#[test]
fn every_single_byte_corruption_is_refused_or_resumes_exactly() {
    let d = fresh_dir("corrupt");
    checkpoint_at(FREE_CUT, &d, 100);
    let path = d.join(FILE);
    let bytes = std::fs::read(&path).expect("checkpoint");
    let expected = resumed(&d).expect("the intact checkpoint resumes");
    const TRIES: usize = 300;
    assert!(bytes.len() >= TRIES, "{} bytes", bytes.len());
    let mut rng = SplitMix(45);
    let (mut refusals, mut identical) = (Vec::new(), 0);
    for i in 0..TRIES {
        // One position in each of 300 equal stretches of the file, so that the header,
        // the scene text, the states and the checksum all get their share.
        let (lo, hi) = (i * bytes.len() / TRIES, (i + 1) * bytes.len() / TRIES);
        let at = lo + rng.below(hi - lo);
        let mut damaged = bytes.clone();
        damaged[at] ^= 1 + rng.below(255) as u8;
        std::fs::write(&path, &damaged).expect("write");
        match resumed(&d) {
            Err(e) => refusals.push((at, e.to_string())),
            Ok(result) => {
                assert!(result == expected, "byte {at} changed: resumed differently");
                identical += 1;
            }
        }
    }
    let kind = |what: &str| refusals.iter().filter(|(_, m)| m.contains(what)).count();
    let (sum, scene) = (kind("checksum mismatch"), kind("scene hash mismatch"));
    let other: Vec<_> = refusals
        .iter()
        .filter(|(_, m)| !m.contains("checksum mismatch") && !m.contains("scene hash"))
        .collect();
    println!(
        "{} bytes, {TRIES} corruptions: {} refused ({sum} checksum mismatch, {scene} scene hash mismatch, {} at the header: {:?}), {identical} resumed identically",
        bytes.len(),
        refusals.len(),
        other.len(),
        other.iter().map(|(at, m)| format!("byte {at}: {m}")).collect::<Vec<_>>()
    );
    assert_eq!(refusals.len() + identical, TRIES);
    // FNV-1a changes at every single-byte change: each one is refused.
    assert_eq!(identical, 0);
    // Besides, every byte of the header (the format's name, the version, the build's
    // version: short strings with their lengths) and of the checksum, each flipped whole.
    let header = 1 + "splinerod-checkpoint".len() + 1 + 1 + env!("CARGO_PKG_VERSION").len();
    for at in (0..header).chain(bytes.len() - 8..bytes.len()) {
        let mut damaged = bytes.clone();
        damaged[at] ^= 0xff;
        std::fs::write(&path, &damaged).expect("write");
        assert!(resumed(&d).is_err(), "byte {at} flipped: resumed");
    }
    std::fs::remove_dir_all(&d).ok();
}

/// The checkpoint in `dir` with its scene text's `from` replaced by `to` (as long), the
/// checksum fixed if `fix_checksum`.
fn edit_scene(dir: &Path, from: &str, to: &str, fix_checksum: bool) {
    assert_eq!(from.len(), to.len());
    let path = dir.join(FILE);
    let mut bytes = std::fs::read(&path).expect("checkpoint");
    let at = bytes.windows(from.len()).position(|w| w == from.as_bytes());
    let at = at.expect("the scene text in the checkpoint");
    bytes[at..at + to.len()].copy_from_slice(to.as_bytes());
    if fix_checksum {
        let end = bytes.len() - 8;
        let sum = fnv1a64(&bytes[..end]);
        bytes[end..].copy_from_slice(&sum.to_le_bytes());
    }
    std::fs::write(&path, &bytes).expect("write");
}

#[test]
fn an_edited_scene_in_a_checkpoint_is_refused() {
    let d = fresh_dir("edited");
    for fix_checksum in [false, true] {
        checkpoint_at(FREE_CUT, &d, 30);
        edit_scene(&d, "stiffness = 1e5", "stiffness = 9e5", fix_checksum);
        let message = resumed(&d).expect_err("edited scene refused").to_string();
        println!("{message}");
        assert!(message.contains("scene hash mismatch"), "{message}");
    }
    // The scene hash fixed too (a varint after the scene text), not the checksum: the
    // checksum sees it.
    checkpoint_at(FREE_CUT, &d, 30);
    let path = d.join(FILE);
    let mut bytes = std::fs::read(&path).expect("checkpoint");
    let edited = FREE_CUT.replace("stiffness = 1e5", "stiffness = 9e5");
    let (old, new) = (fnv1a64(FREE_CUT.as_bytes()), fnv1a64(edited.as_bytes()));
    let text = bytes
        .windows(FREE_CUT.len())
        .position(|w| w == FREE_CUT.as_bytes());
    let end = text.expect("the scene text in the checkpoint") + FREE_CUT.len();
    let hash = varint(old);
    assert_eq!(
        bytes[end..end + hash.len()],
        hash,
        "the scene hash follows the text"
    );
    bytes.splice(end..end + hash.len(), varint(new));
    std::fs::write(&path, &bytes).expect("write");
    edit_scene(&d, "stiffness = 1e5", "stiffness = 9e5", false);
    let message = resumed(&d).expect_err("edited scene refused").to_string();
    println!("{message}");
    assert!(message.contains("checksum mismatch"), "{message}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_malformed_checkpoint_under_a_matching_checksum_is_refused() {
    let d = fresh_dir("malformed");
    checkpoint_at(FREE_CUT, &d, 30);
    let path = d.join(FILE);
    let bytes = std::fs::read(&path).expect("checkpoint");
    let content = &bytes[..bytes.len() - 8];
    let mut junk = content.to_vec();
    junk.extend(b"junk");
    for content in [&content[..content.len() / 2], &junk[..]] {
        let mut file = content.to_vec();
        file.extend(fnv1a64(content).to_le_bytes());
        std::fs::write(&path, &file).expect("write");
        let message = resumed(&d).expect_err("malformed refused").to_string();
        println!("{message}");
        assert!(message.contains("malformed field"), "{message}");
    }
    std::fs::remove_dir_all(&d).ok();
}

/// `x` as a postcard varint (LEB128: 7 bits a byte, low first, high bit = more).
fn varint(mut x: u64) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let low = (x & 0x7f) as u8;
        x >>= 7;
        if x == 0 {
            out.push(low);
            return out;
        }
        out.push(low | 0x80);
    }
}
