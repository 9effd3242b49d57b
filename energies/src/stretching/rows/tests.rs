//! The fused kernels of the rows against the plain ones (only x86-64 has the fused
//! ones).

use super::*;
use crate::Lifecycle;
use splinerod_core::{BSplineSpace, Material};

/// The rows and a remainder product (with a stand-in for the Gram solve) of `e` on
/// `rod`, plain or fused.
fn rows_and_product(e: &Stretching, rod: &Rod, fused: bool) -> (Rows, Vec<Vector3<Real>>) {
    let mut rows = Rows {
        stride: 2 * rod.basis().degree(),
        positions: rod.positions.clone(),
        ..Rows::default()
    };
    rows.db
        .resize(e.table.functions() * rows.stride, Vector3::zeros());
    let v: Vec<Vector3<Real>> = (0..rod.len())
        .map(|i| Vector3::new((i as Real).cos(), 0.2, -0.1 * i as Real))
        .collect();
    let mut out = vec![Vector3::zeros(); rod.len()];
    let len = rod.len() + 1;
    (rows.y, rows.lumped) = (vec![0.0; len], vec![0.0; len]);
    if fused {
        // SAFETY: only called fused where the processor has AVX2 and FMA.
        unsafe {
            rows.table_rows_wide(&e.table, rod);
            rows.project_wide(&v);
            rows.y.iter_mut().for_each(|y| *y *= 1.5);
            rows.spread_wide(0.7, &mut out);
        }
        return (rows, out);
    }
    rows.table_rows::<false>(&e.table, rod);
    rows.project::<false>(&v);
    rows.y.iter_mut().for_each(|y| *y *= 1.5);
    rows.spread::<false>(0.7, &mut out);
    (rows, out)
}

#[test]
fn the_fused_rows_and_products_are_the_plain_ones_to_round_off() {
    if !splinerod_core::lanes::wide() {
        return;
    }
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    for (degree, points) in [(2, 7), (3, 5), (3, 16), (4, 11)] {
        let basis = BSplineSpace::clamped_uniform(degree, points, 1.0).expect("basis");
        let end = Vector3::new(1.1, 0.2, -0.1);
        let mut rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
        for (i, q) in rod.positions.iter_mut().enumerate() {
            *q += Vector3::new(0.0, 0.03 * (i as Real).sin(), 0.02 * (i as Real).cos());
        }
        let mut e = Stretching::new(250.0).expect("stretching");
        e.formulation = super::super::StretchFormulation::MixedConsistent;
        e.begin_step(&rod, 1e-3).expect("table");
        let (plain, out_plain) = rows_and_product(&e, &rod, false);
        let (fused, out_fused) = rows_and_product(&e, &rod, true);
        let close = |a: Real, b: Real, scale: Real| (a - b).abs() <= 1e-13 * scale;
        let scale_b = plain
            .functions
            .iter()
            .map(|r| r.b.abs())
            .fold(0.0, Real::max);
        let scale_db = plain.db.iter().map(|v| v.amax()).fold(0.0, Real::max);
        for (p, f) in plain.functions.iter().zip(&fused.functions) {
            assert_eq!((p.index, p.first, p.width), (f.index, f.first, f.width));
            assert!(close(p.b, f.b, scale_b) && p.m == f.m, "degree {degree}");
        }
        let gap = plain.db.iter().zip(&fused.db).map(|(p, f)| (p - f).amax());
        assert!(gap.fold(0.0, Real::max) <= 1e-13 * scale_db);
        let scale = out_plain.iter().map(|v| v.amax()).fold(0.0, Real::max);
        let gap = out_plain
            .iter()
            .zip(&out_fused)
            .map(|(p, f)| (p - f).amax());
        assert!(gap.fold(0.0, Real::max) <= 1e-13 * scale, "degree {degree}");
        assert_ne!(out_plain, out_fused, "the fused products round differently");
    }
}
