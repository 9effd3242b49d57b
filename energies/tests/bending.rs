//! Bending and clamp checks beyond the generic harness: analytic values, the degree
//! check, the |C'| → 0 guard, and what the definite Hessian changes.

use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, BlockBanded, HessianKind, Material, Real, Rod};
use splinerod_energies::{Bending, Clamp, Energy};

fn material(l: Real) -> Material {
    Material {
        rest_length: l,
        linear_density: 0.1,
    }
}

fn straight(degree: usize, n: usize, l: Real) -> Rod {
    let basis = BSplineSpace::clamped_uniform(degree, n, l).unwrap();
    let end = Vector3::new(l, 0.0, 0.0);
    Rod::straight(material(l), Box::new(basis), Vector3::zeros(), end).unwrap()
}

/// A rod on the parabola \\(C(s) = (s, c s^2, 0)\\), exactly: the control points are the
/// blossoms of `s` and `s²` at the knots (\\(\tfrac{1}{d}\sum_j t_j\\) and
/// \\(\tfrac{2}{d(d-1)}\sum_{j<k} t_j t_k\\)).
fn parabola(degree: usize, n: usize, l: Real, c: Real) -> Rod {
    let mut rod = straight(degree, n, l);
    let t = rod.basis().knots().to_vec();
    let d = degree as Real;
    for (i, q) in rod.positions.iter_mut().enumerate() {
        let u = &t[i + 1..=i + degree];
        let linear = u.iter().sum::<Real>() / d;
        let pairs: Real = (0..degree)
            .flat_map(|j| (j + 1..degree).map(move |k| (j, k)))
            .map(|(j, k)| u[j] * u[k])
            .sum();
        *q = Vector3::new(linear, c * 2.0 * pairs / (d * (d - 1.0)), 0.0);
    }
    rod
}

/// A rod whose control points sit on a circle of radius `r` at the Greville angles.
fn arc(n: usize, l: Real, r: Real) -> Rod {
    let mut rod = straight(3, n, l);
    for q in rod.positions.iter_mut() {
        let phi = q.x / r;
        *q = Vector3::new(r * phi.sin(), r * (1.0 - phi.cos()), 0.0);
    }
    rod
}

fn dense(e: &dyn Energy, rod: &Rod, kind: HessianKind) -> nalgebra::DMatrix<Real> {
    let mut h = BlockBanded::zeros(rod.len(), rod.basis().degree());
    e.add_hessian(rod, kind, &mut h);
    h.to_dense()
}

#[test]
fn parabola_energy_matches_the_closed_form() {
    // C = (s, c s², 0): |C' × C''| = 2c, |C'|² = 1 + 4c²s², so with X = 2cs
    // E = EI c ∫_0^{2cL} dX / (1 + X²)³ = EI c [X/(4(1+X²)²) + 3X/(8(1+X²)) + 3/8 atan X].
    // The curve is exact (degree ≥ 2); the errors are the quadrature of the rational κ²
    // and the guard δ = 1e-10 in the denominator (a bias ≤ 3δ).
    let (ei, l, c) = (0.3, 1.0, 1.0);
    let x: Real = 2.0 * c * l;
    let want = ei
        * c
        * (x / (4.0 * (1.0 + x * x).powi(2)) + 3.0 * x / (8.0 * (1.0 + x * x)) + 0.375 * x.atan());
    let bending = Bending::new(ei).unwrap();
    for degree in [2, 3] {
        for n in [6, 12, 24] {
            let rod = parabola(degree, n, l, c);
            let tip = rod.point(l).unwrap();
            assert!((tip - Vector3::new(l, c * l * l, 0.0)).norm() < 1e-14);
            let error = (bending.energy(&rod) - want).abs() / want;
            println!("d = {degree}, {n} control points: rel err {error:.2e}");
            assert!(error < 1e-4, "d = {degree}, n = {n}: {error:e}");
        }
    }
}

