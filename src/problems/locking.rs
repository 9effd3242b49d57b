//! The membrane-locking study (issue #12): the static catenary (L = 1 m, pins 0.8 m
//! apart, μ = 0.1 kg/m, cubic, clamped uniform knots) against the exact elastic catenary
//! of the same Green–Lagrange law ([`ElasticCatenary`]), at growing axial stiffness.
//!
//! The solve starts from the exact curve sampled at the Greville abscissae (so every
//! formulation is asked for *its* equilibrium next to the true one, not for a path to
//! it) and the error is the largest distance between material points, at 41 points.
//! `EA = ∞` compares with the inextensible catenary.

use crate::problems::elastic_catenary::ElasticCatenary;
use crate::problems::pinned_cable_with;
use crate::{Error, RodSystem};
use nalgebra::Vector3;
use splinerod_core::basis::greville;
use splinerod_core::Real;
use splinerod_energies::StretchFormulation;
use splinerod_integrators::{StaticParams, StaticSolver};

/// Weight per length of the study's cable, N/m.
pub const WEIGHT: Real = 0.1 * 9.81;

/// The study's cable with `n` control points at stiffness `ea`, placed on the exact curve.
pub fn cable_on_exact_curve(
    n: usize,
    ea: Real,
    formulation: StretchFormulation,
) -> Result<(RodSystem, ElasticCatenary), Error> {
    let exact = ElasticCatenary::new(1.0, 0.8, WEIGHT, ea)?;
    let mut system = pinned_cable_with(n, 0.8, ea.min(1e300), formulation)?;
    for i in 0..system.rod.len() {
        let p = exact.point(greville(system.rod.basis(), i));
        system.rod.positions[i] = Vector3::new(p[0], p[1], 0.0);
    }
    Ok((system, exact))
}

/// Largest material-point distance (m) between `system`'s rod and `exact`, at 41 points.
pub fn distance(system: &RodSystem, exact: &ElasticCatenary) -> Result<Real, Error> {
    let mut worst: Real = 0.0;
    for k in 0..=40 {
        let s = k as Real / 40.0;
        let p = exact.point(s);
        let q = system.rod.point(s)?;
        worst = worst.max((q - Vector3::new(p[0], p[1], 0.0)).norm());
    }
    Ok(worst)
}

/// Static equilibrium error (m) with `n` control points at stiffness `ea`.
pub fn static_error(n: usize, ea: Real, formulation: StretchFormulation) -> Result<Real, Error> {
    let (mut system, exact) = cable_on_exact_curve(n, ea, formulation)?;
    StaticSolver::new(StaticParams::default())?.solve(&mut system)?;
    distance(&system, &exact)
}

/// One row of the study: `EA` and the errors at 16, 32 and 64 control points (`None`
/// where the static solve failed).
#[derive(Debug, Clone, PartialEq)]
pub struct LockingRow {
    /// Axial stiffness, N.
    pub stiffness: Real,
    /// Errors at 16, 32 and 64 control points, m.
    pub errors: [Option<Real>; 3],
}

/// Stiffnesses of the study, N.
pub const STIFFNESSES: [Real; 6] = [1e2, 1e4, 1e6, 1e7, 1e8, 1e9];

/// Resolutions of the study.
pub const RESOLUTIONS: [usize; 3] = [16, 32, 64];

/// The study for one formulation.
pub fn study(formulation: StretchFormulation) -> Vec<LockingRow> {
    STIFFNESSES
        .iter()
        .map(|&ea| LockingRow {
            stiffness: ea,
            errors: RESOLUTIONS.map(|n| static_error(n, ea, formulation).ok()),
        })
        .collect()
}

/// The lumped-chain peers' EA-independent error at `n` degrees of freedom, ≈ 0.14 h²
/// with h = L/(n − 1) (measured in the peer comparison, `splinerod report`).
pub fn peer_error(n: usize) -> Real {
    let h = 1.0 / (n - 1) as Real;
    0.14 * h * h
}

/// A catenary shape of the default-form study: rest length, pin distance, linear
/// density (`L`, `D`, `μ`).
pub type Shape = (Real, Real, Real);

/// The study's shapes: a 2 m rope of 0.3 kg/m between pins 1.5 m apart (stretched by
/// gravity by 5.9 % at EA = 100 N), the 1 m cable of the locking study, the same cable
/// nearly taut (pins 0.95 m apart), a deep 3 m rope (pins 1 m apart).
pub const SHAPES: [Shape; 4] = [
    (2.0, 1.5, 0.3),
    (1.0, 0.8, 0.1),
    (1.0, 0.95, 0.1),
    (3.0, 1.0, 0.5),
];

