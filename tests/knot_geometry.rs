//! The initial overhand knot of the knot-tying run (paper §5.2) and the knot diagnostics:
//! crossings of a projection, alternation, signs, tightness, bad input.
//!
//! Run with `--nocapture` to see the figures of each knot: clearance (smallest distance
//! between strands), largest initial strain `max |γ − 1|`, knot length and radius.

use nalgebra::Vector3;
use splinerod::knot::{
    is_alternating, is_trefoil_diagram, knot_extent, overhand_knot, projection_crossings,
    tightness, Crossing, OverhandKnot, OverhandSpec,
};
use splinerod::{BSplineSpace, Error, Material, Real, Rod};

/// Polyline samples for the diagnostics: a few hundred, as documented.
const SAMPLES: usize = 400;
/// Clearance asked of the knots, as a fraction of `size`.
const CLEARANCE: Real = 0.3;

fn spec(control_points: usize) -> OverhandSpec {
    OverhandSpec {
        control_points,
        ..OverhandSpec::default()
    }
}

fn knot(control_points: usize) -> OverhandKnot {
    overhand_knot(&spec(control_points)).expect("valid spec")
}

fn rod(control_points: usize) -> Rod {
    knot(control_points).rod(0.01).expect("valid knot")
}

fn up() -> Vector3<Real> {
    Vector3::y()
}

/// `count` material coordinates uniform over `[0, L]`.
fn coordinates(rod: &Rod, count: usize) -> Vec<Real> {
    let l = rod.material().rest_length;
    (0..count)
        .map(|i| (l * i as Real / (count - 1) as Real).min(l))
        .collect()
}

/// Smallest distance between points more than `3 · CLEARANCE · size` apart in `s`
/// (closer points belong to the same strand), by 600 samples: the sampling error,
/// below `L/600 ≈ 1.2 mm` of `s`, changes the distance by far less than that.
fn clearance(rod: &Rod, size: Real) -> Real {
    let s = coordinates(rod, 600);
    let p: Vec<_> = s.iter().map(|&x| rod.point(x).unwrap()).collect();
    let mut best = Real::INFINITY;
    for i in 0..s.len() {
        for j in i + 1..s.len() {
            if s[j] - s[i] > 3.0 * CLEARANCE * size {
                best = best.min((p[j] - p[i]).norm());
            }
        }
    }
    best
}

/// `max |γ(s) − 1|`, `γ = |C'(s)|`, over 2000 samples (≈ 250 per span for 11 points).
fn max_strain(rod: &Rod) -> Real {
    coordinates(rod, 2000)
        .iter()
        .map(|&s| (rod.tangent(s).unwrap().norm() - 1.0).abs())
        .fold(0.0, Real::max)
}

/// Over (`true`) / under events of all crossings, in order along `s`.
fn over_under_sequence(crossings: &[Crossing]) -> Vec<bool> {
    let mut events: Vec<(Real, bool)> = crossings
        .iter()
        .flat_map(|c| [(c.s_over, true), (c.s_under, false)])
        .collect();
    events.sort_by(|a, b| a.0.total_cmp(&b.0));
    events.into_iter().map(|e| e.1).collect()
}

#[test]
fn overhand_knots_have_the_trefoil_diagram() {
    for n in [11, 20, 40] {
        let rod = rod(n);
        let crossings = projection_crossings(&rod, up(), SAMPLES).unwrap();
        assert_eq!(crossings.len(), 3, "{n} control points: {crossings:?}");
        let sequence = over_under_sequence(&crossings);
        assert!(sequence.windows(2).all(|w| w[0] != w[1]), "{sequence:?}");
        assert!(is_alternating(&crossings));
        assert!(crossings.iter().all(|c| c.sign == crossings[0].sign));
        assert!(is_trefoil_diagram(&crossings));
        let (lo, hi) = knot_extent(&crossings).unwrap();
        assert!(0.0 < lo && lo < hi && hi < rod.material().rest_length);
    }
}

