//! Resource limits: what a scene will ask of the machine, estimated before it runs.
//!
//! A mistyped exponent (`dt = 1e-300`, `samples = 1e12`) should not start a run that
//! cannot finish or that asks the allocator for more memory than exists (which aborts
//! the process). [`Scene::resources`] estimates, from the scene's numbers alone:
//!
//! * steps per member: `duration / dt` (1 for a static solve);
//! * control points one member holds at once: every rod's count, or adaptivity's cap;
//! * output samples: `output.samples` per rod (an ensemble reports member 0's);
//! * contact samples per member: `rest_length / (0.2 r)` per rod, with `[contact]`;
//! * work: control-point steps of the whole run, each contact sample counted as
//!   [`CONTACT_WORK`] control points;
//! * memory, bytes: [`BYTES_PER_CONTROL_POINT`] per control point, [`BYTES_PER_SAMPLE`]
//!   per output sample, [`BYTES_PER_CONTACT_SAMPLE`] per contact sample, and what grows
//!   with the steps (probe trajectories, step times).
//!
//! [`Scene::check_limits`] compares them with [`Limits`] (the CLI's defaults; `splinerod
//! run --allow-large` skips them) and names the field behind the first estimate over its
//! limit. Whatever the limits, [`Scene::check_memory`] refuses a run whose memory
//! estimate exceeds the machine's physical memory: that run could only abort.

use crate::scene::{Method, Scene};
use crate::Error;
use serde::Serialize;

/// Memory per control point of a member, bytes (measured: about 1 600, `bench`'s
/// `bytes_per_cp`; rounded up for the adaptivity and contact caches).
pub const BYTES_PER_CONTROL_POINT: f64 = 2048.0;
/// Memory per output sample, bytes (position, coordinate, tension, and its JSON text).
pub const BYTES_PER_SAMPLE: f64 = 160.0;
/// Memory per contact sample, bytes (its basis row, position, bounds and pair lists).
pub const BYTES_PER_CONTACT_SAMPLE: f64 = 512.0;
/// Memory per step and probe, bytes (a time and a position, and their JSON text).
pub const BYTES_PER_PROBE_STEP: f64 = 128.0;
/// Memory per step, bytes (its wall time, history entries).
pub const BYTES_PER_STEP: f64 = 16.0;
/// Work of one contact sample per step, in plain control-point steps (measured on
/// `knot_tying.toml`: about 0.3; 1 leaves room for denser contact).
pub const CONTACT_WORK: f64 = 1.0;
/// Physical memory assumed where the machine does not say (1 TiB).
const UNKNOWN_MEMORY: f64 = 1024.0 * 1024.0 * 1024.0 * 1024.0;

/// What a run of a scene will need, estimated before it runs.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Resources {
    /// Time steps per member (1 for a static solve).
    pub steps: f64,
    /// Members (1 without `[ensemble]`).
    pub members: f64,
    /// Most control points one member holds at once (all rods).
    pub control_points: f64,
    /// Output samples, all rods (of member 0: the others report summaries).
    pub samples: f64,
    /// Contact samples per member (0 without `[contact]`).
    pub contact_samples: f64,
    /// Control-point steps of the whole run (contact samples weighted by
    /// [`CONTACT_WORK`]).
    pub work: f64,
    /// Memory, bytes.
    pub memory_bytes: f64,
}

/// Largest estimates a run may have (see the module docs); the defaults are the CLI's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Limits {
    /// Steps per member. Default 1e7.
    pub steps: f64,
    /// Control points per member. Default 1e5 (the bench's largest rod; a step of a
    /// slack or contact-laden rod costs up to about 10 µs per control point).
    pub control_points: f64,
    /// Output samples. Default 1e6.
    pub samples: f64,
    /// Control-point steps (about an hour of one core at the default 1e10).
    pub work: f64,
    /// Memory, bytes. Default 4 GiB.
    pub memory_bytes: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            steps: 1e7,
            control_points: 1e5,
            samples: 1e6,
            work: 1e10,
            memory_bytes: 4.0 * 1024.0 * 1024.0 * 1024.0,
        }
    }
}

