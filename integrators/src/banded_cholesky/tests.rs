//! Tests of the banded Cholesky factorisation and its block kernels.
use super::kernels::*;
use super::*;

/// Pseudo-random 3×3 blocks: `k`-th of a fixed sequence.
fn block(k: usize) -> Matrix3<Real> {
    Matrix3::from_fn(|r, c| ((k * 9 + 3 * c + r) as Real * 0.731 + 0.2).sin() * 3.7)
}

#[test]
fn the_written_out_block_arithmetic_is_nalgebras_bit_for_bit() {
    let bits = |e: &[Real]| e.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
    for k in 0..200 {
        let (a, b, s) = (block(3 * k), block(3 * k + 1), block(3 * k + 2));
        let mut ours = entries(&s);
        sub_transposed_times::<false>(&mut ours, &entries(&a), &entries(&b));
        assert_eq!(bits(&ours), bits((s - a.tr_mul(&b)).as_slice()));
        let mut gram = entries(&s);
        sub_gram_lower::<false>(&mut gram, &entries(&a));
        let full = s - a.tr_mul(&a);
        for (c, r) in [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)] {
            assert_eq!(gram[3 * c + r].to_bits(), full[(r, c)].to_bits());
        }
        // Lower triangular factors: the same values (a zero's sign aside).
        let l = a.lower_triangle();
        assert_eq!(
            lower_times::<false>(&entries(&l), &entries(&b)),
            entries(&(l * b))
        );
        let v = b.column(0);
        let (lv, ltv) = (l * v, l.tr_mul(&v));
        let (le, v) = (entries(&l), [v.x, v.y, v.z]);
        assert_eq!(lower_product::<false>(&le, v), [lv.x, lv.y, lv.z]);
        assert_eq!(
            lower_transposed_product::<false>(&le, v),
            [ltv.x, ltv.y, ltv.z]
        );
    }
}

/// A symmetric block with eigenvalues `1, 10^(p/2), 10^p` in a rotated frame (`k`-th).
fn conditioned(k: usize, p: Real) -> Matrix3<Real> {
    let axis = Vector3::new(1.0 + k as Real, (k as Real * 0.37).sin(), 0.3).normalize();
    let r =
        nalgebra::Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(axis), 0.1 + k as Real);
    let d = Matrix3::from_diagonal(&Vector3::new(
        1.0,
        (10.0 as Real).powf(0.5 * p),
        (10.0 as Real).powf(p),
    ));
    r.matrix() * d * r.matrix().transpose()
}

#[test]
fn the_inverse_factor_is_the_column_by_column_choleskys_to_round_off() {
    // Well conditioned: entry by entry against nalgebra's factor, inverted.
    for k in 0..200 {
        let a = block(3 * k);
        let spd = a.tr_mul(&a) + Matrix3::identity() * (0.1 + 0.1 * k as Real);
        let expected = spd
            .cholesky()
            .expect("definite")
            .l()
            .try_inverse()
            .expect("inverse");
        let ours = Matrix3::from_column_slice(&inverse_cholesky(&entries(&spd)).expect("definite"));
        let scale = expected.amax();
        assert!((ours - expected).amax() <= 1e-13 * scale, "block {k}");
        assert_eq!(ours[(0, 1)], 0.0);
    }
    // Ill conditioned (up to 1e12): the factor it implies reproduces the block with
    // a backward error within 10× the column-by-column Cholesky's and below 1e-14.
    for p in [4.0, 8.0, 12.0] {
        for k in 0..50 {
            let s = conditioned(k, p);
            let backward = |linv: Matrix3<Real>| {
                let l = linv.try_inverse().expect("inverse");
                (l * l.transpose() - s).amax() / s.amax()
            };
            let ours =
                Matrix3::from_column_slice(&inverse_cholesky(&entries(&s)).expect("definite"));
            let theirs = s
                .cholesky()
                .expect("definite")
                .l()
                .try_inverse()
                .expect("inverse");
            let (ours, theirs) = (backward(ours), backward(theirs));
            assert!(
                ours <= 1e-14 && ours <= 10.0 * theirs.max(Real::EPSILON),
                "p {p} block {k}: {ours:e} against {theirs:e}"
            );
        }
    }
}

/// The fused factor by rows is the fused one by columns bit for bit, transposed, on
/// every shape of the table of Cholesky variants (where both agree with the dense
/// oracle: `crate::cholesky_variants`); and the fused kernels do round differently from
/// the plain ones.
#[test]
#[cfg(target_arch = "x86_64")]
fn the_row_form_factor_is_the_column_form_fused_one_bit_for_bit() {
    if !Instance::FusedRows.available() {
        return;
    }
    let mut rounded_differently = false;
    for shape in crate::cholesky_variants::SHAPES {
        let (n, bw) = (shape.n, shape.bw);
        let mut a = shape.matrix(0).band_blocks().to_vec();
        // Assembly can leave a diagonal block asymmetric by round-off: both read its
        // lower triangle.
        for i in 0..n {
            a[i * (bw + 1)][(0, 1)] *= 1.0 + 1e-9;
            a[i * (bw + 1)][(1, 2)] *= 1.0 - 1e-9;
        }
        let (mut rows, mut columns, mut plain) = (a.clone(), a.clone(), a);
        let rhs = shape.rhs(0);
        let (mut x_rows, mut x_columns, mut x_plain) = (rhs.clone(), rhs.clone(), rhs);
        let solve = |kernel: Instance, u: &mut [Matrix3<Real>], x: &mut [Real]| {
            kernel.factor_and_solve(u, n, bw, x).expect("definite");
        };
        solve(Instance::FusedRows, &mut rows, &mut x_rows);
        solve(Instance::FusedColumns, &mut columns, &mut x_columns);
        solve(Instance::Plain, &mut plain, &mut x_plain);
        let w = bw + 1;
        for i in 0..n {
            for k in 0..w.min(n - i) {
                let (r, c) = (rows[i * w + k], columns[i * w + k]);
                // Off-diagonal blocks transposed; the diagonal slots alike.
                let r = if k == 0 { r } else { r.transpose() };
                let bits = |m: Matrix3<Real>| m.map(|x| x.to_bits());
                assert_eq!(bits(r), bits(c), "n {n}, bw {bw}, block ({i}, {})", i + k);
            }
        }
        let bits = |x: &[Real]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&x_rows), bits(&x_columns), "n {n}, bw {bw}");
        rounded_differently |= bits(&x_rows) != bits(&x_plain);
    }
    assert!(rounded_differently, "the fused kernels round differently");
}

#[test]
fn indefinite_and_zero_pivots_are_refused() {
    let mut s = entries(&Matrix3::identity());
    s[4] = -1.0;
    assert!(inverse_cholesky(&s).is_none());
    s[4] = 0.0;
    assert!(inverse_cholesky(&s).is_none());
    s[4] = Real::NAN;
    assert!(inverse_cholesky(&s).is_none());
}