#[test]
fn overhand_knots_are_clear_unstretched_and_loose() {
    let size = OverhandSpec::default().size;
    for n in [11, 20, 40] {
        let rod = rod(n);
        let l = rod.material().rest_length;
        let t = tightness(&rod, up(), SAMPLES).unwrap().expect("a knot");
        let crossings = projection_crossings(&rod, up(), SAMPLES).unwrap();
        let min_gap = crossings
            .iter()
            .map(|c| c.gap)
            .fold(Real::INFINITY, Real::min);
        let (clear, strain) = (clearance(&rod, size), max_strain(&rod));
        println!(
            "n = {n:2}: L = {l:.4} m, clearance/size = {:.3}, min crossing gap/size = {:.3}, \
             max |speed − 1| = {strain:.3}, knot length = {:.4} m ({:.2} L), radius = {:.4} m",
            clear / size,
            min_gap / size,
            t.knot_length,
            t.knot_length / l,
            t.radius,
        );
        assert!(clear >= CLEARANCE * size, "clearance {clear}");
        // 8 cubic spans cannot follow the knot at unit speed everywhere; 20 and more can.
        assert!(
            strain < if n == 11 { 0.25 } else { 0.05 },
            "strain {strain}"
        );
        assert_eq!(t.crossings, 3);
        assert!(0.0 < t.knot_length && t.knot_length < l);
        assert!(t.radius > 0.0 && t.radius < size);
    }
}

#[test]
fn smaller_knots_hold_less_rod() {
    // A proxy for tightening: the same rod ends with a smaller knot in between.
    let measures: Vec<_> = [0.1, 0.07, 0.05]
        .iter()
        .map(|&size| {
            let spec = OverhandSpec { size, ..spec(40) };
            let rod = overhand_knot(&spec).unwrap().rod(0.01).unwrap();
            let t = tightness(&rod, up(), SAMPLES).unwrap().unwrap();
            println!(
                "size {size}: knot length {:.4} m, radius {:.4} m",
                t.knot_length, t.radius
            );
            t
        })
        .collect();
    for w in measures.windows(2) {
        assert!(w[1].knot_length < w[0].knot_length && w[1].radius < w[0].radius);
    }
}

#[test]
fn rest_length_is_the_arclength() {
    // The mean speed is exactly 1: the chord length of 4000 samples underestimates the
    // arclength by O(h²) ≈ 1e-6 relative.
    for n in [11, 40] {
        let rod = rod(n);
        let s = coordinates(&rod, 4000);
        let p: Vec<_> = s.iter().map(|&x| rod.point(x).unwrap()).collect();
        let chords: Real = p.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
        let l = rod.material().rest_length;
        assert!((chords / l - 1.0).abs() < 1e-5, "{chords} vs {l}");
    }
}

#[test]
fn ends_are_pinned_on_the_x_axis_and_tails_leave_along_x() {
    let spec = OverhandSpec::default();
    let half = 0.5 * spec.span;
    for (n, min_cos) in [(11, 0.8), (20, 0.95), (40, 0.99)] {
        let knot = knot(n);
        let q = &knot.control_points;
        assert!((q[0] - Vector3::new(-half, 0.0, 0.0)).norm() < 1e-12);
        assert!((q[q.len() - 1] - Vector3::new(half, 0.0, 0.0)).norm() < 1e-12);
        let rod = knot.rod(0.01).unwrap();
        let start = rod.tangent(0.0).unwrap().normalize();
        let end = rod.tangent(knot.rest_length).unwrap().normalize();
        println!("n = {n:2}: end tangents {:.3} {:.3}", start.x, end.x);
        assert!(start.x > min_cos && end.x > min_cos, "{start} {end}");
    }
}

#[test]
fn construction_is_deterministic_and_scale_free() {
    let a = knot(20);
    assert_eq!(a, knot(20));
    let big = overhand_knot(&OverhandSpec {
        size: 1.0,
        span: 3.0,
        ..spec(20)
    })
    .unwrap();
    // Every term of the relaxation scales alike, so the knot scales by 10 up to round-off
    // (amplified a little by the iterations).
    let worst = a
        .control_points
        .iter()
        .zip(&big.control_points)
        .map(|(p, q)| (p * 10.0 - q).norm())
        .fold(0.0, Real::max);
    assert!(worst < 1e-6, "{worst}");
}

