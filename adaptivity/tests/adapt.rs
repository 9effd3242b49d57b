//! The criteria and the adapt step on rods whose answers are known.

use nalgebra::Vector3;
use splinerod_adaptivity::curvature::disturbance;
use splinerod_adaptivity::estimate::SpanError;
use splinerod_adaptivity::{
    AdaptParams, Adapter, Continuity, CurvatureCriterion, ErrorEstimate, InteractionCriterion,
    Refinement, RefinementCriterion, ToleranceCriterion,
};
use splinerod_core::{BSplineSpace, Material, Real, Rod};

fn rod_through(points: Vec<Vector3<Real>>) -> Rod {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, points.len(), 1.0).unwrap();
    Rod::new(material, Box::new(basis), points).unwrap()
}

/// Control points on a circular arc of `angle` radians (a curved, not straight, rod).
fn arc(n: usize, angle: Real) -> Rod {
    let r = 1.0 / angle;
    rod_through(
        (0..n)
            .map(|i| {
                let a = angle * i as Real / (n - 1) as Real;
                Vector3::new(r * a.sin(), r * (1.0 - a.cos()), 0.0)
            })
            .collect(),
    )
}

fn samples(rod: &Rod) -> Vec<Vector3<Real>> {
    (0..=200)
        .map(|k| rod.point(k as Real / 200.0).unwrap())
        .collect()
}

#[test]
fn disturbance_is_zero_straight_half_at_a_right_angle_one_folded() {
    let p = |x: Real, y: Real| Vector3::new(x, y, 0.0);
    let rod = rod_through(vec![
        p(0.0, 0.0),
        p(1.0, 0.0),
        p(1.0, 1.0),
        p(0.0, 1.0),
        p(0.5, 1.0),
    ]);
    assert_eq!(disturbance(&rod, 0), 0.0);
    assert!((disturbance(&rod, 1) - 0.5).abs() < 1e-15);
    assert!((disturbance(&rod, 3) - 1.0).abs() < 1e-15);
    // A repeated control point (zero-length edge) counts as straight, not NaN.
    let rod = rod_through(vec![p(0.0, 0.0), p(1.0, 0.0), p(1.0, 0.0), p(2.0, 0.0)]);
    assert_eq!(disturbance(&rod, 1), 0.0);
}

#[test]
fn curvature_criterion_refines_bends_and_coarsens_straight_parts() {
    let straight = arc(8, 1e-9);
    let bent = arc(8, 6.0);
    let c = CurvatureCriterion::default();
    let mut marks = Vec::new();
    c.mark(&straight, &[], &mut marks);
    assert!(marks.iter().all(|m| matches!(m, Refinement::Remove { .. })));
    assert_eq!(
        marks.len(),
        4,
        "every interior knot of the straight rod: {marks:?}"
    );
    marks.clear();
    c.mark(&bent, &[], &mut marks);
    assert!(marks.iter().all(|m| matches!(m, Refinement::Insert { .. })));
    assert!(!marks.is_empty());
    assert!(
        CurvatureCriterion::new(0.01, 0.05).is_err(),
        "remove above insert"
    );
    assert!(CurvatureCriterion::new(-0.1, 0.0).is_err());
}

#[test]
fn adapt_step_respects_limits_and_keeps_the_shape() {
    let mut rod = arc(8, 6.0);
    let before = samples(&rod);
    let params = AdaptParams {
        max_control_points: 14,
        ..AdaptParams::default()
    };
    let mut adapter = Adapter::new(params)
        .unwrap()
        .with(CurvatureCriterion::default());
    let mut maps = 0;
    let report = adapter
        .adapt(&mut rod, &[], None, &mut |_, _| maps += 1)
        .unwrap();
    assert!(report.inserted > 0 && rod.len() <= 14);
    assert_eq!(maps, report.inserted + report.removed);
    for (a, b) in before.iter().zip(samples(&rod)) {
        assert!((a - b).norm() < 1e-12, "insertion moved the curve");
    }
}

#[test]
fn removal_never_moves_a_curved_rod_beyond_the_tolerance() {
    for tolerance in [1e-9, 1e-5, 1e-3] {
        let mut rod = arc(20, 2.0);
        let before = samples(&rod);
        let params = AdaptParams {
            shape_tolerance: tolerance,
            hysteresis_steps: 0,
            ..AdaptParams::default()
        };
        // Insertion never, removal proposed everywhere: only the tolerance limits it.
        let everything = CurvatureCriterion::new(1.0, 1.0).unwrap();
        let mut adapter = Adapter::new(params).unwrap().with(everything);
        let report = adapter.adapt(&mut rod, &[], None, &mut |_, _| {}).unwrap();
        let moved = before
            .iter()
            .zip(samples(&rod))
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, Real::max);
        println!(
            "tolerance {tolerance:e}: removed {}, moved {moved:.2e}",
            report.removed
        );
        assert!(moved <= tolerance, "moved {moved:e} > {tolerance:e}");
        if tolerance >= 1e-3 {
            assert!(
                report.removed > 0,
                "a loose tolerance should allow removals"
            );
        }
    }
}

