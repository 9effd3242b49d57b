//! The mechanics a [`RodSystem`] gives the error estimator
//! ([`splinerod_adaptivity::estimate`]): on a finer copy of the rod, the residual of the
//! step's equilibrium
//!
//! \\[ \hat r = \nabla \hat E + \hat M (\hat a + \alpha \hat v), \\]
//!
//! with every acting energy (through [`splinerod_energies::Lifecycle::for_finer_rod`]
//! where an energy's data follow the rod's basis or belong to the step), the step's mean acceleration `a = (v₁ − v₀)/Δt` and the damping force mapped
//! exactly onto the finer basis, and zero on coefficients a pin holds.
//!
//! The stiffness is the potential's definite Hessian plus \(2\hat M / t^2\), `t` the
//! simulated time so far: a residual force `r` that has acted for a time `t` moves a
//! mass it is not resisted by elastically by at most `r t² / 2m`, and one that is
//! resisted by at most `K⁻¹ r`. Early in a run (a rod released from a straight, slack
//! start) inertia bounds the estimate; once the motion has lasted, the elastic term
//! does — the equilibrium's spatial error, with the step's acceleration as a load.

use crate::{Error, RodSystem};
use nalgebra::{Matrix3, Vector3};
use serde::Serialize;
use splinerod_adaptivity::estimate::{Corner, SpanError};
use splinerod_adaptivity::{AdaptError, Continuity, ErrorEstimate, Estimator, FineProblem};
use splinerod_core::{
    BlockBanded, CoreError, HessianKind, Real, RefinementOperator, Rod, SavedState,
};
use splinerod_energies::Energy;
use splinerod_integrators::linear::LinearSolver;
use splinerod_integrators::remainder::RemainderCg;

/// The fewest steps a residual is taken to have acted for (the inertial bound's time is
/// at least this many steps).
const MIN_STEPS_ACTING: Real = 20.0;

/// Standard gravity, m/s² (the time scale of the inertial bound).
const STANDARD_GRAVITY: Real = 9.81;

/// The estimator and its scratch state, kept by a [`crate::Simulation`].
#[derive(Debug, Default)]
pub struct ErrorEstimation {
    estimator: Estimator,
    acceleration: Vec<Vector3<Real>>,
    scratch: Scratch,
    schedule: Schedule,
}

/// When estimates are made: every step while the resolution, the interactions or the
/// estimate change or the adapter is not content with it; the interval doubles (up to
/// [`MAX_INTERVAL`]) while none of that happens.
#[derive(Debug, Default)]
struct Schedule {
    /// Steps between estimates now (0 before the first).
    interval: usize,
    /// Steps since the last estimate.
    since: usize,
    /// The knots, interactions and estimate of the last estimate.
    knots: Vec<Real>,
    interactions: Vec<Real>,
    error: Real,
}

/// Most steps between two estimates of a steady rod.
pub const MAX_INTERVAL: usize = 64;

/// An estimate within this fraction of the previous one counts as steady.
const STEADY: Real = 0.25;

/// An estimate below this fraction of the rest length counts as steady whatever it did.
const NEGLIGIBLE: Real = 1e-9;

/// Buffers of the finer problem, kept between estimates.
#[derive(Debug, Default)]
struct Scratch {
    load: Vec<Vector3<Real>>,
    force: Vec<Vector3<Real>>,
    /// Coefficients of the finer rod held by pins.
    held: Vec<usize>,
    flat: Vec<Real>,
    solver: LinearSolver,
    solves: u64,
    /// The correction for a Hessian remainder.
    cg: RemainderCg,
}

impl ErrorEstimation {
    /// Whether an estimate is due after the step just taken (counts the step if not):
    /// the first one, or the rod's knots or the interactions changed since the last,
    /// or the interval has passed. Estimates cost a Newton step on a finer basis, so a
    /// steady run makes one every [`MAX_INTERVAL`] steps at most.
    pub fn due(&mut self, rod: &Rod, interactions: &[Real]) -> bool {
        let s = &mut self.schedule;
        s.since += 1;
        s.interval == 0
            || s.since >= s.interval
            || s.knots != rod.basis().knots()
            || s.interactions != interactions
    }

