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
//! energy hears (through [`Energy::on_knot_change`]) that a knot reached multiplicity
//! `d + 1`, the twist is released and the energy is zero from then on. (Evaluated on a
//! rod it has not heard about, such a knot is just a knot: the curve is still whole.)

pub(crate) mod holonomy;

use crate::Energy;
use holonomy::{
    curvature_binormal, curvature_binormal_jacobians, for_each_sample, is_cut, required_bandwidth,
    signed_angle, transport, wrap, Sample,
};
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, CoreError, HessianKind, KnotMap, Real, Rod};

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
#[derive(Debug, Clone, PartialEq)]
pub struct Twisting {
    /// Torsional stiffness `GJ`, N·m².
    pub stiffness: Real,
    /// Turn Φ of the end clamp about its axis relative to the start clamp, rad.
    pub turn: Real,
    start: Frame,
    end: Frame,
    /// Holonomy of the untwisted state, ψ₀.
    rest: Real,
    /// The continuous value of ψ at the last step start (the branch ψ is unwrapped to).
    branch: Real,
    /// Whether the rod was cut (the twist is released).
    released: bool,
}

impl Twisting {
    /// Twisting between clamps at both ends of `rod`, which starts untwisted: the start
    /// frame is `start` (its axis should be the rod's tangent at `s = 0`), the end frame
    /// its parallel transport along the rod. `GJ > 0`.
    pub fn between_ends(stiffness: Real, rod: &Rod, start: Frame) -> Result<Self, CoreError> {
        splinerod_core::rod::positive("twist_stiffness", stiffness)?;
        check_degree(rod)?;
        let end_axis = rod.tangent(rod.material().rest_length)?;
        let mut director = start.director;
        let mut previous = start.axis;
        for_each_sample(rod, |s| {
            director = transport(&previous, &s.t, &director);
            previous = s.t;
        });
        let director = transport(&previous, &end_axis, &director);
        let end = Frame::new(end_axis, director)?;
        Self::new(stiffness, rod, start, end)
    }

    /// Twisting between clamp frames `start` (at `s = 0`) and `end` (at `s = L`) of
    /// `rod`, which starts untwisted (ψ₀ is its holonomy now). `GJ > 0`.
    pub fn new(stiffness: Real, rod: &Rod, start: Frame, end: Frame) -> Result<Self, CoreError> {
        splinerod_core::rod::positive("twist_stiffness", stiffness)?;
        check_degree(rod)?;
        let mut twisting = Self {
            stiffness,
            turn: 0.0,
            start,
            end,
            rest: 0.0,
            branch: 0.0,
            released: false,
        };
        twisting.rest = twisting.raw_holonomy(rod);
        twisting.branch = twisting.rest;
        Ok(twisting)
    }

    /// The clamp frames (start, end) when the turn is zero.
    pub fn frames(&self) -> (Frame, Frame) {
        (self.start, self.end)
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
        self.holonomy(rod) - self.rest + self.turn
    }

    /// The twisting moment \\(GJ\,\mathrm{Tw}/L\\) the clamps hold, N·m.
    pub fn moment(&self, rod: &Rod) -> Real {
        self.stiffness * self.twist(rod) / rod.material().rest_length
    }

    /// ψ in (−π, π].
    fn raw_holonomy(&self, rod: &Rod) -> Real {
        let mut director = self.start.director;
        let mut previous = self.start.axis;
        for_each_sample(rod, |s| {
            director = transport(&previous, &s.t, &director);
            previous = s.t;
        });
        let director = transport(&previous, &self.end.axis, &director);
        signed_angle(&director, &self.end.director, &self.end.axis)
    }

    /// ψ, continuous from the last step start.
    fn holonomy(&self, rod: &Rod) -> Real {
        self.branch + wrap(self.raw_holonomy(rod) - self.branch)
    }

    /// Walks the samples with their neighbours' tangents: `f(T_{k−1}, sample k, next)`,
    /// `next` the following sample or `None` for the end axis.
    fn walk(&self, rod: &Rod, mut f: impl FnMut(&Vector3<Real>, &Sample, Option<&Sample>)) {
        let mut previous = self.start.axis;
        let mut current: Option<Sample> = None;
        for_each_sample(rod, |s| {
            if let Some(c) = &current {
                f(&previous, c, Some(s));
                previous = c.t;
            }
            current = Some(*s);
        });
        if let Some(c) = &current {
            f(&previous, c, None);
        }
    }

