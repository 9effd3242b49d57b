//! Cholesky factorisation \\(A = U^T U\\) of a symmetric positive definite 3×3-block
//! banded matrix ([`BlockBanded`]) in its own storage layout: `U` is upper block-banded
//! with the same bandwidth (no fill-in), computed block by block with fixed-size 3×3
//! arithmetic,
//!
//! \\[ U_{ii}^T U_{ii} = A_{ii} - \sum_{k<i} U_{ki}^T U_{ki}, \qquad
//! U_{ij} = U_{ii}^{-T}\Big(A_{ij} - \sum_{k<i} U_{ki}^T U_{kj}\Big)\ (i < j \le i + b), \\]
//!
//! then solved by \\(U^T y = r\\), \\(U x = y\\). No symbolic phase and no indirection:
//! O(n b²) flops, all on contiguous blocks. An alternative to the general sparse
//! Cholesky for the banded Newton matrices of a single rod; a matrix with far blocks
//! (self-contact) is refused with an error, since they would fill in the band's gaps:
//! [`crate::linear::LinearSolver`] sends those to the sparse path.

use crate::IntegratorError;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, Real};

/// The factor `U` of a block-banded SPD matrix.
#[derive(Debug, Clone, Default)]
pub struct BandedCholesky {
    n: usize,
    bw: usize,
    /// `U_{i,i+k}` at `i·(bw+1) + k`, `k ≥ 1`; the diagonal slots hold \\(U_{ii}^{-T}\\)
    /// (lower triangular), so that both the factorisation's off-diagonal blocks and the
    /// solves multiply instead of dividing.
    u: Vec<Matrix3<Real>>,
    factored: bool,
}

fn not_definite() -> IntegratorError {
    IntegratorError::NotPositiveDefinite {
        context: "banded Cholesky",
    }
}

/// `(n, bandwidth)` of `a`; an error if it has far blocks, which a band cannot hold
/// (the sparse path takes those).
pub(crate) fn band_shape(a: &BlockBanded) -> Result<(usize, usize), IntegratorError> {
    if a.has_far_blocks() {
        return Err(IntegratorError::SolverState(
            "a banded factorisation cannot hold far blocks (use the sparse path)",
        ));
    }
    Ok((a.dim(), a.bandwidth()))
}

/// Empties `blocks` and refills it with `len` zero blocks (no allocation once sized).
pub(crate) fn reset_blocks(blocks: &mut Vec<Matrix3<Real>>, len: usize) {
    blocks.clear();
    blocks.resize(len, Matrix3::zeros());
}

/// Runs `solve` on each right-hand side of `rhs` (columns of `3n` values), after
/// checking that a factorisation of an `n`-block matrix is in place.
pub(crate) fn for_each_rhs(
    factored: bool,
    n: usize,
    rhs: &mut [Real],
    solve: impl Fn(&mut [Real]),
) -> Result<(), IntegratorError> {
    let dofs = 3 * n;
    if !factored || dofs == 0 || rhs.len() % dofs != 0 {
        return Err(IntegratorError::SolverState(
            "solve before a successful factor",
        ));
    }
    rhs.chunks_exact_mut(dofs).for_each(solve);
    Ok(())
}

/// A 3×3 block's entries, column-major: `(r, c)` at `3c + r` (the storage of
/// [`Matrix3`]).
type Entries = [Real; 9];

/// The entries of `m`.
#[inline(always)]
pub(crate) fn entries(m: &Matrix3<Real>) -> Entries {
    let s = m.as_slice();
    std::array::from_fn(|e| s[e])
}

/// The arithmetic [`inverse_factor`] needs, for one value ([`Real`]) or for every lane
/// at once ([`splinerod_core::Lanes`]).
pub(crate) trait PivotArith: Copy {
    /// `self · b`.
    fn mul(self, b: Self) -> Self;
    /// `self + b`.
    fn add(self, b: Self) -> Self;
    /// `self − b`.
    fn sub(self, b: Self) -> Self;
    /// `self / b`.
    fn div(self, b: Self) -> Self;
    /// \(\sqrt{\text{self}}\).
    fn sqrt(self) -> Self;
    /// `−self`.
    fn neg(self) -> Self;
    /// 1.
    fn one() -> Self;
}

