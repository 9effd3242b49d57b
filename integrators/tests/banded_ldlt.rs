//! The block LDLT of an indefinite banded matrix: solves like a dense LU, finds a
//! direction of negative curvature, refuses singular pivots and far blocks.

use nalgebra::{DVector, Matrix3, Vector3};
use splinerod_core::{BlockBanded, Real};
use splinerod_integrators::banded_ldlt::BandedLdlt;

/// A banded symmetric matrix with negative directions: a spring chain with a
/// negative (compressive) transverse stiffness, plus a mass term.
fn indefinite(n: usize, bw: usize) -> BlockBanded {
    let mut a = BlockBanded::zeros(n, bw);
    for i in 0..n {
        a.add_block(i, i, &Matrix3::from_diagonal(&Vector3::new(1.0, 0.2, 0.3)));
        for j in i + 1..(i + bw + 1).min(n) {
            let k = Matrix3::from_diagonal(&Vector3::new(5.0, -0.4, 0.1 * j as Real));
            a.add_block(i, i, &k);
            a.add_block(j, j, &k);
            a.add_block(i, j, &-k);
        }
    }
    a
}

#[test]
fn solves_an_indefinite_band_like_a_dense_lu() {
    for (n, bw) in [(1, 3), (2, 1), (12, 3), (40, 5)] {
        let a = indefinite(n, bw);
        let dense = a.to_dense();
        let eig = dense.clone().symmetric_eigenvalues();
        assert!(
            n < 12 || eig.min() < 0.0,
            "the test matrix must be indefinite"
        );
        let mut f = BandedLdlt::new();
        f.factor(&a).unwrap();
        let b: Vec<Real> = (0..3 * n).map(|i| ((i * 7) % 11) as Real - 5.0).collect();
        let mut two = [b.clone(), b.clone()].concat();
        f.solve_in_place(&mut two).unwrap();
        let exact = dense.lu().solve(&DVector::from(b)).unwrap();
        for column in two.chunks(3 * n) {
            let error = (DVector::from(column.to_vec()) - &exact).norm() / exact.norm();
            assert!(error < 1e-10, "n {n}: relative error {error:e}");
        }
    }
}

#[test]
fn finds_a_direction_of_negative_curvature() {
    let a = indefinite(12, 3);
    let mut f = BandedLdlt::new();
    f.factor(&a).unwrap();
    let mut d = vec![Vector3::zeros(); 12];
    let e = f.negative_curvature(&mut d).expect("indefinite");
    let mut ad = vec![Vector3::zeros(); 12];
    a.mul_vec(&d, &mut ad);
    let curvature: Real = d.iter().zip(&ad).map(|(x, y)| x.dot(y)).sum();
    assert!(
        e < 0.0 && (curvature - e).abs() < 1e-9 * e.abs(),
        "{curvature} vs {e}"
    );
    let mut spd = BlockBanded::zeros(4, 1);
    (0..4).for_each(|i| spd.add_block(i, i, &Matrix3::identity()));
    f.factor(&spd).unwrap();
    assert!(f.negative_curvature(&mut d[..4]).is_none());
}

#[test]
fn refuses_a_singular_pivot_and_far_blocks() {
    let mut a = BlockBanded::zeros(3, 1);
    a.add_block(0, 0, &Matrix3::from_diagonal(&Vector3::new(1.0, 0.0, 1.0)));
    let mut f = BandedLdlt::new();
    assert!(f.factor(&a).is_err());
    assert!(f.solve_in_place(&mut [0.0; 9]).is_err());
    let mut far = indefinite(6, 1);
    far.add_coupling(0, 5, &Matrix3::identity());
    assert!(f.factor(&far).is_err());
}