    /// \\(h_k = \partial\psi/\partial a_k\\) given the neighbours' tangents.
    fn h(previous: &Vector3<Real>, s: &Sample, next: &Vector3<Real>) -> Vector3<Real> {
        (curvature_binormal(previous, &s.t) + curvature_binormal(&s.t, next)) * (0.5 / s.norm)
    }

    /// Adds \\(c\,\nabla\psi\\) to `gradient`.
    fn add_holonomy_gradient(&self, rod: &Rod, c: Real, gradient: &mut [Vector3<Real>]) {
        self.walk(rod, |previous, s, next| {
            let next_t = next.map_or(self.end.axis, |n| n.t);
            let h = Self::h(previous, s, &next_t) * c;
            for k in 0..s.len {
                gradient[s.first + k] += h * s.d1[k];
            }
        });
    }

    /// Adds \\(c\,\nabla^2\psi\\) (band part) to `hessian`.
    fn add_holonomy_hessian(&self, rod: &Rod, c: Real, hessian: &mut BlockBanded) {
        self.walk(rod, |previous, s, next| {
            let next_t = next.map_or(self.end.axis, |n| n.t);
            let (_, ky_prev) = curvature_binormal_jacobians(previous, &s.t);
            let (kx_next, ky_next) = curvature_binormal_jacobians(&s.t, &next_t);
            let kb = curvature_binormal(previous, &s.t) + curvature_binormal(&s.t, &next_t);
            let p = Matrix3::identity() - s.t * s.t.transpose();
            let diagonal = (ky_prev + kx_next) * p * (0.5 / (s.norm * s.norm))
                - kb * s.a.transpose() * (0.5 / s.norm.powi(3));
            let diagonal = (diagonal + diagonal.transpose()) * (0.5 * c);
            add_pair(hessian, s, None, &diagonal);
            if let Some(n) = next {
                let pn = Matrix3::identity() - n.t * n.t.transpose();
                let off = ky_next * pn * (0.5 * c / (s.norm * n.norm));
                add_pair(hessian, s, Some(n), &off);
            }
        });
    }
}

/// Adds \\(R_a^T H R_b + R_b^T H^T R_a\\) to `hessian` (just \\(R_a^T H R_a\\), `H`
/// symmetric, if `b` is `None`), with \\(R\\) the samples' rows
/// \\(a = \sum_i b_i'(s) q_i\\).
fn add_pair(hessian: &mut BlockBanded, a: &Sample, b: Option<&Sample>, h: &Matrix3<Real>) {
    let same = b.is_none();
    let b = b.unwrap_or(a);
    for i in 0..a.len {
        let range = if same { i..a.len } else { 0..b.len };
        for j in range {
            let (row, col) = (a.first + i, b.first + j);
            let w = a.d1[i] * b.d1[j];
            if !same && row == col {
                hessian.add_block(row, col, &((h + h.transpose()) * w));
            } else {
                hessian.add_block(row, col, &(h * w));
            }
        }
    }
}

fn check_degree(rod: &Rod) -> Result<(), CoreError> {
    let degree = rod.basis().degree();
    if degree >= 2 {
        return Ok(());
    }
    Err(CoreError::InvalidParameter {
        name: "degree",
        value: degree as Real,
        reason: "twisting needs degree >= 2 (a continuous tangent)",
    })
}

impl Energy for Twisting {
    fn name(&self) -> &str {
        "twisting"
    }

    fn energy(&self, rod: &Rod) -> Real {
        let tw = self.twist(rod);
        0.5 * self.stiffness * tw * tw / rod.material().rest_length
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        if !self.released {
            self.add_holonomy_gradient(rod, self.moment(rod), gradient);
        }
    }

    fn add_hessian(&self, rod: &Rod, kind: HessianKind, hessian: &mut BlockBanded) {
        if self.released {
            return;
        }
        let l = rod.material().rest_length;
        if kind == HessianKind::Exact {
            self.add_holonomy_hessian(rod, self.moment(rod), hessian);
        }
        hessian.add_low_rank_with(self.stiffness / l, |u| {
            self.add_holonomy_gradient(rod, 1.0, u);
        });
    }

    fn bandwidth(&self, rod: &Rod) -> usize {
        if self.released {
            rod.basis().degree()
        } else {
            required_bandwidth(rod)
        }
    }

    fn on_knot_change(&mut self, rod: &Rod, map: &KnotMap) {
        let _ = map;
        self.released |= is_cut(rod);
        if !self.released {
            self.branch = self.holonomy(rod);
        }
    }

    fn begin_step(&mut self, rod: &Rod, dt: Real) -> Result<(), CoreError> {
        let _ = dt;
        self.branch = self.holonomy(rod);
        Ok(())
    }
}
