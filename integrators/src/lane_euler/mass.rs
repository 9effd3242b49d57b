//! The lane mass matrices' products of the batched step: \\(y = M x\\) and
//! \\(\sum_{ij} M_{ij}\, x_i \cdot y_j\\), each lane with its own upper band.

use splinerod_core::lanes::{mul_add, ZERO};
use splinerod_core::Lanes;

/// `y = M x` for the lane mass matrices (upper band `m`, bandwidth `bw`) on a field.
/// Each entry is summed in registers in the order of the row-by-row product (the band
/// walked row by row, each row's block added to its point and, mirrored, to the points
/// below): first the rows above it, then its own row from the diagonal on.
#[inline(always)]
pub(super) fn mass_times(m: &[Lanes], bw: usize, x: &[Lanes], y: &mut [Lanes]) {
    let (n, w) = (x.len() / 3, bw + 1);
    let (xs, _) = x.as_chunks::<3>();
    let (ys, rest) = y.as_chunks_mut::<3>();
    rest.fill(ZERO);
    for (j, yj) in ys.iter_mut().enumerate() {
        let mut acc = [ZERO; 3];
        if j < n {
            for (i, xi) in xs.iter().enumerate().take(j).skip(j.saturating_sub(bw)) {
                let mij = m[i * w + j - i];
                for c in 0..3 {
                    mul_add(&mut acc[c], xi[c], mij);
                }
            }
            let row = &m[j * w..(j + 1) * w];
            for (xk, mjk) in xs[j..].iter().zip(row) {
                for c in 0..3 {
                    mul_add(&mut acc[c], xk[c], *mjk);
                }
            }
        }
        *yj = acc;
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

#[cfg(test)]
mod tests {
    use super::*;
    use splinerod_core::{Real, LANES};

    /// The row-by-row product: every row's block added to its point and, mirrored, to
    /// the points below.
    fn by_rows(m: &[Lanes], bw: usize, x: &[Lanes]) -> Vec<Lanes> {
        let (n, w) = (x.len() / 3, bw + 1);
        let mut y = vec![ZERO; x.len()];
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
        y
    }

    #[test]
    fn the_product_sums_each_entry_as_the_row_by_row_product_does() {
        let value = |k: usize, l: usize| ((k * 7 + l * 3) as Real * 0.37).sin();
        for (n, bw) in [(1, 0), (5, 1), (9, 3), (16, 3), (4, 6)] {
            let m: Vec<Lanes> = (0..n * (bw + 1))
                .map(|k| std::array::from_fn(|l| value(k, l)))
                .collect();
            let x: Vec<Lanes> = (0..3 * n)
                .map(|k| std::array::from_fn(|l| value(k + 100, l) - 0.5))
                .collect();
            let mut y = vec![[1.0; LANES]; 3 * n];
            mass_times(&m, bw, &x, &mut y);
            let bits = |v: &[Lanes]| v.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&y),
                bits(&by_rows(&m, bw, &x)),
                "n {n}, bandwidth {bw}"
            );
        }
    }
}
