use crate::basis::{greville, spans, Span};
use crate::proximity::narrow::closest_points_counted;
use crate::proximity::{closest_points, Closest, SpanBoxes};
use crate::{BSplineSpace, BasisSpace, CoreError, Material, Real, Rod};
use nalgebra::Vector3;
use std::collections::HashSet;
use std::f64::consts::TAU;

/// Small deterministic generator (LCG) for noise in `[-1, 1]`.
struct Lcg(u64);
impl Lcg {
    fn next(&mut self) -> Real {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as Real / (1u64 << 53) as Real) * 2.0 - 1.0
    }
}

fn material(l: Real) -> Material {
    Material {
        rest_length: l,
        linear_density: 0.1,
    }
}

/// A helix of `turns` turns (radius `r`, rise `pitch` per turn) with control points at
/// the Greville abscissae, perturbed by `noise`.
fn helix_rod(
    degree: usize,
    n_spans: usize,
    turns: Real,
    pitch: Real,
    noise: Real,
    seed: u64,
) -> Rod {
    let r = 0.1;
    let l = turns * (TAU * r).hypot(pitch);
    let basis = BSplineSpace::clamped_uniform(degree, n_spans + degree, l).unwrap();
    let mut rng = Lcg(seed);
    let positions = (0..basis.count())
        .map(|i| {
            let u = greville(&basis, i) / l;
            let a = TAU * turns * u;
            let jitter = Vector3::new(rng.next(), rng.next(), rng.next()) * noise;
            Vector3::new(r * a.cos(), r * a.sin(), pitch * turns * u) + jitter
        })
        .collect();
    Rod::new(material(l), Box::new(basis), positions).unwrap()
}

/// Largest float below `x` (the last parameter of a span ending at `x`).
fn below(x: Real) -> Real {
    f64::from_bits(x.to_bits() - 1)
}

/// `m` points on a span, ends included.
fn sample(rod: &Rod, span: &Span, m: usize) -> Vec<Vector3<Real>> {
    (0..m)
        .map(|k| {
            let s = span.start + (span.end - span.start) * k as Real / (m - 1) as Real;
            rod.point(s.min(below(span.end))).unwrap()
        })
        .collect()
}

fn min_distance(a: &[Vector3<Real>], b: &[Vector3<Real>]) -> Real {
    a.iter()
        .flat_map(|p| b.iter().map(move |q| (p - q).norm()))
        .fold(Real::INFINITY, Real::min)
}

#[test]
fn broad_phase_is_a_superset_of_close_pairs_on_helices() {
    let (margin, exclusion) = (0.022, 0.1);
    for degree in 2..=4 {
        for seed in 0..3 {
            let rod = helix_rod(degree, 60, 4.0, 0.04, 0.006, seed);
            let boxes = SpanBoxes::new(&rod, margin).unwrap();
            let mut pairs = Vec::new();
            boxes.candidate_pairs(exclusion, &mut pairs).unwrap();
            let found: HashSet<_> = pairs.iter().copied().collect();
            assert_eq!(found.len(), pairs.len(), "duplicates");
            let all: Vec<Span> = spans(rod.basis()).collect();
            assert_eq!(boxes.spans(), &all[..]);
            let points: Vec<_> = all.iter().map(|s| sample(&rod, s, 10)).collect();
            let mut required = 0;
            for i in 0..all.len() {
                for j in i + 1..all.len() {
                    let gap = all[j].start - all[i].end;
                    let near = min_distance(&points[i], &points[j]) < 2.0 * margin;
                    if gap >= exclusion && near {
                        required += 1;
                        assert!(found.contains(&(i, j)), "d={degree} missed ({i}, {j})");
                    }
                    if found.contains(&(i, j)) {
                        assert!(gap >= exclusion);
                    }
                }
            }
            assert!(required > 50, "only {required} close pairs: test too weak");
            assert!(
                pairs.len() < all.len() * all.len() / 4,
                "{} pairs",
                pairs.len()
            );
        }
    }
}

/// Cubic rod of two pieces (cut at s = 1), four spans each; piece A and piece B follow
/// `a(u)` and `b(u)`, `u ∈ [0, 1]` the local Greville abscissa.
fn two_pieces(a: impl Fn(Real) -> Vector3<Real>, b: impl Fn(Real) -> Vector3<Real>) -> Rod {
    let mut knots = vec![0.0; 4];
    knots.extend([0.25, 0.5, 0.75]);
    knots.extend([1.0; 4]);
    knots.extend([1.25, 1.5, 1.75]);
    knots.extend([2.0; 4]);
    let basis = BSplineSpace::new(3, knots).unwrap();
    let positions = (0..basis.count())
        .map(|i| {
            let g = greville(&basis, i);
            if i < 7 {
                a(g)
            } else {
                b(g - 1.0)
            }
        })
        .collect();
    Rod::new(material(2.0), Box::new(basis), positions).unwrap()
}

