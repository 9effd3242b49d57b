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
//! [`HessianKind`](splinerod_core::HessianKind)s: positive semi-definite, without the negative curvature term
//! \\(\phi'/d\, (I - n n^T)\\). It couples control points far apart on the rod, so it
//! is assembled with [`BlockBanded::add_coupling`](splinerod_core::BlockBanded::add_coupling). A crossing with overlap `p` resists
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
//! **Laws and stiffness** (modules `barrier` and [`stiffness`]): the penalty \\(\phi\\)
//! of a fixed stiffness, the same penalty with its stiffness raised between steps so
//! that the deepest contact stays within a gap tolerance, or a log barrier that holds
//! every contact at a gap inside the tolerance whatever its load
//! ([`ContactLaw`]; the scenes' default is the barrier).
//!
//! **Friction** (coefficient `μ`, see the `friction` module): Coulomb friction as a
//! lagged dissipative potential, frozen at [`Contact::begin_step`], on every contact:
//! self, floor and obstacles; each surface may have its own coefficient and a contact
//! takes the smaller of its two (the `surfaces` module).
//!
//! **What is not modelled:** contacts between segments less than `exclusion`
//! apart along the rod (neighbours: a rod bent to radius `r` first touches itself at
//! \\(\pi r\\), the default), which ignores loops shorter than `exclusion + 2 segment`
//! (about `7.3 r` by default: a loop of radius 1.2 r, tighter than the rod allows).

mod as_energy;
mod assemble;
mod barrier;
pub mod close;
pub mod detect;
mod friction;
pub mod obstacle;
mod pair;
mod parameters;
mod penalty;
mod sample_sums;
mod skin;
pub mod stiffness;
mod summary;
mod surface;
mod surfaces;

use detect::{ContactPoint, Detector, SamplePair};
use friction::Friction;
use nalgebra::Vector3;
pub use obstacle::Obstacle;
use pair::pair_rows;
use penalty::Penalty;
use splinerod_core::basis::MAX_ORDER;
use splinerod_core::rod::{non_negative, positive};
use splinerod_core::{CoreError, Real, Rod};
use std::sync::{Mutex, MutexGuard};
pub use stiffness::ContactLaw;
pub use summary::ContactSummary;
use surfaces::SegmentValues;

/// Settings of [`Contact`]. All lengths in m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Rod radius `r` (> 0): centre lines are kept `2r` apart.
    pub radius: Real,
    /// Penalty stiffness `k`, N/m (> 0); the barrier's `κ` with [`ContactLaw::Barrier`];
    /// the first stiffness of an adapting law.
    pub stiffness: Real,
    /// Onset layer `δ` (> 0): the penalty starts at gap `δ` and reaches stiffness `k` at
    /// gap 0. Default `0.1 r`. The barrier's tolerance with [`ContactLaw::Barrier`].
    pub onset: Real,
    /// How contacts resist and whether the stiffness adapts. Default
    /// [`ContactLaw::Penalty`].
    pub law: ContactLaw,
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
            law: ContactLaw::Penalty,
            exclusion: std::f64::consts::PI * radius,
            segment: 2.1 * radius,
            spacing: 0.2 * radius,
            floor: None,
            friction: 0.0,
            slip_speed: 1e-3,
        })
    }

    /// The barrier ([`ContactLaw::Barrier`]) of stiffness `kappa` (N/m, the force scale
    /// `kappa · tolerance · 1.19` at half the tolerance) acting within the gap
    /// `tolerance` (m), for radius `r`; otherwise as [`ContactParams::new`].
    pub fn barrier(radius: Real, tolerance: Real, kappa: Real) -> Result<Self, CoreError> {
        positive("tolerance", tolerance)?;
        let mut params = Self::new(radius, kappa)?;
        params.onset = tolerance;
        params.law = ContactLaw::Barrier;
        Ok(params)
    }

    /// The penalty of least stiffness `k` raised to keep the deepest contact within half
    /// the gap `tolerance` (m) ([`ContactLaw::AdaptivePenalty`]), its onset at the
    /// tolerance; otherwise as [`ContactParams::new`].
    pub fn adaptive(radius: Real, stiffness: Real, tolerance: Real) -> Result<Self, CoreError> {
        positive("tolerance", tolerance)?;
        let mut params = Self::new(radius, stiffness)?;
        params.onset = tolerance;
        params.law = ContactLaw::AdaptivePenalty { tolerance };
        Ok(params)
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
        if let ContactLaw::AdaptivePenalty { tolerance } = self.law {
            positive("tolerance", tolerance)?;
        }
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
    radii: SegmentValues,
    /// Friction coefficients per segment ([`Contact::with_segment_friction`]).
    frictions: SegmentValues,
    /// Friction coefficients per obstacle ([`Contact::with_obstacle_friction`]); empty:
    /// `params.friction` for every obstacle.
    obstacle_friction: Vec<Real>,
    /// The state of the last stiffness update ([`stiffness`]): the smallest gap
    /// measured and a fingerprint of the positions, so a retried step does not update
    /// again.
    adapted_at: Option<[Real; 2]>,
}

impl Clone for Contact {
    fn clone(&self) -> Self {
        Self {
            radii: self.radii.clone(),
            frictions: self.frictions.clone(),
            obstacle_friction: self.obstacle_friction.clone(),
            adapted_at: self.adapted_at,
            params: self.params,
            penalty: self.penalty,
            obstacles: self.obstacles.clone(),
            motion: self.motion.clone(),
            detector: Mutex::new(Detector::default()),
            friction: Mutex::new(Friction::default()),
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
                barrier: params.law == ContactLaw::Barrier,
            },
            adapted_at: None,
            detector: Mutex::new(Detector::default()),
            friction: Mutex::new(Friction::default()),
            obstacles: Vec::new(),
            motion: obstacle::Motion::default(),
            radii: SegmentValues::default(),
            frictions: SegmentValues::default(),
            obstacle_friction: Vec::new(),
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
        self.radii = SegmentValues::new(starts, radii)?;
        Ok(self)
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
        if !self.has_friction() {
            return Ok(());
        }
        let d = self.detected(rod)?;
        let mut weights = [(0, 0.0); 2 * MAX_ORDER];
        let s = &d.samples.s;
        for c in &d.pairs {
            let (a, b) = (s[c.a as usize], s[c.b as usize]);
            let mu = self.friction_at(a).min(self.friction_at(b));
            if mu == 0.0 {
                continue;
            }
            let (w, gap) = (self.pair_weight(&d, c), self.gap(&d, c));
            let lambda = -w * self.penalty.slope(gap);
            let slope = -mu * w * self.penalty.curvature(gap);
            let len = pair_rows(&d, c, &mut weights);
            friction.push(
                &weights[..len],
                &c.normal,
                (mu * lambda, slope),
                Vector3::zeros(),
                None,
            );
        }
        drop(d);
        self.push_surface_friction(rod, dt, |rows, n, bound, moved, obstacle| {
            friction.push(rows, n, bound, moved, obstacle)
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
