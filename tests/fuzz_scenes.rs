//! Fuzzed scenes at the command line: every bundled scene in turn, with two to four
//! fields mutated at once (a field deleted, a value of the wrong type, NaN, ±∞, huge
//! and tiny numbers, arrays shuffled, truncated or extended, an unknown key, the file
//! cut short), run by the `splinerod` binary for a few steps. The run must end within
//! [`TIME_LIMIT`] with exit 0 and finite JSON, or exit 2 and one line of error — never
//! a panic, an abort or a hang.
//!
//! `SPLINEROD_FUZZ_CASES` sets the number of cases (default 300) and
//! `SPLINEROD_FUZZ_SEED` the seed (default fixed, so CI runs the same cases),
//! `SPLINEROD_BIN` another `splinerod` binary to run; a long
//! run: `SPLINEROD_FUZZ_CASES=100000 SPLINEROD_FUZZ_SEED=7 cargo test --release --test
//! fuzz_scenes -- --nocapture`.

use proptest::prelude::*;
use proptest::test_runner::{Config, RngSeed, TestRunner};
use std::cell::Cell;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};
use toml::{Table, Value};

/// Steps each fuzzed run takes (`--max-steps`).
const STEPS: &str = "6";
/// A run taking longer than this is a hang (a few steps of any bundled scene take well
/// under a second; scene setup, the knot fit included, a few).
const TIME_LIMIT: Duration = Duration::from_secs(60);

/// Fields mutated per case: two to four.
const MUTATIONS: std::ops::RangeInclusive<usize> = 2..=4;

/// One change to a scene.
#[derive(Debug, Clone)]
enum Mutation {
    /// Remove the entry.
    Delete,
    /// Replace the entry by this value.
    Replace(Value),
    /// Reverse an array, or rotate it by one.
    Shuffle(bool),
    /// Keep the first `k` elements of an array.
    Truncate(usize),
    /// Append a copy of an array's last element.
    Extend,
    /// Add a key no table knows.
    UnknownKey,
    /// Cut the file's text at this fraction of its length.
    CutFile(f64),
}

fn values() -> impl Strategy<Value = Value> {
    prop_oneof![
        Just(Value::Float(f64::NAN)),
        Just(Value::Float(f64::INFINITY)),
        Just(Value::Float(f64::NEG_INFINITY)),
        Just(Value::Float(1e300)),
        Just(Value::Float(-1e300)),
        Just(Value::Float(1e-300)),
        Just(Value::Float(1e12)),
        Just(Value::Float(0.0)),
        Just(Value::Float(-0.0)),
        Just(Value::Float(-1.0)),
        Just(Value::Float(0.5)),
        Just(Value::Integer(0)),
        Just(Value::Integer(-1)),
        Just(Value::Integer(1_000_000)),
        Just(Value::Integer(1_000_000_000_000)),
        Just(Value::Integer(i64::MAX)),
        Just(Value::String("x".into())),
        Just(Value::Boolean(true)),
        Just(Value::Array(Vec::new())),
        Just(Value::Table(Table::new())),
        (-1e3..1e3f64).prop_map(Value::Float),
    ]
}

fn mutations() -> impl Strategy<Value = Mutation> {
    prop_oneof![
        2 => Just(Mutation::Delete),
        6 => values().prop_map(Mutation::Replace),
        1 => any::<bool>().prop_map(Mutation::Shuffle),
        1 => (0usize..4).prop_map(Mutation::Truncate),
        1 => Just(Mutation::Extend),
        1 => Just(Mutation::UnknownKey),
        1 => (0.0..1.0f64).prop_map(Mutation::CutFile),
    ]
}

/// Every bundled scene: name and text.
fn scenes() -> Vec<(String, String)> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut list: Vec<_> = std::fs::read_dir(&dir)
        .expect("scenes/")
        .map(|e| e.expect("entry").path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    list.sort();
    list.iter()
        .map(|p| {
            let name = p.file_name().expect("name").to_string_lossy().into_owned();
            (name, std::fs::read_to_string(p).expect("scene"))
        })
        .collect()
}

/// Where an entry sits: keys and array indices from the root.
#[derive(Debug, Clone)]
enum Step {
    Key(String),
    Index(usize),
}

