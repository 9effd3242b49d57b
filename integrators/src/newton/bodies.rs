//! Rigid bodies in the Newton system: a bordered KKT system, reduced onto the pins.
//!
//! A body's unknown is \\(y = (u, w)\\): its pose during the solve is
//! \\(x = \hat x + s\,u\\), \\(R = \exp(\[s\,w\]_\times)\hat R\\) with `s = β` for a time
//! step (`u`, `w` are then the velocity and angular velocity at the step's end) and
//! `s = 1` for a static solve. A pin held by the body at its body-fixed point `r` has
//! the target \\(p(y) = x + R r\\) (in the rod's unknowns: \\(c(y) = (p(y) - G\hat q)/\rho\\),
//! ρ the reach), so its linearised constraint is \\(G\Delta x - J\Delta y = c - Gx\\) with
//!
//! \\[ J = \tfrac{s}{\rho}\,P\,\big\[\,I,\ -\[\ell\]_\times T(s w)\,\big\], \\]
//!
//! `ℓ = R r` the lever from the centre of mass (for an exact clamp's tangent pin, the
//! body-fixed point on the held line nearest the control point, with the line's
//! projector `P`), `T` the left Jacobian of SO(3). The body's merit (time step, implicit
//! Euler with the gyroscopic term at the step's start folded into \\(\hat w\\)) is
//!
//! \\[ \Phi_b = \tfrac12 M|u - \hat u|^2 + \tfrac12 (w - \hat w)^T I_w (w - \hat w)
//!     - s F\cdot u - s\tau\cdot w, \qquad
//!     \hat w = \omega_0 - s I_w^{-1}(\omega_0 \times I_w\omega_0), \\]
//!
//! (statics: \\(-F\cdot u - \tau\cdot w\\)), with residual \\(r_b\\) and matrix `B`:
//! `diag(M, I_w)` for a step, the static solver's regularisation ε·diag(M, I_w) for a
//! solve, plus the constraints' geometric stiffness
//! \\(\tfrac{s^2}{\rho}\,\mathrm{sym}(\mu\ell^T) - (\mu\cdot\ell)I\\) from the last
//! multipliers (dropped if it makes `B` indefinite). The body's equation
//! \\(B\Delta y = -(r_b + J^T\mu)\\) eliminates it: the pins' Schur complement gains
//! \\(J B^{-1} J^T\\) (a compliance) and their gaps \\(-J B^{-1} r_b\\)
//! ([`crate::kkt::Constraints`]), and after the multipliers
//! \\(\Delta y = -B^{-1}(r_b + J^T\mu)\\). The multiplier μ is what the pin exerts on the
//! rod (times β in a step), so the body feels −μ: action and reaction are one unknown,
//! solved with the rods in one Newton system, not staggered.

use super::{NewtonProblem, NewtonWorkspace};
use crate::kkt::Constraints;
use crate::{IntegratorError, System};
use nalgebra::{Matrix3, Matrix3x6, Matrix6, UnitQuaternion, Vector3, Vector6};
use splinerod_core::body::{left_jacobian, skew};
use splinerod_core::{Pin, Real, RigidBody, Rod};

/// How a Newton problem moves bodies ([`crate::newton::NewtonProblem::body_form`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum BodyForm {
    /// A time step: poses \\(\hat x + \beta u\\), \\(\exp(\beta w)\hat R\\), reached at
    /// the step's end (the reach must equal β: implicit Euler).
    Dynamic {
        /// The effective step β.
        beta: Real,
        /// The reach ρ (pins hold at \\(\hat q + \rho x\\)).
        reach: Real,
    },
    /// A static solve: `regularization` (1/s²) times diag(M, I_w) on the body's matrix.
    Static {
        /// The static solver's regularisation, ε · max K / max M.
        regularization: Real,
    },
}