#[test]
fn interaction_criterion_inserts_once_and_protects_its_knot() {
    let mut rod = arc(8, 1e-9);
    let c = InteractionCriterion::new(0.01).unwrap();
    let mut adapter = Adapter::new(AdaptParams::default())
        .unwrap()
        .with(c)
        .with(CurvatureCriterion::default());
    let report = adapter
        .adapt(&mut rod, &[0.3], None, &mut |_, _| {})
        .unwrap();
    assert_eq!(report.inserted, 1);
    assert_eq!(rod.knot_multiplicity(0.3), 1);
    for _ in 0..30 {
        adapter
            .adapt(&mut rod, &[0.3], None, &mut |_, _| {})
            .unwrap();
        assert_eq!(rod.knot_multiplicity(0.3), 1, "the grabbed knot must stay");
    }
    assert!(InteractionCriterion::new(0.0).is_err());
}

/// #46: an interaction asking for a corner (multiplicity 3 on a cubic) gets one only
/// where [`Continuity`] allows corners (a string); elsewhere the knot stops at 2 (C¹).
#[test]
fn corners_only_where_the_continuity_allows_them() {
    for (continuity, most) in [
        (Continuity::default(), 2),
        (Continuity::corners_everywhere(1.0), 3),
        (
            Continuity {
                corners_allowed: vec![(0.5, 1.0)],
            },
            2,
        ),
    ] {
        let mut rod = arc(8, 1e-9);
        let c = InteractionCriterion::new(0.01)
            .unwrap()
            .with_multiplicity(3)
            .unwrap();
        let mut adapter = Adapter::new(AdaptParams::default())
            .unwrap()
            .with(c)
            .with_continuity(continuity.clone());
        for _ in 0..3 {
            adapter
                .adapt(&mut rod, &[0.3], None, &mut |_, _| {})
                .unwrap();
        }
        assert_eq!(rod.knot_multiplicity(0.3), most, "{continuity:?}");
        assert_eq!(continuity.hinges(&rod), 0);
    }
}

/// An estimate of `rod` with `errors` per span (midpoints alike), the largest as the
/// global estimate.
fn estimate_of(rod: &Rod, errors: &[Real]) -> ErrorEstimate {
    let knots = rod.basis().knots();
    let mut values: Vec<Real> = knots.to_vec();
    values.dedup();
    let spans: Vec<SpanError> = values
        .windows(2)
        .zip(errors)
        .map(|(w, &error)| SpanError {
            start: w[0],
            end: w[1],
            error,
            midpoint: error,
        })
        .collect();
    ErrorEstimate {
        global: errors.iter().copied().fold(0.0, Real::max),
        control_points: rod.len(),
        spans,
        corners: Vec::new(),
    }
}

/// #46: at `max_control_points` the tolerance criterion trades: the span far above
/// the tolerance is split and the cheapest knot elsewhere goes, keeping the count; below
/// the budget the same estimate only refines, and spans far below the tolerance are
/// coarsened whatever the rest of the rod does.
#[test]
fn the_tolerance_criterion_trades_resolution_at_its_budget() {
    let mut errors = vec![1e-9; 9];
    errors[6] = 1e-2;
    for budget in [12, 40] {
        let mut rod = arc(12, 1e-9);
        let criterion = ToleranceCriterion::new(1e-4).unwrap().with_budget(budget);
        let params = AdaptParams {
            max_control_points: budget,
            hysteresis_steps: 0,
            ..AdaptParams::default()
        };
        let mut adapter = Adapter::new(params).unwrap().with(criterion);
        let estimate = estimate_of(&rod, &errors);
        let (a, b) = (estimate.spans[6].start, estimate.spans[6].end);
        let report = adapter
            .adapt(&mut rod, &[], Some(&estimate), &mut |_, _| {})
            .unwrap();
        assert_eq!(
            rod.knot_multiplicity(0.5 * (a + b)),
            1,
            "the worst span is split"
        );
        assert!(report.removed >= 1, "{report:?}");
        if budget == 12 {
            assert_eq!(rod.len(), 12, "a trade keeps the count: {report:?}");
        }
    }
}