/// Reference minimum of |C(s) − C(t)| over two spans: a 64 × 64 grid, zoomed 80 times
/// onto ±8 cells around its best point.
fn reference(rod: &Rod, a: &Span, b: &Span) -> (Real, Real, Real) {
    let (mut sa, mut sb) = ((a.start, below(a.end)), (b.start, below(b.end)));
    let n = 64;
    let mut best = (Real::INFINITY, 0.0, 0.0);
    for _ in 0..80 {
        let at = |w: (Real, Real), k: usize| w.0 + (w.1 - w.0) * k as Real / n as Real;
        let pb: Vec<_> = (0..=n).map(|k| rod.point(at(sb, k)).unwrap()).collect();
        for i in 0..=n {
            let p = rod.point(at(sa, i)).unwrap();
            for (j, q) in pb.iter().enumerate() {
                let d = (p - q).norm();
                if d < best.0 {
                    best = (d, at(sa, i), at(sb, j));
                }
            }
        }
        let zoom = |w: (Real, Real), c: Real, lim: (Real, Real)| {
            let h = 8.0 * (w.1 - w.0) / n as Real;
            ((c - h).max(lim.0), (c + h).min(lim.1))
        };
        sa = zoom(sa, best.1, (a.start, below(a.end)));
        sb = zoom(sb, best.2, (b.start, below(b.end)));
    }
    best
}

/// Checks the narrow phase on every pair (piece A span, piece B span); returns the
/// overall closest (s, t, distance).
fn check_narrow_phase(rod: &Rod, unique: bool) -> (Real, Real, Real) {
    let all: Vec<Span> = spans(rod.basis()).collect();
    let mut overall = (0.0, 0.0, Real::INFINITY);
    for a in all.iter().filter(|s| s.end <= 1.0) {
        for b in all.iter().filter(|s| s.start >= 1.0) {
            let (c, s, t) = check_pair(rod, a, b);
            assert!(c.s >= a.start && c.s < a.end && c.t >= b.start && c.t < b.end);
            if unique {
                assert!(
                    (c.s - s).abs() < 1e-6 && (c.t - t).abs() < 1e-6,
                    "{c:?} vs {s} {t}"
                );
            }
            if c.distance < overall.2 {
                overall = (c.s, c.t, c.distance);
            }
        }
    }
    overall
}

/// Checks one pair against the reference (distance within 1e-9 relative, consistent
/// point, normal and first-order optimality, at most 8 Newton steps); returns the result
/// and the reference parameters.
fn check_pair(rod: &Rod, a: &Span, b: &Span) -> (Closest, Real, Real) {
    let (c, steps) = closest_points_counted(rod, a, b).unwrap();
    let (d, s, t) = reference(rod, a, b);
    assert!((c.distance - d).abs() <= 1e-9 * d, "{} vs {d}", c.distance);
    assert!(steps <= 8, "{steps} steps");
    assert!(c.s >= a.start && c.s < a.end && c.t >= b.start && c.t < b.end);
    let r = rod.point(c.s).unwrap() - rod.point(c.t).unwrap();
    assert!((r.norm() - c.distance).abs() <= 1e-14);
    assert!((r - c.normal * c.distance).norm() <= 1e-14);
    check_kkt(rod, a, c.s, r.dot(&rod.tangent(c.s).unwrap()));
    check_kkt(rod, b, c.t, -r.dot(&rod.tangent(c.t).unwrap()));
    (c, s, t)
}

#[test]
fn narrow_phase_on_the_candidates_of_a_tight_coil() {
    // Neighbouring turns nearly parallel and nearly touching (pitch 0.0065, margin 0.003).
    for degree in 2..=4 {
        let rod = helix_rod(degree, 60, 3.0, 0.0065, 0.0005, degree as u64);
        let boxes = SpanBoxes::new(&rod, 0.003).unwrap();
        let mut pairs = Vec::new();
        boxes.candidate_pairs(0.1, &mut pairs).unwrap();
        assert!(pairs.len() > 60);
        for &(i, j) in &pairs {
            check_pair(&rod, &boxes.spans()[i], &boxes.spans()[j]);
        }
    }
}

