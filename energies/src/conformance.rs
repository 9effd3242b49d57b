//! A conformance harness that every [`Energy`] must pass, written once and run on each
//! implementation: gradient against central differences of the energy, exact Hessian
//! against central differences of the gradient, symmetry, positive semi-definiteness of
//! the Newton (definite) Hessian, invariance under rigid motions, exact invariance and
//! covariance under knot insertion (\\(E_1(\beta q) = E_0(q)\\),
//! \\(\nabla E_0 = \beta^T \nabla E_1\\)), and zero energy and force at rest.
//!
//! The test rods cover degrees 2–4, clamped, uniform and irregular knots (one repeated),
//! at rest, stretched, compressed and bent in 3D, and closed rods (periodic bases,
//! uniform and irregular) stretched and bent.

use crate::Energy;
use nalgebra::{Rotation3, Vector3};
use splinerod_core::{
    add_operator_columns, BSplineSpace, BasisSpace, BlockBanded, CoreError, HessianKind, Material,
    PeriodicBSplineSpace, Real, Rod,
};

/// Which invariance under rigid motions the energy has.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum RigidInvariance {
    /// Invariant under every rotation and translation (internal energies).
    Full,
    /// Invariant under translations orthogonal to `axis` and rotations about it (gravity
    /// along `axis`).
    AboutAxis(Vector3<Real>),
    /// No invariance to check.
    None,
}

/// What the harness should expect of an energy.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Expectations {
    /// Energy and gradient vanish on a straight rod at rest length.
    pub zero_at_rest: bool,
    /// Rigid-motion invariance.
    pub rigid: RigidInvariance,
    /// Largest relative change of energy and pulled-back gradient allowed under knot
    /// insertion: [`EXACT_TOLERANCE`] for integrands the rod's quadrature integrates
    /// exactly, the quadrature accuracy otherwise.
    pub knot_insertion: Real,
}

/// Largest relative discrepancies the harness measured.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Report {
    /// Gradient vs finite differences of the energy.
    pub gradient: Real,
    /// Exact Hessian vs finite differences of the gradient.
    pub hessian: Real,
    /// Most negative eigenvalue of the definite Hessian, relative to the largest.
    pub definiteness: Real,
    /// Energy change under rigid motion.
    pub rigid: Real,
    /// Energy and gradient change under knot insertion.
    pub refinement: Real,
    /// Energy and gradient at rest, relative to a stretched state's.
    pub rest: Real,
    /// Gradient and Hessian of [`Energy::add_gradient_and_hessian`] against the two
    /// separate calls.
    pub fused: Real,
}

/// Tolerances of the checks. Richardson-extrapolated central differences with
/// h ≈ 1e-5·L leave O(h⁴) truncation and O(ε/h) ≈ 1e-11 round-off relative to the
/// quantity's scale (plain central differences left up to 1.4e-6 of O(h²) truncation on
/// bending's most crumpled test rod), so 1e-6 is generous; the invariances are exact and
/// are held to round-off.
pub const DIFFERENCE_TOLERANCE: Real = 1e-6;
/// Tolerance of exact identities (invariances, symmetry), relative.
pub const EXACT_TOLERANCE: Real = 1e-11;

/// Runs every check on `energy` and returns the measured discrepancies, or a message
/// naming the first failed check with its figures.
pub fn check_energy(energy: &dyn Energy, expect: Expectations) -> Result<Report, String> {
    let mut report = Report::default();
    let setup = |e: CoreError| format!("{}: test setup failed: {e}", energy.name());
    for (label, rod) in test_rods().map_err(setup)? {
        let lifecycle = energy.capabilities().lifecycle;
        if lifecycle.is_some_and(|l| l.supports(&rod).is_err()) {
            continue;
        }
        let fail =
            |what: &str, value: Real| format!("{}: {what} = {value:e} on {label}", energy.name());
        let measure = |value: Real, tol: Real, what: &str, worst: &mut Real| {
            *worst = worst.max(value);
            if value <= tol {
                Ok(())
            } else {
                Err(fail(what, value))
            }
        };
        measure(
            gradient_error(energy, &rod),
            DIFFERENCE_TOLERANCE,
            "gradient error",
            &mut report.gradient,
        )?;
        measure(
            hessian_error(energy, &rod),
            DIFFERENCE_TOLERANCE,
            "Hessian error",
            &mut report.hessian,
        )?;
        measure(
            negativity(energy, &rod),
            EXACT_TOLERANCE,
            "definite Hessian negativity",
            &mut report.definiteness,
        )?;
        measure(
            rigid_error(energy, &rod, expect.rigid),
            EXACT_TOLERANCE,
            "rigid-motion change",
            &mut report.rigid,
        )?;
        measure(
            fused_error(energy, &rod),
            EXACT_TOLERANCE,
            "fused gradient and Hessian change",
            &mut report.fused,
        )?;
        measure(
            refinement_error(energy, &rod).map_err(setup)?,
            expect.knot_insertion,
            "knot-insertion change",
            &mut report.refinement,
        )?;
    }
    if expect.zero_at_rest {
        report.rest = rest_error(energy).map_err(setup)?;
        if report.rest > EXACT_TOLERANCE {
            return Err(format!(
                "{}: energy or force at rest = {:e}",
                energy.name(),
                report.rest
            ));
        }
    }
    Ok(report)
}