impl Scene {
    /// The run's estimated needs (module docs).
    pub fn resources(&self) -> Resources {
        let rods: Vec<_> = (0..self.rod_count()).map(|k| self.rod_spec(k)).collect();
        let steps = match (self.solver.method, self.solver.dt, self.solver.duration) {
            (Method::Static, ..) => 1.0,
            (_, Some(dt), Some(t)) => (t / dt).ceil().max(1.0),
            _ => 1.0,
        };
        let members = self.ensemble.as_ref().map_or(1.0, |e| e.count as f64);
        let listed = self.total_control_points() as f64;
        let capped = self
            .adaptivity
            .as_ref()
            .map(|a| a.max_control_points as f64);
        let control_points = capped.map_or(listed, |cap| cap.max(listed));
        let samples = self.output.samples as f64 * rods.len() as f64;
        let contact_samples = match &self.contact {
            Some(_) => rods
                .iter()
                .filter_map(|r| Some(r.rest_length / (0.2 * r.radius?)))
                .sum(),
            None => 0.0,
        };
        let per_step = control_points + CONTACT_WORK * contact_samples;
        let per_member = BYTES_PER_CONTROL_POINT * control_points
            + BYTES_PER_CONTACT_SAMPLE * contact_samples
            + steps * self.bytes_per_step();
        Resources {
            steps,
            members,
            control_points,
            samples,
            contact_samples,
            work: steps * members * per_step,
            memory_bytes: members * per_member + BYTES_PER_SAMPLE * samples,
        }
    }

    /// Refuses the scene, naming the fields behind the first estimate over `limits`.
    pub fn check_limits(&self, limits: &Limits) -> Result<(), Error> {
        let r = self.resources();
        let steps = "solver.duration / solver.dt";
        let points = match &self.adaptivity {
            Some(_) => "adaptivity.max_control_points",
            None => "rod.control_points",
        };
        let work = self.per_member(&format!("{steps} × {points}"));
        let memory = self.memory_field(&r);
        let checks = [
            (steps.to_string(), "steps", r.steps, limits.steps),
            (
                points.to_string(),
                "control points",
                r.control_points,
                limits.control_points,
            ),
            (
                "output.samples".to_string(),
                "samples",
                r.samples,
                limits.samples,
            ),
            (work, "control-point steps", r.work, limits.work),
            (
                memory,
                "bytes of memory",
                r.memory_bytes,
                limits.memory_bytes,
            ),
        ];
        for (field, what, estimate, limit) in checks {
            if estimate.is_nan() || estimate > limit {
                return Err(Error::TooLarge {
                    field,
                    what,
                    estimate,
                    limit,
                });
            }
        }
        Ok(())
    }

    /// Refuses a run whose memory estimate exceeds this machine's physical memory
    /// (whatever the limits: it could only abort).
    pub fn check_memory(&self) -> Result<(), Error> {
        let r = self.resources();
        let available = physical_memory().unwrap_or(UNKNOWN_MEMORY);
        if r.memory_bytes.is_nan() || r.memory_bytes > available {
            return Err(Error::OutOfMemory {
                field: self.memory_field(&r),
                estimate: r.memory_bytes,
                available,
            });
        }
        Ok(())
    }

    /// This scene with `count` ensemble members (a shard's share), for its estimates;
    /// the scene itself without `[ensemble]`.
    pub fn with_member_count(&self, count: usize) -> Scene {
        let mut sized = self.clone();
        if let Some(e) = &mut sized.ensemble {
            e.count = count;
        }
        sized
    }

    /// Memory that grows with each step of a member, bytes.
    fn bytes_per_step(&self) -> f64 {
        BYTES_PER_STEP + BYTES_PER_PROBE_STEP * self.output.probes.len() as f64
    }

    /// `fields`, times `ensemble.count` for an ensemble.
    fn per_member(&self, fields: &str) -> String {
        match &self.ensemble {
            Some(_) => format!("ensemble.count × {fields}"),
            None => fields.to_string(),
        }
    }

    /// The fields behind the largest part of the memory estimate.
    fn memory_field(&self, r: &Resources) -> String {
        let parts = [
            (BYTES_PER_SAMPLE * r.samples, "output.samples"),
            (
                r.members * BYTES_PER_CONTROL_POINT * r.control_points,
                "rod.control_points",
            ),
            (
                r.members * BYTES_PER_CONTACT_SAMPLE * r.contact_samples,
                "rod.radius",
            ),
            (
                r.members * r.steps * self.bytes_per_step(),
                "solver.duration / solver.dt",
            ),
        ];
        let (_, field) = parts
            .iter()
            .fold(parts[0], |a, &b| if b.0 > a.0 { b } else { a });
        match field {
            "output.samples" => field.to_string(),
            _ => self.per_member(field),
        }
    }
}

/// Total physical memory, bytes, where the system says (Linux: `/proc/meminfo`).
fn physical_memory() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemTotal:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024.0)
}
