//! Running a scene to its end and collecting the result that `splinerod run` prints and
//! writes as JSON.

use crate::estimate::{ErrorEstimation, EstimateOutput};
use crate::knot_track::KnotTrack;
use crate::observe::{Frame, Observer};
use crate::scene::{MemberSummary, Method, Scene};
use crate::{Error, RodSystem, StepReport};
use nalgebra::Vector3;
use serde::Serialize;
use splinerod_core::Real;
use splinerod_energies::ContactSummary;
use splinerod_integrators::{StaticSolver, StepStats};
use std::collections::BTreeMap;
use std::time::Instant;

/// Positions of evenly spaced material points at the end.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Samples {
    /// Material coordinates, fractions of the rest length.
    pub s: Vec<Real>,
    /// Their positions, m.
    pub positions: Vec<[Real; 3]>,
    /// Axial tension there, N (the stretching energy's tension field; absent without one).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub tension: Vec<Real>,
}

/// The trajectory of one material point.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Probe {
    /// Material coordinate, fraction of the rest length.
    pub s: Real,
    /// Times, s (the initial state first).
    pub t: Vec<Real>,
    /// Positions at those times, m.
    pub positions: Vec<[Real; 3]>,
}

/// Solver counters summed over the run.
#[derive(Debug, Clone, Copy, Default, Serialize, PartialEq)]
pub struct SolverTotals {
    /// Newton iterations (numeric factorisations).
    pub newton_iterations: usize,
    /// Symbolic analyses.
    pub symbolic_analyses: usize,
    /// Line-search step reductions.
    pub line_search_cuts: usize,
    /// Steps whose Newton iterations did not reach the tolerance (only with
    /// `solver.accept_unconverged = true`; otherwise such a step is split).
    pub unconverged_steps: usize,
    /// Integrator steps accepted (sub-steps; equals `steps` when none was split).
    pub substeps: usize,
    /// Sub-steps rolled back and retried shorter.
    pub rejected_steps: usize,
    /// Shortest accepted sub-step, s (`null` for a static solve).
    pub smallest_dt: Option<Real>,
    /// Pseudo-transient continuation steps of a static solve whose Newton failed.
    pub continuation_steps: usize,
    /// Multiplier updates of an inextensible rod (static: until the mean strain of every
    /// tension function is below 1e-12; dynamic: one per step).
    pub multiplier_updates: usize,
}

/// Contact over the run (scenes with `[contact]`).
#[derive(Debug, Clone, Copy, Default, Serialize, PartialEq)]
pub struct ContactStats {
    /// Smallest (centre-line distance between touching parts) / (2 · radius) seen at the
    /// start or at the end of any step; `null` if nothing came within the penalty's reach.
    pub min_clearance_ratio: Option<Real>,
    /// Most contacts at once.
    pub max_pairs: usize,
}

impl ContactStats {
    /// Folds in one contact summary of a rod of radius `radius`.
    pub(crate) fn add(&mut self, summary: &ContactSummary, radius: Real) {
        self.max_pairs = self.max_pairs.max(summary.pairs);
        if let Some(d) = summary.min_distance {
            let ratio = d / (2.0 * radius);
            self.min_clearance_ratio =
                Some(self.min_clearance_ratio.map_or(ratio, |r| r.min(ratio)));
        }
    }
}

/// Everything `splinerod run` reports.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RunResult {
    /// Simulated time at the end, s.
    pub time: Real,
    /// Time steps taken (0 for a static solve).
    pub steps: usize,
    /// Control points at the end.
    pub control_points: usize,
    /// Wall time of the solve, s.
    pub wall_seconds: Real,
    /// End positions of evenly spaced material points.
    pub samples: Samples,
    /// Trajectories of the probed material points.
    pub probes: Vec<Probe>,
    /// Final energies, J: `kinetic` and one entry per energy term (`stretch`, `gravity`).
    pub energy: BTreeMap<String, Real>,
    /// Final knot vector, fractions of the rest length.
    pub knots: Vec<Real>,
    /// Solver counters.
    pub solver: SolverTotals,
    /// Forces the pins exert on the rod at the end, N (static solves only).
    pub pin_forces: Vec<[Real; 3]>,
    /// Mechanically independent pieces at the end (1 + the number of cuts).
    pub pieces: usize,
    /// `[t, n]`: the initial number of control points and every change of it.
    pub control_points_history: Vec<[Real; 2]>,
    /// Median wall time of one step (integration and adaptivity), s; 0 for a static solve.
    /// For an ensemble: of one step of the whole ensemble.
    pub median_step_seconds: Real,
    /// Per-member summaries of an `[ensemble]` run (absent otherwise); the other fields
    /// then describe member 0, except `wall_seconds` and `solver` (the whole ensemble).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ensemble: Vec<MemberSummary>,
    /// Contact statistics (absent without `[contact]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactStats>,
    /// Tightness of the knot over time (scenes with `[rod.overhand]` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub knot: Option<KnotTrack>,
    /// The error estimate (tolerance-driven `[adaptivity]`, or `output.error_estimate`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adaptivity: Option<EstimateOutput>,
}

