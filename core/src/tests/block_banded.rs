//! The block band's fused passes against the passes they fuse.

use crate::{BlockBanded, Real, SymBanded};
use nalgebra::{Matrix3, Vector3};

/// A block band of `n` points and bandwidth `bw` with entries that round differently
/// under scaling, a far block and a low-rank term.
fn band(n: usize, bw: usize) -> BlockBanded {
    let mut a = BlockBanded::zeros(n, bw);
    for i in 0..n {
        for j in i..(i + bw + 1).min(n) {
            let t = (7 * i + 3 * j) as Real;
            a.add_block(
                i,
                j,
                &Matrix3::from_fn(|r, c| (t + 0.3 * (r + 2 * c) as Real).sin()),
            );
        }
    }
    a.add_coupling(
        0,
        n - 1,
        &Matrix3::from_fn(|r, c| 0.1 + (r * c) as Real / 3.0),
    );
    let u: Vec<Vector3<Real>> = (0..n)
        .map(|i| Vector3::repeat(1.0 / (1 + i) as Real))
        .collect();
    a.add_low_rank(0.7, &u);
    a
}

#[test]
fn scaling_and_adding_the_mass_in_one_pass_equals_the_two_passes_bit_for_bit() {
    let (n, bw) = (9, 4);
    let mut m = SymBanded::zeros(n, 3);
    for i in 0..n {
        for j in i..(i + 4).min(n) {
            m.add(i, j, 1.0 / (1 + i + 2 * j) as Real);
        }
    }
    let (s, c) = (1e-3_f64.powi(2) / 3.0, |i: usize| 1.0 + 0.1 * i as Real);
    let mut two = band(n, bw);
    two.scale(s);
    two.add_row_scaled_scalar(c, &m);
    let mut one = band(n, bw);
    one.scale_and_add_row_scaled_scalar(s, c, &m);
    assert_eq!(one.band_blocks(), two.band_blocks());
    assert_eq!(one.far_blocks(), two.far_blocks());
    assert_eq!(one.low_rank(), two.low_rank());
}