/// One body during a solve.
#[derive(Debug, Clone, Default)]
struct Iterate {
    mass: Real,
    /// World inertia at the solve's start.
    inertia: Matrix3<Real>,
    base_x: Vector3<Real>,
    base_r: UnitQuaternion<Real>,
    /// Reference velocities \\(\hat u, \hat w\\).
    reference: Vector6<Real>,
    /// External force and torque.
    load: Vector6<Real>,
    y: Vector6<Real>,
    dy: Vector6<Real>,
    saved: Vector6<Real>,
    residual: Vector6<Real>,
    inverse: Matrix6<Real>,
    /// Longest lever from the centre of mass (m), for measuring a rotation's motion.
    reach: Real,
}

/// One held pin.
#[derive(Debug, Clone, Copy)]
struct Link {
    pin: usize,
    body: usize,
    point: Vector3<Real>,
    axis: Option<Vector3<Real>>,
    lever: Vector3<Real>,
    jac: Matrix3x6<Real>,
}

/// The bodies of a solve and the pins they hold (inactive without bodies).
#[derive(Debug, Default)]
pub(crate) struct Coupling {
    form: Option<BodyForm>,
    bodies: Vec<Iterate>,
    links: Vec<Link>,
    /// The system's pins with the held ones following the bodies.
    pub pins: Vec<Pin>,
}

impl Coupling {
    /// Whether bodies take part in the solve under way.
    pub fn active(&self) -> bool {
        self.form.is_some()
    }

    /// Ends the coupling (a solve without bodies, or a tangent solve).
    pub fn clear(&mut self) {
        self.form = None;
    }

    /// Starts a solve: reads the system's bodies and attachments (none: inactive); the
    /// step starts from `base` when given (one per body of the system), else from the
    /// system's bodies.
    pub fn begin(
        &mut self,
        system: &dyn System,
        form: Option<BodyForm>,
        base: Option<&[RigidBody]>,
    ) -> Result<bool, IntegratorError> {
        self.form = None;
        if system.bodies().is_empty() {
            return Ok(false);
        }
        let bodies = match base {
            Some(base) if base.len() == system.bodies().len() => base,
            Some(_) => {
                return Err(IntegratorError::SolverState(
                    "a step's base has another number of bodies than the system",
                ))
            }
            None => system.bodies(),
        };
        let form = form.ok_or(IntegratorError::SolverState(
            "rigid bodies are integrated by implicit Euler, BDF2 and the static solver only",
        ))?;
        let s = match form {
            BodyForm::Dynamic { beta, reach } if beta != reach => {
                return Err(IntegratorError::SolverState(
                    "rigid bodies need a scheme whose reach is its step (implicit Euler, BDF2)",
                ))
            }
            BodyForm::Dynamic { beta, .. } => beta,
            BodyForm::Static { .. } => 1.0,
        };
        self.pins.clear();
        self.pins.extend_from_slice(system.pins());
        self.links.clear();
        for a in system.attachments() {
            if a.pin >= self.pins.len() || a.body >= bodies.len() {
                return Err(IntegratorError::SolverState(
                    "an attachment names a pin or a body the system does not have",
                ));
            }
            let (lever, jac) = (Vector3::zeros(), Matrix3x6::zeros());
            let (pin, body, point, axis) = (a.pin, a.body, a.point, a.axis);
            self.links.push(Link {
                pin,
                body,
                point,
                axis,
                lever,
                jac,
            });
        }
        self.bodies.clear();
        for (k, b) in bodies.iter().enumerate() {
            b.check()
                .map_err(|_| IntegratorError::NonFinite { what: "rigid body" })?;
            let inertia = b.world_inertia();
            let w0 = b.angular_velocity;
            let (y, reference) = match form {
                BodyForm::Dynamic { .. } => {
                    let gyro = inertia
                        .try_inverse()
                        .map_or(Vector3::zeros(), |inv| inv * w0.cross(&(inertia * w0)));
                    let w_ref = w0 - gyro * s;
                    (stack(b.velocity, w0), stack(b.velocity, w_ref))
                }
                BodyForm::Static { .. } => (Vector6::zeros(), Vector6::zeros()),
            };
            let reach = self
                .links
                .iter()
                .filter(|l| l.body == k)
                .map(|l| l.point.norm())
                .fold((inertia.trace() / b.mass).sqrt(), Real::max);
            self.bodies.push(Iterate {
                mass: b.mass,
                inertia,
                base_x: b.position,
                base_r: b.orientation,
                reference,
                load: stack(b.force, b.torque),
                y,
                reach,
                ..Iterate::default()
            });
        }
        self.form = Some(form);
        Ok(true)
    }

