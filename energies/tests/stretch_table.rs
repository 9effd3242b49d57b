//! The mixed stretching form's tabulated integrals (`stretching/table.rs`, used once
//! `begin_step` has seen the rod) give the energy, gradient and Hessian of the point-by-
//! point sweep up to round-off: on every conformance test rod (degrees 2–4, clamped,
//! uniform and irregular knots), with a rest curve, for the inextensible rod with
//! non-zero multipliers, after knot insertions, and far from the origin.
use nalgebra::Vector3;
use splinerod_core::{BlockBanded, HessianKind, Real, RefinementOperator, Rod};
use splinerod_energies::conformance::test_rods;
use splinerod_energies::{Energy, StretchFormulation, Stretching};
use splinerod_energies::{HessianRemainder, Lifecycle};

/// Energy, gradient and Hessian (both kinds) of `e`, through the fused call.
fn evaluate(
    e: &dyn Energy,
    rod: &Rod,
    kind: HessianKind,
) -> (Real, Vec<Vector3<Real>>, BlockBanded) {
    let mut g = vec![Vector3::zeros(); rod.len()];
    let mut h = BlockBanded::zeros(rod.len(), e.bandwidth(rod));
    e.add_gradient_and_hessian(rod, kind, &mut g, &mut h);
    (e.energy(rod), g, h)
}

/// The same rod under a new topology epoch: a table made for `rod` does not match it,
/// so the energy evaluates it by the sweep.
fn untabled(rod: &Rod) -> Rod {
    rod.refined(&[], &mut RefinementOperator::default())
        .expect("copy")
}

/// Largest relative difference between the sweep (on an untabled copy of `rod`) and the
/// table of `e` (after `begin_step` on `rod`), over energy, gradient (fused and alone)
/// and both Hessians, at `rod`'s positions moved by `moved`.
fn discrepancy(e: &Stretching, rod: &Rod, moved: impl Fn(&mut Rod)) -> Real {
    let mut tabled = e.clone();
    tabled.begin_step(rod, 1e-3).expect("begin_step");
    discrepancy_of(&tabled, rod, moved)
}

/// [`discrepancy`] for an energy whose table is already made for `rod`.
fn discrepancy_of(e: &Stretching, rod: &Rod, moved: impl Fn(&mut Rod)) -> Real {
    let (mut table_rod, mut sweep_rod) = (rod.clone(), untabled(rod));
    moved(&mut table_rod);
    moved(&mut sweep_rod);
    let mut worst: Real = 0.0;
    for kind in [HessianKind::Exact, HessianKind::Definite] {
        let (e0, g0, h0) = evaluate(e, &sweep_rod, kind);
        let (e1, g1, h1) = evaluate(e, &table_rod, kind);
        let scale_g = g0
            .iter()
            .map(|v| v.amax())
            .fold(Real::MIN_POSITIVE, Real::max);
        let (d0, d1) = (h0.to_dense(), h1.to_dense());
        let scale_h = d0.amax().max(Real::MIN_POSITIVE);
        let mut alone = vec![Vector3::zeros(); rod.len()];
        e.add_gradient(&table_rod, &mut alone);
        let dg = g0.iter().zip(&g1).zip(&alone);
        let dg = dg
            .map(|((a, b), c)| (a - b).amax().max((a - c).amax()))
            .fold(0.0, Real::max);
        worst = worst
            .max((e0 - e1).abs() / e0.abs().max(Real::MIN_POSITIVE))
            .max(dg / scale_g)
            .max((d0 - d1).amax() / scale_h);
    }
    worst
}

/// Moves every control point by a smooth, non-rigid amount.
fn wiggle(rod: &mut Rod) {
    for (i, q) in rod.positions.iter_mut().enumerate() {
        *q += Vector3::new(0.01 * (i as Real).sin(), 0.02, -0.01 * i as Real);
    }
}

#[test]
fn table_equals_sweep_on_every_test_rod() {
    for (label, rod) in test_rods().expect("test rods") {
        for ea in [3.0, 1e6] {
            let e = Stretching::new(ea).expect("stretching");
            let d = discrepancy(&e, &rod, |_| {});
            assert!(d < 1e-11, "{label}, EA = {ea}: relative difference {d:e}");
        }
    }
}

