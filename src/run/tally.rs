//! What each member of a run records after every stage ([`Tally`]: solver counters,
//! probes, the control-point history, contact statistics, knot tracking, error
//! estimates, stage times) and the scene's cuts it makes when they fall due
//! ([`CutSchedule`]).

use crate::run::bodies::BodyTrack;
use crate::run::knot_track::KnotTrack;
use crate::run::totals::{ContactStats, SolverTotals};
use crate::scene::Scene;
use crate::world::estimate::EstimateOutput;
use crate::{Error, RodSystem, Simulation, StageTimes, StepReport};
use splinerod_adaptivity::Continuity;
use splinerod_core::Real;
use splinerod_energies::EnergySummary;
use std::time::Instant;

/// The trajectory of one material point.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize, PartialEq)]
pub struct Probe {
    /// The rod named by the probe's entry (`None`, JSON `null`: a plain fraction, on the
    /// first rod). Always written: checkpoints are a format without field names.
    pub rod: Option<String>,
    /// Material coordinate, fraction of that rod's rest length.
    pub s: Real,
    /// Times, s (the initial state first).
    pub t: Vec<Real>,
    /// Positions at those times, m.
    pub positions: Vec<[Real; 3]>,
}

/// What a member accumulated besides its final state.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct Tally {
    pub(crate) solver: SolverTotals,
    pub(crate) probes: Vec<Probe>,
    pub(crate) bodies: Vec<BodyTrack>,
    pub(crate) history: Vec<[Real; 2]>,
    pub(crate) contact: Option<ContactStats>,
    pub(crate) knot: Option<KnotTrack>,
    pub(crate) estimates: Option<EstimateOutput>,
    /// Wall time of each stage, summed over the run.
    pub(crate) stages: StageTimes,
    pub(crate) cuts: CutSchedule,
    /// Recorded states with a hinge ([`Continuity::hinges`]): a corner on a rod with
    /// bending or twist. Zero unless a knot was inserted by hand.
    pub(crate) hinge_steps: usize,
    /// Where the scene allows corners (built at the first record; not saved).
    #[serde(skip)]
    continuity: Option<Continuity>,
}

impl Tally {
    /// The tally of a member of `scene` at its start (its energies' summary included).
    pub(crate) fn new(scene: &Scene, system: &RodSystem) -> Result<Self, Error> {
        let mut tally = Self {
            solver: SolverTotals::default(),
            probes: probes_at_start(scene, system)?,
            bodies: crate::run::bodies::tracks_at_start(system),
            history: vec![[0.0, system.rod.distinct_len() as Real]],
            contact: None,
            knot: None,
            estimates: None,
            stages: StageTimes::default(),
            cuts: CutSchedule::new(scene)?,
            hinge_steps: 0,
            continuity: None,
        };
        tally.summary(&system.summary()?);
        if scene.rod.overhand.is_some() {
            let mut track = KnotTrack::default();
            track.record(system, 0.0, true)?;
            tally.knot = Some(track);
        }
        Ok(tally)
    }

    /// Folds in the energies' summary of one state.
    fn summary(&mut self, summary: &EnergySummary) {
        if let Some(c) = &summary.contact {
            self.contact.get_or_insert_default().add(c);
        }
    }

    /// Records one stage's report and the state after it; makes the cuts now due.
    /// Returns the wall time it took.
    pub(crate) fn record(
        &mut self,
        scene: &Scene,
        sim: &mut Simulation,
        report: &StepReport,
        dt: Real,
    ) -> Result<Real, Error> {
        let start = Instant::now();
        self.solver.add(report, dt > 0.0);
        self.summary(&report.energies);
        if let (Some(_), Some(e)) = (report.error_estimate, sim.error_estimate()) {
            let changed = report.adapt.inserted + report.adapt.removed > 0;
            let out = self.estimates.get_or_insert_default();
            out.record(sim.time, e, changed);
        }
        if let Some(track) = &mut self.knot {
            track.record(&sim.system, sim.time, false)?;
        }
        let time = sim.time;
        self.cuts.apply(time, dt, |s| sim.cut(s))?;
        self.count(sim.time, sim.system.rod.distinct_len());
        let continuity = self.continuity.get_or_insert_with(|| scene.continuity());
        if continuity.hinges(&sim.system.rod) > 0 {
            self.hinge_steps += 1;
        }
        self.probe(scene, &sim.system, sim.time)?;
        crate::run::bodies::record_simulation(&mut self.bodies, sim);
        Ok(start.elapsed().as_secs_f64())
    }

    /// The final estimate and knot record of a member at the end of its run.
    pub(crate) fn close(&mut self, sim: &mut Simulation) -> Result<(), Error> {
        let time = sim.time;
        if let Some(e) = sim.estimate_now()? {
            let out = self.estimates.get_or_insert_default();
            out.record(time, e, true);
        }
        if let Some(track) = &mut self.knot {
            track.record(&sim.system, sim.time, true)?;
        }
        Ok(())
    }

    /// Appends the probed material points of `system` at time `t`.
    fn probe(&mut self, scene: &Scene, system: &RodSystem, t: Real) -> Result<(), Error> {
        for (probe, spec) in self.probes.iter_mut().zip(&scene.output.probes) {
            probe.t.push(t);
            let p = system.rod.point(scene.probe_coordinate(spec)?)?;
            probe.positions.push(p.into());
        }
        Ok(())
    }

    /// Records the control-point count at time `t` if it changed.
    fn count(&mut self, t: Real, n: usize) {
        if self.history.last().is_some_and(|h| h[1] != n as Real) {
            self.history.push([t, n as Real]);
        }
    }
}

/// Each probed material point of `scene` where `system` starts, at time 0.
fn probes_at_start(scene: &Scene, system: &RodSystem) -> Result<Vec<Probe>, Error> {
    scene
        .output
        .probes
        .iter()
        .map(|spec| {
            let p = system.rod.point(scene.probe_coordinate(spec)?)?;
            Ok(Probe {
                rod: spec.rod.clone(),
                s: spec.at,
                t: vec![0.0],
                positions: vec![p.into()],
            })
        })
        .collect()
}

/// The scene's cuts in time order, applied once each.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
pub(crate) struct CutSchedule {
    cuts: Vec<(Real, Real)>,
    next: usize,
}

impl CutSchedule {
    /// The cuts of `scene` (material coordinates in m), sorted by time.
    pub(crate) fn new(scene: &Scene) -> Result<Self, Error> {
        let mut cuts = scene
            .cuts
            .iter()
            .map(|c| Ok((c.time, scene.entry_coordinate(c.rod.as_deref(), c.at)?)))
            .collect::<Result<Vec<_>, Error>>()?;
        cuts.sort_by(|a, b| a.0.total_cmp(&b.0));
        Ok(Self { cuts, next: 0 })
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