#[test]
fn degree_one_is_rejected_and_degree_two_accepted() {
    let err = Bending::for_rod(1.0, &straight(1, 6, 1.0)).unwrap_err();
    assert!(err.to_string().contains("degree"), "{err}");
    assert!(Bending::for_rod(1.0, &straight(2, 6, 1.0)).is_ok());
    assert!(Bending::new(0.0).is_err());
    assert!(Bending::new(Real::NAN).is_err());
}

#[test]
fn collapsed_tangent_gives_finite_values() {
    // Every control point at one place: C' = C'' = 0; also a rod folded onto itself.
    let mut rod = straight(3, 8, 1.0);
    rod.positions.iter_mut().for_each(|q| *q = Vector3::zeros());
    let mut folded = straight(3, 8, 1.0);
    folded.positions[4] = folded.positions[2];
    folded.positions[3].y += 1e-9;
    let bending = Bending::new(2.0).unwrap();
    for rod in [rod, folded] {
        let mut g = vec![Vector3::zeros(); rod.len()];
        bending.add_gradient(&rod, &mut g);
        assert!(bending.energy(&rod).is_finite());
        assert!(g.iter().all(|v| v.iter().all(|x| x.is_finite())));
        for kind in [HessianKind::Exact, HessianKind::Definite] {
            assert!(dense(&bending, &rod, kind).iter().all(|x| x.is_finite()));
        }
    }
}

#[test]
fn definite_hessian_clamps_only_where_needed() {
    let bending = Bending::new(1.0).unwrap();
    // Straight (stretched) rod: every density Hessian is PSD, definite = exact.
    let mut rod = straight(3, 10, 1.0);
    rod.positions.iter_mut().for_each(|q| *q *= 1.2);
    let (e, d) = (
        dense(&bending, &rod, HessianKind::Exact),
        dense(&bending, &rod, HessianKind::Definite),
    );
    assert!((&e - &d).amax() <= 1e-14 * e.amax());
    // A strongly bent rod: the exact Hessian is indefinite, the definite one is not.
    let rod = arc(10, 1.0, 0.2);
    let (e, d) = (
        dense(&bending, &rod, HessianKind::Exact),
        dense(&bending, &rod, HessianKind::Definite),
    );
    let (min_e, min_d) = (
        e.symmetric_eigenvalues().min(),
        d.symmetric_eigenvalues().min(),
    );
    println!("bent arc: min eigenvalue exact {min_e:e}, definite {min_d:e}");
    assert!(min_e < -1e-6 * e.amax());
    assert!(min_d >= -1e-12 * d.amax());
}

#[test]
fn clamp_penalises_rotation_not_stretch() {
    let rod = straight(3, 8, 1.0);
    let clamp = Clamp::here(&rod, 0.0, 100.0).unwrap();
    assert_eq!(clamp.energy(&rod), 0.0);
    // Stretching along the clamp direction costs nothing.
    let mut stretched = rod.clone();
    stretched.positions.iter_mut().for_each(|q| *q *= 1.3);
    assert!(clamp.energy(&stretched).abs() < 1e-20);
    // Rotating the rod by θ about z costs k sin²θ / 2 (unit stretch).
    let theta: Real = 0.01;
    let rotation = nalgebra::Rotation3::new(Vector3::new(0.0, 0.0, theta));
    let mut turned = rod.clone();
    turned.positions.iter_mut().for_each(|q| *q = rotation * *q);
    let want = 0.5 * 100.0 * theta.sin().powi(2);
    assert!((clamp.energy(&turned) - want).abs() < 1e-12 * want);
    assert!(Clamp::new(0.0, Vector3::zeros(), 1.0).is_err());
    assert!(Clamp::new(-0.1, Vector3::x(), 1.0).is_err());
    assert!(Clamp::here(&rod, 1.5, 1.0).is_err());
    assert_eq!(Clamp::stiffness_for(2.0, 0.5), 4e6);
}