    /// Records the estimate just made for the schedule. The interval doubles when the
    /// adapter is `content` with it (far within its tolerance; `None`: no adapter), the
    /// knots are the last estimate's and the estimate is steady (within `STEADY` of
    /// the last, or negligible).
    pub fn schedule(&mut self, rod: &Rod, interactions: &[Real], content: Option<bool>) {
        let s = &mut self.schedule;
        let error = self.estimator.estimate.max();
        // Below NEGLIGIBLE · L an estimate is round-off and Newton tolerance, not a trend.
        let negligible = error <= NEGLIGIBLE * rod.material().rest_length;
        let unchanged = negligible || (error - s.error).abs() <= STEADY * s.error;
        let steady = content.unwrap_or(true)
            && unchanged
            && s.interval > 0
            && s.knots == rod.basis().knots();
        s.interval = if steady {
            (2 * s.interval).min(MAX_INTERVAL)
        } else {
            1
        };
        s.since = 0;
        s.error = error;
        s.knots.clear();
        s.knots.extend_from_slice(rod.basis().knots());
        s.interactions.clear();
        s.interactions.extend_from_slice(interactions);
    }

    /// The schedule, the last estimate and the step's acceleration, for a checkpoint.
    pub(crate) fn save(&self) -> SavedState {
        let mut out = SavedState::default();
        let s = &self.schedule;
        out.ints([s.interval as u64, s.since as u64].into_iter());
        out.reals(&s.knots);
        out.reals(&s.interactions);
        out.real(s.error);
        let e = &self.estimator.estimate;
        out.int(e.control_points as u64);
        out.real(e.global);
        let spans = e
            .spans
            .iter()
            .flat_map(|x| [x.start, x.end, x.error, x.midpoint]);
        out.reals(&spans.collect::<Vec<_>>());
        out.reals(
            &e.corners
                .iter()
                .flat_map(|c| [c.at, c.error])
                .collect::<Vec<_>>(),
        );
        out.ints(e.corners.iter().map(|c| c.multiplicity as u64));
        out.vectors(&self.acceleration);
        out
    }

    /// Reads back what [`save`](Self::save) wrote.
    pub(crate) fn load(&mut self, saved: &SavedState) -> Result<(), Error> {
        let bad = || Error::Core(CoreError::StateMismatch("an error estimate"));
        let mut input = saved.reader();
        let s = &mut self.schedule;
        let counts = input.ints()?;
        let [interval, since] = counts else {
            return Err(bad());
        };
        (s.interval, s.since) = (*interval as usize, *since as usize);
        input.reals_into(&mut s.knots)?;
        input.reals_into(&mut s.interactions)?;
        s.error = input.real()?;
        let e = &mut self.estimator.estimate;
        e.control_points = input.index()?;
        e.global = input.real()?;
        let mut xs = Vec::new();
        input.reals_into(&mut xs)?;
        e.spans = xs
            .chunks_exact(4)
            .map(|c| SpanError {
                start: c[0],
                end: c[1],
                error: c[2],
                midpoint: c[3],
            })
            .collect();
        input.reals_into(&mut xs)?;
        let multiplicities = input.ints()?;
        if multiplicities.len() * 2 != xs.len() {
            return Err(bad());
        }
        e.corners = xs
            .chunks_exact(2)
            .zip(multiplicities)
            .map(|(c, &m)| Corner {
                at: c[0],
                error: c[1],
                multiplicity: m as usize,
            })
            .collect();
        input.vectors_into(&mut self.acceleration)?;
        input.finish()?;
        Ok(())
    }

    /// Where the finer copy may repeat an interaction point's knot up to the degree: as
    /// the adapter may ([`Continuity`]).
    pub fn set_continuity(&mut self, continuity: &Continuity) {
        self.estimator.continuity.clone_from(continuity);
    }

    /// The latest estimate.
    pub fn latest(&self) -> &ErrorEstimate {
        &self.estimator.estimate
    }

    /// Estimates the error of `system`'s rod after a step of `dt` seconds that started
    /// with velocities `start` (ignored if its length differs: no inertial load); `dt`
    /// = 0 estimates a static equilibrium (no inertia at all).
    pub fn run(
        &mut self,
        system: &RodSystem,
        interactions: &[Real],
        start: &[Vector3<Real>],
        dt: Real,
    ) -> Result<&ErrorEstimate, Error> {
        let pendulum = (system.rod.material().rest_length / STANDARD_GRAVITY).sqrt();
        // A static equilibrium (no step: `dt` = 0) has no inertial bound.
        let elapsed = if dt > 0.0 {
            system.time.max(MIN_STEPS_ACTING * dt).min(pendulum)
        } else {
            0.0
        };
        let rod = &system.rod;
        self.acceleration.clear();
        if start.len() == rod.len() && dt > 0.0 {
            let a = rod
                .velocities
                .iter()
                .zip(start)
                .map(|(v, v0)| (v - v0) / dt);
            self.acceleration.extend(a);
        }
        let mut problem = Mechanics {
            system,
            acceleration: &self.acceleration,
            scratch: &mut self.scratch,
            elapsed,
        };
        Ok(self.estimator.run(rod, interactions, &mut problem)?)
    }
}