    /// Takes the problem's form again (a static solve's regularisation changes between
    /// iterations); the kind of form must stay.
    pub fn set_form(&mut self, form: Option<BodyForm>) {
        if let (Some(now), Some(new)) = (self.form, form) {
            if std::mem::discriminant(&now) == std::mem::discriminant(&new) {
                self.form = Some(new);
            }
        }
    }

    /// The pins the bodies hold (they go through the Schur complement).
    pub fn held_pins(&self) -> impl Iterator<Item = usize> + '_ {
        self.links.iter().map(|l| l.pin)
    }

    /// `s` (β or 1) and `s/ρ`.
    fn scales(&self) -> (Real, Real) {
        match self.form {
            Some(BodyForm::Dynamic { beta, reach }) => (beta, beta / reach),
            _ => (1.0, 1.0),
        }
    }

    /// Body `k`'s pose at its iterate.
    fn pose(&self, k: usize) -> (Vector3<Real>, UnitQuaternion<Real>) {
        let (s, _) = self.scales();
        let b = &self.bodies[k];
        let u = b.y.fixed_rows::<3>(0).into_owned();
        let w = b.y.fixed_rows::<3>(3).into_owned();
        (b.base_x + u * s, UnitQuaternion::new(w * s) * b.base_r)
    }

    /// Moves the held pins to the bodies' iterates and linearises them at the rod's
    /// applied positions.
    pub fn refresh(&mut self, rod: &Rod) -> Result<(), IntegratorError> {
        let (s, ratio) = self.scales();
        for i in 0..self.links.len() {
            let link = self.links[i];
            let (x, r) = self.pose(link.body);
            let w = self.bodies[link.body].y.fixed_rows::<3>(3).into_owned();
            let arm = r * link.point;
            let pin = &mut self.pins[link.pin];
            pin.position = x + arm;
            let (lever, projector) = match link.axis {
                Some(axis) => {
                    let a = r * axis;
                    pin.slides_along = Some(a);
                    let row = pin.row(rod)?;
                    let held = row.combine(&row.value, &rod.positions);
                    (arm + a * a.dot(&(held - pin.position)), pin.projector())
                }
                None => (arm, Matrix3::identity()),
            };
            let turn = -skew(&lever) * left_jacobian(&(w * s));
            let mut jac = Matrix3x6::zeros();
            jac.fixed_view_mut::<3, 3>(0, 0).copy_from(&projector);
            jac.fixed_view_mut::<3, 3>(0, 3)
                .copy_from(&(projector * turn));
            self.links[i].lever = lever;
            self.links[i].jac = jac * ratio;
        }
        Ok(())
    }

    /// Body `k`'s own potential at its iterate ([`System::add_body_potential`]) with
    /// its gradient and Hessian in the unknowns `y`: \(s\,(g_x, T^T g_\theta)\) and
    /// \(J^T H J\), \(J = \mathrm{diag}(sI, sT)\).
    fn potential(&self, system: &dyn System, k: usize) -> (Real, Vector6<Real>, Matrix6<Real>) {
        let (s, _) = self.scales();
        let (x, r) = self.pose(k);
        let (mut g, mut h) = (Vector6::zeros(), Matrix6::zeros());
        let e = system.add_body_potential(k, (&x, &r), &mut g, &mut h);
        if e == 0.0 && g == Vector6::zeros() && h == Matrix6::zeros() {
            return (e, g, h);
        }
        let w = self.bodies[k].y.fixed_rows::<3>(3).into_owned();
        let mut jac = Matrix6::identity() * s;
        jac.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(left_jacobian(&(w * s)) * s));
        (e, jac.transpose() * g, jac.transpose() * h * jac)
    }

    /// Each body's residual and (inverted) matrix at its iterate, with its own
    /// potential and the geometric stiffness of the multipliers `mu` of the last
    /// iteration.
    pub fn assemble(
        &mut self,
        system: &dyn System,
        mu: &[Vector3<Real>],
    ) -> Result<(), IntegratorError> {
        let (s, ratio) = self.scales();
        let form = self.form.ok_or(IntegratorError::SolverState("no bodies"))?;
        for k in 0..self.bodies.len() {
            let (_, pg, ph) = self.potential(system, k);
            let b = &mut self.bodies[k];
            let mass = Matrix6::from_diagonal(&stack(Vector3::repeat(b.mass), Vector3::zeros()))
                + embed(&b.inertia);
            let (residual, matrix) = match form {
                BodyForm::Dynamic { .. } => (mass * (b.y - b.reference) - b.load * s, mass),
                BodyForm::Static { regularization } => (-b.load, mass * regularization),
            };
            let (residual, matrix) = (residual + pg, matrix + ph);
            let mut geometric = Matrix3::zeros();
            for l in self.links.iter().filter(|l| l.body == k) {
                let m = mu.get(l.pin).copied().unwrap_or_default();
                let outer = m * l.lever.transpose();
                geometric +=
                    (outer + outer.transpose()) * 0.5 - Matrix3::identity() * m.dot(&l.lever);
            }
            let geometric = embed(&(geometric * (s * ratio)));
            let inverse = (matrix + geometric)
                .cholesky()
                .or_else(|| matrix.cholesky())
                .ok_or(IntegratorError::SolverState(
                    "a rigid body's Newton matrix is not positive definite \
                     (a static body only the rod's pins hold still?)",
                ))?
                .inverse();
            b.residual = residual;
            b.inverse = inverse;
        }
        Ok(())
    }

    /// Hands the constraints the bodies' compliance \\(J B^{-1} J^T\\) between the pins
    /// of each body and the gap offsets \\(J B^{-1} r_b\\).
    pub fn couple(&self, constraints: &mut Constraints) {
        let blocks = self.links.iter().flat_map(|a| {
            let inverse = &self.bodies[a.body].inverse;
            self.links
                .iter()
                .filter(move |b| b.body == a.body)
                .map(move |b| (a.pin, b.pin, a.jac * inverse * b.jac.transpose()))
        });
        let offsets = self.links.iter().map(|l| {
            let b = &self.bodies[l.body];
            (l.pin, l.jac * (b.inverse * b.residual))
        });
        constraints.set_coupling(blocks, offsets);
    }

    /// The bodies' steps from the multipliers, \\(\Delta y = -B^{-1}(r_b + J^T\mu)\\);
    /// returns their part of the slope, \\(\sum (r_b + J^T\mu)\cdot\Delta y\\).
    pub fn direction(&mut self, mu: &[Vector3<Real>]) -> Real {
        let mut slope = 0.0;
        for (k, b) in self.bodies.iter_mut().enumerate() {
            let mut g = b.residual;
            for l in self.links.iter().filter(|l| l.body == k) {
                g += l.jac.transpose() * mu[l.pin];
            }
            b.dy = -(b.inverse * g);
            slope += g.dot(&b.dy);
        }
        slope
    }

    /// The largest motion of a body's point in the step (m): the centre of mass's and
    /// the rotation's at the longest lever.
    pub fn motion(&self) -> Real {
        let (s, _) = self.scales();
        let each = self.bodies.iter().map(|b| {
            let u = b.dy.fixed_rows::<3>(0).amax();
            let w = b.dy.fixed_rows::<3>(3).norm() * b.reach;
            s * u.max(w)
        });
        each.fold(0.0, Real::max)
    }

    /// Scales the bodies' steps (the step limit).
    pub fn scale_step(&mut self, factor: Real) {
        self.bodies.iter_mut().for_each(|b| b.dy *= factor);
    }

    /// Remembers the iterate a line search starts from.
    pub fn save(&mut self) {
        self.bodies.iter_mut().for_each(|b| b.saved = b.y);
    }

    /// The iterate at `t` along the step from the saved one.
    pub fn stage(&mut self, t: Real) {
        self.bodies
            .iter_mut()
            .for_each(|b| b.y = b.saved + b.dy * t);
    }

    /// The bodies' part of the merit at their iterates.
    pub fn merit(&self, system: &dyn System) -> Real {
        let Some(form) = self.form else { return 0.0 };
        let (s, _) = self.scales();
        let potential: Real = (0..self.bodies.len())
            .map(|k| {
                let (x, r) = self.pose(k);
                let (mut g, mut h) = (Vector6::zeros(), Matrix6::zeros());
                system.add_body_potential(k, (&x, &r), &mut g, &mut h)
            })
            .sum();
        let each = self.bodies.iter().map(|b| {
            let work = -s * b.load.dot(&b.y);
            match form {
                BodyForm::Dynamic { .. } => {
                    let d = b.y - b.reference;
                    let (du, dw) = (d.fixed_rows::<3>(0), d.fixed_rows::<3>(3));
                    0.5 * b.mass * du.norm_squared() + 0.5 * dw.dot(&(b.inertia * dw)) + work
                }
                BodyForm::Static { .. } => work,
            }
        });
        each.sum::<Real>() + potential
    }

    /// Writes the bodies' iterates into the system: poses, and velocities of a step
    /// (zero after a static solve).
    pub fn write_back(&self, system: &mut dyn System) {
        let Some(form) = self.form else { return };
        for (k, (body, b)) in system.bodies_mut().iter_mut().zip(&self.bodies).enumerate() {
            let (x, r) = self.pose(k);
            body.position = x;
            body.orientation = UnitQuaternion::new_normalize(r.into_inner());
            (body.velocity, body.angular_velocity) = match form {
                BodyForm::Dynamic { .. } => {
                    (b.y.fixed_rows::<3>(0).into(), b.y.fixed_rows::<3>(3).into())
                }
                BodyForm::Static { .. } => (Vector3::zeros(), Vector3::zeros()),
            };
        }
    }
}

