//! Twisting of an isotropic rod between two clamps, with the twist eliminated
//! quasi-statically.
//!
//! The material frame is the parallel-transported (twist-free) frame turned by an angle
//! θ(s). For an isotropic rod (equal bending stiffnesses, no intrinsic twist) the
//! twisting moment \\(GJ\,\theta'\\) is the only load on θ, so at equilibrium it is
//! uniform along the rod: \\(\theta' = \mathrm{Tw}/L\\), with the total twist
//! \\(\mathrm{Tw}\\) fixed by the clamps. Twist waves travel \\(\sqrt{GJ/\rho J}\\),
//! ≈ (L/r) times faster than bending waves, so this is exact for everything slower than
//! torsional vibration, and θ leaves the unknowns (Bergou et al. 2010 make the same
//! choice; ARCHITECTURE.md gives the measurements):
//!
//! \\[ E_t = \frac{GJ}{2L}\,\mathrm{Tw}^2, \qquad
//!     \mathrm{Tw} = \psi(q) - \psi_0 + \Phi, \\]
//!
//! with ψ the holonomy of the centreline between the clamp frames ([`holonomy`]: the
//! angle by which the start clamp's director, parallel-transported along the rod, misses
//! the end clamp's), \\(\psi_0\\) its value in the untwisted start state and Φ the
//! [`turn`](Twisting::turn) of the end clamp relative to the start clamp (rad). ψ is
//! defined mod 2π; [`Twisting::begin_step`] keeps it continuous from step to step (a
//! step must not change it by π). Călugăreanu's theorem \\(\mathrm{Lk} = \mathrm{Tw} +
//! \mathrm{Wr}\\) is built in: the clamps fix the link, so writhe trades with twist.
//!
//! **Derivatives.** \\(\nabla E = \tfrac{GJ}{L}\mathrm{Tw}\,\nabla\psi\\) and
//! \\(\nabla^2 E = \tfrac{GJ}{L}(\nabla\psi\,\nabla\psi^T + \mathrm{Tw}\,\nabla^2\psi)\\):
//! the second term lies in the band, the first couples every control point with every
//! other and is added as a rank-one term ([`BlockBanded::add_low_rank`]; solvers apply it
//! by Sherman–Morrison in O(n)). [`HessianKind::Definite`] keeps the rank-one term and
//! drops \\(\mathrm{Tw}\,\nabla^2\psi\\) (indefinite: it is what makes a twisted rod
//! buckle).
//!
//! **Knot insertion.** The tangent samples follow the knots, so ψ changes by the
//! sampling error (second order in the sample spacing), which the conformance harness
//! measures; the curve itself does not move.
//!
//! **Cut rods.** A cut leaves pieces with a free end, which carry no twist: once the
//! energy hears (through [`crate::Lifecycle::on_knot_change`]) that a knot reached multiplicity
//! `d + 1`, the twist is released and the energy is zero from then on. (Evaluated on a
//! rod it has not heard about, such a knot is just a knot: the curve is still whole.)

mod closed;
pub mod grip;
pub mod holonomy;
mod lifecycle;
mod window;

use crate::capabilities::{Capabilities, Lifecycle};
use crate::Energy;
use holonomy::{
    curvature_binormal, curvature_binormal_jacobians, signed_angle, transport, wrap, Samples,
    COARSE, FINE, WEIGHTS,
};
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, CoreError, HessianKind, Keyframes, Real, Rod};
use std::sync::{Mutex, MutexGuard};
use window::Window;

/// A clamp's frame: the tangent axis and a director across it (both unit).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Unit tangent axis.
    pub axis: Vector3<Real>,
    /// Unit director orthogonal to `axis`.
    pub director: Vector3<Real>,
}

impl Frame {
    /// The frame with tangent `axis` and the director nearest to `hint` across it (both
    /// normalised); errors if `axis` is zero or not finite, or `hint` is parallel to it.
    pub fn new(axis: Vector3<Real>, hint: Vector3<Real>) -> Result<Self, CoreError> {
        let invalid = |name, value| CoreError::InvalidParameter {
            name,
            value,
            reason: "must be finite and non-zero (the director not along the axis)",
        };
        let norm = axis.norm();
        if !(norm.is_finite() && norm > 0.0) {
            return Err(invalid("frame_axis", norm));
        }
        let axis = axis / norm;
        let across = hint - axis * axis.dot(&hint);
        let length = across.norm();
        if !(length.is_finite() && length > 1e-9 * hint.norm()) {
            return Err(invalid("frame_director", length));
        }
        Ok(Self {
            axis,
            director: across / length,
        })
    }