struct Mechanics<'a> {
    system: &'a RodSystem,
    acceleration: &'a [Vector3<Real>],
    scratch: &'a mut Scratch,
    /// Simulated time so far, s (0: no inertial bound, a static estimate).
    elapsed: Real,
}

impl Mechanics<'_> {
    /// Every acting energy, as evaluated on `fine`.
    fn for_each_energy(&self, fine: &Rod, f: impl FnMut(&dyn Energy)) {
        for_each_energy_of(self.system, fine, f);
    }
}

/// Every acting energy of `system`, as evaluated on `fine`.
fn for_each_energy_of(system: &RodSystem, fine: &Rod, mut f: impl FnMut(&dyn Energy)) {
    for e in &system.energies {
        match e
            .capabilities()
            .lifecycle
            .and_then(|l| l.for_finer_rod(fine))
        {
            Some(copy) => f(copy.as_ref()),
            None => f(e.as_ref()),
        }
    }
    system.active_grabs().for_each(&mut f);
}

impl Mechanics<'_> {
    /// [`FineProblem::solve`] with the coefficients `held` kept at zero: the banded
    /// stiffness factorised, and the step corrected for the energies' Hessian remainder
    /// by conjugate gradients preconditioned with it (as Newton does,
    /// [`splinerod_integrators::remainder`]).
    fn solve_held(
        &mut self,
        fine: &Rod,
        stiffness: &mut BlockBanded,
        rhs: &mut [Vector3<Real>],
        held: &[usize],
    ) -> Result<bool, AdaptError> {
        hold(stiffness, held);
        let mut remainder = false;
        self.for_each_energy(fine, |e| {
            let r = e.capabilities().remainder;
            remainder |= r.is_some_and(|r| r.has_remainder(fine));
        });
        let s = &mut *self.scratch;
        s.flat.clear();
        s.flat.extend(rhs.iter().flat_map(|v| [v.x, v.y, v.z]));
        s.solves += 1;
        s.solver.periodic = fine.basis().periodic_count();
        if s.solver.factor(stiffness, s.solves).is_err()
            || s.solver.solve_in_place(&mut s.flat).is_err()
        {
            return Ok(false);
        }
        if remainder {
            let (solver, energies) = (&mut s.solver, &self.system);
            let zero_held =
                |z: &mut [Real]| held.iter().for_each(|&k| z[3 * k..3 * k + 3].fill(0.0));
            let corrected = s.cg.correct(
                &mut s.flat,
                0.0,
                &mut |v, sign, out| {
                    for_each_energy_of(energies, fine, |e| {
                        if let Some(r) = e.capabilities().remainder {
                            r.add_remainder(fine, v, sign, out);
                        }
                    });
                    held.iter().for_each(|&k| out[k] = Vector3::zeros());
                },
                &mut |z| {
                    zero_held(z);
                    solver.solve_in_place(z)?;
                    zero_held(z);
                    Ok(())
                },
            );
            if corrected.is_err() {
                return Ok(false);
            }
        }
        for (v, x) in rhs.iter_mut().zip(s.flat.chunks_exact(3)) {
            *v = Vector3::new(x[0], x[1], x[2]);
        }
        Ok(s.flat.iter().all(|x| x.is_finite()))
    }
}

