//! Ensembles across machines: four `--shard K/4` runs as separate processes, merged by
//! `splinerod merge`, equal one run of the whole ensemble bit for bit (all but the
//! wall-clock fields); so do 8 members run as 1, 3 and 8 shards (shards of one member
//! and groups of the batched step cut short included); bad shards and merges exit 2
//! naming the problem, and more shards than members are refused for every `K`.

use crate::common;

use common::cli::{ok, splinerod};
use serde_json::Value;
use std::path::{Path, PathBuf};

/// A 40-member version of the bundled ensemble, written to a fresh directory.
fn setup(test: &str) -> (PathBuf, PathBuf) {
    setup_with(test, 40)
}

/// A `count`-member version of the bundled ensemble, written to a fresh directory.
fn setup_with(test: &str, count: usize) -> (PathBuf, PathBuf) {
    let dir = std::env::temp_dir().join(format!("splinerod-shards-{}-{test}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let text = std::fs::read_to_string("scenes/ensemble_cables.toml").expect("scene");
    assert!(text.contains("count = 1000"));
    let text = text.replace("count = 1000", &format!("count = {count}"));
    let scene = dir.join("ensemble.toml");
    std::fs::write(&scene, &text).expect("scene written");
    let other = dir.join("other.toml");
    std::fs::write(&other, text.replace("seed = 7", "seed = 8")).expect("scene written");
    (dir, scene)
}

/// The error line of a command that must exit with 2.
fn fails(args: &[&str]) -> String {
    let out = splinerod(args);
    assert_eq!(out.status.code(), Some(2), "{args:?}");
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The JSON of `path` without the wall-clock fields.
fn result(path: &Path) -> Value {
    let text = std::fs::read_to_string(path).expect("JSON written");
    let mut value: Value = serde_json::from_str(&text).expect("JSON");
    let map = value.as_object_mut().expect("object");
    for key in ["wall_seconds", "median_step_seconds", "stage_seconds"] {
        assert!(map.remove(key).is_some(), "{key} missing");
    }
    value
}

fn s(p: &Path) -> &str {
    p.to_str().expect("UTF-8 path")
}

#[test]
fn four_shards_merged_equal_one_run() {
    let (dir, scene) = setup("merge");
    let whole = dir.join("whole.json");
    ok(&["run", s(&scene), "--json", s(&whole)]);
    let shards: Vec<PathBuf> = (1..=4)
        .map(|k| dir.join(format!("shard{k}.json")))
        .collect();
    for (k, path) in shards.iter().enumerate() {
        let shard = format!("{}/4", k + 1);
        ok(&["run", s(&scene), "--shard", &shard, "--json", s(path)]);
    }
    let merged = dir.join("merged.json");
    // Any order.
    let order = [&shards[2], &shards[0], &shards[3], &shards[1]];
    let mut args = vec!["merge", s(&merged)];
    args.extend(order.iter().map(|p| s(p)));
    ok(&args);
    let (a, b) = (result(&whole), result(&merged));
    assert_eq!(a["ensemble"].as_array().map(Vec::len), Some(40));
    assert_eq!(a, b);
    // A shard holds its members only.
    let second = result(&shards[1]);
    assert_eq!(second["ensemble"][0]["index"], 10);
    assert_eq!(second["shard"]["members"], serde_json::json!([10, 20]));

    // Bad merges: a shard missing, one given twice, a shard of another scene.
    let three: Vec<&str> = shards[..3].iter().map(|p| s(p)).collect();
    let msg = fails(&[&["merge", s(&merged)], three.as_slice()].concat());
    assert!(msg.contains("3 of 4 shards"), "{msg}");
    let twice = [s(&shards[0]), s(&shards[0]), s(&shards[2]), s(&shards[3])];
    let msg = fails(&[&["merge", s(&merged)], twice.as_slice()].concat());
    assert!(msg.contains("missing or given twice"), "{msg}");
    let foreign = dir.join("foreign.json");
    ok(&[
        "run",
        s(&dir.join("other.toml")),
        "--shard",
        "2/4",
        "--json",
        s(&foreign),
    ]);
    let mixed = [s(&shards[0]), s(&foreign), s(&shards[2]), s(&shards[3])];
    let msg = fails(&[&["merge", s(&merged)], mixed.as_slice()].concat());
    assert!(msg.contains("another run"), "{msg}");
    let msg = fails(&["merge", s(&merged), s(&whole)]);
    assert!(msg.contains("not the JSON of a --shard run"), "{msg}");
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_shards_exit_2_naming_the_flag() {
    let (dir, scene) = setup("bad");
    for bad in ["5/4", "0/0", "1/0", "x", "2"] {
        let msg = fails(&["run", s(&scene), "--shard", bad]);
        assert!(msg.contains("--shard"), "{bad}: {msg}");
    }
    let msg = fails(&["run", s(&scene), "--shard", "1/41"]);
    assert!(msg.contains("40 members"), "{msg}");
    let msg = fails(&["run", "scenes/hanging_cable.toml", "--shard", "1/2"]);
    assert!(msg.contains("[ensemble]"), "{msg}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Runs `scene` as `n` shards and merges them; the merged JSON's path.
fn sharded(dir: &Path, scene: &Path, n: usize) -> PathBuf {
    let shards: Vec<PathBuf> = (1..=n)
        .map(|k| {
            let path = dir.join(format!("of{n}-{k}.json"));
            let shard = format!("{k}/{n}");
            ok(&["run", s(scene), "--shard", &shard, "--json", s(&path)]);
            path
        })
        .collect();
    let merged = dir.join(format!("merged{n}.json"));
    let mut args = vec!["merge", s(&merged)];
    args.extend(shards.iter().map(|p| s(p)));
    ok(&args);
    merged
}

#[test]
fn eight_members_as_one_three_or_eight_shards_merge_to_the_one_run_bit_for_bit() {
    // 8 shards: every shard a single member (once stepped alone, not batched: 95 JSON
    // values differed); 3 shards: members 0..2, 2..5, 5..8, so groups of the batched
    // step cut short ([2, 3] and [4] against [0..4] and [4..8] in the one run).
    let (dir, scene) = setup_with("eight", 8);
    let whole = dir.join("whole.json");
    ok(&["run", s(&scene), "--json", s(&whole)]);
    let one = result(&whole);
    assert_eq!(one["ensemble"].as_array().map(Vec::len), Some(8));
    let batched = one["solver"]["batched_steps"].as_u64().expect("count");
    assert!(
        batched >= 1500,
        "nearly every member-step batched: {batched}"
    );
    for n in [1, 3, 8] {
        let merged = result(&sharded(&dir, &scene, n));
        // Compared value by value (JSON numbers are written round-trip exact).
        assert_eq!(merged, one, "{n} shards");
    }
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn more_shards_than_members_are_refused_for_every_shard() {
    let (dir, scene) = setup_with("too-many", 5);
    for k in 1..=7 {
        let msg = fails(&["run", s(&scene), "--shard", &format!("{k}/7")]);
        assert!(
            msg.contains("--shard") && msg.contains(&format!("{k}/7")),
            "{msg}"
        );
        assert!(
            msg.contains("7 shards") && msg.contains("5 members"),
            "{msg}"
        );
    }
    // Up to one shard per member, every shard runs.
    let merged = result(&sharded(&dir, &scene, 5));
    assert_eq!(merged["ensemble"].as_array().map(Vec::len), Some(5));
    std::fs::remove_dir_all(&dir).ok();
}
