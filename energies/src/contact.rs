//! [`Contact`]: a smooth penalty keeping a rod of radius `r` off itself, off the other
//! pieces of its cuts, and above a floor plane (paper §3.2: collision detection and
//! response before the forces; the paper's response is a penalty too).
//!
//! **Self-contact.** A repulsive potential between material points of the rod: with
//! centre-line distance \\(d(s, t) = |C(s) - C(t)|\\) and gap \\(g = d - 2r\\),
//!
//! \\[ E = \frac{1}{(2r)^2} \iint_{|s - t| \gtrsim \text{exclusion}} \phi\big(g(s, t)\big)\,
//! ds\, dt \approx \sum_{(a, b)} \frac{w_a w_b}{(2r)^2}\, \phi(g_{ab}), \\]
//!
//! with the penalty \\(\phi\\) of the `penalty` module (stiffness `k`, onset layer `δ`) and the
//! double integral sampled on material points `s_a` with weights `w_a` (see [`detect`]:
//! contact segments, a broad phase over bounding balls, sample pairs within the reach
//! `2r + δ`). Crossing strands and strands lying alongside each other are the same
//! case: the energy of a line contact grows with its length, and nothing jumps when a
//! contact slides or changes type. With \\(u_i = b_i(s_a) - b_i(s_b)\\) and
//! \\(n = (C(s_a) - C(s_b))/d\\), each pair adds \\(\tfrac{w_a w_b}{(2r)^2} \phi'(g)\,
//! u_i\, n\\) to the gradient (exact) and
//! \\(\tfrac{w_a w_b}{(2r)^2} \phi''(g)\, u u^T \otimes n n^T\\) to the Hessian for both
//! [`HessianKind`]s: positive semi-definite, without the negative curvature term
//! \\(\phi'/d\, (I - n n^T)\\). It couples control points far apart on the rod, so it
//! is assembled with [`BlockBanded::add_coupling`]. A crossing with overlap `p` resists
//! with a force of about \\(\pi k p^2 / (2r)\\) (the patch where the strands overlap
//! grows with `p`).
//!
//! **Floor.** A plane \\(n_f \cdot x = h\\) pushes on the rod's quadrature points with
//! the gap \\(g(s) = n_f \cdot C(s) - h - r\\) and the energy per unit rest length
//! \\(\tfrac{1}{2r}\, \phi(g(s))\\): a length of rod equal to its diameter pressed into
//! the floor resists like one self-contact.
//!
//! **Obstacles** (module [`obstacle`]): rigid planes, spheres and capsules, with the
//! floor's penalty per unit length on the detection's material samples.
//!
//! **Friction** (coefficient `μ`, see the `friction` module): Coulomb friction as a
//! lagged dissipative potential, frozen at [`Contact::begin_step`], on every contact:
//! self, floor and obstacles.
//!
//! **What is not modelled:** contacts between segments less than `exclusion`
//! apart along the rod (neighbours: a rod bent to radius `r` first touches itself at
//! \\(\pi r\\), the default), which ignores loops shorter than `exclusion + 2 segment`
//! (about `7.3 r` by default: a loop of radius 1.2 r, tighter than the rod allows).

mod assemble;
pub mod detect;
mod friction;
pub mod obstacle;
mod pair;
mod penalty;
mod sample_sums;
mod skin;
mod surface;

use crate::{Energy, EnergySummary};
use detect::{ContactPoint, Detector, SamplePair};
use friction::Friction;
use nalgebra::Vector3;
pub use obstacle::Obstacle;
use pair::pair_rows;
use penalty::Penalty;
use splinerod_core::basis::MAX_ORDER;
use splinerod_core::rod::{non_negative, positive};
use splinerod_core::{
    BlockBanded, CoreError, HessianKind, KnotMap, Real, Rod, SavedState, StateReader,
};
use std::sync::{Mutex, MutexGuard};