impl FineProblem for Mechanics<'_> {
    fn evaluate(
        &mut self,
        fine: &Rod,
        op: &RefinementOperator,
        residual: &mut [Vector3<Real>],
        stiffness: &mut BlockBanded,
    ) -> Result<(), AdaptError> {
        self.for_each_energy(fine, |e| {
            e.add_gradient(fine, residual);
            e.add_hessian(fine, HessianKind::Definite, stiffness);
        });
        if self.elapsed > 0.0 {
            stiffness.add_scaled_scalar(2.0 / self.elapsed.powi(2), fine.mass_matrix());
        }
        // Inertia and damping: M̂ (â + α v̂).
        let Scratch {
            load, force, held, ..
        } = &mut *self.scratch;
        op.apply(self.acceleration, load);
        for (i, (l, v)) in load.iter_mut().zip(&fine.velocities).enumerate() {
            *l += v * fine.damping_at(i);
        }
        force.resize(fine.len(), Vector3::zeros());
        fine.mass_matrix().mul_vec3(load, force);
        for (r, f) in residual.iter_mut().zip(force.iter()) {
            *r += f;
        }
        held.clear();
        for pin in &self.system.pins {
            let row = pin.row(fine)?;
            let values = row.value.iter().take(fine.basis().degree() + 1);
            held.extend(
                values
                    .enumerate()
                    .filter(|(_, &b)| b != 0.0)
                    .map(|(k, _)| row.first + k),
            );
        }
        // A closed rod's copies across the seam are held with what they copy.
        if let Some(m) = fine.basis().periodic_count() {
            for i in 0..held.len() {
                let k = held[i];
                let copy = if k < m { k + m } else { k - m };
                if copy < fine.len() {
                    held.push(copy);
                }
            }
        }
        for &k in held.iter() {
            residual[k] = Vector3::zeros();
        }
        Ok(())
    }

    fn solve(
        &mut self,
        fine: &Rod,
        stiffness: &mut BlockBanded,
        rhs: &mut [Vector3<Real>],
    ) -> Result<bool, AdaptError> {
        let held = std::mem::take(&mut self.scratch.held);
        let solved = self.solve_held(fine, stiffness, rhs, &held);
        self.scratch.held = held;
        solved
    }

    fn bandwidth(&self, fine: &Rod) -> usize {
        let mut w = fine.basis().degree();
        self.for_each_energy(fine, |e| w = w.max(e.bandwidth(fine)));
        w
    }
}

/// Interval of simulated time between history entries when the resolution is unchanged, s.
const HISTORY_INTERVAL: Real = 0.05;

/// JSON `adaptivity`: the error estimate of a run.
#[derive(Debug, Clone, Default, Serialize, serde::Deserialize, PartialEq)]
pub struct EstimateOutput {
    /// The last estimate (after the last step), m.
    pub estimated_error: Real,
    /// How uneven the last estimate is: its largest span estimate over the median one
    /// ([`ErrorEstimate::spread`]; `null` in JSON when undefined).
    pub estimated_spread: Option<Real>,
    /// `[t, control points, estimated error, spread]` after every step that changed
    /// the resolution and at least every 0.05 s (of the estimates made: while the rod
    /// is steady they are up to 64 steps apart); the count is that of the rod estimated
    /// (the step's, before its adapt stage); the spread is
    /// [`ErrorEstimate::spread`] (`NaN`, JSON `null`, when undefined).
    pub history: Vec<[Real; 4]>,
}

impl EstimateOutput {
    /// Records `estimate` made at time `t`; `changed`: the step changed the resolution.
    pub fn record(&mut self, t: Real, estimate: &ErrorEstimate, changed: bool) {
        let (n, error, spread) = (estimate.control_points, estimate.max(), estimate.spread());
        self.estimated_error = error;
        self.estimated_spread = Some(spread).filter(|s| s.is_finite());
        let due = self
            .history
            .last()
            .is_none_or(|h| t >= h[0] + HISTORY_INTERVAL * (1.0 - 1e-9));
        let entry = [t, n as Real, error, spread];
        match self.history.last_mut() {
            // A second estimate of the same state (the run's final one) replaces it.
            Some(last) if last[0] == t && last[1] == entry[1] => *last = entry,
            _ if changed || due => self.history.push(entry),
            _ => {}
        }
    }
}

/// Decouples the coefficients `held` in `a` (identity rows and columns, scaled like
/// the diagonal), so that a solve keeps them at the right-hand side's zero.
fn hold(a: &mut BlockBanded, held: &[usize]) {
    let (n, w) = (a.dim(), a.bandwidth());
    for &k in held {
        let scale = a.block(k, k).trace().abs().max(1.0) / 3.0;
        for j in k.saturating_sub(w)..(k + w + 1).min(n) {
            a.set_block(k, j, &Matrix3::zeros());
        }
        a.set_block(k, k, &(Matrix3::identity() * scale));
    }
    for f in a.far_blocks_mut() {
        if held.contains(&f.row) || held.contains(&f.col) {
            f.block = Matrix3::zeros();
        }
    }
}