    /// The frame with tangent `axis` and some director across it.
    pub fn along(axis: Vector3<Real>) -> Result<Self, CoreError> {
        let a = axis.abs();
        let hint = if a.x <= a.y && a.x <= a.z {
            Vector3::x()
        } else if a.y <= a.z {
            Vector3::y()
        } else {
            Vector3::z()
        };
        Self::new(axis, hint)
    }
}

/// Twisting energy with torsional stiffness `GJ` between two clamp frames.
#[derive(Debug)]
pub struct Twisting {
    /// Torsional stiffness `GJ`, N·m².
    pub stiffness: Real,
    /// Turn Φ of the end clamp about its axis relative to the start clamp, rad.
    pub turn: Real,
    start: Frame,
    end: Frame,
    /// The clamp frames before any gripper turned them ([`Twisting::grip`]).
    base: [Frame; 2],
    /// The grippers' rolls about the clamp axes (start, end), rad: part of `turn`.
    rolls: [Real; 2],
    /// Holonomies of the two polygons in the untwisted state, ψ₀.
    rest: [Real; 2],
    /// The continuous values of the polygons' ψ at the last step start (the branches
    /// they are unwrapped to).
    branch: [Real; 2],
    /// Whether the rod was cut (the twist is released).
    released: bool,
    /// Turn schedules of the start and end clamps about their axes (rad against s);
    /// [`crate::Lifecycle::drive`] sets `turn` to their difference.
    schedules: [Option<Keyframes<Real>>; 2],
    /// The tangent samples (rows cached per basis, tangents per call).
    samples: Mutex<Samples>,
    /// Whether this is the twist of a closed rod ([`Twisting::around_loop`]): the
    /// polygons close on themselves and there are no clamps.
    closed: bool,
}

impl Clone for Twisting {
    fn clone(&self) -> Self {
        Self {
            stiffness: self.stiffness,
            turn: self.turn,
            start: self.start,
            end: self.end,
            base: self.base,
            rolls: self.rolls,
            rest: self.rest,
            branch: self.branch,
            released: self.released,
            schedules: self.schedules.clone(),
            samples: Mutex::default(),
            closed: self.closed,
        }
    }
}

impl Twisting {
    /// Twisting between clamps at both ends of `rod`, which starts untwisted: the start
    /// frame is `start` (its axis should be the rod's tangent at `s = 0`), the end frame
    /// its parallel transport along the rod. `GJ > 0`.
    pub fn between_ends(stiffness: Real, rod: &Rod, start: Frame) -> Result<Self, CoreError> {
        check_degree(rod)?;
        let end_axis = rod.tangent(rod.material().rest_length)?;
        Self::between_axes(stiffness, rod, start, end_axis)
    }

    /// [`Twisting::between_ends`] with the end clamp's axis `end_axis` (a clamp holding
    /// a direction of its own; the rod's tangent there in `between_ends`): the end
    /// director is the start's parallel-transported along the rod and on to `end_axis`.
    pub fn between_axes(
        stiffness: Real,
        rod: &Rod,
        start: Frame,
        end_axis: Vector3<Real>,
    ) -> Result<Self, CoreError> {
        check_degree(rod)?;
        let mut samples = Samples::default();
        samples.prepare(rod);
        let director = transported(&samples, FINE, &start, &end_axis);
        let end = Frame::new(end_axis, director)?;
        Self::new(stiffness, rod, start, end)
    }

    /// Twisting between clamp frames `start` (at `s = 0`) and `end` (at `s = L`) of
    /// `rod`, which starts untwisted (ψ₀ is its holonomy now). `GJ > 0`.
    pub fn new(stiffness: Real, rod: &Rod, start: Frame, end: Frame) -> Result<Self, CoreError> {
        Self::starting(stiffness, rod, [start, end], 0.0, false)
    }

    /// The energy with its rest holonomies ψ₀ those of `rod` now, and twist `turn`.
    fn starting(
        stiffness: Real,
        rod: &Rod,
        [start, end]: [Frame; 2],
        turn: Real,
        closed: bool,
    ) -> Result<Self, CoreError> {
        splinerod_core::rod::positive("twist_stiffness", stiffness)?;
        check_degree(rod)?;
        let mut twisting = Self {
            stiffness,
            turn,
            start,
            end,
            base: [start, end],
            rolls: [0.0; 2],
            rest: [0.0; 2],
            branch: [0.0; 2],
            released: false,
            schedules: [None, None],
            samples: Mutex::default(),
            closed,
        };
        let raw = {
            let samples = twisting.prepared(rod);
            [FINE, COARSE].map(|p| twisting.raw_holonomy(&samples, p))
        };
        (twisting.rest, twisting.branch) = (raw, raw);
        Ok(twisting)
    }

