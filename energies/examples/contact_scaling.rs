//! Timing of the self-contact detection and assembly of [`Contact`] on a tightly coiled
//! rod with 100 to 100 000 knot spans: a cubic clamped B-spline helix whose pitch is
//! `1.8 r` (consecutive turns overlap by `0.2 r`, so every part of the rod is in contact
//! with the turns above and below it). The spans per turn and the rod radius relative
//! to the span length are fixed, so the work per span is the same for every size and
//! linear scaling shows as flat figures per span.
//!
//! For each size, every repetition moves the control points by a tiny deterministic
//! perturbation (so the detection's position cache is invalidated, as between two
//! Newton iterates) and times, in order:
//!
//! - `energy`: `Contact::energy`, i.e. the full detection as the energy evaluation runs
//!   it (sample placement, segment boxes, sort and sweep, sample pairs) plus the
//!   penalty sum;
//! - `grad`: `Contact::add_gradient` on that (cached) detection;
//! - `hess`: `Contact::add_hessian` into a `BlockBanded` (reset before, untimed);
//! - `summary`: `Contact::summary`, the closest points on the curve of every candidate
//!   segment pair (not needed by the energy; for reporting and refinement).
//!
//! `step` is `energy + grad + hess`, the contact cost of one Newton iterate. Times are
//! means over the repetitions, in ns per knot span: at least 3 repetitions and about
//! 0.3 s per size, but fewer (at least one) when one more would take a size past 50 s
//! (2 for 100 000 spans on a typical machine, about 25 s each). `cold` is the first
//! detection of a new `Contact` (segments, samples and their basis rows, built once
//! per basis), timed once. The growth ratios compare the time per span with that of
//! the previous size (1.00 = linear).
//!
//! Run with `cargo run --release -p splinerod-energies --example contact_scaling`.

use nalgebra::Vector3;
use splinerod_core::basis::greville;
use splinerod_core::{BSplineSpace, BlockBanded, CoreError, HessianKind, Material, Real, Rod};
use splinerod_energies::{Contact, ContactParams, ContactSummary, Energy};
use std::f64::consts::TAU;
use std::hint::black_box;
use std::time::{Duration, Instant};

/// Coil radius, m.
const COIL_RADIUS: f64 = 0.05;
/// Knot spans per turn.
const SPANS_PER_TURN: usize = 16;
/// Rod radius `r`, m: about 0.2 span lengths (span ≈ 2π · 0.05 / 16 ≈ 0.0196 m).
const ROD_RADIUS: f64 = 0.004;
/// Rise per turn, m: `1.8 r`, below the contact distance `2r`.
const PITCH: f64 = 1.8 * ROD_RADIUS;
/// Penalty stiffness, N/m (irrelevant to the cost).
const STIFFNESS: f64 = 1.0e3;
/// Amplitude of the per-repetition perturbation of the control points, m.
const JITTER: f64 = 1.0e-7 * ROD_RADIUS;
/// Least total timed work per size.
const MIN_TOTAL: Duration = Duration::from_millis(300);
/// Least repetitions per size.
const MIN_REPS: usize = 3;
/// Fewer repetitions than [`MIN_REPS`] (but at least one) when one more would take the
/// timed loop of a size past this: the largest size takes about 25 s per repetition.
const BUDGET: Duration = Duration::from_secs(50);

/// A cubic clamped uniform rod with `n` spans whose control points lie on the helix
/// (curve parameter = rest arclength).
fn helix(n: usize) -> Result<Rod, CoreError> {
    let turns = n as f64 / SPANS_PER_TURN as f64;
    let length = turns * (TAU * COIL_RADIUS).hypot(PITCH);
    let basis = BSplineSpace::clamped_uniform(3, n + 3, length)?;
    let positions = (0..n + 3)
        .map(|i| {
            let u = greville(&basis, i) / length;
            let a = TAU * turns * u;
            Vector3::new(
                COIL_RADIUS * a.cos(),
                COIL_RADIUS * a.sin(),
                PITCH * turns * u,
            )
        })
        .collect();
    let material = Material {
        rest_length: length,
        linear_density: 0.01,
    };
    Rod::new(material, Box::new(basis), positions)
}

/// Moves the control points of `rod` from `base` by a tiny deterministic offset that
/// differs between consecutive repetitions.
fn perturb(rod: &mut Rod, base: &[Vector3<f64>], rep: usize) {
    let sign = if rep % 2 == 0 { 1.0 } else { -1.0 };
    for (i, (q, b)) in rod.positions.iter_mut().zip(base).enumerate() {
        let t = 0.7 * i as f64 + 0.3 * rep as f64;
        *q = b + Vector3::new(t.sin(), t.cos(), (1.3 * t).sin()) * (sign * JITTER);
    }
}

/// Mean times of one size.
#[derive(Default)]
struct Times {
    cold: Duration,
    energy: Duration,
    gradient: Duration,
    hessian: Duration,
    summary: Duration,
    reps: usize,
}

impl Times {
    fn total(&self) -> Duration {
        self.energy + self.gradient + self.hessian + self.summary
    }

    /// Mean ns per span of a summed duration.
    fn per_span(&self, d: Duration, n: usize) -> f64 {
        d.as_secs_f64() * 1e9 / (self.reps as f64 * n as f64)
    }

    /// Mean ns per span of `[energy, grad, hess, summary, step]`.
    fn row(&self, n: usize) -> [f64; 5] {
        [
            self.per_span(self.energy, n),
            self.per_span(self.gradient, n),
            self.per_span(self.hessian, n),
            self.per_span(self.summary, n),
            self.per_span(self.energy + self.gradient + self.hessian, n),
        ]
    }
}

