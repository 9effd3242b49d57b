//! Coulomb friction as a lagged dissipative potential (the incremental-potential form
//! of implicit Euler). At the start of a step every contact — a pair of material samples
//! or a floor point — is frozen as a *lag*: its normal force \\(\lambda\\) (the penalty
//! force then), its tangent projector \\(T = I - n n^T\\) and its weights `w` on the
//! control points (the sample pair's \\(b_k(s_a) - b_k(s_b)\\), or the floor point's
//! \\(b_k(s)\\)). During the step its tangential slip is
//! \\(u = T (\sum_k w_k (q_k - q_k^{start}) - m)\\), with `m` how far the surface moves in
//! the step (a moving obstacle; zero otherwise), and the friction potential
//!
//! \\[ D = \sum_{\text{lags}} \mu \lambda f_0(|u|), \qquad
//! f_0(y) = \begin{cases} y^2 / (2\epsilon) & y < \epsilon \\\\ y - \epsilon/2 & y \ge \epsilon \end{cases} \\]
//!
//! resists with force \\(\mu\lambda\\) once a contact slides more than `ε` in the step
//! (Coulomb), and like a stiff spring \\(\mu\lambda/\epsilon\\) below (sticking, smoothed).
//! Its Hessian is \\(\mu\lambda\, w w^T \otimes H_u\\) with \\(H_u = T/\epsilon\\) sticking and
//! \\(H_u = (T - \hat u \hat u^T)/|u|\\) sliding (positive semi-definite). Lagging the normal
//! force and the directions keeps the potential convex in the step; it is exact for
//! implicit Euler as the steps shrink, and dissipative for the other integrators.

use nalgebra::{Matrix3, Vector3};
use splinerod_core::basis::MAX_ORDER;
use splinerod_core::{BlockBanded, Real, Rod};

/// One frozen contact.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Lag {
    pub weights: [(usize, Real); 2 * MAX_ORDER],
    pub len: usize,
    pub tangent: Matrix3<Real>,
    /// Largest friction force `μ λ`, N: the contact's coefficient times its normal force.
    pub bound: Real,
    /// The derivative of `bound` by the contact's relative position \\(\sum_k w_k q_k\\)
    /// at the step's start, N/m: \\(-\mu w \phi''(g)\, n\\) (the gap's gradient is the
    /// normal; the normal itself held).
    pub bound_rate: Vector3<Real>,
    /// How far the surface touched moves in the step (a moving obstacle), m: slip is
    /// measured against it.
    pub surface_motion: Vector3<Real>,
    /// The obstacle touched (`None`: a pair of samples or the floor).
    pub obstacle: Option<usize>,
}

/// The lags of the current step and the positions it started from.
#[derive(Debug, Clone, Default)]
pub(crate) struct Friction {
    pub lags: Vec<Lag>,
    start: Vec<Vector3<Real>>,
    epoch: Option<u64>,
    /// Slip `ε` of this step, m.
    eps: Real,
}

impl Friction {
    /// Starts a step at the rod's state with slip `eps` (m): clears the lags (fill them
    /// with [`Self::push`]).
    pub fn begin(&mut self, rod: &Rod, eps: Real) {
        self.eps = eps;
        self.lags.clear();
        self.start.clone_from(&rod.positions);
        self.epoch = Some(rod.topology_epoch());
    }

    /// Adds a lag with weights `weights`, normal `normal`, largest friction force
    /// `bound` (`μ λ`, N) and its derivative by the gap `bound_slope` (N/m), the
    /// surface's motion in the step `surface_motion` (zero but for moving obstacles).
    pub fn push(
        &mut self,
        weights: &[(usize, Real)],
        normal: &Vector3<Real>,
        (bound, bound_slope): (Real, Real),
        surface_motion: Vector3<Real>,
        obstacle: Option<usize>,
    ) {
        let mut lag = Lag {
            weights: [(0, 0.0); 2 * MAX_ORDER],
            len: weights.len().min(2 * MAX_ORDER),
            tangent: Matrix3::identity() - normal * normal.transpose(),
            bound,
            bound_rate: normal * bound_slope,
            surface_motion,
            obstacle,
        };
        lag.weights[..lag.len].copy_from_slice(&weights[..lag.len]);
        self.lags.push(lag);
    }

    /// Whether the lags apply to `rod` (same basis as at the step's start).
    fn active(&self, rod: &Rod) -> bool {
        self.epoch == Some(rod.topology_epoch()) && self.start.len() == rod.len() && self.eps > 0.0
    }

