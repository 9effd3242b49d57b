//! Every energy shipped with splinerod passes the conformance harness. Adding an energy
//! means adding one entry to `energies()`.

use nalgebra::Vector3;
use splinerod_core::{BlockBanded, HessianKind, Real, Rod};
use splinerod_energies::conformance::{
    check_energy, Expectations, RigidInvariance, EXACT_TOLERANCE,
};
use splinerod_energies::Lifecycle;
use splinerod_energies::{
    finite_difference_hessian, Bending, Clamp, Energy, Gravity, PointSpring, StretchFormulation,
    Stretching,
};

/// Relative change of bending energy and force allowed under knot insertion: the
/// quadrature error of the rational κ² on the harness's test rods. Measured: the
/// pulled-back gradient changes by up to 1.8e-2 (the harness's maximum), the energy by
/// up to 1.7e-3 on the "bent" rods (a few control points with 0.3 m wiggles: curvature
/// barely resolved), 6e-6 on the compressed and 1e-9 on the stretched ones (energy only).
const BENDING_KNOT_INSERTION: Real = 3e-2;

/// Relative change of the mixed stretching energy and force under knot insertion on the
/// harness's test rods: the tension space refines with the knots (see the module docs
/// of `stretching::mixed`; the energy change is bounded by the unresolved strain energy,
/// tested in `tests/adaptivity.rs`). Measured: 0.20 on these deliberately under-resolved
/// rods (a few control points, strain varying by tens of percent per span).
const MIXED_KNOT_INSERTION: Real = 0.3;

/// The same with the projection guard (`stretching/guard.rs`), whose sum over the spans
/// changes with them where the strain varies inside a span by more than 10 %: measured
/// 0.40 on these rods.
const GUARDED_KNOT_INSERTION: Real = 0.5;

fn consistent(ea: Real) -> Stretching {
    let mut s = Stretching::new(ea).unwrap();
    s.formulation = StretchFormulation::MixedConsistent;
    s
}

fn guarded(formulation: StretchFormulation) -> Stretching {
    let mut s = Stretching::new(100.0).unwrap();
    s.formulation = formulation;
    s.guard = true;
    s
}

fn pointwise(ea: Real) -> Stretching {
    let mut s = Stretching::new(ea).unwrap();
    s.formulation = StretchFormulation::Pointwise;
    s
}

fn energies() -> Vec<(Box<dyn Energy>, Expectations)> {
    let g = Vector3::new(0.0, -9.81, 0.0);
    let x = Vector3::new(1.0, 0.0, 0.0);
    vec![
        (
            Box::new(pointwise(100.0)),
            Expectations {
                zero_at_rest: true,
                rigid: RigidInvariance::Full,
                knot_insertion: EXACT_TOLERANCE,
            },
        ),
        (
            Box::new(Stretching::new(100.0).unwrap()),
            Expectations {
                zero_at_rest: true,
                rigid: RigidInvariance::Full,
                knot_insertion: MIXED_KNOT_INSERTION,
            },
        ),
        (
            // Gradient and Hessian (banded part plus remainder) against differences.
            Box::new(consistent(100.0)),
            Expectations {
                zero_at_rest: true,
                rigid: RigidInvariance::Full,
                knot_insertion: MIXED_KNOT_INSERTION,
            },
        ),
        (
            // The projection guard on both mixed forms (acting on the bent test rods).
            Box::new(guarded(StretchFormulation::Mixed)),
            Expectations {
                zero_at_rest: true,
                rigid: RigidInvariance::Full,
                knot_insertion: GUARDED_KNOT_INSERTION,
            },
        ),
        (
            Box::new(guarded(StretchFormulation::MixedConsistent)),
            Expectations {
                zero_at_rest: true,
                rigid: RigidInvariance::Full,
                knot_insertion: GUARDED_KNOT_INSERTION,
            },
        ),
        (
            Box::new(PointSpring::new(0.37, Vector3::new(0.2, -0.1, 0.05), 50.0).unwrap()),
            Expectations {
                zero_at_rest: false,
                rigid: RigidInvariance::None,
                knot_insertion: EXACT_TOLERANCE,
            },
        ),
        (
            Box::new(Gravity::new(g).unwrap()),
            Expectations {
                zero_at_rest: false,
                rigid: RigidInvariance::AboutAxis(g),
                knot_insertion: EXACT_TOLERANCE,
            },
        ),
        (
            Box::new(Bending::new(0.7).unwrap()),
            Expectations {
                zero_at_rest: true,
                rigid: RigidInvariance::Full,
                knot_insertion: BENDING_KNOT_INSERTION,
            },
        ),
        (
            Box::new(Clamp::new(0.4, x, 50.0).unwrap()),
            Expectations {
                zero_at_rest: true,
                rigid: RigidInvariance::AboutAxis(x),
                knot_insertion: EXACT_TOLERANCE,
            },
        ),
    ]
}

#[test]
fn every_energy_conforms() {
    for (energy, expect) in energies() {
        let report = check_energy(energy.as_ref(), expect).unwrap_or_else(|e| panic!("{e}"));
        println!("{}: {report:?}", energy.name());
    }
}

