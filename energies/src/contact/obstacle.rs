//! Rigid obstacles: planes, spheres and capsules (cylinders with rounded ends) the rod
//! stays out of, with the same penalty and friction as the rod's own contacts.
//!
//! With \\(d(x)\\) the signed distance from a point to the obstacle's surface and
//! \\(n(x) = \nabla d\\) the outward normal, a material sample `a` of the rod (rest
//! arclength weight \\(w_a\\), position \\(x_a = \sum_i b_i(s_a) q_i\\)) has the gap
//! \\(g_a = d(x_a) - r\\) and adds
//!
//! \\[ E = \sum_a \frac{w_a}{2r}\, \phi(g_a), \qquad
//! \frac{\partial E}{\partial q_i} = \sum_a \frac{w_a}{2r}\, \phi'(g_a)\, b_i(s_a)\, n_a, \\]
//!
//! (as the floor: a length of rod equal to its diameter pressed into an obstacle resists
//! like one self-contact). The Hessian keeps \\(\tfrac{w_a}{2r} \phi''(g_a)\, b_i b_j\,
//! n_a n_a^T\\); the exact kind ([`splinerod_core::HessianKind::Exact`]) adds the
//! surface-curvature term \\(\tfrac{w_a}{2r} \phi'(g_a)\, b_i b_j\, \nabla n\\), with
//! \\(\nabla n = (I - n n^T)/\rho\\) at a distance ρ from a sphere's centre or a
//! capsule's cap, \\((I - n n^T - u u^T)/\rho\\) from a capsule's axis of direction `u`,
//! zero for a plane — negative semi-definite (φ' < 0 in contact), so the Newton steps'
//! definite kind drops it, as self-contact drops the normal's turning.
//! The samples are those of the self-contact detection (spacing `0.2 r` by default), so
//! an obstacle much thinner than a knot span is still seen.
//!
//! An obstacle may move by a keyframed translation ([`Contact::with_moving_obstacle`]):
//! [`Lifecycle::drive`](crate::Lifecycle::drive) places it for the step's end, and its friction
//! contacts measure slip against its surface's motion in the step.

use super::surface::PenaltyPoint;
use super::Contact;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{CoreError, Keyframes, Real, Rod};

/// A rigid, static obstacle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Obstacle {
    /// The half-space on the `normal` side of the plane through `point` (unit normal).
    Plane {
        /// A point of the plane, m.
        point: Vector3<Real>,
        /// Unit normal, pointing to where the rod may be.
        normal: Vector3<Real>,
    },
    /// A ball.
    Sphere {
        /// Centre, m.
        centre: Vector3<Real>,
        /// Radius, m (> 0).
        radius: Real,
    },
    /// The points within `radius` of the segment `a`–`b`.
    Capsule {
        /// One end of the axis, m.
        a: Vector3<Real>,
        /// The other end, m (≠ `a`).
        b: Vector3<Real>,
        /// Radius, m (> 0).
        radius: Real,
    },
}

impl Obstacle {
    /// This obstacle moved by `d`.
    pub fn translated(&self, d: &Vector3<Real>) -> Self {
        match *self {
            Obstacle::Plane { point, normal } => Obstacle::Plane {
                point: point + d,
                normal,
            },
            Obstacle::Sphere { centre, radius } => Obstacle::Sphere {
                centre: centre + d,
                radius,
            },
            Obstacle::Capsule { a, b, radius } => Obstacle::Capsule {
                a: a + d,
                b: b + d,
                radius,
            },
        }
    }