/// Settings of [`Contact`]. All lengths in m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Rod radius `r` (> 0): centre lines are kept `2r` apart.
    pub radius: Real,
    /// Penalty stiffness `k`, N/m (> 0).
    pub stiffness: Real,
    /// Onset layer `δ` (> 0): the penalty starts at gap `δ` and reaches stiffness `k` at
    /// gap 0. Default `0.1 r`.
    pub onset: Real,
    /// Contact segments closer than this along the rod never touch (≥ 0). Default `π r`.
    pub exclusion: Real,
    /// Length of the contact segments of the broad phase (> 0), in rest arclength.
    /// Default `2.1 r`.
    pub segment: Real,
    /// Largest distance between material sample points along the rod (> 0), m of rest
    /// arclength. It must resolve the contact patch (about \\(2\sqrt{2r\delta}\\) wide
    /// across a crossing). Default `0.2 r`.
    pub spacing: Real,
    /// Floor plane `(n_f, h)`: unit normal and height, the rod staying on the `+n_f` side.
    pub floor: Option<(Vector3<Real>, Real)>,
    /// Coulomb friction coefficient `μ` (≥ 0), applied through [`Contact::begin_step`].
    /// Default 0.
    pub friction: Real,
    /// Sliding speed `ε_v` (> 0, m/s) below which friction acts as a stiff spring
    /// (sticking, slip `ε = ε_v · dt` per step); beyond it the friction force is `μ λ`.
    /// A resting contact on a slope creeps at about `ε_v tan θ / μ`. Default 1e-3 m/s.
    pub slip_speed: Real,
}

impl ContactParams {
    /// Self-contact only, for radius `r` and stiffness `k`, with the default onset and
    /// exclusion.
    pub fn new(radius: Real, stiffness: Real) -> Result<Self, CoreError> {
        positive("radius", radius)?;
        positive("stiffness", stiffness)?;
        Ok(Self {
            radius,
            stiffness,
            onset: 0.1 * radius,
            exclusion: std::f64::consts::PI * radius,
            segment: 2.1 * radius,
            spacing: 0.2 * radius,
            floor: None,
            friction: 0.0,
            slip_speed: 1e-3,
        })
    }

    /// Adds the floor `y = height` (normal `+y`).
    pub fn with_floor(mut self, height: Real) -> Result<Self, CoreError> {
        if !height.is_finite() {
            return Err(CoreError::InvalidParameter {
                name: "floor",
                value: height,
                reason: "must be finite",
            });
        }
        self.floor = Some((Vector3::y(), height));
        Ok(self)
    }

    /// Checks every setting.
    pub fn validate(&self) -> Result<(), CoreError> {
        positive("radius", self.radius)?;
        positive("stiffness", self.stiffness)?;
        positive("onset", self.onset)?;
        non_negative("exclusion", self.exclusion)?;
        positive("segment", self.segment)?;
        positive("spacing", self.spacing)?;
        non_negative("friction", self.friction)?;
        positive("slip_speed", self.slip_speed)?;
        if let Some((normal, height)) = self.floor {
            let unit = (normal.norm() - 1.0).abs() < 1e-12;
            if !unit || !height.is_finite() {
                return Err(CoreError::InvalidParameter {
                    name: "floor",
                    value: normal.norm(),
                    reason: "needs a unit normal and a finite height",
                });
            }
        }
        Ok(())
    }

    /// Centre-line distance at which the penalty starts, `2r + δ`.
    pub fn reach(&self) -> Real {
        2.0 * self.radius + self.onset
    }
}

/// The contact energy (module docs). Detection buffers sit behind a mutex so that the
/// `&self` energy methods can reuse them; one rod is never evaluated from two threads at
/// once, so the lock is uncontended.
#[derive(Debug)]
pub struct Contact {
    params: ContactParams,
    penalty: Penalty,
    detector: Mutex<Detector>,
    friction: Mutex<Friction>,
    /// Rigid obstacles (see [`obstacle`]), where they are now.
    obstacles: Vec<Obstacle>,
    /// Their keyframed motion.
    motion: obstacle::Motion,
    /// Radii per segment of a joined rod (see [`Contact::with_segment_radii`]).
    radii: SegmentRadii,
}

/// The radius of each segment of a joined rod: `starts[k]` is where segment `k` starts
/// in the parameter; empty for one radius (`params.radius`).
#[derive(Debug, Clone, Default, PartialEq)]
struct SegmentRadii {
    starts: Vec<Real>,
    values: Vec<Real>,
}

impl Clone for Contact {
    fn clone(&self) -> Self {
        Self {
            radii: self.radii.clone(),
            params: self.params,
            penalty: self.penalty,
            obstacles: self.obstacles.clone(),
            motion: self.motion.clone(),
            detector: Mutex::new(Detector::default()),
            friction: Mutex::new(Friction::default()),
        }
    }
}