fn paths(value: &Value, prefix: &mut Vec<Step>, out: &mut Vec<Vec<Step>>) {
    match value {
        Value::Table(t) => {
            for (k, v) in t {
                prefix.push(Step::Key(k.clone()));
                out.push(prefix.clone());
                paths(v, prefix, out);
                prefix.pop();
            }
        }
        Value::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                prefix.push(Step::Index(i));
                out.push(prefix.clone());
                paths(v, prefix, out);
                prefix.pop();
            }
        }
        _ => {}
    }
}

/// The entry's container and its place in it.
fn container<'a>(root: &'a mut Value, path: &[Step]) -> &'a mut Value {
    let mut at = root;
    for step in path {
        at = match (at, step) {
            (Value::Table(t), Step::Key(k)) => t.get_mut(k).expect("key"),
            (Value::Array(a), Step::Index(i)) => &mut a[*i],
            _ => unreachable!("paths come from this value"),
        };
    }
    at
}

/// The mutated scene's text.
fn mutate(text: &str, pick: usize, mutation: &Mutation) -> String {
    if let Mutation::CutFile(f) = mutation {
        let mut cut = (text.len() as f64 * f) as usize;
        while !text.is_char_boundary(cut) {
            cut -= 1;
        }
        return text[..cut].to_string();
    }
    // An earlier mutation may have cut the file or emptied it: nothing left to mutate.
    let Ok(table) = text.parse::<Table>() else {
        return text.to_string();
    };
    let mut root = Value::Table(table);
    let mut all = Vec::new();
    paths(&root, &mut Vec::new(), &mut all);
    if all.is_empty() {
        return text.to_string();
    }
    let path = &all[pick % all.len()];
    let (last, parent) = path.split_last().expect("non-empty path");
    let parent = container(&mut root, parent);
    match (mutation, parent, last) {
        (Mutation::Delete, Value::Table(t), Step::Key(k)) => {
            t.remove(k);
        }
        (Mutation::Delete, Value::Array(a), Step::Index(i)) => {
            a.remove(*i);
        }
        (Mutation::Replace(v), Value::Table(t), Step::Key(k)) => {
            t.insert(k.clone(), v.clone());
        }
        (Mutation::Replace(v), Value::Array(a), Step::Index(i)) => a[*i] = v.clone(),
        (Mutation::UnknownKey, Value::Table(t), _) => {
            t.insert("fuzz_unknown".into(), Value::Integer(1));
        }
        (m, parent, last) => {
            let entry = match (parent, last) {
                (Value::Table(t), Step::Key(k)) => t.get_mut(k).expect("key"),
                (Value::Array(a), Step::Index(i)) => &mut a[*i],
                _ => unreachable!("paths come from this value"),
            };
            if let Value::Array(a) = entry {
                match m {
                    Mutation::Shuffle(true) => a.reverse(),
                    Mutation::Shuffle(false) if !a.is_empty() => a.rotate_left(1),
                    Mutation::Truncate(k) => a.truncate(*k),
                    Mutation::Extend => {
                        if let Some(x) = a.last().cloned() {
                            a.push(x);
                        }
                    }
                    _ => {}
                }
            }
        }
    }
    toml::to_string(&root).expect("a TOML value serialises")
}

/// What the binary did with a scene.
struct Outcome {
    code: Option<i32>,
    stderr: String,
    json: Option<String>,
}

fn run_cli(dir: &Path, text: &str) -> Outcome {
    let scene = dir.join("case.toml");
    let json = dir.join("case.json");
    std::fs::write(&scene, text).expect("write case");
    let _ = std::fs::remove_file(&json);
    let binary = std::env::var_os("SPLINEROD_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_splinerod")));
    let mut child = Command::new(binary)
        .args(["run", "--max-steps", STEPS, "--json"])
        .arg(&json)
        .arg(&scene)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .expect("spawn splinerod");
    let start = Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().expect("wait") {
            break Some(status);
        }
        if start.elapsed() > TIME_LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            break None;
        }
        std::thread::sleep(Duration::from_millis(5));
    };
    let mut stderr = String::new();
    if let Some(mut pipe) = child.stderr.take() {
        use std::io::Read;
        let _ = pipe.read_to_string(&mut stderr);
    }
    Outcome {
        code: status.and_then(|s| s.code()),
        stderr,
        json: std::fs::read_to_string(&json).ok(),
    }
}

