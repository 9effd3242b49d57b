//! Implicit Euler for [`LANES`] rods of one shape at once (batched ensembles, #17):
//! the Newton iterations of [`crate::ImplicitEuler`] on the incremental potential
//!
//! \\[ \Phi(x) = \tfrac12 (x - v_0)^T M (x - v_0) + E(q_0 + h x) + \tfrac{h\alpha}{2}\, x^T M x, \\]
//!
//! residual \\(r = M((1 + h\alpha) x - v_0) + h \nabla E\\), Newton matrix
//! \\(A = (1 + h\alpha) M + h^2 K\\), with the pins that hold single control points
//! eliminated (see `point_pins.rs`: \\(A_{jk} \to 0\\), \\(A_{kk} \to I\\),
//! \\(b_j \to b_j - A_{jk}\delta_k\\), \\(b_k \to \delta_k\\)), every lane in the same
//! arithmetic loop ([`splinerod_core::lanes`]; the potential comes from a
//! [`LanePotential`]) and the factorisation batched ([`BatchedBandedCholesky`]).
//!
//! Each lane makes the decisions of the scalar solver with its own
//! [`ConvergenceTracker`] (the scalar solver's type, see [`crate::convergence`]): it
//! stops when its step moves no point by more than `tolerance · L` (or by the round-off
//! band once its steps stall), and a converged lane stops moving while the others
//! iterate. What the lockstep does
//! not replicate fails the lane alone ([`LaneEuler::outcome`] says why): a matrix that
//! is not positive definite (the scalar solver then switches to an indefinite or
//! definite factorisation), a step the line search would shorten, a solve that does not
//! converge, a non-finite value, per-point damping. The lanes never mix (every
//! operation is lane by lane), so a lane's result and its failure do not depend on the
//! other lanes. Shapes and settings outside the batched form (pins that are not single
//! control points, rods of different knots or pins, a closed rod, the sparse solver, a
//! step limit) fail the whole step with a [`LaneFallback`]. The caller steps the rods
//! of failed lanes one by one, so a failure changes no result; each lane's result
//! equals the scalar solver's up to round-off.

mod kept;
pub use kept::StartState;
mod mass;
mod pins;

use crate::batched::BatchedBandedCholesky;
use crate::convergence::ConvergenceTracker;
use crate::linear::LinearSolverKind;
use crate::newton::NewtonParams;
use crate::StepStats;
use kept::{Keep, Kept};
use mass::{mass_bilinear, mass_times};
use nalgebra::Vector3;
use splinerod_core::lanes::{mul_add, LaneBlock, ZERO};
use splinerod_core::{Derivatives, LaneBand, Lanes, Pin, Real, Rod, LANES};

/// The potential energy of [`LANES`] rods of one shape, in lane form.
pub trait LanePotential {
    /// Adds to `energy` each lane's potential energy at positions `q` (coordinate `c` of
    /// point `i` at `3i + c`) and, with `derivatives`, its gradient and its exact Hessian
    /// (upper band) times the scale given there. Per lane, whether it could (a lane it
    /// could not evaluate fails, alone: the answer for one lane must not depend on the
    /// others).
    fn add(
        &self,
        q: &[Lanes],
        energy: &mut Lanes,
        derivatives: Option<Derivatives<'_>>,
    ) -> [bool; LANES];
}

/// Why a batched step was not taken: the rods must be stepped one by one.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LaneFallback(pub &'static str);

/// One lane's step, as [`crate::Integrator::step`] would have left it (its start
/// state, damping and end state checked finite).
#[derive(Debug, Clone, Copy)]
pub struct LaneOutcome<'a> {
    /// End-of-step control points.
    pub positions: &'a [Vector3<Real>],
    /// End-of-step velocities.
    pub velocities: &'a [Vector3<Real>],
    /// Newton's counters.
    pub stats: StepStats,
    /// The forces the pins exerted, N, one per pin.
    pub pin_forces: &'a [Vector3<Real>],
}