/// Times `f` once, adding its duration to `total`.
fn timed<T>(total: &mut Duration, f: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let value = black_box(f());
    *total += start.elapsed();
    value
}

/// Everything measured for `n` spans.
struct Run {
    n: usize,
    segments: usize,
    summary: ContactSummary,
    far_blocks: usize,
    times: Times,
}

fn measure(n: usize) -> Result<Run, CoreError> {
    let mut rod = helix(n)?;
    let params = ContactParams::new(ROD_RADIUS, STIFFNESS)?;
    let contact = Contact::new(params)?;
    // One piece: the rest length divided into segments of at most `segment`.
    let segments = (rod.material().rest_length / params.segment)
        .ceil()
        .max(1.0) as usize;
    let base = rod.positions.clone();
    let mut gradient = vec![Vector3::zeros(); rod.len()];
    let bandwidth = rod.basis().degree();
    let mut hessian = BlockBanded::zeros(rod.len(), bandwidth);

    let mut times = Times::default();
    let e = timed(&mut times.cold, || contact.energy(&rod));
    if !e.is_finite() {
        return Err(CoreError::InvalidParameter {
            name: "contact energy",
            value: e,
            reason: "is not finite on the helix",
        });
    }
    // Warm-up: the Hessian's list of far blocks at its final size (the detection's
    // buffers are sized by the cold call; the gradient allocates nothing and the
    // closest points' buffer is small next to their cost).
    contact.add_hessian(&rod, HessianKind::Definite, &mut hessian);

    let mut summary = None;
    let started = Instant::now();
    loop {
        let done = times.reps >= MIN_REPS && times.total() >= MIN_TOTAL;
        // Would one more repetition take the loop past the budget? (The largest size.)
        let next = started.elapsed() + times.total() / times.reps.max(1) as u32;
        if done || (times.reps > 0 && next > BUDGET) {
            break;
        }
        perturb(&mut rod, &base, times.reps);
        gradient.iter_mut().for_each(|g| *g = Vector3::zeros());
        hessian.reset(rod.len(), bandwidth);
        timed(&mut times.energy, || contact.energy(&rod));
        timed(&mut times.gradient, || {
            contact.add_gradient(&rod, &mut gradient)
        });
        let kind = HessianKind::Definite;
        timed(&mut times.hessian, || {
            contact.add_hessian(&rod, kind, &mut hessian)
        });
        summary = Some(timed(&mut times.summary, || contact.summary(&rod))?);
        times.reps += 1;
    }
    Ok(Run {
        n,
        segments,
        summary: summary.expect("at least one repetition"),
        far_blocks: hessian.far_blocks().len(),
        times,
    })
}

fn main() -> Result<(), CoreError> {
    let params = ContactParams::new(ROD_RADIUS, STIFFNESS)?;
    println!(
        "helix: coil radius {COIL_RADIUS} m, {SPANS_PER_TURN} spans/turn, rod radius r = \
         {ROD_RADIUS} m, pitch {PITCH:.4} m = 1.8 r; segment {:.2} r, spacing {:.2} r, reach \
         {:.2} r, exclusion {:.2} r",
        params.segment / ROD_RADIUS,
        params.spacing / ROD_RADIUS,
        params.reach() / ROD_RADIUS,
        params.exclusion / ROD_RADIUS,
    );
    println!();
    println!(
        "{:>7} {:>7} {:>8} {:>8} {:>5} {:>8} {:>6} {:>4} | ns/span: {:>7} {:>7} {:>7} {:>7} \
         {:>7} {:>7} | {:>6}",
        "spans",
        "segs",
        "cands",
        "touch",
        "c/seg",
        "far",
        "dmin/r",
        "reps",
        "cold",
        "energy",
        "grad",
        "hess",
        "summary",
        "step",
        "growth"
    );
    let mut runs: Vec<Run> = Vec::new();
    for n in [100, 1_000, 10_000, 100_000] {
        let run = measure(n)?;
        let t = &run.times;
        let row = t.row(n);
        let growth = runs.last().map(|prev| row[4] / prev.times.row(prev.n)[4]);
        let s = &run.summary;
        println!(
            "{:>7} {:>7} {:>8} {:>8} {:>5.2} {:>8} {:>6.3} {:>4} | ns/span: {:>7.0} {:>7.0} \
             {:>7.0} {:>7.0} {:>7.0} {:>7.0} | {:>6}",
            n,
            run.segments,
            s.candidates,
            s.pairs,
            s.candidates as f64 / run.segments as f64,
            run.far_blocks,
            s.min_distance.map_or(Real::NAN, |d| d / ROD_RADIUS),
            t.reps,
            t.cold.as_secs_f64() * 1e9 / n as f64,
            row[0],
            row[1],
            row[2],
            row[3],
            row[4],
            growth.map_or("-".to_string(), |g| format!("{g:.2}")),
        );
        runs.push(run);
    }
    println!();
    println!("growth of the time per span, relative to the previous size (1.00 = linear):");
    println!(
        "{:>7} | {:>7} {:>7} {:>7} {:>7} {:>7}",
        "spans", "energy", "grad", "hess", "summary", "step"
    );
    for pair in runs.windows(2) {
        let (a, b) = (pair[0].times.row(pair[0].n), pair[1].times.row(pair[1].n));
        let g: Vec<String> = (0..5).map(|k| format!("{:>7.2}", b[k] / a[k])).collect();
        println!("{:>7} | {}", pair[1].n, g.join(" "));
    }
    Ok(())
}
