//! Exactness of refinement (paper §3.2): inserting a knot anywhere changes the basis but
//! not the curve, its motion, its energies or its momentum; removing the inserted knot
//! gives back the original control points.

use proptest::prelude::*;
use splinerod::prelude::*;

/// A rod of `degree` on clamped uniform knots with the given control points and
/// velocities (flattened triples).
fn rod(degree: usize, points: &[[Real; 3]], velocities: &[[Real; 3]]) -> Rod {
    let material = Material {
        rest_length: 1.3,
        linear_density: 0.07,
    };
    let basis = BSplineSpace::clamped_uniform(degree, points.len(), 1.3).expect("basis");
    let positions = points.iter().map(|p| Vector3::from(*p)).collect();
    let mut rod = Rod::new(material, Box::new(basis), positions).expect("rod");
    for (v, w) in rod.velocities.iter_mut().zip(velocities) {
        *v = Vector3::from(*w);
    }
    rod
}

/// Everything that must not change, measured on the rod.
struct Observables {
    points: Vec<Vector3<Real>>,
    velocities: Vec<Vector3<Real>>,
    energies: [Real; 3],
    /// The size of the terms each energy sums (the gravity energy is a sum of
    /// `m g·q` of either sign, so its value can be far smaller than its round-off).
    scales: [Real; 3],
    momentum: Vector3<Real>,
}

fn observe(rod: &Rod) -> Observables {
    let l = rod.material().rest_length;
    let samples = (0..=50).map(|k| l * k as Real / 50.0);
    let mut stretch = Stretching::new(80.0).expect("stiffness");
    // The pointwise form: its energy is invariant under insertion (the mixed one is
    // bounded instead, tested in tests/adaptivity.rs).
    stretch.formulation = StretchFormulation::Pointwise;
    let g = Vector3::new(0.3, -9.81, 0.1);
    let gravity = Gravity::new(g).expect("gravity");
    let mass = rod.material().linear_density * l;
    let reach = rod.positions.iter().map(|q| q.norm()).fold(0.0, Real::max);
    let (kinetic, strain) = (rod.kinetic_energy(), stretch.energy(rod));
    Observables {
        points: samples.clone().map(|s| rod.point(s).expect("s")).collect(),
        velocities: samples.map(|s| rod.velocity(s).expect("s")).collect(),
        energies: [kinetic, strain, gravity.energy(rod)],
        scales: [kinetic.abs(), strain.abs(), mass * g.norm() * reach],
        momentum: rod.linear_momentum(),
    }
}

fn close(a: Real, b: Real, scale: Real) -> bool {
    (a - b).abs() <= 1e-12 * scale.max(Real::MIN_POSITIVE)
}

fn assert_unchanged(before: &Observables, after: &Observables) -> Result<(), TestCaseError> {
    let point_scale = before.points.iter().map(|p| p.amax()).fold(1.0, Real::max);
    let speed_scale = before
        .velocities
        .iter()
        .map(|v| v.amax())
        .fold(1e-300, Real::max);
    for (a, b) in before.points.iter().zip(&after.points) {
        prop_assert!((a - b).amax() <= 1e-12 * point_scale, "point {a} -> {b}");
    }
    for (a, b) in before.velocities.iter().zip(&after.velocities) {
        prop_assert!((a - b).amax() <= 1e-12 * speed_scale, "velocity {a} -> {b}");
    }
    let energies = before.energies.iter().zip(&after.energies);
    for (k, ((a, b), scale)) in energies.zip(&before.scales).enumerate() {
        prop_assert!(close(*a, *b, *scale), "energy {k}: {a} -> {b}");
    }
    let m = before.momentum.amax();
    prop_assert!((before.momentum - after.momentum).amax() <= 1e-12 * m);
    Ok(())
}

fn coordinates(n: std::ops::Range<usize>) -> impl Strategy<Value = Vec<[Real; 3]>> {
    prop::collection::vec(prop::array::uniform3(-2.0..2.0f64), n)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn insertion_changes_nothing_and_removal_restores(
        degree in 1usize..=5,
        points in coordinates(6..14),
        velocities in coordinates(14..15),
        fractions in prop::collection::vec(0.001..0.999f64, 1..4),
    ) {
        let mut rod = rod(degree, &points, &velocities);
        let original = rod.positions.clone();
        let before = observe(&rod);
        let mut inserted = Vec::new();
        for f in &fractions {
            let map = rod.insert_knot(f * 1.3).expect("insertion inside the domain");
            inserted.push(map.knot_index());
        }
        prop_assert_eq!(rod.len(), original.len() + fractions.len());
        assert_unchanged(&before, &observe(&rod))?;
        // Undo in reverse order: each removal is exact because the knot was inserted.
        for index in inserted.into_iter().rev() {
            rod.remove_knot(index, 1e-12).expect("removing an inserted knot");
        }
        prop_assert_eq!(rod.len(), original.len());
        let scale = original.iter().map(|p| p.amax()).fold(1.0, Real::max);
        for (a, b) in original.iter().zip(&rod.positions) {
            prop_assert!((a - b).amax() <= 1e-12 * scale, "{a} -> {b}");
        }
    }
}
