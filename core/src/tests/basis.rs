use super::all_test_spaces;
use crate::quadrature::GaussLegendre;
use crate::{BSplineSpace, BasisSpace, BasisValues, CoreError, Real};

fn eval(space: &dyn BasisSpace, s: Real) -> BasisValues {
    let mut b = BasisValues::default();
    space.evaluate(s, &mut b).unwrap();
    b
}

/// Value of function `i` at `s` (zero where it is not among the non-zero ones).
fn value_of(space: &dyn BasisSpace, i: usize, s: Real, which: usize) -> Real {
    let b = eval(space, s);
    if i < b.first || i >= b.first + b.order {
        return 0.0;
    }
    [b.value, b.d1, b.d2][which][i - b.first]
}

#[test]
fn partition_of_unity_and_non_negativity() {
    // Sums of order ≤ 10 terms of O(1): round-off below 1e-14.
    for space in all_test_spaces() {
        let (a, b) = space.domain();
        for k in 0..=200 {
            let s = a + (b - a) * k as Real / 200.0;
            let v = eval(&space, s);
            let sum: Real = v.value[..v.order].iter().sum();
            let d1: Real = v.d1[..v.order].iter().sum();
            assert!(
                (sum - 1.0).abs() < 1e-14,
                "sum {sum} at {s} degree {}",
                space.degree()
            );
            assert!(
                d1.abs() < 1e-10 * (1.0 + v.d1[..v.order].iter().map(|x| x.abs()).sum::<Real>())
            );
            assert!(v.value[..v.order].iter().all(|&x| x >= -1e-15));
        }
    }
}

#[test]
fn derivatives_match_finite_differences() {
    // Central differences with h = 1e-6 have truncation O(h²·b''') and round-off
    // O(1e-16/h): 1e-6 relative to the derivative scale is ample.
    for space in all_test_spaces() {
        let (a, b) = space.domain();
        let h = 1e-6 * (b - a);
        let scale = (space.count() as Real / (b - a)).powi(2);
        for k in 1..40 {
            let s = a + (b - a) * (k as Real + 0.123) / 40.3;
            for i in 0..space.count() {
                let fd1 =
                    (value_of(&space, i, s + h, 0) - value_of(&space, i, s - h, 0)) / (2.0 * h);
                let d1 = value_of(&space, i, s, 1);
                assert!((fd1 - d1).abs() < 1e-5 * scale.sqrt(), "d1 {d1} vs {fd1}");
                if space.degree() >= 2 {
                    let fd2 =
                        (value_of(&space, i, s + h, 1) - value_of(&space, i, s - h, 1)) / (2.0 * h);
                    let d2 = value_of(&space, i, s, 2);
                    assert!((fd2 - d2).abs() < 1e-5 * scale, "d2 {d2} vs {fd2}");
                }
            }
        }
    }
}

#[test]
fn clamped_curve_interpolates_its_ends() {
    let space = BSplineSpace::clamped_uniform(3, 9, 1.0).unwrap();
    assert_eq!(eval(&space, 0.0).value[0], 1.0);
    let end = eval(&space, 1.0);
    assert_eq!(end.first + end.order, 9);
    assert_eq!(end.value[end.order - 1], 1.0);
}

#[test]
fn gauss_legendre_is_exact_to_degree_2m_minus_1() {
    // ∫_0^1 x^k dx = 1/(k+1); exact rule up to round-off (1e-15).
    for m in 1..=12 {
        let rule = GaussLegendre::new(m);
        for k in 0..2 * m {
            let q: Real = rule
                .nodes
                .iter()
                .zip(&rule.weights)
                .map(|(x, w)| w * x.powi(k as i32))
                .sum();
            assert!((q - 1.0 / (k as Real + 1.0)).abs() < 1e-14, "m {m} k {k}");
        }
        if m > 6 {
            continue; // beyond 6 points the degree-2m error drops below 1e-12
        }
        let k = 2 * m;
        let q: Real = rule
            .nodes
            .iter()
            .zip(&rule.weights)
            .map(|(x, w)| w * x.powi(k as i32))
            .sum();
        assert!(
            (q - 1.0 / (k as Real + 1.0)).abs() > 1e-12,
            "m {m} should not be exact at {k}"
        );
    }
}