    /// Tangential slip of `lag` since the step's start.
    fn slip(&self, lag: &Lag, q: &[Vector3<Real>]) -> Vector3<Real> {
        let moved: Vector3<Real> = lag.weights[..lag.len]
            .iter()
            .map(|&(k, w)| (q[k] - self.start[k]) * w)
            .sum();
        lag.tangent * (moved - lag.surface_motion)
    }

    /// \\(D\\) at the rod's positions.
    pub fn energy(&self, rod: &Rod) -> Real {
        if !self.active(rod) {
            return 0.0;
        }
        let eps = self.eps;
        let f0 = |y: Real| {
            if y < eps {
                0.5 * y * y / eps
            } else {
                y - 0.5 * eps
            }
        };
        self.lags
            .iter()
            .map(|lag| lag.bound * f0(self.slip(lag, &rod.positions).norm()))
            .sum()
    }

    /// Adds \\(\partial D/\partial q\\).
    pub fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        self.add_scaled_gradient(rod, 1.0, gradient);
    }

    /// Adds `scale` \\(\partial D/\partial q\\) (with `scale = 1/μ`: the derivative of
    /// the gradient by a coefficient μ every lag's bound `μλ` is linear in, the lags held).
    pub fn add_scaled_gradient(&self, rod: &Rod, scale: Real, gradient: &mut [Vector3<Real>]) {
        if !self.active(rod) {
            return;
        }
        let eps = self.eps;
        for lag in &self.lags {
            let u = self.slip(lag, &rod.positions);
            let force = u * (scale * lag.bound / u.norm().max(eps));
            for &(k, w) in &lag.weights[..lag.len] {
                gradient[k] += force * w;
            }
        }
    }

    /// Adds the derivative of \\(\partial D/\partial q\\) by the step's start positions
    /// applied to their derivative `start_rate` (one per control point). With
    /// \\(\dot a = \sum_j w_j \dot q_j^{start}\\): the slip is
    /// \\(u = T(\sum_k w_k (q_k - q_k^{start}) - m)\\), so each lag adds
    /// \\(-w_k H_u T \dot a\\) (`H_u` the Hessian block of [`Self::add_hessian`]), and
    /// its bound \\(\mu\lambda\\) follows the gap at the start, adding
    /// \\(w_k\, u\, (\partial_a(\mu\lambda) \cdot \dot a)/\max(|u|, \epsilon)\\). The
    /// normal (and so `T`) and ε are held: exact on planes and the floor.
    pub fn add_start_rate(
        &self,
        rod: &Rod,
        start_rate: &[Vector3<Real>],
        out: &mut [Vector3<Real>],
    ) {
        if !self.active(rod) || start_rate.len() != self.start.len() {
            return;
        }
        for lag in &self.lags {
            let weights = &lag.weights[..lag.len];
            let moved: Vector3<Real> = weights.iter().map(|&(k, w)| start_rate[k] * w).sum();
            let u = self.slip(lag, &rod.positions);
            let bound_rate = lag.bound_rate.dot(&moved);
            let rate = u * (bound_rate / u.norm().max(self.eps))
                - self.block(lag, &rod.positions) * (lag.tangent * moved);
            for &(k, w) in weights {
                out[k] += rate * w;
            }
        }
    }

    /// The Hessian block \\(\mu\lambda H_u\\) of `lag` at the positions `q`.
    fn block(&self, lag: &Lag, q: &[Vector3<Real>]) -> Matrix3<Real> {
        // The same operations as the Hessian always had (bit for bit).
        let u = self.slip(lag, q);
        let y = u.norm();
        let h = if y < self.eps {
            lag.tangent / self.eps
        } else {
            let along = u / y;
            (lag.tangent - along * along.transpose()) / y
        };
        h * lag.bound
    }

    /// Adds to `forces[i]` the friction force the rod exerts on obstacle `i` at its
    /// positions (the reaction to the force of each lag on the rod).
    pub fn add_obstacle_forces(&self, rod: &Rod, forces: &mut [Vector3<Real>]) {
        if !self.active(rod) {
            return;
        }
        for lag in &self.lags {
            if let Some(f) = lag.obstacle.and_then(|i| forces.get_mut(i)) {
                let u = self.slip(lag, &rod.positions);
                *f += u * (lag.bound / u.norm().max(self.eps));
            }
        }
    }

    /// Adds the (positive semi-definite) Hessian of \\(D\\).
    pub fn add_hessian(&self, rod: &Rod, hessian: &mut BlockBanded) {
        if !self.active(rod) {
            return;
        }
        for lag in &self.lags {
            let h = self.block(lag, &rod.positions);
            let weights = &lag.weights[..lag.len];
            for (a, &(i, wi)) in weights.iter().enumerate() {
                for &(j, wj) in &weights[a..] {
                    hessian.add_coupling(i, j, &(h * (wi * wj)));
                }
            }
        }
    }
}