    /// Checks the shape: finite values, a unit normal, positive radii, a capsule axis of
    /// non-zero length.
    pub fn validate(&self) -> Result<(), CoreError> {
        let invalid = |name, value, reason| {
            Err(CoreError::InvalidParameter {
                name,
                value,
                reason,
            })
        };
        let finite = |v: &Vector3<Real>| v.iter().all(|x| x.is_finite());
        match *self {
            Obstacle::Plane { point, normal } => {
                if !finite(&point) {
                    return invalid("plane point", Real::NAN, "must be finite");
                }
                let n = normal.norm();
                if n.is_nan() || (n - 1.0).abs() >= 1e-12 {
                    return invalid("plane normal", n, "must be a unit vector");
                }
            }
            Obstacle::Sphere { centre, radius } => {
                if !finite(&centre) {
                    return invalid("sphere centre", Real::NAN, "must be finite");
                }
                splinerod_core::rod::positive("sphere radius", radius)?;
            }
            Obstacle::Capsule { a, b, radius } => {
                if !finite(&a) || !finite(&b) {
                    return invalid("capsule axis", Real::NAN, "must be finite");
                }
                if (b - a).norm() == 0.0 {
                    return invalid("capsule axis", 0.0, "its ends must differ");
                }
                splinerod_core::rod::positive("capsule radius", radius)?;
            }
        }
        Ok(())
    }

    /// The derivative \\(\nabla n\\) of the outward unit normal at `x` (the surface's
    /// curvature seen from `x`; module docs).
    pub fn normal_derivative(&self, x: &Vector3<Real>) -> Matrix3<Real> {
        let turning = |v: Vector3<Real>, along: Option<Vector3<Real>>| {
            let rho = v.norm();
            if rho == 0.0 {
                return Matrix3::zeros();
            }
            let n = v / rho;
            let mut m = Matrix3::identity() - n * n.transpose();
            if let Some(u) = along {
                m -= u * u.transpose();
            }
            m / rho
        };
        match *self {
            Obstacle::Plane { .. } => Matrix3::zeros(),
            Obstacle::Sphere { centre, .. } => turning(x - centre, None),
            Obstacle::Capsule { a, b, .. } => {
                let axis = b - a;
                let t = (x - a).dot(&axis) / axis.norm_squared();
                let core = a + axis * t.clamp(0.0, 1.0);
                let side = (t > 0.0 && t < 1.0).then(|| axis.normalize());
                turning(x - core, side)
            }
        }
    }

    /// Signed distance (m) from `x` to the surface (negative inside) and the outward
    /// unit normal there.
    pub fn distance(&self, x: &Vector3<Real>) -> (Real, Vector3<Real>) {
        match *self {
            Obstacle::Plane { point, normal } => (normal.dot(&(x - point)), normal),
            Obstacle::Sphere { centre, radius } => away_from(x - centre, radius),
            Obstacle::Capsule { a, b, radius } => {
                let axis = b - a;
                let t = ((x - a).dot(&axis) / axis.norm_squared()).clamp(0.0, 1.0);
                away_from(x - (a + axis * t), radius)
            }
        }
    }
}

/// Distance and normal from a core point at offset `v`, for a surface `radius` away.
fn away_from(v: Vector3<Real>, radius: Real) -> (Real, Vector3<Real>) {
    let d = v.norm();
    // At the core itself any direction is outward; take a fixed one.
    let n = if d > 0.0 { v / d } else { Vector3::y() };
    (d - radius, n)
}

/// Obstacles moving on keyframed translations: their shapes at zero translation, their
/// paths (`None`: static) and the time they were last driven to.
#[derive(Debug, Clone, Default)]
pub(crate) struct Motion {
    pub base: Vec<Obstacle>,
    pub paths: Vec<Option<Keyframes<Vector3<Real>>>>,
    pub time: Real,
}

impl Motion {
    /// How far obstacle `i` moves over the `dt` seconds before the time it was driven to.
    pub fn step(&self, i: usize, dt: Real) -> Vector3<Real> {
        match self.paths.get(i).and_then(Option::as_ref) {
            Some(path) => path.at(self.time) - path.at(self.time - dt),
            None => Vector3::zeros(),
        }
    }
}

impl Contact {
    /// Adds a rigid obstacle moving by the translations `path` (m against s; its shape
    /// as given is at zero translation), builder style.
    pub fn with_moving_obstacle(
        mut self,
        obstacle: Obstacle,
        path: Keyframes<Vector3<Real>>,
    ) -> Result<Self, CoreError> {
        obstacle.validate()?;
        while self.motion.paths.len() < self.obstacles.len() {
            let i = self.motion.paths.len();
            self.motion.base.push(self.obstacles[i]);
            self.motion.paths.push(None);
        }
        self.obstacles.push(obstacle.translated(&path.at(0.0)));
        self.motion.base.push(obstacle);
        self.motion.paths.push(Some(path));
        Ok(self)
    }