/// What a run accumulated besides the final state.
pub(crate) struct Tally {
    pub(crate) time: Real,
    pub(crate) steps: usize,
    pub(crate) wall: Real,
    pub(crate) solver: SolverTotals,
    pub(crate) probes: Vec<Probe>,
    pub(crate) pin_forces: Vec<Vector3<Real>>,
    pub(crate) history: Vec<[Real; 2]>,
    pub(crate) step_seconds: Vec<Real>,
    pub(crate) contact: Option<ContactStats>,
    pub(crate) knot: Option<KnotTrack>,
    pub(crate) estimates: Option<EstimateOutput>,
}

impl Tally {
    pub(crate) fn new(system: &RodSystem, probes: Vec<Probe>) -> Self {
        Self {
            time: 0.0,
            steps: 0,
            wall: 0.0,
            solver: SolverTotals::default(),
            probes,
            pin_forces: Vec::new(),
            history: vec![[0.0, system.rod.len() as Real]],
            step_seconds: Vec::new(),
            contact: None,
            knot: None,
            estimates: None,
        }
    }

    /// Folds in the contacts of `system` now (no-op without contact).
    pub(crate) fn contact(&mut self, system: &RodSystem) -> Result<(), Error> {
        if let Some(c) = &system.contact {
            let summary = c.summary(&system.rod)?;
            self.contact_summary(&summary, c.params().radius);
        }
        Ok(())
    }

    fn contact_summary(&mut self, summary: &ContactSummary, radius: Real) {
        self.contact.get_or_insert_default().add(summary, radius);
    }

    /// Adds one step's solver counters.
    pub(crate) fn add(&mut self, report: &StepReport) {
        let totals = &mut self.solver;
        totals.newton_iterations += report.solver.newton_iterations;
        totals.symbolic_analyses += report.solver.symbolic_analyses;
        totals.line_search_cuts += report.solver.line_search_cuts;
        totals.unconverged_steps += usize::from(!report.solver.converged);
        totals.substeps += report.substeps.substeps;
        totals.rejected_steps += report.substeps.rejected;
        let h = report.substeps.smallest_dt;
        totals.smallest_dt = Some(totals.smallest_dt.map_or(h, |s| s.min(h)));
    }

    /// Adds one step's counters and contact summary (`radius` of the rod, m).
    pub(crate) fn add_step(&mut self, report: &StepReport, radius: Real) {
        self.add(report);
        if let Some(summary) = &report.contact {
            self.contact_summary(summary, radius);
        }
    }

    /// Appends the probed material points of `system` at time `t`.
    pub(crate) fn probe(
        &mut self,
        scene: &Scene,
        system: &RodSystem,
        t: Real,
    ) -> Result<(), Error> {
        for probe in &mut self.probes {
            probe.t.push(t);
            let p = system.rod.point(scene.material_coordinate(probe.s))?;
            probe.positions.push(p.into());
        }
        Ok(())
    }

    /// Records the control-point count at time `t` if it changed.
    pub(crate) fn count(&mut self, t: Real, n: usize) {
        if self.history.last().is_some_and(|h| h[1] != n as Real) {
            self.history.push([t, n as Real]);
        }
    }
}

/// Runs `scene` to its end.
pub fn run(scene: &Scene) -> Result<RunResult, Error> {
    run_observed(scene, &mut [])
}

/// Runs `scene` to its end, showing every step to `observers` (in order).
pub fn run_observed(
    scene: &Scene,
    observers: &mut [&mut dyn Observer],
) -> Result<RunResult, Error> {
    match (scene.solver.method, &scene.ensemble) {
        (Method::Static, _) => run_static(scene, observers),
        (_, Some(_)) => crate::run_ensemble::run_ensemble(scene, observers),
        _ => run_dynamic(scene, observers),
    }
}

pub(crate) fn frame<'a>(
    scene: &'a Scene,
    system: &'a RodSystem,
    time: Real,
    step: usize,
) -> Frame<'a> {
    let total_steps = scene.step_count();
    Frame {
        scene,
        system,
        time,
        step,
        total_steps,
    }
}

