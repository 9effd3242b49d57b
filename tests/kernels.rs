//! The kernel set as a recorded setting (`SPLINEROD_KERNELS`, `splinerod_core::kernels`):
//! the binary run in subprocesses under each set records it in JSON `kernels`; shards of
//! different sets are not merged and a checkpoint is not resumed under another set
//! (exit 2, naming both sets); a value not understood exits 2 naming the variable and
//! the value. Every subprocess gets the variable explicitly, so these tests mean the
//! same in CI's portable pass.

use crate::common;

use common::cli::{fresh_dir, scene_variant};
use serde_json::Value;
use splinerod::kernels::{KernelSet, ENV};
use std::path::Path;
use std::process::{Command, Output};

/// The binary's output for `args` under `SPLINEROD_KERNELS=kernels`.
fn under(kernels: &str, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_splinerod"))
        .env(ENV, kernels)
        .args(args)
        .output()
        .expect("splinerod runs")
}

/// [`under`], which must succeed.
fn ok_under(kernels: &str, args: &[&str]) {
    let out = under(kernels, args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{kernels} {args:?}: {err}");
}

/// [`under`], which must exit 2 with one error line; the line.
fn refused_under(kernels: &str, args: &[&str]) -> String {
    let out = under(kernels, args);
    let line = String::from_utf8_lossy(&out.stderr).trim_end().to_string();
    assert_eq!(out.status.code(), Some(2), "{kernels} {args:?}: {line}");
    assert!(
        line.starts_with("error: ") && !line.contains('\n'),
        "{line}"
    );
    line
}

fn json(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).expect("JSON written");
    serde_json::from_str(&text).expect("JSON")
}

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

/// The fastest set's name, and the other set a test can make a file claim (both names
/// have 8 bytes, so a checkpoint can be edited in place).
fn sets() -> (&'static str, &'static str) {
    let fastest = KernelSet::fastest().name();
    let other = if fastest == "portable" {
        "avx2-fma"
    } else {
        "portable"
    };
    (fastest, other)
}

#[test]
fn results_record_their_kernel_set_and_sets_are_never_merged() {
    let d = fresh_dir("kernels-merge");
    let scene = scene_variant(&d, "ensemble_cables.toml", &[("count = 1000", "count = 8")]);
    let (fastest, _) = sets();
    let (auto, portable) = (d.join("auto.json"), d.join("portable.json"));
    ok_under("auto", &["run", s(&scene), "--json", s(&auto)]);
    ok_under("portable", &["run", s(&scene), "--json", s(&portable)]);
    let (a, p) = (json(&auto), json(&portable));
    assert_eq!(a["kernels"], fastest);
    assert_eq!(p["kernels"], "portable");
    let differing = a["ensemble"]
        .as_array()
        .expect("members")
        .iter()
        .zip(p["ensemble"].as_array().expect("members"))
        .filter(|(x, y)| x != y)
        .count();
    println!("{fastest} against portable: {differing} of 8 members differ");
    // Shard 1 under the fastest set, shard 2 under the plain kernels.
    let (one, two) = (d.join("one.json"), d.join("two.json"));
    ok_under(
        "auto",
        &["run", s(&scene), "--shard", "1/2", "--json", s(&one)],
    );
    ok_under(
        "portable",
        &["run", s(&scene), "--shard", "2/2", "--json", s(&two)],
    );
    let mut shard_two = json(&two);
    if fastest == "portable" {
        // No AVX2 and FMA here: make shard 2 claim the other set.
        shard_two["kernels"] = "avx2-fma".into();
        std::fs::write(&two, shard_two.to_string()).expect("write");
    }
    let other = shard_two["kernels"].as_str().expect("a name").to_string();
    let merged = d.join("merged.json");
    let msg = refused_under("auto", &["merge", s(&merged), s(&one), s(&two)]);
    println!("{msg}");
    assert!(msg.contains(&format!("\"{fastest}\"")), "{msg}");
    assert!(msg.contains(&format!("\"{other}\"")), "{msg}");
    assert!(!merged.exists());
    // A shard recording no set (an older splinerod's) is refused too.
    let mut old = json(&one);
    old.as_object_mut().expect("object").remove("kernels");
    std::fs::write(&one, old.to_string()).expect("write");
    ok_under(
        "auto",
        &["run", s(&scene), "--shard", "2/2", "--json", s(&two)],
    );
    let msg = refused_under("auto", &["merge", s(&merged), s(&one), s(&two)]);
    assert!(msg.contains("no kernel set"), "{msg}");
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_checkpoint_resumes_under_its_own_kernel_set_only() {
    let d = fresh_dir("kernels-resume");
    let ck = d.join("ck");
    let json_out = d.join("r.json");
    let (fastest, other) = sets();
    let line = [
        "run",
        "scenes/hanging_cable.toml",
        "--checkpoint",
        s(&ck),
        "--max-steps",
        "20",
        "--json",
        s(&json_out),
    ];
    ok_under("auto", &line);
    let path = ck.join("checkpoint.bin");
    let written = std::fs::read(&path).expect("checkpoint");
    let resume = ["resume", s(&ck)];
    if fastest == "portable" {
        // No second set to run here: the checkpoint claims the other one instead.
        let at = written
            .windows(8)
            .position(|w| w == fastest.as_bytes())
            .expect("the set's name in the checkpoint");
        let mut edited = written.clone();
        edited[at..at + 8].copy_from_slice(other.as_bytes());
        std::fs::write(&path, edited).expect("write");
        let msg = refused_under("auto", &resume);
        assert!(msg.contains(fastest) && msg.contains(other), "{msg}");
        std::fs::write(&path, &written).expect("write");
    } else {
        let msg = refused_under("portable", &resume);
        println!("{msg}");
        assert!(
            msg.contains("\"avx2-fma\"") && msg.contains("\"portable\""),
            "{msg}"
        );
        assert!(msg.contains(ENV), "{msg}");
    }
    // Under its own set it resumes, and the result says which.
    ok_under("auto", &resume);
    assert_eq!(json(&json_out)["kernels"], fastest);
    std::fs::remove_dir_all(&d).ok();
}

#[test]
fn a_kernel_setting_not_understood_exits_2_naming_the_variable_and_the_value() {
    for bad in ["fastest", "AVX", "plain"] {
        let msg = refused_under(
            bad,
            &["run", "scenes/hanging_cable.toml", "--max-steps", "1"],
        );
        assert!(
            msg.contains(ENV) && msg.contains(&format!("\"{bad}\"")),
            "{msg}"
        );
        let msg = refused_under(bad, &["merge", "out.json", "a.json"]);
        assert!(msg.contains(ENV), "{msg}");
    }
    if !KernelSet::Avx2Fma.available() {
        let msg = refused_under("avx2-fma", &["run", "scenes/hanging_cable.toml"]);
        assert!(msg.contains("lacks"), "{msg}");
    }
    // The accepted values run.
    for good in ["auto", "portable", ""] {
        ok_under(
            good,
            &["run", "scenes/hanging_cable.toml", "--max-steps", "1"],
        );
    }
}
