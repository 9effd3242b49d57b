//! Implicit (backward) Euler: \\(v^+ = v_0 + h M^{-1} f(q^+, v^+)\\),
//! \\(q^+ = q_0 + h v^+\\), solved by Newton on the incremental potential
//!
//! \\[ \Phi(v) = \tfrac12 (v - v_0)^T M (v - v_0) + E(q_0 + h v) + \tfrac{h\alpha}{2} v^T M v, \\]
//!
//! whose gradient is the residual \\(M(v - v_0) + h\nabla E + h\alpha M v\\) and whose
//! Newton matrix is \\((1 + h\alpha) M + h^2 K\\). Pins hold \\(C(s_p, t + h) = p\\), i.e.
//! \\(G v = (p - G q_0)/h\\). First order; damps a mode of angular frequency ω by
//! \\(1/\sqrt{1 + (\omega h)^2}\\) per step, so it never gains energy.

use crate::newton::{self, NewtonParams, NewtonProblem, NewtonWorkspace};
use crate::{error::positive, Integrator, IntegratorError, StepStats, System};
use nalgebra::Vector3;
use splinerod_core::{rod::check_finite, BasisValues, BlockBanded, HessianKind, Pin, Real, Rod};

/// Implicit Euler with Newton iterations (an [`Integrator`]).
#[derive(Debug, Default)]
pub struct ImplicitEuler {
    /// Newton settings.
    pub params: NewtonParams,
    workspace: NewtonWorkspace,
    q0: Vec<Vector3<Real>>,
    v0: Vec<Vector3<Real>>,
    x: Vec<Vector3<Real>>,
    scratch: Vec<Vector3<Real>>,
}

impl ImplicitEuler {
    /// An implicit Euler integrator with the given Newton settings.
    pub fn new(params: NewtonParams) -> Result<Self, IntegratorError> {
        params.validate()?;
        Ok(Self {
            params,
            ..Self::default()
        })
    }

    /// Pin forces of the last step, N (one per pin, acting on the rod).
    pub fn pin_forces(&self, dt: Real) -> impl Iterator<Item = Vector3<Real>> + '_ {
        self.workspace.multipliers().iter().map(move |m| m / dt)
    }
}

struct EulerProblem<'a> {
    q0: &'a [Vector3<Real>],
    v0: &'a [Vector3<Real>],
    h: Real,
    alpha: Real,
    scratch: &'a mut [Vector3<Real>],
    hessian: HessianKind,
}

impl NewtonProblem for EulerProblem<'_> {
    fn apply(&self, rod: &mut Rod, x: &[Vector3<Real>]) {
        rod.velocities.copy_from_slice(x);
        for ((q, q0), v) in rod.positions.iter_mut().zip(self.q0).zip(x) {
            *q = q0 + v * self.h;
        }
    }

    fn residual(&mut self, system: &dyn System, r: &mut [Vector3<Real>]) {
        let rod = system.rod();
        let tmp = &mut *self.scratch;
        for ((t, v), v0) in tmp.iter_mut().zip(&rod.velocities).zip(self.v0) {
            *t = v * (1.0 + self.h * self.alpha) - v0;
        }
        rod.mass_matrix().mul_vec3(tmp, r);
        tmp.iter_mut().for_each(|t| *t = Vector3::zeros());
        system.add_potential_gradient(tmp);
        r.iter_mut()
            .zip(tmp.iter())
            .for_each(|(r, g)| *r += g * self.h);
    }

    fn matrix(&mut self, system: &dyn System, a: &mut BlockBanded) {
        let rod = system.rod();
        a.reset(rod.len(), rod.basis().degree());
        system.add_potential_hessian(self.hessian, a);
        a.scale(self.h * self.h);
        a.add_scaled_scalar(1.0 + self.h * self.alpha, rod.mass_matrix());
    }

    fn merit(&mut self, system: &dyn System) -> Real {
        let rod = system.rod();
        let tmp = &mut *self.scratch;
        tmp.iter_mut()
            .zip(&rod.velocities)
            .zip(self.v0)
            .for_each(|((t, v), v0)| *t = v - v0);
        let inertia = 0.5 * rod.mass_matrix().bilinear_vec3(tmp, tmp);
        let damping = 0.5
            * self.h
            * self.alpha
            * rod
                .mass_matrix()
                .bilinear_vec3(&rod.velocities, &rod.velocities);
        inertia + system.potential_energy() + damping
    }

    fn target(&self, row: &BasisValues, pin: &Pin) -> Vector3<Real> {
        (pin.position - row.combine(&row.value, self.q0)) / self.h
    }

    fn length_per_unknown(&self) -> Real {
        self.h
    }

    fn on_not_positive_definite(&mut self) -> bool {
        let retry = self.hessian == HessianKind::Exact;
        self.hessian = HessianKind::Definite;
        retry
    }
}

impl Integrator for ImplicitEuler {
    fn name(&self) -> &str {
        "implicit-euler"
    }

    fn step(&mut self, system: &mut dyn System, dt: Real) -> Result<StepStats, IntegratorError> {
        positive("dt", dt)?;
        let rod = system.rod();
        let alpha = rod.damping;
        if !(alpha.is_finite() && alpha >= 0.0) {
            let reason = "must be finite and non-negative";
            return Err(IntegratorError::InvalidParameter {
                name: "damping",
                value: alpha,
                reason,
            });
        }
        rod.check_finite()?;
        let n = rod.len();
        for v in [&mut self.q0, &mut self.v0, &mut self.x, &mut self.scratch] {
            v.resize(n, Vector3::zeros());
        }
        self.q0.copy_from_slice(&rod.positions);
        self.v0.copy_from_slice(&rod.velocities);
        self.x.copy_from_slice(&rod.velocities);
        let mut problem = EulerProblem {
            q0: &self.q0,
            v0: &self.v0,
            h: dt,
            alpha,
            scratch: &mut self.scratch,
            hessian: HessianKind::Exact,
        };
        let result = newton::solve(
            &mut problem,
            system,
            &mut self.x,
            &self.params,
            &mut self.workspace,
        )
        .and_then(|stats| {
            let rod = system.rod();
            check_finite("position", &rod.positions)
                .and_then(|_| check_finite("velocity", &rod.velocities))
                .map_err(|_| IntegratorError::NonFinite {
                    what: "positions or velocities",
                })?;
            Ok(stats)
        });
        match result {
            Ok(stats) => Ok(stats),
            Err(e) => {
                let rod = system.rod_mut();
                rod.positions.copy_from_slice(&self.q0);
                rod.velocities.copy_from_slice(&self.v0);
                Err(e)
            }
        }
    }
}