pub(crate) fn notify_finish(
    observers: &mut [&mut dyn Observer],
    frame: &Frame<'_>,
    result: RunResult,
) -> Result<RunResult, Error> {
    for o in observers.iter_mut() {
        o.finish(frame, &result)?;
    }
    Ok(result)
}

fn run_static(scene: &Scene, observers: &mut [&mut dyn Observer]) -> Result<RunResult, Error> {
    let mut system = scene.build_system()?;
    let l = scene.rod.rest_length;
    for cut in &scene.cuts {
        system.rod.cut(cut.at * l)?;
    }
    // Grabs pull to their final targets.
    system.time = scene.grabs.iter().map(|g| g.end_time).fold(0.0, Real::max);
    let (t, RodSystem { rod, grabs, .. }) = (system.time, &mut system);
    for g in grabs.iter_mut() {
        g.update(t, rod)?;
    }
    let mut tally = Tally::new(&system, probes_at_start(scene, &system)?);
    tally.contact(&system)?;
    for o in observers.iter_mut() {
        o.start(&frame(scene, &system, 0.0, 0))?;
    }
    let mut solver = StaticSolver::new(scene.static_params())?;
    let start = Instant::now();
    let (stats, multiplier_updates) = solve_with_multipliers(&mut solver, &mut system)?;
    tally.wall = start.elapsed().as_secs_f64();
    tally.solver = SolverTotals {
        newton_iterations: stats.newton_iterations,
        symbolic_analyses: stats.symbolic_analyses,
        line_search_cuts: stats.line_search_cuts,
        continuation_steps: solver.continuation_steps(),
        multiplier_updates,
        ..SolverTotals::default()
    };
    tally.pin_forces = solver.pin_forces().to_vec();
    tally.contact(&system)?;
    if scene.output.error_estimate {
        let grabs = system.grabs.iter().map(|g| g.spring.at).collect::<Vec<_>>();
        let mut estimation = ErrorEstimation::default();
        let e = estimation.run(&system, &grabs, &[], 0.0)?;
        let out = tally.estimates.get_or_insert_default();
        out.record(0.0, e.control_points, e.max(), true);
    }
    let result = finish(scene, &system, tally)?;
    notify_finish(observers, &frame(scene, &system, 0.0, 0), result)
}

/// Largest mean strain an inextensible rod's static equilibrium may keep.
const INEXTENSIBLE_TOLERANCE: Real = 1e-12;

/// Multiplier updates a static solve may take to reach it.
const MAX_MULTIPLIER_UPDATES: usize = 40;

/// The static solve, repeated with updated multipliers while a constraint (the
/// inextensible rod) is violated by more than [`INEXTENSIBLE_TOLERANCE`]; the summed
/// counters and the number of updates.
fn solve_with_multipliers(
    solver: &mut StaticSolver,
    system: &mut RodSystem,
) -> Result<(StepStats, usize), Error> {
    let mut stats = solver.solve(system)?;
    for updates in 0..MAX_MULTIPLIER_UPDATES {
        let violation = system.update_multipliers(true);
        if violation <= INEXTENSIBLE_TOLERANCE {
            return Ok((stats, updates));
        }
        let more = solver.solve(system)?;
        stats.add_counts(&more);
    }
    let violation = system.update_multipliers(true);
    if violation <= INEXTENSIBLE_TOLERANCE {
        return Ok((stats, MAX_MULTIPLIER_UPDATES));
    }
    Err(Error::Scene(format!(
        "rod.stretch_stiffness = \"inextensible\": a mean strain of {violation:.3e} remains \
         after {MAX_MULTIPLIER_UPDATES} multiplier updates (tolerance {INEXTENSIBLE_TOLERANCE:e})"
    )))
}