    /// Moves the obstacles to their places at time `t`.
    pub(crate) fn move_obstacles(&mut self, t: Real) {
        self.motion.time = t;
        for (i, path) in self.motion.paths.iter().enumerate() {
            if let Some(path) = path {
                self.obstacles[i] = self.motion.base[i].translated(&path.at(t));
            }
        }
    }

    /// Calls `f` for every sample of the rod within the penalty's reach of an obstacle.
    pub(crate) fn for_each_obstacle_point(
        &self,
        rod: &Rod,
        mut f: impl FnMut(&PenaltyPoint<'_>),
    ) -> Result<(), CoreError> {
        if self.obstacles.is_empty() {
            return Ok(());
        }
        let d = self.detected(rod)?;
        let onset = self.params.onset;
        let samples = &d.samples;
        for (k, x) in samples.position.iter().enumerate() {
            let r = self.radius_at(samples.s[k]);
            for (i, o) in self.obstacles.iter().enumerate() {
                let (distance, normal) = o.distance(x);
                let gap = distance - r;
                if gap < onset {
                    f(&PenaltyPoint {
                        gap,
                        weight: samples.weight[k] / (2.0 * r),
                        normal,
                        first: samples.first[k] as usize,
                        row: samples.row(k),
                        obstacle: Some(i),
                        radius: r,
                        s: samples.s[k],
                        at: *x,
                    });
                }
            }
        }
        Ok(())
    }

    /// Appends, for every obstacle the rod touches, the material coordinate of its
    /// sample closest to it (an interaction point for refinement criteria).
    pub(crate) fn obstacle_interaction_points(
        &self,
        rod: &Rod,
        out: &mut Vec<Real>,
    ) -> Result<(), CoreError> {
        if self.obstacles.is_empty() {
            return Ok(());
        }
        let d = self.detected(rod)?;
        let onset = self.params.onset;
        for o in &self.obstacles {
            let samples = d.samples.position.iter().zip(&d.samples.s);
            let gaps = samples.map(|(x, &s)| o.distance(x).0 - self.radius_at(s));
            let closest = gaps.enumerate().min_by(|a, b| a.1.total_cmp(&b.1));
            if let Some((k, _)) = closest.filter(|(_, g)| *g < onset) {
                out.push(d.samples.s[k]);
            }
        }
        Ok(())
    }

    /// The force the rod exerts on each obstacle now, N: the reaction to the penalty
    /// \\(-w\, \phi'(g)\, n\\) at every sample touching it, plus friction's (the lags of
    /// the step under way, at the current positions).
    pub fn obstacle_forces(&self, rod: &Rod) -> Result<Vec<Vector3<Real>>, CoreError> {
        let mut forces = vec![Vector3::zeros(); self.obstacles.len()];
        self.for_each_obstacle_point(rod, |p| {
            if let Some(f) = p.obstacle.and_then(|i| forces.get_mut(i)) {
                *f += p.normal * (p.weight * self.penalty.slope(p.gap));
            }
        })?;
        if self.has_friction() {
            let friction = self.friction_state();
            friction.add_obstacle_forces(rod, &mut forces);
        }
        Ok(forces)
    }

    /// Number of points of the rod within the penalty's reach of the floor (quadrature
    /// points) or an obstacle (samples), and the smallest distance of the centre line
    /// from either over the rod's radius (`None` without such contacts).
    pub(crate) fn obstacle_summary(&self, rod: &Rod) -> Result<(usize, Option<Real>), CoreError> {
        let (mut count, mut least) = (0, None::<Real>);
        self.for_each_surface_point(rod, |p| {
            count += 1;
            let ratio = (p.gap + p.radius) / p.radius;
            least = Some(least.map_or(ratio, |l| l.min(ratio)));
        })?;
        Ok((count, least))
    }
}