/// What the detection found at the rod's current positions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSummary {
    /// Contacts: pairs of contact segments closer than the reach `2r + δ`.
    pub pairs: usize,
    /// Candidate segment pairs of the broad phase.
    pub candidates: usize,
    /// Smallest centre-line distance among the contacts, m (`None` without contacts).
    pub min_distance: Option<Real>,
    /// The smallest clearance ratio (`None` without contacts): centre-line distance
    /// over the diameter `2r` between strands, over the radius `r` from the floor or an
    /// obstacle;
    /// below 1 the rod overlaps.
    pub min_clearance_ratio: Option<Real>,
    /// Points of the rod within the penalty's reach of the floor or an obstacle.
    pub obstacle_contacts: usize,
}

impl ContactSummary {
    /// The summary of two sets of contacts together.
    pub fn merged(&self, other: &ContactSummary) -> ContactSummary {
        let min = |a: Option<Real>, b: Option<Real>| match (a, b) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        ContactSummary {
            pairs: self.pairs + other.pairs,
            candidates: self.candidates + other.candidates,
            min_distance: min(self.min_distance, other.min_distance),
            min_clearance_ratio: min(self.min_clearance_ratio, other.min_clearance_ratio),
            obstacle_contacts: self.obstacle_contacts + other.obstacle_contacts,
        }
    }
}

impl Contact {
    /// A contact energy with validated `params`.
    pub fn new(params: ContactParams) -> Result<Self, CoreError> {
        params.validate()?;
        Ok(Self {
            params,
            penalty: Penalty {
                k: params.stiffness,
                delta: params.onset,
            },
            detector: Mutex::new(Detector::default()),
            friction: Mutex::new(Friction::default()),
            obstacles: Vec::new(),
            motion: obstacle::Motion::default(),
            radii: SegmentRadii::default(),
        })
    }

    /// Rods of different radii (builder style): `radii[k]` for the segment of a joined
    /// rod that starts at parameter `starts[k]` (increasing, the first 0). Strands of
    /// radii \(r_a, r_b\) keep their centre lines \(r_a + r_b\) apart, with the pair
    /// weight \(w_a w_b / (r_a + r_b)^2\); the floor and obstacles keep each at its own
    /// radius. `params.radius` should be the smallest (it sets the sample spacing and
    /// the onset layer).
    pub fn with_segment_radii(
        mut self,
        starts: &[Real],
        radii: &[Real],
    ) -> Result<Self, CoreError> {
        for &r in radii {
            positive("radius", r)?;
        }
        let increasing = starts.windows(2).all(|w| w[0] < w[1]);
        if starts.len() != radii.len() || !increasing || starts.first() != Some(&0.0) {
            return Err(CoreError::InvalidParameter {
                name: "segment starts",
                value: starts.len() as Real,
                reason: "one increasing start per radius, the first at 0",
            });
        }
        self.radii = SegmentRadii {
            starts: starts.to_vec(),
            values: radii.to_vec(),
        };
        Ok(self)
    }

    /// The radius of the rod at material coordinate `s`.
    pub fn radius_at(&self, s: Real) -> Real {
        let r = &self.radii;
        if r.values.is_empty() {
            return self.params.radius;
        }
        let k = r.starts.partition_point(|&t| t <= s).saturating_sub(1);
        r.values[k]
    }

    /// The largest radius.
    fn max_radius(&self) -> Real {
        self.radii
            .values
            .iter()
            .fold(self.params.radius, |a, &b| a.max(b))
    }

    /// Centre-line distance at which the penalty can start for some pair, `2 r_max + δ`.
    fn reach(&self) -> Real {
        2.0 * self.max_radius() + self.params.onset
    }

    /// Adds rigid obstacles (builder style), each validated.
    pub fn with_obstacles(
        mut self,
        obstacles: impl IntoIterator<Item = Obstacle>,
    ) -> Result<Self, CoreError> {
        for o in obstacles {
            o.validate()?;
            self.obstacles.push(o);
        }
        Ok(self)
    }

    /// The rigid obstacles.
    pub fn obstacles(&self) -> &[Obstacle] {
        &self.obstacles
    }

    /// The settings.
    pub fn params(&self) -> &ContactParams {
        &self.params
    }