/// First-order optimality of a bound-constrained minimum with gradient `g` at `s`.
fn check_kkt(rod: &Rod, span: &Span, s: Real, g: Real) {
    let scale = 1e-9 * rod.tangent(s).unwrap().norm();
    if s <= span.start {
        assert!(g >= -scale, "lower bound, g = {g}");
    } else if s >= below(span.end) {
        assert!(g <= scale, "upper bound, g = {g}");
    } else {
        assert!(g.abs() <= scale, "interior, g = {g}");
    }
}

fn arc(u: Real) -> Vector3<Real> {
    Vector3::new(u, 0.2 * u * u, 0.0)
}

#[test]
fn narrow_phase_matches_sampling_on_crossing_pieces() {
    let rod = two_pieces(arc, |u| {
        Vector3::new(0.5 + 0.1 * (u - 0.5).powi(2), u - 0.5, 0.05 + 0.02 * u)
    });
    let (s, t, d) = check_narrow_phase(&rod, true);
    assert!(d > 0.05 && d < 0.07 && s > 0.3 && s < 0.7 && t > 1.3 && t < 1.7);
}

#[test]
fn narrow_phase_handles_parallel_pieces() {
    // Piece B is piece A shifted: every pair of matching points is at the minimum.
    let offset = Vector3::new(0.0, 0.0, 0.07);
    let rod = two_pieces(arc, |u| arc(u) + offset);
    let (_, _, d) = check_narrow_phase(&rod, false);
    assert!((d - 0.07).abs() < 1e-12);
}

#[test]
fn narrow_phase_finds_endpoint_and_edge_minima() {
    // Corner: end of A against start of B.
    let rod = two_pieces(arc, |u| Vector3::new(1.3 + u, 0.5 + u, 0.1 * u));
    let (s, t, _) = check_narrow_phase(&rod, true);
    assert!(s == below(1.0) && t == 1.0, "{s} {t}");
    // Edge: end of A against the inside of B.
    let rod = two_pieces(arc, |u| Vector3::new(1.25, u - 0.3, 0.0));
    let (s, t, d) = check_narrow_phase(&rod, true);
    assert!(
        s == below(1.0) && t > 1.0 && t < 2.0 && d > 0.2,
        "{s} {t} {d}"
    );
}

#[test]
fn narrow_phase_rejects_foreign_spans() {
    let rod = two_pieces(arc, arc);
    let a = spans(rod.basis()).next().unwrap();
    let bad = Span { end: 0.3, ..a };
    assert!(matches!(
        closest_points(&rod, &bad, &a),
        Err(CoreError::InvalidParameter { .. })
    ));
}

/// A straight cubic rod along x with `n` spans on `[0, 2]`, cut at `s = 1`.
fn cut_rod(n: usize) -> Rod {
    let basis = BSplineSpace::clamped_uniform(3, n + 3, 2.0).unwrap();
    let end = Vector3::new(2.0, 0.0, 0.0);
    let mut rod = Rod::straight(material(2.0), Box::new(basis), Vector3::zeros(), end).unwrap();
    rod.cut(1.0).unwrap();
    rod
}

#[test]
fn pieces_after_a_cut_are_candidates() {
    let mut rod = cut_rod(20);
    let mut boxes = SpanBoxes::new(&rod, 0.02).unwrap();
    let mut pairs = Vec::new();
    // Exclusion beyond the rod length: only pairs on different pieces can remain. Right
    // after the cut the pieces still touch at s = 1.
    boxes.candidate_pairs(10.0, &mut pairs).unwrap();
    assert!(!pairs.is_empty());
    let piece = |i: usize, b: &SpanBoxes| b.piece(i);
    assert!(pairs
        .iter()
        .all(|&(i, j)| piece(i, &boxes) != piece(j, &boxes)));
    // Swing piece B across piece A: x = 0.5, along y, 1 cm above.
    let first_b = (0..boxes.len()).find(|&i| boxes.piece(i) == 1).unwrap();
    let first_b = boxes.spans()[first_b].first;
    for q in &mut rod.positions[first_b..] {
        *q = Vector3::new(0.5, q.x - 1.5, 0.01);
    }
    boxes.update(&rod, 0.02).unwrap();
    boxes.candidate_pairs(10.0, &mut pairs).unwrap();
    let spans = boxes.spans();
    let crossing = pairs.iter().any(|&(i, j)| {
        let (a, b) = (spans[i], spans[j]);
        a.start <= 0.5 && a.end >= 0.5 && b.start <= 1.5 && b.end >= 1.5
    });
    assert!(crossing, "{pairs:?}");
    let c = pairs
        .iter()
        .map(|&(i, j)| closest_points(&rod, &spans[i], &spans[j]).unwrap().distance)
        .fold(Real::INFINITY, Real::min);
    assert!((c - 0.01).abs() < 1e-12, "{c}");
}