/// The harness must be able to fail: a stretching energy with a wrong Hessian is caught.
#[test]
fn harness_catches_a_wrong_hessian() {
    struct Wrong(Stretching);
    impl Energy for Wrong {
        fn energy(&self, rod: &Rod) -> Real {
            self.0.energy(rod)
        }
        fn add_gradient(&self, rod: &Rod, g: &mut [Vector3<Real>]) {
            self.0.add_gradient(rod, g)
        }
        fn add_hessian(&self, rod: &Rod, kind: HessianKind, h: &mut BlockBanded) {
            self.0.add_hessian(rod, kind, h);
            self.0.add_hessian(rod, kind, h); // twice: wrong by a factor 2
        }
    }
    let expect = Expectations {
        zero_at_rest: true,
        rigid: RigidInvariance::Full,
        knot_insertion: EXACT_TOLERANCE,
    };
    let err = check_energy(&Wrong(Stretching::new(10.0).unwrap()), expect).unwrap_err();
    assert!(err.contains("Hessian error"), "{err}");
}

/// The default finite-difference Hessian agrees with the lumped mixed stretching's exact
/// one (the consistent form's banded part is not its whole Hessian: the harness checks
/// it with the remainder).
#[test]
fn default_hessian_matches_exact_stretching() {
    // Closed rods are left out: their Hessian couples the two sides of the seam, outside
    // the band this finite-difference Hessian fills (the harness checks it densely).
    let rods = splinerod_energies::conformance::test_rods().expect("test rods");
    for (label, rod) in rods.into_iter().filter(|(_, r)| !r.is_closed()) {
        let mut e = Stretching::new(100.0).unwrap();
        e.formulation = StretchFormulation::Mixed;
        let n = rod.len();
        let d = rod.basis().degree();
        let (mut exact, mut fd) = (BlockBanded::zeros(n, d), BlockBanded::zeros(n, d));
        e.add_hessian(&rod, HessianKind::Exact, &mut exact);
        finite_difference_hessian(&e, &rod, &mut fd);
        let (a, b) = (exact.to_dense(), fd.to_dense());
        // O(h²) truncation with h = 6e-6 L: 1e-6 relative is ample.
        assert!(
            (&a - &b).amax() < 1e-6 * a.amax(),
            "{label}: {}",
            (&a - &b).amax() / a.amax()
        );
    }
}

#[test]
fn bad_parameters_are_errors() {
    assert!(Stretching::new(0.0).is_err());
    assert!(Stretching::new(Real::NAN).is_err());
    assert!(Gravity::new(Vector3::new(0.0, Real::INFINITY, 0.0)).is_err());
}

/// The definite stretching Hessian assembled independently: the exact 3×3 density
/// Hessian at each quadrature point with its negative eigenvalues set to zero.
fn eigen_clamped_stretching_hessian(rod: &Rod, ea: Real) -> BlockBanded {
    let mut out = BlockBanded::zeros(rod.len(), rod.basis().degree());
    for qp in rod.quadrature().points() {
        let c1: Vector3<Real> = qp
            .d1
            .iter()
            .enumerate()
            .map(|(a, w)| rod.positions[qp.first + a] * *w)
            .sum();
        let g2 = c1.norm_squared();
        let exact =
            (nalgebra::Matrix3::identity() * (g2 - 1.0) + c1 * c1.transpose() * 2.0) * (0.5 * ea);
        let eig = exact.symmetric_eigen();
        let clamped = eig.eigenvalues.map(|l| l.max(0.0));
        let h = eig.eigenvectors
            * nalgebra::Matrix3::from_diagonal(&clamped)
            * eig.eigenvectors.transpose()
            * qp.weight;
        for (a, da) in qp.d1.iter().enumerate() {
            for (b, db) in qp.d1.iter().enumerate().skip(a) {
                out.add_block(qp.first + a, qp.first + b, &(h * (da * db)));
            }
        }
    }
    out
}

#[test]
fn definite_stretching_hessian_is_the_eigen_clamped_one() {
    let ea = 100.0;
    let stretch = pointwise(ea);
    for (name, rod) in splinerod_energies::conformance::test_rods().expect("test rods") {
        let mut got = BlockBanded::zeros(rod.len(), rod.basis().degree());
        stretch.add_hessian(&rod, HessianKind::Definite, &mut got);
        let (got, want) = (
            got.to_dense(),
            eigen_clamped_stretching_hessian(&rod, ea).to_dense(),
        );
        let error = (&got - &want).amax() / want.amax();
        assert!(error < 1e-12, "{name}: relative difference {error:e}");
    }
}

/// Bending reads the basis' second derivatives: a rod tabulated without them is refused
/// with an error naming why, at the step's start (not a silent zero energy).
#[test]
fn bending_refuses_a_rod_without_second_derivatives() {
    let rods = splinerod_energies::conformance::test_rods().expect("test rods");
    let (_, rod) = rods.into_iter().next().expect("a rod");
    let mut bending = Bending::new(1e-3).unwrap();
    assert!(bending.begin_step(&rod, 1e-3).is_ok());
    let lean = rod.without_second_derivatives();
    let err = bending.begin_step(&lean, 1e-3).unwrap_err().to_string();
    assert!(err.contains("second derivatives"), "{err}");
    assert!(bending.supports(&lean).is_err());
}