    /// These clamps turning about their axes on schedules (rad; `None`: held still):
    /// [`crate::Lifecycle::drive`] sets [`turn`](Self::turn) to `end(t) − start(t)`.
    pub fn with_turns(
        mut self,
        start: Option<Keyframes<Real>>,
        end: Option<Keyframes<Real>>,
    ) -> Self {
        self.schedules = [start, end];
        self.drive(0.0);
        self
    }

    /// The clamp frames (start, end) when the turn is zero (carried by their grippers,
    /// [`Twisting::grip`]).
    pub fn frames(&self) -> (Frame, Frame) {
        (self.start, self.end)
    }

    /// Carries clamp `end`'s frame (0: at `s = 0`, 1: at `s = L`) with its gripper's
    /// `rotation` against its start ([`grip::carried`]: axis \(R a_0\), director the
    /// swing \(M d_0\)) and sets its roll to `roll` (rad; the branch of
    /// [`grip::carried`]'s φ the caller follows), which adds to the turn Φ (the start's
    /// with a minus sign). A rotation that is not finite, or `end > 1`, changes nothing.
    pub fn grip(&mut self, end: usize, rotation: &Matrix3<Real>, roll: Real) {
        let Some(base) = self.base.get(end) else {
            return;
        };
        let (Ok((frame, _)), true) = (grip::carried(base, rotation), roll.is_finite()) else {
            return;
        };
        let sign = if end == 0 { -1.0 } else { 1.0 };
        self.turn += sign * (roll - self.rolls[end]);
        self.rolls[end] = roll;
        match end {
            0 => self.start = frame,
            _ => self.end = frame,
        }
    }

    /// Whether a cut released the twist.
    pub fn released(&self) -> bool {
        self.released
    }

    /// The total twist Tw of the rod's material frame, rad (0 once cut).
    pub fn twist(&self, rod: &Rod) -> Real {
        if self.released {
            return 0.0;
        }
        self.twist_of(&self.prepared(rod))
    }

    /// The twisting moment \\(GJ\,\mathrm{Tw}/L\\) the clamps hold, N·m.
    pub fn moment(&self, rod: &Rod) -> Real {
        self.stiffness * self.twist(rod) / rod.material().rest_length
    }