impl PivotArith for Real {
    #[inline(always)]
    fn mul(self, b: Self) -> Self {
        self * b
    }
    #[inline(always)]
    fn add(self, b: Self) -> Self {
        self + b
    }
    #[inline(always)]
    fn sub(self, b: Self) -> Self {
        self - b
    }
    #[inline(always)]
    fn div(self, b: Self) -> Self {
        self / b
    }
    #[inline(always)]
    fn sqrt(self) -> Self {
        Real::sqrt(self)
    }
    #[inline(always)]
    fn neg(self) -> Self {
        -self
    }
    #[inline(always)]
    fn one() -> Self {
        1.0
    }
}

/// \(L^{-1}\) of the Cholesky factor \(L L^T = s\) of a symmetric 3×3 block given
/// by its lower entries `[s00, s10, s20, s11, s21, s22]`, as
/// `[i00, i10, i20, i11, i21, i22]`, with the leading minors
/// `[s00, d2, s00 · det s]`: `s` is positive definite exactly when all three are
/// positive (the inverse is meaningless otherwise; the caller checks).
///
/// With \(d_2 = s_{00}s_{11} - s_{10}^2\), \(e = s_{00}s_{22} - s_{20}^2\),
/// \(c = s_{00}s_{21} - s_{10}s_{20}\) and \(d_3 = d_2 e - c^2 = s_{00} \det s\):
///
/// \[ L^{-1}_{00} = s_{00}^{-1/2}, \quad L^{-1}_{11} = \sqrt{s_{00}/d_2}, \quad
///     L^{-1}_{22} = \sqrt{s_{00} d_2 / d_3}, \quad
///     L_{21} = \frac{c}{s_{00}} L^{-1}_{11}, \]
///
/// so the three square roots and divisions are independent of each other instead of
/// each waiting on the one before, as in the column-by-column Cholesky (the
/// factorisation's critical path runs through every diagonal block). The rounding
/// differs from the column-by-column Cholesky's, with the same order of error (tested
/// against it).
#[inline(always)]
pub(crate) fn inverse_factor<T: PivotArith>(lower: [T; 6]) -> ([T; 6], [T; 3]) {
    let [s00, s10, s20, s11, s21, s22] = lower;
    let d2 = s00.mul(s11).sub(s10.mul(s10));
    let e = s00.mul(s22).sub(s20.mul(s20));
    let c = s00.mul(s21).sub(s10.mul(s20));
    let d3 = d2.mul(e).sub(c.mul(c));
    let i00 = T::one().div(s00.sqrt());
    let i11 = s00.div(d2).sqrt();
    let i22 = s00.mul(d2).div(d3).sqrt();
    let l21 = c.mul(i00.mul(i00)).mul(i11);
    let i10 = s10.mul(i00).mul(i00).mul(i11).neg();
    let i21 = l21.mul(i11).mul(i22).neg();
    let i20 = s20.mul(i00).mul(i00).add(l21.mul(i10)).mul(i22).neg();
    ([i00, i10, i20, i11, i21, i22], [s00, d2, d3])
}

/// [`inverse_factor`] of the column-major block `s` as a column-major block, or `None`
/// if `s` is not positive definite (a leading minor not positive) or the inverse not
/// finite.
#[inline(always)]
pub(crate) fn inverse_cholesky(s: &Entries) -> Option<Entries> {
    let ([i00, i10, i20, i11, i21, i22], minors) =
        inverse_factor([s[0], s[1], s[2], s[4], s[5], s[8]]);
    let inverse = [i00, i10, i20, 0.0, i11, i21, 0.0, 0.0, i22];
    let definite = minors.iter().all(|&m| m > 0.0);
    (definite && inverse.iter().all(|x| x.is_finite())).then_some(inverse)
}

