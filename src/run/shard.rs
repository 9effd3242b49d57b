//! Ensembles across machines: `splinerod run SCENE.toml --shard K/N` runs the members of
//! shard `K` of `N` (a contiguous block of member indices), and `splinerod merge OUT.json
//! SHARD.json…` combines the shards' results into the JSON one run of the whole
//! ensemble writes. Every member draws from its own random stream (`[ensemble]`), so a
//! member computes the same wherever it runs: the merged result equals the single run's
//! bit for bit, except the wall-clock fields (`wall_seconds`, the sum of the shards';
//! `median_step_seconds` and `stage_seconds`, shard 1's).
//!
//! A shard's JSON is a run's JSON whose top-level fields describe its first member, plus
//! `shard` (`index`, `count`, `members` as `[start, end)`, and `scene`, a fingerprint of
//! the parsed scene, so shards of different scenes are never merged). Like every result
//! it records the kernel set that computed it (`kernels`, [`splinerod_core::kernels`]):
//! the bits above hold under one set, so shards of different sets are not merged
//! either (the error names both sets).
//!
//! A member computes the same bits whichever shard it lands in, for any `N`: the
//! batched step's groups follow the whole ensemble's numbering and a member's lanes
//! never depend on its lane-mates (`world/lanes.rs`). `N` may be at most the number of
//! members; more is refused for every `K`.

use crate::run::totals::SolverTotals;
use crate::{Error, Scene};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use std::ops::Range;

/// Shard `index` (1-based) of `count`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which shard, `1..=count`.
    pub index: usize,
    /// How many shards.
    pub count: usize,
}

/// What a shard's JSON records about it (`shard`).
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct ShardInfo {
    /// Which shard, `1..=count`.
    pub index: usize,
    /// How many shards.
    pub count: usize,
    /// Its members, `[start, end)`.
    pub members: [usize; 2],
    /// Fingerprint of the parsed scene (FNV-1a of its full description), in hex.
    pub scene: String,
}

impl Shard {
    /// `"K/N"` with `1 ≤ K ≤ N`; errors name `--shard`.
    pub fn parse(text: &str) -> Result<Shard, Error> {
        let bad = |reason: &str| Error::field("--shard", format!("\"{text}\""), reason);
        let (k, n) = text
            .split_once('/')
            .ok_or_else(|| bad("expected K/N, e.g. 2/4"))?;
        let (Ok(index), Ok(count)) = (k.trim().parse::<usize>(), n.trim().parse::<usize>()) else {
            return Err(bad("expected K/N with whole numbers, e.g. 2/4"));
        };
        if count == 0 || index == 0 || index > count {
            return Err(bad("needs 1 ≤ K ≤ N"));
        }
        Ok(Shard { index, count })
    }

    /// The members of this shard in an ensemble of `total`: a contiguous block of at
    /// least one member, the blocks of shards 1..N in order covering `0..total`. Errors
    /// when `scene` has no `[ensemble]` or has fewer members than shards (then for every
    /// K alike, so that a set of shards either all run or none does).
    pub fn members(&self, scene: &Scene) -> Result<Range<usize>, Error> {
        let field = "--shard";
        let given = format!("{}/{}", self.index, self.count);
        let Some(total) = scene.ensemble.as_ref().map(|e| e.count) else {
            return Err(Error::field(
                field,
                given,
                "only an [ensemble] scene can be sharded",
            ));
        };
        let (k, n) = (self.index, self.count);
        if n > total {
            let reason = format!(
                "{n} shards but the ensemble has {total} members: give at most {total} shards (each runs at least one member)"
            );
            return Err(Error::field(field, given, reason));
        }
        // With n ≤ total every block holds at least one member. In u128: no overflow.
        let bound = |j: usize| (j as u128 * total as u128 / n as u128) as usize;
        Ok(bound(k - 1)..bound(k))
    }

    /// The record of this shard of `scene` with `members`.
    pub fn info(&self, scene: &Scene, members: &Range<usize>) -> ShardInfo {
        ShardInfo {
            index: self.index,
            count: self.count,
            members: [members.start, members.end],
            scene: fingerprint(scene),
        }
    }
}

/// FNV-1a (64 bits) of the scene's full description, in hex.
fn fingerprint(scene: &Scene) -> String {
    let text = format!("{scene:?}");
    let hash = text.bytes().fold(0xcbf2_9ce4_8422_2325_u64, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3)
    });
    format!("{hash:016x}")
}