#[test]
fn bad_spaces_are_rejected_with_named_values() {
    use CoreError::*;
    assert!(matches!(
        BSplineSpace::new(3, vec![0.0, 0.0, 1.0]),
        Err(TooFewControlPoints { .. })
    ));
    assert!(matches!(
        BSplineSpace::new(1, vec![0.0, 0.0, 0.5, 0.4, 1.0, 1.0]),
        Err(KnotsNotSorted { index: 3, .. })
    ));
    assert!(matches!(
        BSplineSpace::new(1, vec![0.0, 0.0, Real::NAN, 1.0, 1.0]),
        Err(NonFiniteKnot { index: 2, .. })
    ));
    assert!(matches!(
        BSplineSpace::clamped_uniform(0, 4, 1.0),
        Err(InvalidDegree { .. })
    ));
    assert!(matches!(
        BSplineSpace::clamped_uniform(3, 3, 1.0),
        Err(TooFewControlPoints { .. })
    ));
    assert!(matches!(
        BSplineSpace::clamped_uniform(3, 5, -1.0),
        Err(InvalidParameter { .. })
    ));
    assert!(matches!(
        BSplineSpace::new(1, vec![0.0, 0.0, 0.5, 0.5, 0.5, 1.0, 1.0]),
        Err(MultiplicityTooHigh {
            multiplicity: 3,
            ..
        })
    ));
    let space = BSplineSpace::clamped_uniform(3, 5, 1.0).unwrap();
    let mut b = BasisValues::default();
    assert!(matches!(
        space.evaluate(1.5, &mut b),
        Err(OutsideDomain { .. })
    ));
    assert!(matches!(
        space.evaluate(Real::NAN, &mut b),
        Err(OutsideDomain { .. })
    ));
}

/// The degree-specialised evaluation does the run-time degree's operations in the same
/// order: the same bits, for every degree, on irregular knots, at every span.
#[test]
fn specialised_evaluation_matches_the_run_time_degree_bit_for_bit() {
    use crate::bspline::derivatives;
    for d in 1..=crate::MAX_DEGREE {
        let mut knots = vec![0.0; d + 1];
        knots.extend((1..12).map(|i| (i as Real / 12.0).powf(1.3)));
        knots.extend(vec![1.0; d + 1]);
        let space = BSplineSpace::new(d, knots.clone()).expect("space");
        let (mut fast, mut reference) = (BasisValues::default(), BasisValues::default());
        for i in 0..997 {
            let s = i as Real / 996.0;
            space.evaluate(s, &mut fast).expect("evaluate");
            derivatives::<0>(d, &knots, fast.first + d, s, &mut reference);
            let bits = |b: &BasisValues| {
                let all = b.value.iter().chain(&b.d1).chain(&b.d2);
                all.map(|x| x.to_bits()).collect::<Vec<_>>()
            };
            assert_eq!(bits(&fast), bits(&reference), "degree {d}, s = {s}");
            assert_eq!((fast.first, fast.order), (reference.first, reference.order));
        }
    }
}

#[test]
fn values_alone_equal_the_values_of_a_full_evaluation_bit_for_bit() {
    let periodic = crate::PeriodicBSplineSpace::uniform(3, 9, 1.0).expect("periodic");
    let mut spaces: Vec<Box<dyn BasisSpace>> = vec![Box::new(periodic)];
    spaces.extend(all_test_spaces().into_iter().map(|s| s.clone_box()));
    for space in &spaces {
        let (a, b) = space.domain();
        let (mut full, mut alone) = (BasisValues::default(), BasisValues::default());
        for k in 0..=300 {
            let s = a + (b - a) * k as Real / 300.0;
            space.evaluate(s, &mut full).expect("evaluate");
            space.evaluate_values(s, &mut alone).expect("values");
            let bits = |b: &BasisValues| b.value.map(Real::to_bits);
            assert_eq!(bits(&alone), bits(&full), "{space:?} at s = {s}");
            assert_eq!((alone.first, alone.order), (full.first, full.order));
        }
        let outside = space.evaluate_values(b + 1.0, &mut alone);
        assert!(outside.is_err(), "{space:?}: s outside the domain");
    }
}

#[test]
fn walking_the_quadrature_table_gives_each_point_as_indexed() {
    use crate::quadrature::{QuadPoint, QuadratureTable};
    let key = |q: &QuadPoint<'_>| {
        let bits = |v: &[Real]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let rows = [q.value, q.d1, q.d2, q.lower].map(bits);
        (q.s.to_bits(), q.weight.to_bits(), q.first, rows)
    };
    for space in all_test_spaces() {
        for lean in [false, true] {
            let table = QuadratureTable::new(&space, 4).expect("table");
            let table = if lean {
                table.without_second_derivatives()
            } else {
                table
            };
            let walked: Vec<_> = table.walk().map(|q| key(&q)).collect();
            let indexed: Vec<_> = (0..table.len()).map(|p| key(&table.point(p))).collect();
            assert_eq!(walked, indexed, "degree {}, lean {lean}", space.degree());
        }
    }
}