/// `s − (a₀b₀ + a₁b₁ + a₂b₂)`: with `FUSED` three fused multiply-subtracts (one
/// instruction each on processors with FMA), else as written (nalgebra's order,
/// \((a_0 b_0 + a_1 b_1) + a_2 b_2\), then subtracted).
#[inline(always)]
fn sub_dot<const FUSED: bool>(s: Real, a: [Real; 3], b: [Real; 3]) -> Real {
    if FUSED {
        (-a[2]).mul_add(b[2], (-a[1]).mul_add(b[1], (-a[0]).mul_add(b[0], s)))
    } else {
        s - (a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
    }
}

/// `a₀b₀ + … + a_k b_k` for the first `k + 1 ≤ 3` terms (fused with `FUSED`).
#[inline(always)]
fn dot<const FUSED: bool>(a: [Real; 3], b: [Real; 3], terms: usize) -> Real {
    let mut sum = a[0] * b[0];
    for t in 1..terms {
        sum = if FUSED {
            a[t].mul_add(b[t], sum)
        } else {
            sum + a[t] * b[t]
        };
    }
    sum
}

/// Column `c` of a column-major 3×3 block.
#[inline(always)]
fn column(m: &Entries, c: usize) -> [Real; 3] {
    [m[3 * c], m[3 * c + 1], m[3 * c + 2]]
}

/// `s −= aᵀ b` for 3×3 blocks: each entry of the product a dot product of two columns
/// ([`sub_dot`]).
#[inline(always)]
fn sub_transposed_times<const FUSED: bool>(s: &mut Entries, a: &Entries, b: &Entries) {
    for c in 0..3 {
        for r in 0..3 {
            s[3 * c + r] = sub_dot::<FUSED>(s[3 * c + r], column(a, r), column(b, c));
        }
    }
}

/// The lower entries (`r ≥ c`) of `s −= aᵀ a`, in the order of [`sub_transposed_times`]:
/// the diagonal block's update is symmetric, and [`inverse_cholesky`] reads only them.
#[inline(always)]
fn sub_gram_lower<const FUSED: bool>(s: &mut Entries, a: &Entries) {
    for c in 0..3 {
        for r in c..3 {
            s[3 * c + r] = sub_dot::<FUSED>(s[3 * c + r], column(a, r), column(a, c));
        }
    }
}

/// `l m` for a lower triangular `l`: without the products by `l`'s zeros, the other
/// terms in nalgebra's order (row `r` sums \(l_{rt} m_{tc}\) for `t ≤ r`).
#[inline(always)]
fn lower_times<const FUSED: bool>(l: &Entries, m: &Entries) -> Entries {
    let mut out = [0.0; 9];
    for c in 0..3 {
        let mc = column(m, c);
        for r in 0..3 {
            out[3 * c + r] = dot::<FUSED>([l[r], l[3 + r], l[6 + r]], mc, r + 1);
        }
    }
    out
}

impl BandedCholesky {
    /// An empty factor.
    pub fn new() -> Self {
        Self::default()
    }

    /// Factorises `a` (reusing the storage when the size allows). Errors with
    /// [`IntegratorError::SolverState`] if `a` has far blocks, which a band cannot hold.
    pub fn factor(&mut self, a: &BlockBanded) -> Result<(), IntegratorError> {
        self.factored = false;
        let (n, bw) = band_shape(a)?;
        (self.n, self.bw) = (n, bw);
        self.u.clear();
        self.u.extend_from_slice(a.band_blocks());
        factor_blocks(&mut self.u, n, bw)?;
        self.factored = true;
        Ok(())
    }

    /// Solves `A x = b` in place for `k = rhs.len() / (3n)` right-hand sides stored
    /// column after column (3 coordinates per control point).
    pub fn solve_in_place(&self, rhs: &mut [Real]) -> Result<(), IntegratorError> {
        for_each_rhs(self.factored, self.n, rhs, |column| self.solve_one(column))
    }

    fn solve_one(&self, x: &mut [Real]) {
        solve_blocks(&self.u, self.n, self.bw, x);
    }
}

/// Factorises a band in place: on entry `u[i·(bw+1) + k]` holds \\(A_{i,i+k}\\) (the
/// layout of [`BlockBanded`]'s band), on exit \\(U_{i,i+k}\\), with the diagonal slots
/// holding \\(U_{ii}^{-T}\\). Each block of `A` is read before its slot is written, and
/// only rows already final are read besides. On processors with AVX2 and FMA the
/// products are fused (one rounding each; the same algorithm).
pub(crate) fn factor_blocks(
    u: &mut [Matrix3<Real>],
    n: usize,
    bw: usize,
) -> Result<(), IntegratorError> {
    #[cfg(target_arch = "x86_64")]
    if splinerod_core::lanes::wide() {
        // SAFETY: the processor has AVX2 and FMA (checked on the line above).
        return unsafe { factor_blocks_wide(u, n, bw) };
    }
    factor_blocks_with::<false>(u, n, bw)
}

/// [`factor_blocks_with`] fused, compiled for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn factor_blocks_wide(
    u: &mut [Matrix3<Real>],
    n: usize,
    bw: usize,
) -> Result<(), IntegratorError> {
    factor_blocks_with::<true>(u, n, bw)
}

