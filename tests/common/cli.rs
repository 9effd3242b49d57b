//! Running the `splinerod` binary from tests: a command's output, success, a refusal
//! with one error line, fresh temporary directories and edited copies of bundled scenes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// The binary's output for `args`.
pub fn splinerod(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_splinerod"))
        .args(args)
        .output()
        .expect("splinerod runs")
}

/// Runs `args`, which must succeed.
pub fn ok(args: &[&str]) {
    let out = splinerod(args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// The one error line of `args`, which must exit with 2.
pub fn refused(args: &[&str]) -> String {
    let out = splinerod(args);
    let line = String::from_utf8_lossy(&out.stderr).trim_end().to_string();
    assert_eq!(out.status.code(), Some(2), "{args:?}: {line}");
    assert!(
        !line.contains('\n') && line.starts_with("error: "),
        "one line: {line}"
    );
    line
}

/// A fresh, empty temporary directory for `test` (unique in the process: the
/// integration tests share one).
pub fn fresh_dir(test: &str) -> PathBuf {
    static MADE: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let n = MADE.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let d = std::env::temp_dir().join(format!("splinerod-{}-{n}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("temp dir");
    d
}

/// `scenes/NAME` with each `(from, to)` replaced (each must occur), written into `dir`.
pub fn scene_variant(dir: &Path, name: &str, edits: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(Path::new("scenes").join(name)).expect("scene");
    for (from, to) in edits {
        assert!(text.contains(from), "{name} has no `{from}`");
        text = text.replace(from, to);
    }
    let path = dir.join(name);
    std::fs::write(&path, text).expect("scene written");
    path
}

/// Writes `text` as `scene.toml` into a fresh directory for `test` and runs `splinerod
/// run` on it, which must exit with 2 and one error line; that line.
pub fn refused_scene(test: &str, text: &str) -> String {
    let dir = fresh_dir(test);
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).expect("scene written");
    let line = refused(&["run", path.to_str().expect("a UTF-8 path")]);
    let _ = std::fs::remove_dir_all(&dir);
    line
}