/// Sets every pin's right-hand side from `pins` (set up in the constraints first).
pub(super) fn set_targets(
    problem: &dyn NewtonProblem,
    rod: &Rod,
    pins: &[Pin],
    ws: &mut NewtonWorkspace,
) -> Result<(), IntegratorError> {
    ws.constraints.setup(rod, pins)?;
    for (p, pin) in pins.iter().enumerate() {
        ws.constraints.targets[p] = problem.target(&ws.constraints.rows()[p], pin);
    }
    Ok(())
}

/// The rigid bodies at the iterate: their pins moved and linearised, their matrices
/// and the compliance they add to the pins' Schur complement ([`bodies`]).
pub(super) fn couple_bodies(
    problem: &dyn NewtonProblem,
    system: &dyn System,
    ws: &mut NewtonWorkspace,
) -> Result<(), IntegratorError> {
    let rod = system.rod();
    ws.coupling.set_form(problem.body_form());
    ws.coupling.refresh(rod)?;
    let pins = std::mem::take(&mut ws.coupling.pins);
    let set = set_targets(problem, rod, &pins, ws);
    ws.coupling.pins = pins;
    set?;
    ws.coupling.assemble(system, &ws.multipliers)?;
    ws.coupling.couple(&mut ws.constraints);
    Ok(())
}

/// `(a, b)` as one 6-vector.
fn stack(a: Vector3<Real>, b: Vector3<Real>) -> Vector6<Real> {
    Vector6::new(a.x, a.y, a.z, b.x, b.y, b.z)
}

/// A 3×3 block in the rotational corner of a 6×6 matrix.
fn embed(m: &Matrix3<Real>) -> Matrix6<Real> {
    let mut out = Matrix6::zeros();
    out.fixed_view_mut::<3, 3>(3, 3).copy_from(m);
    out
}