fn run_dynamic(scene: &Scene, observers: &mut [&mut dyn Observer]) -> Result<RunResult, Error> {
    let mut sim = scene.build()?;
    let dt = scene.solver.dt.unwrap_or_default();
    let mut tally = Tally::new(&sim.system, probes_at_start(scene, &sim.system)?);
    let mut cuts = CutSchedule::new(scene);
    tally.contact(&sim.system)?;
    if scene.rod.overhand.is_some() {
        let mut track = KnotTrack::default();
        track.record(&sim.system, 0.0, true)?;
        tally.knot = Some(track);
    }
    let radius = scene.rod.radius.unwrap_or_default();
    for o in observers.iter_mut() {
        o.start(&frame(scene, &sim.system, 0.0, 0))?;
    }
    let start = Instant::now();
    for _ in 0..scene.step_count() {
        let step_start = Instant::now();
        let report = sim.step(dt)?;
        tally.add_step(&report, radius);
        if let (Some(error), Some(e)) = (report.error_estimate, sim.error_estimate()) {
            let changed = report.adapt.inserted + report.adapt.removed > 0;
            let out = tally.estimates.get_or_insert_default();
            out.record(sim.time, e.control_points, error, changed);
        }
        if let Some(track) = &mut tally.knot {
            track.record(&sim.system, sim.time, false)?;
        }
        cuts.apply(sim.time, dt, |s| sim.cut(s))?;
        let wall = step_start.elapsed().as_secs_f64();
        tally.step_seconds.push(wall);
        tally.count(sim.time, sim.system.rod.len());
        tally.probe(scene, &sim.system, sim.time)?;
        let now = frame(scene, &sim.system, sim.time, sim.steps);
        for o in observers.iter_mut() {
            o.step(&now, &report, wall)?;
        }
    }
    tally.wall = start.elapsed().as_secs_f64();
    if let Some(e) = sim.estimate_now()? {
        let (n, error) = (e.control_points, e.max());
        let out = tally.estimates.get_or_insert_default();
        out.record(sim.time, n, error, true);
    }
    if let Some(track) = &mut tally.knot {
        track.record(&sim.system, sim.time, true)?;
    }
    (tally.time, tally.steps) = (sim.time, sim.steps);
    tally.pin_forces = sim.integrator.pin_forces();
    let result = finish(scene, &sim.system, tally)?;
    notify_finish(
        observers,
        &frame(scene, &sim.system, sim.time, sim.steps),
        result,
    )
}

pub(crate) fn probes_at_start(scene: &Scene, system: &RodSystem) -> Result<Vec<Probe>, Error> {
    scene
        .output
        .probes
        .iter()
        .map(|&s| {
            let p = system.rod.point(scene.material_coordinate(s))?;
            Ok(Probe {
                s,
                t: vec![0.0],
                positions: vec![p.into()],
            })
        })
        .collect()
}

pub(crate) fn finish(
    scene: &Scene,
    system: &RodSystem,
    mut tally: Tally,
) -> Result<RunResult, Error> {
    let rod = &system.rod;
    let m = scene.output.samples;
    let s: Vec<Real> = (0..m).map(|k| k as Real / (m - 1) as Real).collect();
    let positions = s
        .iter()
        .map(|&f| rod.point(scene.material_coordinate(f)).map(Into::into))
        .collect::<Result<_, _>>()?;
    let tension = system.tension(
        &s.iter()
            .map(|&f| scene.material_coordinate(f))
            .collect::<Vec<_>>(),
    );
    let mut energy = BTreeMap::from([("kinetic".to_string(), rod.kinetic_energy())]);
    energy.extend(system.energy_breakdown());
    let l = rod.material().rest_length;
    Ok(RunResult {
        time: tally.time,
        steps: tally.steps,
        control_points: rod.len(),
        wall_seconds: tally.wall,
        samples: Samples {
            s,
            positions,
            tension,
        },
        probes: tally.probes,
        energy,
        knots: rod.basis().knots().iter().map(|k| k / l).collect(),
        solver: tally.solver,
        pin_forces: tally.pin_forces.iter().map(|f| (*f).into()).collect(),
        pieces: rod.pieces(),
        control_points_history: tally.history,
        median_step_seconds: median(&mut tally.step_seconds),
        ensemble: Vec::new(),
        contact: tally.contact,
        knot: tally.knot,
        adaptivity: tally.estimates,
    })
}

/// The scene's cuts in time order, applied once each.
pub(crate) struct CutSchedule {
    cuts: Vec<(Real, Real)>,
    next: usize,
}

impl CutSchedule {
    /// The cuts of `scene` (material coordinates in m), sorted by time.
    pub(crate) fn new(scene: &Scene) -> Self {
        let mut cuts: Vec<_> = scene
            .cuts
            .iter()
            .map(|c| (c.time, scene.material_coordinate(c.at)))
            .collect();
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
        Self { cuts, next: 0 }
    }

    /// Calls `cut` for every cut due by `time` (a step of `dt` just ended) not yet made.
    pub(crate) fn apply(
        &mut self,
        time: Real,
        dt: Real,
        mut cut: impl FnMut(Real) -> Result<(), Error>,
    ) -> Result<(), Error> {
        while self.next < self.cuts.len() && self.cuts[self.next].0 <= time + 1e-9 * dt {
            cut(self.cuts[self.next].1)?;
            self.next += 1;
        }
        Ok(())
    }
}

/// Median of `values` (0 if empty); reorders them.
pub(crate) fn median(values: &mut [Real]) -> Real {
    if values.is_empty() {
        return 0.0;
    }
    let mid = values.len() / 2;
    *values.select_nth_unstable_by(mid, Real::total_cmp).1
}