/// The result of the whole ensemble from its shards' results (any order): errors name
/// the offending shard unless they are the `count` shards of one scene, each once.
pub fn merge(shards: &[Value]) -> Result<Value, Error> {
    let mut infos = Vec::with_capacity(shards.len());
    for (i, shard) in shards.iter().enumerate() {
        let info: ShardInfo = shard
            .get("shard")
            .cloned()
            .and_then(|v| serde_json::from_value(v).ok())
            .ok_or_else(|| shard_error(i, "not the JSON of a --shard run"))?;
        infos.push((info, i));
    }
    infos.sort_by_key(|(info, _)| info.index);
    let Some((first, _)) = infos.first() else {
        return Err(Error::field(
            "merge",
            "no shards",
            "give every shard's JSON",
        ));
    };
    let (count, scene) = (first.count, first.scene.clone());
    same_kernels(shards, &infos)?;
    let mut next = 0;
    for (k, (info, i)) in infos.iter().enumerate() {
        if info.count != count || info.scene != scene {
            return Err(shard_error(
                *i,
                "a shard of another run (scene or shard count differ)",
            ));
        }
        if info.index != k + 1 || info.members[0] != next {
            return Err(shard_error(*i, "shards missing or given twice"));
        }
        next = info.members[1];
    }
    if infos.len() != count {
        let reason = format!("{} of {count} shards given", infos.len());
        return Err(Error::field("merge", infos.len(), reason));
    }
    let ordered: Vec<&Value> = infos.iter().map(|(_, i)| &shards[*i]).collect();
    combine(&ordered)
}

/// Shard 1's result with every shard's members, solver totals and wall time (and
/// `interrupted` if any shard was).
fn combine(ordered: &[&Value]) -> Result<Value, Error> {
    let mut merged = ordered[0].clone();
    let mut members = Vec::new();
    let (mut solver, mut wall) = (SolverTotals::default(), 0.0);
    let mut interrupted = false;
    for shard in ordered {
        let part = |key: &str| shard.get(key).cloned().unwrap_or(Value::Null);
        interrupted |= part("interrupted").as_bool().unwrap_or(false);
        if let Value::Array(list) = part("ensemble") {
            members.extend(list);
        }
        solver += serde_json::from_value(part("solver"))?;
        wall += part("wall_seconds").as_f64().unwrap_or(0.0);
    }
    if let Value::Object(map) = &mut merged {
        map.remove("shard");
        map.insert("ensemble".into(), Value::Array(members));
        map.insert("solver".into(), serde_json::to_value(solver)?);
        map.insert("wall_seconds".into(), wall.into());
        if interrupted {
            map.insert("interrupted".into(), true.into());
        }
    }
    Ok(merged)
}

/// Refuses shards computed under different kernel sets (or recording none), naming
/// both sets; `infos` are the shards' records with their file positions, shard 1 first.
fn same_kernels(shards: &[Value], infos: &[(ShardInfo, usize)]) -> Result<(), Error> {
    let kernels = |i: usize| shards[i].get("kernels").and_then(Value::as_str);
    let first = infos[0].1;
    let Some(set) = kernels(first) else {
        return Err(shard_error(
            first,
            "records no kernel set (`kernels`): written by an older splinerod",
        ));
    };
    for &(_, i) in &infos[1..] {
        match kernels(i) {
            Some(other) if other == set => {}
            Some(other) => {
                let reason = format!(
                    "shards computed under different kernel sets: file {} \"{set}\", file {} \"{other}\"; their results differ at round-off: run every shard under one set ({})",
                    first + 1,
                    i + 1,
                    splinerod_core::kernels::ENV
                );
                return Err(Error::field("merge", format!("file {}", i + 1), reason));
            }
            None => {
                let reason = "records no kernel set (`kernels`): written by an older splinerod";
                return Err(shard_error(i, reason));
            }
        }
    }
    Ok(())
}

fn shard_error(i: usize, reason: &str) -> Error {
    Error::field("merge", format!("file {}", i + 1), reason)
}

/// [`merge`] of the shards' JSON files at `paths`; an unreadable file or one that is not
/// JSON is an error naming it.
pub fn merge_files(paths: &[std::path::PathBuf]) -> Result<serde_json::Value, Error> {
    let mut values = Vec::with_capacity(paths.len());
    for path in paths {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.display().to_string(),
            source,
        })?;
        let value = serde_json::from_str(&text).map_err(|e| {
            let reason = format!("not JSON: {e}");
            Error::field("merge", path.display(), reason)
        })?;
        values.push(value);
    }
    merge(&values)
}