fn spaces() -> Result<Vec<(String, BSplineSpace)>, CoreError> {
    let mut out = Vec::new();
    for d in 2..=4 {
        out.push((
            format!("clamped d={d}"),
            BSplineSpace::clamped_uniform(d, d + 5, 1.3)?,
        ));
        out.push((
            format!("uniform d={d}"),
            BSplineSpace::uniform(d, d + 4, 1.3)?,
        ));
        let mut irregular = BSplineSpace::clamped_uniform(d, d + 3, 1.3)?;
        for s in [0.2, 0.5, 0.5, 0.71] {
            irregular.insert_knot(s)?;
        }
        out.push((format!("irregular d={d}"), irregular));
    }
    Ok(out)
}

/// Deterministic pseudo-random numbers in [-1, 1].
fn noise(i: usize, k: usize) -> Real {
    ((i * 7919 + k * 104_729) as Real * 0.618_033_988_75).sin()
}

fn rod_on(space: &BSplineSpace, stretch: Real, wiggle: Real) -> Result<Rod, CoreError> {
    let material = Material {
        rest_length: 1.3,
        linear_density: 0.2,
    };
    let end = Vector3::new(1.3 * stretch, 0.0, 0.0);
    let mut rod = Rod::straight(material, Box::new(space.clone()), Vector3::zeros(), end)?;
    for (i, q) in rod.positions.iter_mut().enumerate() {
        *q += Vector3::new(noise(i, 0), noise(i, 1), noise(i, 2)) * wiggle;
    }
    Ok(rod)
}

/// Labelled rods in varied states.
pub fn test_rods() -> Result<Vec<(String, Rod)>, CoreError> {
    let mut out = Vec::new();
    for (name, space) in spaces()? {
        for (state, stretch, wiggle) in [
            ("stretched", 1.15, 0.02),
            ("compressed", 0.7, 0.05),
            ("bent", 1.0, 0.3),
        ] {
            out.push((format!("{name}, {state}"), rod_on(&space, stretch, wiggle)?));
        }
    }
    for d in 2..=4 {
        let uniform = PeriodicBSplineSpace::uniform(d, d + 5, 1.3)?;
        let breaks = vec![0.0, 0.1, 0.3, 0.45, 0.45, 0.6, 0.9, 1.0, 1.22];
        let irregular = PeriodicBSplineSpace::new(d, breaks, 1.3)?;
        for (name, space) in [("uniform", uniform), ("irregular", irregular)] {
            for (state, stretch, wiggle) in [("stretched", 1.15, 0.02), ("bent", 1.0, 0.1)] {
                let label = format!("closed {name} d={d}, {state}");
                out.push((label, ring_on(space.clone(), stretch, wiggle)?));
            }
        }
    }
    Ok(out)
}

/// A closed rod on `space` (period 1.3 m): the ring of its rest length scaled by
/// `stretch`, its distinct control points moved by up to `wiggle` (the copies across
/// the seam follow).
fn ring_on(space: PeriodicBSplineSpace, stretch: Real, wiggle: Real) -> Result<Rod, CoreError> {
    let material = Material {
        rest_length: 1.3,
        linear_density: 0.2,
    };
    let radius = stretch * 1.3 / std::f64::consts::TAU;
    let m = space.breaks().len();
    let (center, normal) = (Vector3::new(0.1, 0.0, -0.2), Vector3::new(0.2, 0.1, 1.0));
    let ring = Rod::ring(material, Box::new(space), center, normal, radius)?;
    let mut positions = ring.positions.clone();
    for (i, q) in positions.iter_mut().enumerate() {
        let j = i % m;
        *q += Vector3::new(noise(j, 0), noise(j, 1), noise(j, 2)) * wiggle;
    }
    Rod::new(material, ring.basis().clone_box(), positions)
}