#[test]
fn table_equals_sweep_with_a_rest_curve_and_multipliers() {
    for (label, rod) in test_rods().expect("test rods") {
        // A rest curve that is not arclength: the rod itself, then moved.
        let rest = Stretching::with_rest_shape(40.0, &rod).expect("rest shape");
        let d = discrepancy(&rest, &rod, wiggle);
        assert!(d < 1e-11, "{label}, rest curve: relative difference {d:e}");
        // The inextensible rod after one multiplier update (non-zero multipliers).
        let mut inext = Stretching::inextensible(&rod);
        let mut moved = rod.clone();
        wiggle(&mut moved);
        inext.update_multipliers(&moved, false);
        let d = discrepancy(&inext, &rod, wiggle);
        assert!(
            d < 1e-11,
            "{label}, inextensible: relative difference {d:e}"
        );
    }
}

#[test]
fn table_follows_knot_insertions() {
    for (label, rod) in test_rods().expect("test rods") {
        let mut rod = rod;
        let mut e = Stretching::with_rest_shape(25.0, &rod).expect("rest shape");
        e.begin_step(&rod, 1e-3).expect("begin_step");
        let (a, b) = rod.basis().domain();
        for x in [0.31, 0.5, 0.77] {
            let map = rod.insert_knot(a + x * (b - a)).expect("insert");
            e.on_knot_change(&rod, &map);
        }
        let d = discrepancy_of(&e, &rod, wiggle);
        assert!(d < 1e-11, "{label}: refined table against the sweep {d:e}");
    }
}

#[test]
fn table_keeps_its_digits_far_from_the_origin() {
    for (label, rod) in test_rods().expect("test rods") {
        let mut tabled = Stretching::new(1e4).expect("stretching");
        tabled.begin_step(&rod, 1e-3).expect("begin_step");
        let mut far = rod.clone();
        far.positions
            .iter_mut()
            .for_each(|q| *q += Vector3::new(1e3, -2e3, 5e2));
        let (_, g_near, _) = evaluate(&tabled, &rod, HessianKind::Exact);
        let (_, g_far, _) = evaluate(&tabled, &far, HessianKind::Exact);
        let scale = g_near.iter().map(|v| v.amax()).fold(0.0, Real::max);
        let moved = g_near
            .iter()
            .zip(&g_far)
            .map(|(a, b)| (a - b).amax())
            .fold(0.0, Real::max);
        assert!(
            moved <= 1e-10 * scale,
            "{label}: translation changed the gradient by {:e}",
            moved / scale
        );
    }
}

/// The consistent form (`stretching/rows.rs` keeps the rows of `B` from the table, the
/// fused pass of `stretching/tabulated.rs` adds the derivatives from them) against the
/// sweep on every test rod, open and closed, with its remainder product too.
#[test]
fn table_equals_sweep_for_the_consistent_form() {
    for (label, rod) in test_rods().expect("test rods") {
        for ea in [3.0, 1e6] {
            let mut e = Stretching::new(ea).expect("stretching");
            e.formulation = StretchFormulation::MixedConsistent;
            let d = discrepancy(&e, &rod, wiggle);
            assert!(d < 1e-11, "{label}, EA = {ea}: relative difference {d:e}");
            let mut tabled = e.clone();
            tabled.begin_step(&rod, 1e-3).expect("begin_step");
            let v: Vec<Vector3<Real>> = (0..rod.len())
                .map(|i| Vector3::new((i as Real).sin(), 0.3, (0.7 * i as Real).cos()))
                .collect();
            let product = |e: &Stretching, rod: &Rod| {
                let mut out = vec![Vector3::zeros(); rod.len()];
                e.add_remainder(rod, &v, 1.0, &mut out);
                out
            };
            let (swept, table) = (product(&tabled, &untabled(&rod)), product(&tabled, &rod));
            let scale = swept
                .iter()
                .map(|v| v.amax())
                .fold(Real::MIN_POSITIVE, Real::max);
            let gap = swept.iter().zip(&table).map(|(a, b)| (a - b).amax());
            let gap = gap.fold(0.0, Real::max) / scale;
            assert!(
                gap < 1e-11,
                "{label}, EA = {ea}: remainder differs by {gap:e}"
            );
        }
    }
}