/// Whether every number at `keys` (and below) in the JSON is a number, not `null`.
fn finite_at(value: &serde_json::Value, keys: &[&str]) -> Result<(), String> {
    fn walk(v: &serde_json::Value, at: &str) -> Result<(), String> {
        match v {
            serde_json::Value::Null => Err(format!("null (a non-finite number) at {at}")),
            serde_json::Value::Array(a) => a.iter().try_for_each(|x| walk(x, at)),
            serde_json::Value::Object(o) => o.values().try_for_each(|x| walk(x, at)),
            _ => Ok(()),
        }
    }
    for key in keys {
        let v = value.get(key).ok_or_else(|| format!("no `{key}`"))?;
        walk(v, key)?;
    }
    Ok(())
}

/// Exit 0 with finite JSON, or exit 2 with one line naming the problem.
fn judge(outcome: &Outcome) -> Result<(), String> {
    match outcome.code {
        Some(0) => {
            let text = outcome.json.as_deref().ok_or("exit 0 without JSON")?;
            let value: serde_json::Value =
                serde_json::from_str(text).map_err(|e| format!("JSON unreadable: {e}"))?;
            finite_at(&value, &["time", "samples", "energy", "knots"])
        }
        Some(2) => {
            let line = outcome.stderr.trim_end();
            if line.starts_with("error: ") && !line.contains('\n') {
                Ok(())
            } else {
                Err(format!("exit 2 without one error line: {line:?}"))
            }
        }
        None if outcome.stderr.is_empty() => Err("hung or killed by a signal".into()),
        code => Err(format!("exit {code:?}: {}", outcome.stderr.trim_end())),
    }
}

fn env_number(name: &str, default: u64) -> u64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

/// The CI run: 300 cases, fixed seed (both overridable, see the module docs).
#[test]
fn mutated_scenes_end_cleanly() {
    fuzz(
        env_number("SPLINEROD_FUZZ_CASES", 300) as u32,
        env_number("SPLINEROD_FUZZ_SEED", 0x5eed),
    );
}

/// The larger run of issue #45's acceptance: 3 000 cases, another seed (a few minutes).
#[test]
#[ignore = "a few minutes; run with --ignored"]
fn three_thousand_mutated_scenes_end_cleanly() {
    fuzz(3000, 7);
}

/// Runs `cases` fuzzed scenes from `seed`; panics naming the first that fails.
fn fuzz(cases: u32, seed: u64) {
    let scenes = scenes();
    let dir: PathBuf = std::env::temp_dir().join(format!("splinerod-fuzz-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let config = Config {
        cases,
        rng_seed: RngSeed::Fixed(seed),
        failure_persistence: None,
        max_shrink_iters: 64,
        ..Config::default()
    };
    let mut runner = TestRunner::new(config);
    let (exit0, exit2) = (Cell::new(0usize), Cell::new(0usize));
    let start = Instant::now();
    // Each case mutates 2-4 fields of a scene, one after the other.
    let visited = std::cell::RefCell::new(std::collections::BTreeSet::new());
    let changes = proptest::collection::vec((any::<usize>(), mutations()), MUTATIONS);
    let strategy = (0..scenes.len(), changes);
    let result = runner.run(&strategy, |(k, changes)| {
        visited.borrow_mut().insert(k);
        let (name, text) = &scenes[k];
        let mutated = changes
            .iter()
            .fold(text.clone(), |t, (pick, m)| mutate(&t, *pick, m));
        let mutation = changes.iter().map(|c| &c.1).collect::<Vec<_>>();
        let outcome = run_cli(&dir, &mutated);
        let done = exit0.get() + exit2.get() + 1;
        if done % 1000 == 0 {
            eprintln!("{done} cases, {:.0} s", start.elapsed().as_secs_f64());
        }
        match outcome.code {
            Some(0) => exit0.set(exit0.get() + 1),
            Some(2) => exit2.set(exit2.get() + 1),
            _ => {}
        }
        judge(&outcome).map_err(|why| {
            TestCaseError::fail(format!(
                "{name} with {mutation:?}: {why}\n--- scene ---\n{mutated}"
            ))
        })
    });
    let _ = std::fs::remove_dir_all(&dir);
    println!(
        "{cases} fuzzed scenes (seed {seed}) in {:.1} s: {} ran, {} refused",
        start.elapsed().as_secs_f64(),
        exit0.get(),
        exit2.get()
    );
    if let Err(e) = result {
        panic!("{e}");
    }
    // With the default number of cases and seed, every bundled scene was mutated.
    if cases >= 300 {
        let missed: Vec<_> = (0..scenes.len())
            .filter(|k| !visited.borrow().contains(k))
            .map(|k| &scenes[k].0)
            .collect();
        assert!(missed.is_empty(), "scenes never fuzzed: {missed:?}");
    }
}
