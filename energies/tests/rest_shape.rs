//! Stretching with a rest curve (the paper's I₀): the initial shape is unstrained, the
//! default rest state is recovered for arclength-parametrised rods, derivatives match
//! finite differences, and knot insertion leaves the energy unchanged.

use nalgebra::Vector3;
use splinerod_core::{
    add_operator_columns, BSplineSpace, BlockBanded, HessianKind, Material, Real, Rod,
};
use splinerod_energies::{finite_difference_hessian, Energy, StretchFormulation, Stretching};
use splinerod_energies::{HessianRemainder, Lifecycle};

/// A curved rod whose parametrisation is far from arclength.
fn wavy() -> Rod {
    let n = 9;
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, 1.0).unwrap();
    let positions = (0..n)
        .map(|i| {
            let x = (i as Real / (n - 1) as Real).powi(2) * 1.3;
            Vector3::new(x, 0.2 * (3.0 * x).sin(), 0.1 * x * x)
        })
        .collect();
    Rod::new(material, Box::new(basis), positions).unwrap()
}

fn gradient(e: &dyn Energy, rod: &Rod) -> Vec<Vector3<Real>> {
    let mut g = vec![Vector3::zeros(); rod.len()];
    e.add_gradient(rod, &mut g);
    g
}

#[test]
fn the_initial_shape_is_at_rest() {
    let rod = wavy();
    let e = Stretching::with_rest_shape(100.0, &rod).unwrap();
    assert!(e.energy(&rod).abs() < 1e-20);
    assert!(gradient(&e, &rod).iter().all(|g| g.norm() < 1e-12));
    // The default rest state would see this rod strongly strained.
    assert!(Stretching::new(100.0).unwrap().energy(&rod) > 1.0);
}

#[test]
fn an_arclength_rod_gives_the_default_energy() {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, 8, 1.0).unwrap();
    let mut rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), Vector3::x()).unwrap();
    let rest = Stretching::with_rest_shape(100.0, &rod).unwrap();
    let plain = Stretching::new(100.0).unwrap();
    for (i, q) in rod.positions.iter_mut().enumerate() {
        *q *= 1.1;
        q.y += 0.01 * (i as Real).sin();
    }
    let (a, b) = (rest.energy(&rod), plain.energy(&rod));
    assert!((a - b).abs() <= 1e-12 * b, "{a} vs {b}");
}

#[test]
fn derivatives_match_finite_differences() {
    let mut rod = wavy();
    let e = Stretching::with_rest_shape(100.0, &rod).unwrap();
    for (i, q) in rod.positions.iter_mut().enumerate() {
        *q += Vector3::new((1.7 * i as Real).sin(), (0.9 * i as Real).cos(), 0.3) * 0.02;
    }
    let g = gradient(&e, &rod);
    let scale = g.iter().map(|v| v.amax()).fold(0.0, Real::max);
    let h = 1e-6;
    for i in 0..rod.len() {
        for a in 0..3 {
            let (mut p, mut m) = (rod.clone(), rod.clone());
            p.positions[i][a] += h;
            m.positions[i][a] -= h;
            let fd = (e.energy(&p) - e.energy(&m)) / (2.0 * h);
            assert!(
                (fd - g[i][a]).abs() <= 1e-6 * scale,
                "{i}.{a}: {fd} vs {}",
                g[i][a]
            );
        }
    }
    // The whole Hessian (banded part and remainder) against central differences of the
    // gradient, column by column.
    let n = rod.len();
    let mut exact = BlockBanded::zeros(n, e.bandwidth(&rod));
    e.add_hessian(&rod, HessianKind::Exact, &mut exact);
    let mut exact = exact.to_dense();
    add_operator_columns(n, &mut exact, |v, out| e.add_remainder(&rod, v, 1.0, out));
    let mut fd = nalgebra::DMatrix::zeros(3 * n, 3 * n);
    for c in 0..3 * n {
        let (mut p, mut m) = (rod.clone(), rod.clone());
        p.positions[c / 3][c % 3] += h;
        m.positions[c / 3][c % 3] -= h;
        let (gp, gm) = (gradient(&e, &p), gradient(&e, &m));
        for (r, (a, b)) in gp.iter().zip(&gm).enumerate() {
            for k in 0..3 {
                fd[(3 * r + k, c)] = (a[k] - b[k]) / (2.0 * h);
            }
        }
    }
    assert!((&exact - &fd).amax() <= 1e-6 * exact.amax());
    // The pointwise form's banded Hessian is the library's finite-difference default.
    let mut pointwise = Stretching::with_rest_shape(100.0, &wavy()).unwrap();
    pointwise.formulation = StretchFormulation::Pointwise;
    let d = rod.basis().degree();
    let (mut exact, mut fd) = (BlockBanded::zeros(n, d), BlockBanded::zeros(n, d));
    pointwise.add_hessian(&rod, HessianKind::Exact, &mut exact);
    finite_difference_hessian(&pointwise, &rod, &mut fd);
    let (exact, fd) = (exact.to_dense(), fd.to_dense());
    assert!((&exact - &fd).amax() <= 1e-6 * exact.amax());
}

#[test]
fn knot_insertion_keeps_the_energy() {
    let rest_rod = wavy();
    let mut e = Stretching::with_rest_shape(100.0, &rest_rod).unwrap();
    let mut rod = rest_rod.clone();
    for q in rod.positions.iter_mut() {
        *q *= 1.05;
    }
    let before = e.energy(&rod);
    for s in [0.37, 0.5, 0.81] {
        let map = rod.insert_knot(s).unwrap();
        e.on_knot_change(&rod, &map);
    }
    let after = e.energy(&rod);
    // g₀^{-3/2} is not polynomial: the quadrature is exact only up to its own error.
    assert!(
        (after - before).abs() <= 1e-4 * before,
        "{before} vs {after}"
    );
}