#[test]
fn straight_rod_has_no_crossing() {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, 12, 1.0).unwrap();
    let end = Vector3::new(1.0, 0.0, 0.0);
    let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).unwrap();
    for d in [Vector3::x(), Vector3::y(), Vector3::new(0.3, -1.0, 2.0)] {
        assert!(projection_crossings(&rod, d, SAMPLES).unwrap().is_empty());
        assert_eq!(tightness(&rod, d, SAMPLES).unwrap(), None);
    }
    assert_eq!(knot_extent(&[]), None);
}

#[test]
fn fewer_than_three_crossings_are_no_trefoil() {
    let crossings = projection_crossings(&rod(20), up(), SAMPLES).unwrap();
    assert!(!is_trefoil_diagram(&crossings[..1]));
    assert!(!is_trefoil_diagram(&crossings[..2]));
    assert!(!is_trefoil_diagram(&[]));
}

#[test]
fn crossing_signs_do_not_depend_on_the_side_seen_from() {
    let rod = rod(20);
    let above = projection_crossings(&rod, up(), SAMPLES).unwrap();
    let below = projection_crossings(&rod, -up(), SAMPLES).unwrap();
    assert_eq!(above.len(), below.len());
    // Over and under swap and the picture mirrors: each sign is unchanged.
    assert!(above.iter().zip(&below).all(|(a, b)| a.sign == b.sign));
    assert!(is_trefoil_diagram(&below));
}

fn field_of(result: Result<impl std::fmt::Debug, Error>) -> String {
    match result {
        Err(Error::InvalidField { field, .. }) => field,
        other => panic!("expected an invalid field, got {other:?}"),
    }
}

#[test]
fn bad_specs_name_the_field() {
    let base = OverhandSpec::default();
    let cases = [
        (
            "size",
            OverhandSpec {
                size: Real::NAN,
                ..base
            },
        ),
        ("size", OverhandSpec { size: -0.1, ..base }),
        (
            "size",
            OverhandSpec {
                size: Real::INFINITY,
                ..base
            },
        ),
        ("span", OverhandSpec { span: 0.0, ..base }),
        ("span", OverhandSpec { span: -1.0, ..base }),
        (
            "span",
            OverhandSpec {
                span: 0.5 * base.min_span(),
                ..base
            },
        ),
        (
            "control_points",
            OverhandSpec {
                control_points: 3,
                ..base
            },
        ),
        ("degree", OverhandSpec { degree: 0, ..base }),
        ("degree", OverhandSpec { degree: 12, ..base }),
    ];
    for (field, spec) in cases {
        assert_eq!(field_of(overhand_knot(&spec)), field, "{spec:?}");
    }
}

#[test]
fn too_few_control_points_for_a_long_rod_are_reported() {
    // 8 spans over 0.9 m of rod leave too little for the knot: the B-spline unknots.
    let spec = OverhandSpec {
        span: 0.5,
        ..OverhandSpec::default()
    };
    assert_eq!(field_of(overhand_knot(&spec)), "control_points");
}

#[test]
fn bad_diagnostic_inputs_name_the_field() {
    let rod = rod(11);
    assert_eq!(field_of(projection_crossings(&rod, up(), 1)), "samples");
    assert_eq!(field_of(tightness(&rod, up(), 0)), "samples");
    let zero = Vector3::zeros();
    assert_eq!(
        field_of(projection_crossings(&rod, zero, SAMPLES)),
        "direction"
    );
    let nan = Vector3::new(Real::NAN, 1.0, 0.0);
    assert_eq!(field_of(tightness(&rod, nan, SAMPLES)), "direction");
}

#[test]
fn other_degrees_give_a_knot_or_name_control_points() {
    // Degree 1 is left out: its projection folds back sharply at some control point,
    // where chords of a uniform sampling can cross (see `projection_crossings`).
    for degree in [2, 3, 5, 9] {
        for control_points in [degree + 1, 11] {
            let spec = OverhandSpec {
                degree,
                control_points,
                ..OverhandSpec::default()
            };
            match overhand_knot(&spec) {
                Ok(knot) => {
                    let rod = knot.rod(0.01).unwrap();
                    let crossings = projection_crossings(&rod, up(), SAMPLES).unwrap();
                    assert!(is_trefoil_diagram(&crossings), "{spec:?}");
                }
                Err(e) => assert_eq!(field_of(Err::<(), _>(e)), "control_points", "{spec:?}"),
            }
        }
    }
}