    fn detected(&self, rod: &Rod) -> Result<MutexGuard<'_, Detector>, CoreError> {
        let mut detector = self.detector.lock().unwrap_or_else(|e| e.into_inner());
        let p = &self.params;
        let every_sample = !self.obstacles.is_empty();
        detector.detect(
            rod,
            self.reach(),
            p.exclusion,
            [p.segment, p.spacing],
            every_sample,
        )?;
        Ok(detector)
    }

    /// Runs `f` on the closest points of every pair of contact segments closer than the
    /// reach (computed on the curve; not needed by the energy itself).
    pub fn for_each_contact(
        &self,
        rod: &Rod,
        mut f: impl FnMut(&ContactPoint),
    ) -> Result<(), CoreError> {
        let mut d = self.detected(rod)?;
        d.closest(rod, self.reach())?;
        d.closest.iter().for_each(&mut f);
        Ok(())
    }

    /// Counts and closest distance of the contacts at the rod's positions.
    pub fn summary(&self, rod: &Rod) -> Result<ContactSummary, CoreError> {
        let mut d = self.detected(rod)?;
        d.closest(rod, self.reach())?;
        let min_distance = d.closest.iter().map(|c| c.distance).reduce(Real::min);
        let (pairs, candidates) = (d.closest.len(), d.candidate_count());
        let strands = d
            .closest
            .iter()
            .map(|c| c.distance / (self.radius_at(c.s) + self.radius_at(c.t)))
            .reduce(Real::min);
        drop(d);
        let (obstacle_contacts, obstacles) = self.obstacle_summary(rod)?;
        let min_clearance_ratio = match (strands, obstacles) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        };
        Ok(ContactSummary {
            pairs,
            candidates,
            min_distance,
            min_clearance_ratio,
            obstacle_contacts,
        })
    }

    /// Whether no two material samples are closer than `r` (half the diameter): the
    /// states Newton's line search may move to (`System::admissible`). With a Newton
    /// step limit below `r/2`, strands cannot pass through each other between iterates,
    /// however long the time step. A failed detection is not admissible.
    pub fn admissible(&self, rod: &Rod) -> bool {
        let Ok(d) = self.detected(rod) else {
            return false;
        };
        let apart = d
            .pairs
            .iter()
            .all(|p| 2.0 * p.distance >= self.sum_of_radii(&d, p));
        drop(d);
        // No centre line inside an obstacle.
        let mut outside = true;
        let seen = self.for_each_obstacle_point(rod, |p| outside &= p.gap + p.radius > 0.0);
        apart && outside && seen.is_ok()
    }

    /// Starts a time step of `dt` seconds at the rod's state: freezes every contact's
    /// normal force and directions for friction (see the `friction` module). Call it
    /// before each step; without it (or with `μ = 0`) there is no friction.
    pub fn begin_step(&self, rod: &Rod, dt: Real) -> Result<(), CoreError> {
        positive("dt", dt)?;
        let mut friction = self.friction.lock().unwrap_or_else(|e| e.into_inner());
        friction.begin(rod, self.params.slip_speed * dt);
        if self.params.friction == 0.0 {
            return Ok(());
        }
        let d = self.detected(rod)?;
        let mut weights = [(0, 0.0); 2 * MAX_ORDER];
        for c in &d.pairs {
            let lambda = -self.pair_weight(&d, c) * self.penalty.slope(self.gap(&d, c));
            let len = pair_rows(&d, c, &mut weights);
            friction.push(&weights[..len], &c.normal, lambda, Vector3::zeros(), None);
        }
        drop(d);
        self.push_surface_friction(rod, dt, |rows, n, lambda, moved, obstacle| {
            friction.push(rows, n, lambda, moved, obstacle)
        })
    }

    pub(crate) fn friction_state(&self) -> MutexGuard<'_, Friction> {
        self.friction.lock().unwrap_or_else(|e| e.into_inner())
    }

    /// Appends the material coordinates of both sides of every contact, and of the
    /// closest point to every obstacle touched (for the interaction refinement criterion).
    pub fn interaction_points(&self, rod: &Rod, out: &mut Vec<Real>) -> Result<(), CoreError> {
        self.for_each_contact(rod, |c| out.extend([c.s, c.t]))?;
        self.obstacle_interaction_points(rod, out)
    }
}

impl Energy for Contact {
    fn name(&self) -> &str {
        "contact"
    }

    fn begin_step(&mut self, rod: &Rod, dt: Real) -> Result<(), CoreError> {
        Contact::begin_step(self, rod, dt)
    }

    fn drive(&mut self, t: Real) {
        self.move_obstacles(t);
    }

    fn on_knot_change(&mut self, _rod: &Rod, _map: &KnotMap) {
        let detector = self.detector.get_mut().unwrap_or_else(|e| e.into_inner());
        detector.forget_topology();
    }

    fn save_state(&self, out: &mut SavedState) {
        let detector = self.detector.lock().unwrap_or_else(|e| e.into_inner());
        detector.save_state(out);
    }

    fn load_state(&mut self, rod: &Rod, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        let detector = self.detector.get_mut().unwrap_or_else(|e| e.into_inner());
        detector.load_state(rod, input)
    }

