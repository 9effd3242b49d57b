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

/// An SPD band of `n` blocks and bandwidth `bw`: `Bᵀ B + I` for a random band `B`,
/// stored as the upper band (the layout [`factor_blocks`] takes).
fn spd_band(n: usize, bw: usize) -> Vec<Matrix3<Real>> {
    let w = bw + 1;
    let mut full = nalgebra::DMatrix::<Real>::identity(3 * n, 3 * n);
    let b = nalgebra::DMatrix::from_fn(3 * n, 3 * n, |r, c| {
        let near = (r / 3).abs_diff(c / 3) <= bw / 2;
        if near {
            ((r * 31 + c * 17) as Real * 0.37).sin()
        } else {
            0.0
        }
    });
    full += b.transpose() * b;
    let mut u = vec![Matrix3::zeros(); n * w];
    for i in 0..n {
        for k in 0..w.min(n - i) {
            u[i * w + k] = full.fixed_view::<3, 3>(3 * i, 3 * (i + k)).into();
        }
    }
    u
}

#[test]
fn the_fused_and_the_plain_kernels_solve_alike_to_round_off() {
    for (n, bw) in [(1, 0), (2, 1), (7, 3), (16, 5), (23, 5), (30, 2)] {
        fused_and_plain_solve(n, bw);
    }
}

/// The plain factor solves `A x = b` for an SPD band of `n` blocks and bandwidth `bw`,
/// and the fused one (where the processor has FMA) gives the same `x` to round-off.
fn fused_and_plain_solve(n: usize, bw: usize) {
    let a = spd_band(n, bw);
    let rhs: Vec<Real> = (0..3 * n).map(|k| (k as Real * 0.71).cos()).collect();
    let solve = |fused: bool| {
        let (mut u, mut x) = (a.clone(), rhs.clone());
        if fused {
            // SAFETY: only called where the processor has AVX2 and FMA.
            #[cfg(target_arch = "x86_64")]
            unsafe {
                rows::factor_rows(&mut u, n, bw).expect("definite");
                solve_blocks_wide(&u, n, bw, &mut x);
            }
        } else {
            factor_blocks_with::<false>(&mut u, n, bw).expect("definite");
            solve_blocks_with::<false, false>(&u, n, bw, &mut x);
        }
        x
    };
    let plain = solve(false);
    // A x = b, through the band (upper blocks and their transposes).
    let w = bw + 1;
    let mut residual = rhs.clone();
    for i in 0..n {
        for k in 0..w.min(n - i) {
            let block = a[i * w + k];
            let (xi, xj) = (get3(&plain, i), get3(&plain, i + k));
            let ri = get3(&residual, i) - block * xj;
            set3(&mut residual, i, ri);
            if k > 0 {
                let rj = get3(&residual, i + k) - block.tr_mul(&xi);
                set3(&mut residual, i + k, rj);
            }
        }
    }
    let scale = plain.iter().fold(0.0, |m: Real, x| m.max(x.abs()));
    let worst = residual.iter().fold(0.0, |m: Real, r| m.max(r.abs()));
    assert!(
        worst <= 1e-12 * scale.max(1.0),
        "n {n}, bw {bw}: residual {worst:e}"
    );
    #[cfg(target_arch = "x86_64")]
    if splinerod_core::lanes::wide() {
        let fused = solve(true);
        let gap = plain
            .iter()
            .zip(&fused)
            .fold(0.0, |m: Real, (p, f)| m.max((p - f).abs()));
        assert!(gap <= 1e-12 * scale, "n {n}, bw {bw}: gap {gap:e}");
        assert_ne!(plain, fused, "the fused kernels round differently");
    }
}

#[test]
#[cfg(target_arch = "x86_64")]
fn the_row_form_factor_is_the_column_form_fused_one_bit_for_bit() {
    if !splinerod_core::lanes::wide() {
        return;
    }
    for (n, bw) in [(1, 0), (2, 1), (7, 3), (16, 3), (16, 5), (23, 5), (30, 2)] {
        let mut a = spd_band(n, bw);
        // Assembly can leave a diagonal block asymmetric by round-off: both read its
        // lower triangle.
        for i in 0..n {
            a[i * (bw + 1)][(0, 1)] *= 1.0 + 1e-9;
            a[i * (bw + 1)][(1, 2)] *= 1.0 - 1e-9;
        }
        let (mut rows, mut columns) = (a.clone(), a.clone());
        let rhs: Vec<Real> = (0..3 * n).map(|k| (k as Real * 0.53).sin()).collect();
        let (mut x_rows, mut x_columns) = (rhs.clone(), rhs);
        // SAFETY: the processor has AVX2 and FMA (checked above).
        unsafe {
            rows::factor_rows(&mut rows, n, bw).expect("definite");
            factor_blocks_wide(&mut columns, n, bw).expect("definite");
            solve_blocks_wide(&rows, n, bw, &mut x_rows);
        }
        solve_blocks_with::<true, false>(&columns, n, bw, &mut x_columns);
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
    }
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