fn gradient_of(energy: &dyn Energy, rod: &Rod) -> Vec<Vector3<Real>> {
    let mut g = vec![Vector3::zeros(); rod.len()];
    energy.add_gradient(rod, &mut g);
    g
}

/// Largest difference between the fused gradient and Hessian and the separate calls,
/// relative to the separate ones' largest entries.
fn fused_error(energy: &dyn Energy, rod: &Rod) -> Real {
    let n = rod.len();
    let bandwidth = energy.bandwidth(rod);
    let (mut g0, mut g1) = (vec![Vector3::zeros(); n], vec![Vector3::zeros(); n]);
    let (mut h0, mut h1) = (
        BlockBanded::zeros(n, bandwidth),
        BlockBanded::zeros(n, bandwidth),
    );
    energy.add_gradient(rod, &mut g0);
    energy.add_hessian(rod, HessianKind::Exact, &mut h0);
    energy.add_gradient_and_hessian(rod, HessianKind::Exact, &mut g1, &mut h1);
    let dg = g0.iter().zip(&g1).map(|(a, b)| (a - b).amax());
    let (d0, d1) = (h0.to_dense(), h1.to_dense());
    let gradient = dg.fold(0.0, Real::max) / max_norm(&g0).max(Real::MIN_POSITIVE);
    gradient.max((&d0 - &d1).amax() / d0.amax().max(Real::MIN_POSITIVE))
}

fn max_norm(v: &[Vector3<Real>]) -> Real {
    v.iter().map(|x| x.amax()).fold(0.0, Real::max)
}

/// Central difference of `f` along coordinate `a` of control point `i` with step `h`,
/// Richardson-extrapolated from steps `h` and `h/2`: \\((4 D_{h/2} - D_h)/3\\) cancels
/// the O(h²) truncation, leaving O(h⁴) and O(ε/h) round-off.
fn richardson<T, F>(rod: &Rod, i: usize, a: usize, h: Real, mut f: F) -> Vec<T>
where
    T: Copy + std::ops::Sub<Output = T> + std::ops::Mul<Real, Output = T>,
    F: FnMut(&Rod) -> Vec<T>,
{
    let mut probe = rod.clone();
    let mut central = |step: Real| {
        probe.positions[i][a] = rod.positions[i][a] + step;
        let plus = f(&probe);
        probe.positions[i][a] = rod.positions[i][a] - step;
        let minus = f(&probe);
        probe.positions[i][a] = rod.positions[i][a];
        plus.into_iter()
            .zip(minus)
            .map(|(p, m)| (p - m) * (0.5 / step))
            .collect::<Vec<T>>()
    };
    let (coarse, fine) = (central(h), central(0.5 * h));
    fine.into_iter()
        .zip(coarse)
        .map(|(f, c)| (f * 4.0 - c) * (1.0 / 3.0))
        .collect()
}

fn gradient_error(energy: &dyn Energy, rod: &Rod) -> Real {
    let g = gradient_of(energy, rod);
    let h = 1e-5 * rod.material().rest_length;
    let mut worst: Real = 0.0;
    for i in 0..rod.len() {
        for a in 0..3 {
            let fd = richardson(rod, i, a, h, |r| vec![energy.energy(r)])[0];
            worst = worst.max((fd - g[i][a]).abs());
        }
    }
    worst / max_norm(&g).max(Real::MIN_POSITIVE)
}

/// The dense Hessian: the banded part and, column by column, the remainder
/// ([`crate::HessianRemainder`]).
fn hessian_of(energy: &dyn Energy, rod: &Rod, kind: HessianKind) -> nalgebra::DMatrix<Real> {
    let n = rod.len();
    let mut h = BlockBanded::zeros(n, energy.bandwidth(rod));
    energy.add_hessian(rod, kind, &mut h);
    let mut dense = h.to_dense();
    if let Some(r) = energy.capabilities().remainder {
        if r.has_remainder(rod) {
            add_operator_columns(n, &mut dense, |v, out| r.add_remainder(rod, v, 1.0, out));
        }
    }
    dense
}