/// [`factor_blocks`], its products fused with `FUSED`.
#[inline(always)]
fn factor_blocks_with<const FUSED: bool>(
    u: &mut [Matrix3<Real>],
    n: usize,
    bw: usize,
) -> Result<(), IntegratorError> {
    let w = bw + 1;
    for i in 0..n {
        // Rows above are final (read only); row i is being written.
        let (done, rest) = u.split_at_mut(i * w);
        let len = w.min(rest.len());
        let row = &mut rest[..len];
        // Diagonal block.
        let mut s = entries(&row[0]);
        for k in i.saturating_sub(bw)..i {
            sub_gram_lower::<FUSED>(&mut s, &entries(&done[k * w + (i - k)]));
        }
        let linv = inverse_cholesky(&s).ok_or_else(not_definite)?;
        row[0] = Matrix3::from_column_slice(&linv);
        // Off-diagonal blocks of row i.
        for j in i + 1..(i + w).min(n) {
            let mut m = entries(&row[j - i]);
            for k in j.saturating_sub(bw)..i {
                let a = entries(&done[k * w + (i - k)]);
                sub_transposed_times::<FUSED>(&mut m, &a, &entries(&done[k * w + (j - k)]));
            }
            // U_ij = L⁻¹ m with L = U_iiᵀ lower triangular.
            row[j - i] = Matrix3::from_column_slice(&lower_times::<FUSED>(&linv, &m));
        }
    }
    Ok(())
}

/// The 3-vector of control point `i` in a flat array of coordinates.
#[inline]
pub(crate) fn get3(x: &[Real], i: usize) -> Vector3<Real> {
    Vector3::new(x[3 * i], x[3 * i + 1], x[3 * i + 2])
}

/// Writes the 3-vector of control point `i` into a flat array of coordinates.
#[inline]
pub(crate) fn set3(x: &mut [Real], i: usize, v: Vector3<Real>) {
    x[3 * i..3 * i + 3].copy_from_slice(v.as_slice());
}

/// Solves `A x = b` in place for one right-hand side with the factor of
/// [`factor_blocks`]. The 3×3 products are written out on the column-major storage
/// (measured: half the instructions of nalgebra's generic products here), and fused on
/// processors with AVX2 and FMA, as in [`factor_blocks`].
pub(crate) fn solve_blocks(u: &[Matrix3<Real>], n: usize, bw: usize, x: &mut [Real]) {
    #[cfg(target_arch = "x86_64")]
    if splinerod_core::lanes::wide() {
        // SAFETY: the processor has AVX2 and FMA (checked on the line above).
        return unsafe { solve_blocks_wide(u, n, bw, x) };
    }
    solve_blocks_with::<false>(u, n, bw, x)
}

/// [`solve_blocks_with`] fused, compiled for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
unsafe fn solve_blocks_wide(u: &[Matrix3<Real>], n: usize, bw: usize, x: &mut [Real]) {
    solve_blocks_with::<true>(u, n, bw, x)
}