/// Stiffnesses of the default-form study, N.
pub const FORM_STIFFNESSES: [Real; 5] = [1e2, 1e3, 1e4, 1e6, 1e9];

/// The static catenary scene of `shape` at stiffness `ea` with `n` control points placed
/// on the exact curve (at the Greville abscissae), with `stretch_formulation = form`
/// (`None`: the default, `"auto"`), and the exact curve.
pub fn catenary_scene(
    (l, d, mu): Shape,
    ea: Real,
    n: usize,
    form: Option<&str>,
) -> Result<(crate::Scene, ElasticCatenary), Error> {
    let exact = ElasticCatenary::new(l, d, mu * 9.81, ea)?;
    let basis = splinerod_core::BSplineSpace::clamped_uniform(3, n, l)?;
    let points: Vec<String> = (0..n)
        .map(|i| {
            let p = exact.point(greville(&basis, i));
            format!("[{:e}, {:e}, 0.0]", p[0], p[1])
        })
        .collect();
    let form = form.map_or(String::new(), |f| {
        format!("stretch_formulation = \"{f}\"\n")
    });
    let text = format!(
        "[rod]\nrest_length = {l:e}\nlinear_density = {mu:e}\nstretch_stiffness = {ea:e}\n\
         {form}control_points = {n}\ninitial_control_points = [{}]\n\
         [[pins]]\nat = 0.0\n[[pins]]\nat = 1.0\n[world]\ngravity = [0.0, -9.81, 0.0]\n\
         [solver]\nmethod = \"static\"\n[output]\nsamples = 41\n",
        points.join(", ")
    );
    Ok((crate::Scene::from_toml(&text)?, exact))
}

/// The static equilibrium error (m, 41 material points) of [`catenary_scene`] and the
/// form the run used; `None` where the solve failed.
pub fn form_error(
    shape: Shape,
    ea: Real,
    n: usize,
    form: Option<&str>,
) -> Result<Option<(Real, String)>, Error> {
    let (scene, exact) = catenary_scene(shape, ea, n, form)?;
    let Ok(result) = crate::run(&scene) else {
        return Ok(None);
    };
    let l = exact.length;
    let points = result.samples.s.iter().zip(&result.samples.positions);
    let error = points
        .map(|(&f, p)| {
            let q = exact.point(f * l);
            (p[0] - q[0]).hypot(p[1] - q[1]).hypot(p[2])
        })
        .fold(0.0, Real::max);
    Ok(Some((error, result.rod.stretch_formulation_used)))
}

/// One row of the default-form study: a shape, a stiffness, and per resolution (16, 32,
/// 64 points) the errors of the pointwise, lumped mixed, consistent mixed and default
/// forms (`None` where a solve failed) with the form the default chose.
#[derive(Debug, Clone, PartialEq)]
pub struct FormRow {
    /// `L`, `D`, `μ`.
    pub shape: Shape,
    /// Axial stiffness, N.
    pub stiffness: Real,
    /// Per resolution: `[pointwise, mixed, mixed-consistent, default]` errors (m).
    pub errors: [[Option<Real>; 4]; 3],
    /// Per resolution: the form the default chose.
    pub chosen: [String; 3],
}

/// The default-form study over [`SHAPES`] and [`FORM_STIFFNESSES`].
pub fn form_study() -> Result<Vec<FormRow>, Error> {
    form_study_of(&SHAPES, &FORM_STIFFNESSES)
}

/// The default-form study over `shapes` × `stiffnesses` (N), at every one of
/// [`RESOLUTIONS`].
pub fn form_study_of(shapes: &[Shape], stiffnesses: &[Real]) -> Result<Vec<FormRow>, Error> {
    let mut rows = Vec::new();
    for &shape in shapes {
        for &ea in stiffnesses {
            let mut row = FormRow {
                shape,
                stiffness: ea,
                errors: [[None; 4]; 3],
                chosen: Default::default(),
            };
            for (k, n) in RESOLUTIONS.into_iter().enumerate() {
                for (j, form) in [
                    Some("pointwise"),
                    Some("mixed"),
                    Some("mixed-consistent"),
                    None,
                ]
                .into_iter()
                .enumerate()
                {
                    let result = form_error(shape, ea, n, form)?;
                    row.errors[k][j] = result.as_ref().map(|r| r.0);
                    if form.is_none() {
                        row.chosen[k] = result.map_or(String::new(), |r| r.1);
                    }
                }
            }
            rows.push(row);
        }
    }
    Ok(rows)
}