    fn time_dependent(&self) -> bool {
        self.motion.paths.iter().any(Option::is_some)
    }

    fn interaction_points(&self, rod: &Rod, out: &mut Vec<Real>) -> Result<(), CoreError> {
        Contact::interaction_points(self, rod, out)
    }

    fn admissible(&self, rod: &Rod) -> bool {
        Contact::admissible(self, rod)
    }

    fn summary(&self, rod: &Rod) -> Result<EnergySummary, CoreError> {
        Ok(EnergySummary {
            contact: Some(Contact::summary(self, rod)?),
            ..EnergySummary::default()
        })
    }

    fn add_obstacle_forces(
        &self,
        rod: &Rod,
        out: &mut Vec<Vector3<Real>>,
    ) -> Result<(), CoreError> {
        out.extend(self.obstacle_forces(rod)?);
        Ok(())
    }

    /// The same contact without friction (its frozen data belong to the coarse rod's
    /// step), for estimators evaluating the energies on a finer copy.
    fn for_finer_rod(&self, _fine: &Rod) -> Option<Box<dyn Energy>> {
        let mut params = self.params;
        params.friction = 0.0;
        let copy = Contact::new(params).and_then(|c| c.with_obstacles(self.obstacles.clone()));
        copy.ok().map(|c| Box::new(c) as Box<dyn Energy>)
    }

    fn energy(&self, rod: &Rod) -> Real {
        let Ok(d) = self.detected(rod) else {
            return Real::NAN;
        };
        let e: Real = d
            .pairs
            .iter()
            .map(|c| self.pair_weight(&d, c) * self.penalty.value(self.gap(&d, c)))
            .sum();
        drop(d);
        let surfaces = self.surface_energy(rod).unwrap_or(Real::NAN);
        e + surfaces + self.friction_state().energy(rod, self.params.friction)
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let Ok(mut d) = self.detected(rod) else {
            gradient
                .iter_mut()
                .for_each(|g| *g = Vector3::repeat(Real::NAN));
            return;
        };
        // Each pair's force acts on its two samples (see `sample_sums`).
        let mut sums = std::mem::take(&mut d.sums);
        sums.clear(d.samples.s.len());
        for c in &d.pairs {
            let force = c.normal * (self.pair_weight(&d, c) * self.penalty.slope(self.gap(&d, c)));
            sums.add_force(c.a, &force);
            sums.add_force(c.b, &-force);
        }
        sums.spread_forces(&d.samples, gradient);
        d.sums = sums;
        drop(d);
        if self.add_surface_gradient(rod, gradient).is_err() {
            gradient
                .iter_mut()
                .for_each(|g| *g = Vector3::repeat(Real::NAN));
            return;
        }
        let mu = self.params.friction;
        self.friction_state().add_gradient(rod, mu, gradient);
    }

    fn add_hessian(&self, rod: &Rod, kind: HessianKind, hessian: &mut BlockBanded) {
        let Ok(mut d) = self.detected(rod) else {
            hessian.scale(Real::NAN);
            return;
        };
        let mut local = std::mem::take(&mut d.group_hessian);
        let mut sums = std::mem::take(&mut d.sums);
        sums.clear(d.samples.s.len());
        let samples = &d.samples;
        let first = |k: u32| samples.first[k as usize] as usize;
        for &(start, end) in &d.groups {
            let pairs = &d.pairs[start..end];
            let order = samples.order;
            // Each strand's samples touch a run of consecutive control points.
            let run = |side: fn(&SamplePair) -> u32| {
                let firsts = pairs
                    .iter()
                    .map(|c| samples.first[side(c) as usize] as usize);
                let (lo, hi) = firsts.fold((usize::MAX, 0), |(lo, hi), f| (lo.min(f), hi.max(f)));
                lo..hi + order
            };
            local.start(run(|c| c.a), run(|c| c.b));
            for c in pairs {
                let m = self.pair_hessian(&d, c, kind);
                sums.add_block(c.a, &m);
                sums.add_block(c.b, &m);
                let a = (c.a, first(c.a), samples.row(c.a as usize));
                local.add_cross(a, (first(c.b), samples.row(c.b as usize)), &m);
            }
            local.finish(hessian);
        }
        sums.spread_blocks(samples, hessian);
        local.flush(hessian);
        d.group_hessian = local;
        d.sums = sums;
        drop(d);
        if self.add_surface_hessian(rod, hessian).is_err() {
            hessian.scale(Real::NAN);
            return;
        }
        let mu = self.params.friction;
        self.friction_state().add_hessian(rod, mu, hessian);
    }
}
