//! The lane mass matrices' products of the batched step: \\(y = M x\\) and
//! \\(\sum_{ij} M_{ij}\, x_i \cdot y_j\\), each lane with its own upper band.

use splinerod_core::lanes::{mul_add, ZERO};
use splinerod_core::Lanes;

/// `y = M x` for the lane mass matrices (upper band `m`, bandwidth `bw`) on a field.
#[inline(always)]
pub(super) fn mass_times(m: &[Lanes], bw: usize, x: &[Lanes], y: &mut [Lanes]) {
    let (n, w) = (x.len() / 3, bw + 1);
    y.fill(ZERO);
    for i in 0..n {
        let row = &m[i * w..(i + 1) * w];
        for c in 0..3 {
            mul_add(&mut y[3 * i + c], x[3 * i + c], row[0]);
        }
        for k in 1..w.min(n - i) {
            for c in 0..3 {
                mul_add(&mut y[3 * i + c], x[3 * (i + k) + c], row[k]);
                mul_add(&mut y[3 * (i + k) + c], x[3 * i + c], row[k]);
            }
        }
    }
}

/// \\(\sum_{ij} M_{ij}\, x_i \cdot y_j\\) per lane.
#[inline(always)]
pub(super) fn mass_bilinear(m: &[Lanes], bw: usize, x: &[Lanes], y: &[Lanes]) -> Lanes {
    let (n, w) = (x.len() / 3, bw + 1);
    let mut sum = ZERO;
    let dot = |i: usize, j: usize| -> Lanes {
        let mut d = ZERO;
        for c in 0..3 {
            mul_add(&mut d, x[3 * i + c], y[3 * j + c]);
        }
        d
    };
    for i in 0..n {
        let row = &m[i * w..(i + 1) * w];
        mul_add(&mut sum, row[0], dot(i, i));
        for k in 1..w.min(n - i) {
            let both = splinerod_core::lanes::add(dot(i, i + k), dot(i + k, i));
            mul_add(&mut sum, row[k], both);
        }
    }
    sum
}