/// [`solve_blocks`], its products fused with `FUSED`.
#[inline(always)]
fn solve_blocks_with<const FUSED: bool>(u: &[Matrix3<Real>], n: usize, bw: usize, x: &mut [Real]) {
    let w = bw + 1;
    // Uᵀ y = b: y_i = U_iiᵀ⁻¹ (b_i − Σ_{k<i} U_kiᵀ y_k).
    for i in 0..n {
        let (done, rest) = x.split_at_mut(3 * i);
        let mut r = [rest[0], rest[1], rest[2]];
        let lo = i.saturating_sub(bw);
        for (k, y) in (lo..i).zip(done[3 * lo..].chunks_exact(3)) {
            let m = entries(&u[k * w + (i - k)]);
            let y = [y[0], y[1], y[2]];
            for (c, r) in r.iter_mut().enumerate() {
                *r = sub_dot::<FUSED>(*r, column(&m, c), y);
            }
        }
        rest[..3].copy_from_slice(&lower_product::<FUSED>(&entries(&u[i * w]), r));
    }
    // U x = y: x_i = U_ii⁻¹ (y_i − Σ_{j>i} U_ij x_j).
    for i in (0..n).rev() {
        let (head, later) = x.split_at_mut(3 * i + 3);
        let own = &mut head[3 * i..];
        let mut r = [own[0], own[1], own[2]];
        let row = &u[i * w + 1..(i * w + w).min(u.len())];
        for (block, xj) in row.iter().zip(later[..3 * (n - i - 1)].chunks_exact(3)) {
            let m = entries(block);
            let xj = [xj[0], xj[1], xj[2]];
            for (c, r) in r.iter_mut().enumerate() {
                *r = sub_dot::<FUSED>(*r, [m[c], m[3 + c], m[6 + c]], xj);
            }
        }
        own.copy_from_slice(&lower_transposed_product::<FUSED>(&entries(&u[i * w]), r));
    }
}

/// `l v` for a lower triangular `l`: row `r` sums \(l_{rt} v_t\) for `t ≤ r` (no products
/// by zeros), fused with `FUSED`.
#[inline(always)]
fn lower_product<const FUSED: bool>(l: &Entries, v: [Real; 3]) -> [Real; 3] {
    std::array::from_fn(|r| dot::<FUSED>([l[r], l[3 + r], l[6 + r]], v, r + 1))
}

/// `lᵀ v` for a lower triangular `l`: row `c` sums \(l_{tc} v_t\) for `t ≥ c`, fused
/// with `FUSED`.
#[inline(always)]
fn lower_transposed_product<const FUSED: bool>(l: &Entries, v: [Real; 3]) -> [Real; 3] {
    std::array::from_fn(|c| {
        let from_c = |x: [Real; 3]| std::array::from_fn(|t| x[(c + t).min(2)]);
        dot::<FUSED>(from_c(column(l, c)), from_c(v), 3 - c)
    })
}

#[cfg(test)]
mod tests {
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
        let r = nalgebra::Rotation3::from_axis_angle(
            &nalgebra::Unit::new_normalize(axis),
            0.1 + k as Real,
        );
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
            let ours =
                Matrix3::from_column_slice(&inverse_cholesky(&entries(&spd)).expect("definite"));
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
        let (n, bw) = (23, 5);
        let a = spd_band(n, bw);
        let rhs: Vec<Real> = (0..3 * n).map(|k| (k as Real * 0.71).cos()).collect();
        let solve = |fused: bool| {
            let (mut u, mut x) = (a.clone(), rhs.clone());
            if fused {
                // SAFETY: only called where the processor has AVX2 and FMA.
                #[cfg(target_arch = "x86_64")]
                unsafe {
                    factor_blocks_wide(&mut u, n, bw).expect("definite");
                    solve_blocks_wide(&u, n, bw, &mut x);
                }
            } else {
                factor_blocks_with::<false>(&mut u, n, bw).expect("definite");
                solve_blocks_with::<false>(&u, n, bw, &mut x);
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
        assert!(residual.iter().all(|r| r.abs() <= 1e-12 * scale.max(1.0)));
        #[cfg(target_arch = "x86_64")]
        if splinerod_core::lanes::wide() {
            let fused = solve(true);
            let gap = plain
                .iter()
                .zip(&fused)
                .fold(0.0, |m: Real, (p, f)| m.max((p - f).abs()));
            assert!(gap <= 1e-12 * scale, "gap {gap:e}");
            assert_ne!(plain, fused, "the fused kernels round differently");
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
}