#[test]
fn updates_reuse_buffers_and_warm_start_sorts_correctly() {
    let mut rod = helix_rod(3, 200, 10.0, 0.03, 0.0, 1);
    let mut boxes = SpanBoxes::new(&rod, 0.02).unwrap();
    let mut pairs = Vec::new();
    boxes.candidate_pairs(0.05, &mut pairs).unwrap();
    let capacities = boxes.capacities();
    let mut rng = Lcg(7);
    for q in rod.positions.iter_mut() {
        *q += Vector3::new(rng.next(), rng.next(), rng.next()) * 0.003;
    }
    boxes.update(&rod, 0.02).unwrap();
    boxes.candidate_pairs(0.05, &mut pairs).unwrap();
    assert_eq!(boxes.capacities(), capacities);
    let out = pairs.capacity();
    for _ in 0..2 {
        boxes.update(&rod, 0.02).unwrap();
        boxes.candidate_pairs(0.05, &mut pairs).unwrap();
        assert_eq!(boxes.capacities(), capacities);
        assert_eq!(pairs.capacity(), out);
    }
    // The warm-started order gives the same pairs as a fresh sort.
    let mut fresh = Vec::new();
    SpanBoxes::new(&rod, 0.02)
        .unwrap()
        .candidate_pairs(0.05, &mut fresh)
        .unwrap();
    let (mut a, mut b) = (pairs.clone(), fresh);
    a.sort_unstable();
    b.sort_unstable();
    assert_eq!(a, b);
    assert_eq!(boxes.axis(), 2);
}

#[test]
fn invalid_margin_and_exclusion_are_rejected() {
    let rod = cut_rod(4);
    assert!(SpanBoxes::new(&rod, -1.0).is_err());
    assert!(SpanBoxes::new(&rod, Real::NAN).is_err());
    let boxes = SpanBoxes::new(&rod, 0.0).unwrap();
    assert!(boxes.candidate_pairs(-0.1, &mut Vec::new()).is_err());
}

/// The sort and sweep visits pairs in an order set by the boxes alone: boxes with equal
/// lower bounds (a rod lying across the sweep axis) come by index whatever the warm start
/// left, so a cold sweep (after a resume) and a warm one agree pair for pair.
#[test]
fn the_sweep_order_does_not_depend_on_the_warm_start() {
    use crate::proximity::BoxSweep;
    // Boxes along x, and a second row across x at x = 0.3: equal lower bounds there.
    let mut lower: Vec<Vector3<Real>> = (0..20)
        .map(|i| Vector3::new(0.05 * i as Real, 0.0, 0.0))
        .collect();
    lower.extend((0..8).map(|k| Vector3::new(0.3, -0.2 + 0.05 * k as Real, 0.01)));
    let upper: Vec<Vector3<Real>> = lower.iter().map(|l| l + Vector3::repeat(0.06)).collect();
    let pairs_of = |sweep: &mut BoxSweep, lower: &[Vector3<Real>], upper: &[Vector3<Real>]| {
        sweep.sort(lower, upper);
        let mut out = Vec::new();
        sweep.pairs(lower, upper, 0.0, |i, j| out.push((i, j)));
        out
    };
    let mut cold = BoxSweep::default();
    let expected = pairs_of(&mut cold, &lower, &upper);
    assert!(expected.len() > 20, "{} pairs", expected.len());
    // A warm start from boxes where the second row's lower bounds fall with the index:
    // a stable warm sort would keep that order among the ties.
    let mut spread = lower.clone();
    for (k, l) in spread[20..].iter_mut().enumerate() {
        l.x += 0.01 * (8 - k) as Real;
    }
    let spread_upper: Vec<Vector3<Real>> =
        spread.iter().map(|l| l + Vector3::repeat(0.06)).collect();
    let mut warm = BoxSweep::default();
    pairs_of(&mut warm, &spread, &spread_upper);
    assert_eq!(pairs_of(&mut warm, &lower, &upper), expected);
}