/// The arguments of one batched step ([`LaneEuler::step`], [`LaneEuler::step_kept`]).
#[derive(Clone, Copy)]
pub struct LaneStep<'a> {
    /// Each lane's rod (read, not changed).
    pub rods: [&'a Rod; LANES],
    /// Each lane's pins.
    pub pins: [&'a [Pin]; LANES],
    /// The lanes' potential energy.
    pub potential: &'a dyn LanePotential,
    /// Block bandwidth of the potential's Hessian.
    pub bandwidth: usize,
    /// Newton's settings.
    pub params: &'a NewtonParams,
    /// The time step, s.
    pub dt: Real,
}

/// Buffers of the batched implicit Euler step (no allocation once sized).
#[derive(Debug, Default)]
pub struct LaneEuler {
    n: usize,
    /// Block bandwidth of the Newton matrix.
    bw: usize,
    q0: Vec<Lanes>,
    v0: Vec<Lanes>,
    x: Vec<Lanes>,
    q: Vec<Lanes>,
    r: Vec<Lanes>,
    gradient: Vec<Lanes>,
    flat: Vec<Lanes>,
    trial: Vec<Lanes>,
    mass: Vec<Lanes>,
    mass_bw: usize,
    alpha: Lanes,
    /// Each lane's convergence decisions.
    trackers: [ConvergenceTracker; LANES],
    /// Control points the pins hold, and their targets for `x`.
    pins: Vec<usize>,
    /// The knots `pin_points` were found on, and per pin (place, tangent, sliding) the
    /// control point it holds alone, if any.
    pin_knots: Vec<Real>,
    pin_points: Vec<((u64, bool, bool), Option<usize>)>,
    targets: Vec<[Lanes; 3]>,
    multipliers: Vec<[Lanes; 3]>,
    /// Per pin at `k`: blocks `A_jk`, `j = k − bw ..= k + bw`, before elimination.
    saved: Vec<LaneBlock>,
    a: LaneBand,
    factor: BatchedBandedCholesky,
    stats: [StepStats; LANES],
    /// Why each lane failed, if it did.
    failed: [Option<&'static str>; LANES],
    out_q: [Vec<Vector3<Real>>; LANES],
    out_v: [Vec<Vector3<Real>>; LANES],
    forces: [Vec<Vector3<Real>>; LANES],
    /// The state of steps kept in the lanes ([`Self::step_kept`]).
    kept: Kept,
}

impl LaneEuler {
    /// One implicit Euler step of `step.dt` for each lane's rod (read, not changed) with
    /// its pins, the potential `step.potential` whose Hessian has block bandwidth
    /// `step.bandwidth`; the results are read with [`Self::outcome`].
    pub fn step(&mut self, step: &LaneStep<'_>) -> Result<(), LaneFallback> {
        self.end_kept_run();
        self.dispatch(step, Keep::No)
    }

    /// Checks the settings and runs [`Self::step_lanes`], compiled for the widest lanes
    /// the processor has.
    fn dispatch(&mut self, input: &LaneStep<'_>, keep: Keep) -> Result<(), LaneFallback> {
        let params = input.params;
        if params.linear_solver != LinearSolverKind::Banded || params.max_step.is_some() {
            return Err(LaneFallback("solver settings"));
        }
        if !(input.dt.is_finite() && input.dt > 0.0) {
            return Err(LaneFallback("time step"));
        }
        #[cfg(target_arch = "x86_64")]
        if splinerod_core::lanes::wide() {
            // SAFETY: the processor has AVX2 and FMA (checked on the line above).
            return unsafe { self.step_wide(input, keep) };
        }
        self.step_lanes(input, keep)
    }

    /// [`Self::step_lanes`] compiled for AVX2 (four lanes per instruction instead of
    /// two; the arithmetic is the same, so are the results).
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,fma")]
    unsafe fn step_wide(&mut self, input: &LaneStep<'_>, keep: Keep) -> Result<(), LaneFallback> {
        self.step_lanes(input, keep)
    }

    /// The step of [`Self::step`] once its settings are checked.
    #[inline(always)]
    fn step_lanes(&mut self, input: &LaneStep<'_>, keep: Keep) -> Result<(), LaneFallback> {
        self.failed = [None; LANES];
        let (bandwidth, params, dt) = (input.bandwidth, input.params, input.dt);
        match keep {
            Keep::Next => self.restart(input.rods, params),
            Keep::No | Keep::First => self.gather(input.rods, bandwidth, params)?,
        }
        self.place_pins(input.rods, input.pins, dt)?;
        self.newton(input.potential, bandwidth, params, dt);
        match keep {
            Keep::No => self.scatter(dt),
            Keep::First | Keep::Next => self.keep_end(dt),
        }
        Ok(())
    }

    /// Lane `l`'s result of the last successful [`Self::step`], or why the lane failed
    /// (its rod must then be stepped alone).
    pub fn outcome(&self, l: usize) -> Result<LaneOutcome<'_>, LaneFallback> {
        if let Some(why) = self.failed[l] {
            return Err(LaneFallback(why));
        }
        Ok(LaneOutcome {
            positions: &self.out_q[l],
            velocities: &self.out_v[l],
            stats: self.stats[l],
            pin_forces: &self.forces[l],
        })
    }

    /// Marks lane `l` failed (the first reason stays).
    fn fail(&mut self, l: usize, why: &'static str) {
        self.failed[l].get_or_insert(why);
    }

    /// Whether lane `l` is still iterating.
    fn live(&self, l: usize) -> bool {
        self.failed[l].is_none() && !self.stats[l].converged
    }

    /// Reads the rods' states, mass matrices, damping and tolerances into lane form.
    #[inline(always)]
    fn gather(
        &mut self,
        rods: [&Rod; LANES],
        bandwidth: usize,
        params: &NewtonParams,
    ) -> Result<(), LaneFallback> {
        let n = rods[0].len();
        let mass_bw = rods[0].mass_matrix().bandwidth();
        let knots = rods[0].basis().knots();
        let shape = |rod: &&Rod| {
            let same = |k: &[Real]| k.iter().zip(knots).all(|(a, b)| a.to_bits() == b.to_bits());
            let k = rod.basis().knots();
            rod.len() == n
                && !rod.is_closed()
                && rod.mass_matrix().bandwidth() == mass_bw
                && k.len() == knots.len()
                && same(k)
        };
        if !rods.iter().all(shape) || mass_bw > bandwidth {
            return Err(LaneFallback("shape"));
        }
        (self.n, self.mass_bw) = (n, mass_bw);
        for v in [
            &mut self.q0,
            &mut self.v0,
            &mut self.x,
            &mut self.q,
            &mut self.r,
            &mut self.gradient,
            &mut self.flat,
            &mut self.trial,
        ] {
            v.resize(3 * n, ZERO);
        }
        self.mass.resize(n * (mass_bw + 1), ZERO);
        for (l, rod) in rods.iter().enumerate() {
            let alpha = rod.uniform_damping().filter(|a| a.is_finite() && *a >= 0.0);
            if alpha.is_none() {
                self.fail(l, "damping");
            }
            self.alpha[l] = alpha.unwrap_or(0.0);
            self.trackers[l] = ConvergenceTracker::new(params, rod.material().rest_length);
            for (i, (p, v)) in rod.positions.iter().zip(&rod.velocities).enumerate() {
                for c in 0..3 {
                    self.q0[3 * i + c][l] = p[c];
                    self.v0[3 * i + c][l] = v[c];
                }
            }
            for (m, &v) in self.mass.iter_mut().zip(rod.mass_matrix().band()) {
                m[l] = v;
            }
        }
        for l in 0..LANES {
            let finite = |v: &[Lanes]| v.iter().all(|x| x[l].is_finite());
            if !(finite(&self.q0) && finite(&self.v0)) {
                self.fail(l, "non-finite state");
            }
        }
        self.x.copy_from_slice(&self.v0);
        Ok(())
    }

    /// Newton's iterations, lane by lane decisions (see the module docs).
    #[inline(always)]
    fn newton(
        &mut self,
        potential: &dyn LanePotential,
        bandwidth: usize,
        params: &NewtonParams,
        dt: Real,
    ) {
        self.stats = [StepStats {
            batched: 1,
            ..StepStats::default()
        }; LANES];
        loop {
            // Live lanes have done the same iterations: all or none may start one.
            let mut more = false;
            for l in 0..LANES {
                more |= self.live(l) && self.trackers[l].next_iteration();
            }
            if !more {
                break;
            }
            let energy = self.assemble(potential, bandwidth, dt);
            self.eliminate_pins();
            let definite = self.factor.factor_band(&mut self.a);
            for l in (0..LANES).filter(|&l| !definite[l]) {
                self.fail(l, "not positive definite");
            }
            self.flat
                .iter_mut()
                .zip(&self.r)
                .for_each(|(b, r)| *b = r.map(|x| -x));
            self.apply_pin_targets();
            let solved = self.factor.solve_in_place(&mut self.flat);
            self.factor.release_band(&mut self.a);
            if solved.is_err() {
                (0..LANES).for_each(|l| self.fail(l, "solve"));
                return;
            }
            let (residual, slope) = self.pin_multipliers_and_slope();
            let full = self.step_lengths(dt);
            let mut search = [false; LANES];
            let active: [bool; LANES] = std::array::from_fn(|l| self.live(l));
            for l in (0..LANES).filter(|&l| active[l]) {
                let tracker = self.trackers[l];
                let stats = &mut self.stats[l];
                stats.newton_iterations = tracker.iterations();
                stats.residual = residual[l];
                if !(residual[l].is_finite() && full[l].is_finite()) {
                    self.fail(l, "non-finite step");
                } else if tracker.check_divergence(full[l]).is_err() {
                    self.fail(l, "diverged");
                }
                search[l] = params.line_search
                    && tracker.searches(full[l])
                    && !tracker.converging(full[l])
                    && slope[l] < 0.0
                    && self.feasible(l);
            }
            self.take_steps(potential, active, search, energy, slope, dt);
            for l in 0..LANES {
                // A lane takes its full step: the taken step is the full one.
                if self.live(l) && self.trackers[l].verdict(full[l], full[l]).done() {
                    self.stats[l].converged = true;
                }
            }
        }
        for l in 0..LANES {
            if !params.accepts(self.stats[l].converged) {
                self.fail(l, "not converged");
            }
        }
    }

    /// Positions `q = q₀ + h x`, the potential's energy (returned), the residual `r` and
    /// the Newton matrix `A = h² K + (1 + hα) M` at them.
    #[inline(always)]
    fn assemble(&mut self, potential: &dyn LanePotential, bandwidth: usize, dt: Real) -> Lanes {
        for ((q, q0), x) in self.q.iter_mut().zip(&self.q0).zip(&self.x) {
            *q = std::array::from_fn(|l| q0[l] + x[l] * dt);
        }
        self.bw = bandwidth;
        // Blocks the potential does not write are zeroed by the mass pass below.
        self.a.clear_lazily(self.n, bandwidth);
        self.gradient.fill(ZERO);
        let mut energy = ZERO;
        let derivatives = Derivatives {
            gradient: &mut self.gradient,
            hessian: &mut self.a,
            hessian_scale: dt * dt,
        };
        let evaluated = potential.add(&self.q, &mut energy, Some(derivatives));
        for l in (0..LANES).filter(|&l| !evaluated[l]) {
            self.fail(l, "potential");
        }
        let scale: Lanes = std::array::from_fn(|l| 1.0 + dt * self.alpha[l]);
        for ((t, x), v0) in self.trial.iter_mut().zip(&self.x).zip(&self.v0) {
            *t = std::array::from_fn(|l| x[l] * scale[l] - v0[l]);
        }
        mass_times(&self.mass, self.mass_bw, &self.trial, &mut self.r);
        for (r, g) in self.r.iter_mut().zip(&self.gradient) {
            for l in 0..LANES {
                r[l] += g[l] * dt;
            }
        }
        let (w, stride) = (self.mass_bw + 1, bandwidth + 1);
        let blocks = self.a.blocks_mut();
        for i in 0..self.n {
            let row = &mut blocks[i * stride..i * stride + stride.min(self.n - i)];
            for (k, m) in self.mass[i * w..(i + 1) * w]
                .iter()
                .enumerate()
                .take(row.len())
            {
                for e in [0, 4, 8] {
                    mul_add(&mut row[k][e], scale, *m);
                }
            }
        }
        energy
    }

    /// Per lane the largest move of a control point in the step, m.
    #[inline(always)]
    fn step_lengths(&self, dt: Real) -> Lanes {
        let mut full = ZERO;
        for d in &self.flat {
            for l in 0..LANES {
                // NaN propagates: max would drop it.
                full[l] = if d[l].abs() > full[l] || d[l].is_nan() {
                    d[l].abs()
                } else {
                    full[l]
                };
            }
        }
        full.map(|f| f * dt)
    }

    /// Takes the full step in the active lanes; where a lane searches, its merit must
    /// decrease by Armijo's rule (or within rounding), else the scalar solver would
    /// shorten the step: the lane fails.
    #[inline(always)]
    fn take_steps(
        &mut self,
        potential: &dyn LanePotential,
        active: [bool; LANES],
        search: [bool; LANES],
        energy: Lanes,
        slope: Lanes,
        dt: Real,
    ) {
        let phi0 = search.contains(&true).then(|| self.merit(energy, dt));
        for ((t, x), d) in self.trial.iter_mut().zip(&self.x).zip(&self.flat) {
            // Each lane's sum taken, kept where the lane is active (a select, no branch).
            *t = std::array::from_fn(|l| {
                let moved = x[l] + d[l];
                if active[l] {
                    moved
                } else {
                    x[l]
                }
            });
        }
        std::mem::swap(&mut self.x, &mut self.trial);
        let Some(phi0) = phi0 else {
            return;
        };
        for ((q, q0), x) in self.q.iter_mut().zip(&self.q0).zip(&self.x) {
            *q = std::array::from_fn(|l| q0[l] + x[l] * dt);
        }
        let mut trial_energy = ZERO;
        let evaluated = potential.add(&self.q, &mut trial_energy, None);
        for l in (0..LANES).filter(|&l| !evaluated[l]) {
            trial_energy[l] = Real::NAN;
        }
        let phi = self.merit(trial_energy, dt);
        for l in (0..LANES).filter(|&l| search[l]) {
            let armijo = phi[l] <= phi0[l] + 1e-4 * slope[l];
            let noise = (phi[l] - phi0[l]).abs() <= 1e-14 * phi0[l].abs();
            if !phi[l].is_finite() || !(armijo || noise) {
                self.fail(l, "line search");
            }
        }
    }

    /// The merit \\(\Phi\\) at the current `x` with the potential's `energy` there.
    #[inline(always)]
    fn merit(&mut self, energy: Lanes, dt: Real) -> Lanes {
        for ((t, x), v0) in self.trial.iter_mut().zip(&self.x).zip(&self.v0) {
            *t = std::array::from_fn(|l| x[l] - v0[l]);
        }
        let inertia = mass_bilinear(&self.mass, self.mass_bw, &self.trial, &self.trial);
        let motion = mass_bilinear(&self.mass, self.mass_bw, &self.x, &self.x);
        std::array::from_fn(|l| 0.5 * inertia[l] + energy[l] + 0.5 * dt * self.alpha[l] * motion[l])
    }

    /// Writes each lane's end state and pin forces (checked finite).
    #[inline(always)]
    fn scatter(&mut self, dt: Real) {
        let n = self.n;
        for l in 0..LANES {
            if self.failed[l].is_some() {
                continue;
            }
            let (q, v) = (&mut self.out_q[l], &mut self.out_v[l]);
            q.resize(n, Vector3::zeros());
            v.resize(n, Vector3::zeros());
            for i in 0..n {
                for c in 0..3 {
                    let x = self.x[3 * i + c][l];
                    v[i][c] = x;
                    q[i][c] = self.q0[3 * i + c][l] + x * dt;
                }
            }
            let finite = |f: &[Vector3<Real>]| f.iter().all(|p| p.iter().all(|x| x.is_finite()));
            if !(finite(q) && finite(v)) {
                self.failed[l] = Some("non-finite state");
                continue;
            }
            let forces = &mut self.forces[l];
            forces.clear();
            let mu = self.multipliers.iter();
            forces.extend(mu.map(|m| Vector3::new(m[0][l], m[1][l], m[2][l]) / dt));
        }
    }
}