    /// The samples, prepared for `rod`.
    fn prepared(&self, rod: &Rod) -> MutexGuard<'_, Samples> {
        let mut samples = self.samples.lock().unwrap_or_else(|e| e.into_inner());
        samples.prepare(rod);
        samples
    }

    /// The polygons' holonomies, each continuous from its branch.
    fn holonomies(&self, samples: &Samples) -> [Real; 2] {
        [FINE, COARSE].map(|p| {
            let raw = self.raw_holonomy(samples, p);
            self.branch[p] + wrap(raw - self.branch[p])
        })
    }

    fn twist_of(&self, samples: &Samples) -> Real {
        let psi = self.holonomies(samples);
        (0..2)
            .map(|p| WEIGHTS[p] * (psi[p] - self.rest[p]))
            .sum::<Real>()
            + self.turn
    }

    /// ψ of polygon `p`, in (−π, π].
    fn raw_holonomy(&self, samples: &Samples, p: usize) -> Real {
        if self.closed {
            return closed::loop_holonomy(samples, p);
        }
        let director = transported(samples, p, &self.start, &self.end.axis);
        signed_angle(&director, &self.end.director, &self.end.axis)
    }

    /// The tangents before and after vertex `j` of polygon `p`.
    fn neighbours(&self, samples: &Samples, p: usize, j: usize) -> (Vector3<Real>, Vector3<Real>) {
        let (t, polygon) = (&samples.t, &samples.polygons[p]);
        if self.closed {
            let n = polygon.len();
            return (t[polygon[(j + n - 1) % n]], t[polygon[(j + 1) % n]]);
        }
        let previous = if j == 0 {
            self.start.axis
        } else {
            t[polygon[j - 1]]
        };
        let next = polygon.get(j + 1).map_or(self.end.axis, |&k| t[k]);
        (previous, next)
    }

    /// Adds \\(c\,\nabla\psi\\) to `gradient` (ψ the weighted sum of the polygons').
    fn add_holonomy_gradient(&self, samples: &Samples, c: Real, gradient: &mut [Vector3<Real>]) {
        for (p, polygon) in samples.polygons.iter().enumerate() {
            for (j, &k) in polygon.iter().enumerate() {
                let (previous, next) = self.neighbours(samples, p, j);
                let t = &samples.t[k];
                let kb = curvature_binormal(&previous, t) + curvature_binormal(t, &next);
                let h = kb * (0.5 * c * WEIGHTS[p] / samples.norm[k]);
                let row = &samples.rows[k];
                for i in 0..row.len {
                    gradient[row.first + i] += h * row.d1[i];
                }
            }
        }
    }

    /// Adds \\(c\,\nabla^2\psi\\) (band part) to `hessian`.
    fn add_holonomy_hessian(
        &self,
        samples: &Samples,
        c: Real,
        degree: usize,
        hessian: &mut BlockBanded,
    ) {
        let mut window = Window::new(degree + 1);
        for (p, polygon) in samples.polygons.iter().enumerate() {
            let c = c * WEIGHTS[p];
            for (j, &k) in polygon.iter().enumerate() {
                let (previous, next) = self.neighbours(samples, p, j);
                let (t, a, norm) = (&samples.t[k], &samples.a[k], samples.norm[k]);
                let (_, ky_prev) = curvature_binormal_jacobians(&previous, t);
                let (kx_next, ky_next) = curvature_binormal_jacobians(t, &next);
                let kb = curvature_binormal(&previous, t) + curvature_binormal(t, &next);
                let projector = Matrix3::identity() - t * t.transpose();
                let diagonal = (ky_prev + kx_next) * projector * (0.5 / (norm * norm))
                    - kb * a.transpose() * (0.5 / norm.powi(3));
                let diagonal = (diagonal + diagonal.transpose()) * (0.5 * c);
                let row = &samples.rows[k];
                window.add(hessian, row, None, &diagonal);
                let wrap = self.closed.then(|| polygon[0]);
                if let Some(n) = polygon.get(j + 1).copied().or(wrap) {
                    let tn = &samples.t[n];
                    let pn = Matrix3::identity() - tn * tn.transpose();
                    let off = ky_next * pn * (0.5 * c / (norm * samples.norm[n]));
                    window.add(hessian, row, Some(&samples.rows[n]), &off);
                }
            }
            window.flush(hessian);
        }
    }
}

/// The director `start.director` carried by parallel transport from `start.axis` along
/// the samples to `axis`.
fn transported(
    samples: &Samples,
    polygon: usize,
    start: &Frame,
    axis: &Vector3<Real>,
) -> Vector3<Real> {
    let mut director = start.director;
    let mut previous = start.axis;
    for &k in &samples.polygons[polygon] {
        let t = &samples.t[k];
        director = transport(&previous, t, &director);
        previous = *t;
    }
    transport(&previous, axis, &director)
}

fn check_degree(rod: &Rod) -> Result<(), CoreError> {
    crate::bending::degree_at_least_two(rod, "twisting needs degree >= 2 (a continuous tangent)")
}

impl Energy for Twisting {
    fn name(&self) -> &str {
        "twist"
    }

    fn energy(&self, rod: &Rod) -> Real {
        let tw = self.twist(rod);
        0.5 * self.stiffness * tw * tw / rod.material().rest_length
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        if self.released {
            return;
        }
        let samples = self.prepared(rod);
        let moment = self.stiffness * self.twist_of(&samples) / rod.material().rest_length;
        self.add_holonomy_gradient(&samples, moment, gradient);
    }

    fn add_hessian(&self, rod: &Rod, kind: HessianKind, hessian: &mut BlockBanded) {
        if self.released {
            return;
        }
        let samples = self.prepared(rod);
        let l = rod.material().rest_length;
        if kind == HessianKind::Exact {
            let moment = self.stiffness * self.twist_of(&samples) / l;
            self.add_holonomy_hessian(&samples, moment, rod.basis().degree(), hessian);
        }
        hessian.add_low_rank_with(self.stiffness / l, |u| {
            self.add_holonomy_gradient(&samples, 1.0, u);
        });
    }

    fn bandwidth(&self, rod: &Rod) -> usize {
        if self.released {
            return rod.basis().degree();
        }
        let mut samples = self.samples.lock().unwrap_or_else(|e| e.into_inner());
        samples.bandwidth(rod)
    }

    fn capabilities(&self) -> Capabilities<'_> {
        Capabilities {
            lifecycle: Some(self),
            summary: Some(self),
            parameters: Some(self),
            ..Capabilities::default()
        }
    }

    fn lifecycle_mut(&mut self) -> Option<&mut dyn Lifecycle> {
        Some(self)
    }
}