fn hessian_error(energy: &dyn Energy, rod: &Rod) -> Real {
    let exact = hessian_of(energy, rod, HessianKind::Exact);
    let h = 1e-5 * rod.material().rest_length;
    let mut worst: Real = 0.0;
    for i in 0..rod.len() {
        for a in 0..3 {
            let column = richardson(rod, i, a, h, |r| gradient_of(energy, r));
            for (j, fd) in column.iter().enumerate() {
                for b in 0..3 {
                    worst = worst.max((fd[b] - exact[(3 * j + b, 3 * i + a)]).abs());
                }
            }
        }
    }
    let asymmetry = (&exact - exact.transpose()).amax();
    worst.max(asymmetry) / exact.amax().max(Real::MIN_POSITIVE)
}

fn negativity(energy: &dyn Energy, rod: &Rod) -> Real {
    let h = hessian_of(energy, rod, HessianKind::Definite);
    let scale = h.amax();
    if scale == 0.0 {
        return 0.0;
    }
    let eig = h.symmetric_eigenvalues();
    (-eig.min()).max(0.0) / scale
}

fn rigid_error(energy: &dyn Energy, rod: &Rod, rigid: RigidInvariance) -> Real {
    let (rotation, shift) = match rigid {
        RigidInvariance::None => return 0.0,
        RigidInvariance::Full => (
            Rotation3::new(Vector3::new(0.3, -1.1, 0.7)),
            Vector3::new(0.5, -2.0, 1.5),
        ),
        RigidInvariance::AboutAxis(axis) => {
            let axis = axis.normalize();
            let across = axis.cross(&Vector3::new(0.3, 0.5, 0.7)).normalize();
            (Rotation3::new(axis * 0.9), across * 1.7)
        }
    };
    let mut moved = rod.clone();
    moved
        .positions
        .iter_mut()
        .for_each(|q| *q = rotation * *q + shift);
    let (e0, e1) = (energy.energy(rod), energy.energy(&moved));
    (e1 - e0).abs() / e0.abs().max(Real::MIN_POSITIVE)
}

fn refinement_error(energy: &dyn Energy, rod: &Rod) -> Result<Real, CoreError> {
    let mut refined = rod.clone();
    let mut maps = Vec::new();
    for s in [0.123, 0.5, 1.0001] {
        maps.push(refined.insert_knot(s)?);
    }
    let (e0, e1) = (energy.energy(rod), energy.energy(&refined));
    // Pull the refined gradient back: ∇E_0 = β_1ᵀ β_2ᵀ β_3ᵀ ∇E_1.
    let mut g = gradient_of(energy, &refined);
    for map in maps.iter().rev() {
        g = (0..map.old_count())
            .map(|j| (0..g.len()).map(|i| g[i] * map.weight(i, j)).sum())
            .collect();
    }
    let mut g0 = gradient_of(energy, rod);
    // A closed rod's copies across the seam move with what they copy: compare the
    // gradients along such motions (the sums over each control point and its copy).
    if let Some(m) = rod.basis().periodic_count() {
        for v in [&mut g, &mut g0] {
            for i in m..v.len() {
                let copy = v[i];
                v[i - m] += copy;
            }
            v.truncate(m);
        }
    }
    let scale = max_norm(&g0).max(Real::MIN_POSITIVE);
    let dg = g
        .iter()
        .zip(&g0)
        .map(|(a, b)| (a - b).amax())
        .fold(0.0, Real::max);
    Ok(((e1 - e0).abs() / e0.abs().max(Real::MIN_POSITIVE)).max(dg / scale))
}

fn rest_error(energy: &dyn Energy) -> Result<Real, CoreError> {
    let space = BSplineSpace::clamped_uniform(3, 9, 1.3)?;
    let rest = rod_on(&space, 1.0, 0.0)?;
    // Stretched and bent, so that every kind of energy has a non-zero scale.
    let stretched = rod_on(&space, 1.1, 0.05)?;
    let scale_e = energy.energy(&stretched).abs().max(Real::MIN_POSITIVE);
    let scale_g = max_norm(&gradient_of(energy, &stretched)).max(Real::MIN_POSITIVE);
    Ok((energy.energy(&rest).abs() / scale_e).max(max_norm(&gradient_of(energy, &rest)) / scale_g))
}
