//! The 3×3 block arithmetic of the banded Cholesky factorisation and its solves,
//! written out on the column-major entries, each product plain (nalgebra's order) or,
//! with `FUSED`, a fused multiply-add (one instruction on processors with FMA).

use nalgebra::Matrix3;
use splinerod_core::Real;

/// A 3×3 block's entries, column-major: `(r, c)` at `3c + r` (the storage of
/// [`Matrix3`]).
pub(crate) type Entries = [Real; 9];

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
pub(super) fn sub_dot<const FUSED: bool>(s: Real, a: [Real; 3], b: [Real; 3]) -> Real {
    if FUSED {
        (-a[2]).mul_add(b[2], (-a[1]).mul_add(b[1], (-a[0]).mul_add(b[0], s)))
    } else {
        s - (a[0] * b[0] + a[1] * b[1] + a[2] * b[2])
    }
}

/// `a₀b₀ + … + a_k b_k` for the first `k + 1 ≤ 3` terms (fused with `FUSED`).
#[inline(always)]
pub(super) fn dot<const FUSED: bool>(a: [Real; 3], b: [Real; 3], terms: usize) -> Real {
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
pub(super) fn column(m: &Entries, c: usize) -> [Real; 3] {
    [m[3 * c], m[3 * c + 1], m[3 * c + 2]]
}

/// `s −= aᵀ b` for 3×3 blocks: each entry of the product a dot product of two columns
/// ([`sub_dot`]).
#[inline(always)]
pub(super) fn sub_transposed_times<const FUSED: bool>(s: &mut Entries, a: &Entries, b: &Entries) {
    for c in 0..3 {
        for r in 0..3 {
            s[3 * c + r] = sub_dot::<FUSED>(s[3 * c + r], column(a, r), column(b, c));
        }
    }
}

/// The lower entries (`r ≥ c`) of `s −= aᵀ a`, in the order of [`sub_transposed_times`]:
/// the diagonal block's update is symmetric, and [`inverse_cholesky`] reads only them.
#[inline(always)]
pub(super) fn sub_gram_lower<const FUSED: bool>(s: &mut Entries, a: &Entries) {
    for c in 0..3 {
        for r in c..3 {
            s[3 * c + r] = sub_dot::<FUSED>(s[3 * c + r], column(a, r), column(a, c));
        }
    }
}

/// `l m` for a lower triangular `l`: without the products by `l`'s zeros, the other
/// terms in nalgebra's order (row `r` sums \(l_{rt} m_{tc}\) for `t ≤ r`).
#[inline(always)]
pub(super) fn lower_times<const FUSED: bool>(l: &Entries, m: &Entries) -> Entries {
    let mut out = [0.0; 9];
    for c in 0..3 {
        let mc = column(m, c);
        for r in 0..3 {
            out[3 * c + r] = dot::<FUSED>([l[r], l[3 + r], l[6 + r]], mc, r + 1);
        }
    }
    out
}

/// `l v` for a lower triangular `l`: row `r` sums \(l_{rt} v_t\) for `t ≤ r` (no products
/// by zeros), fused with `FUSED`.
#[inline(always)]
pub(super) fn lower_product<const FUSED: bool>(l: &Entries, v: [Real; 3]) -> [Real; 3] {
    std::array::from_fn(|r| dot::<FUSED>([l[r], l[3 + r], l[6 + r]], v, r + 1))
}

/// `lᵀ v` for a lower triangular `l`: row `c` sums \(l_{tc} v_t\) for `t ≥ c`, fused
/// with `FUSED`.
#[inline(always)]
pub(super) fn lower_transposed_product<const FUSED: bool>(l: &Entries, v: [Real; 3]) -> [Real; 3] {
    std::array::from_fn(|c| {
        let from_c = |x: [Real; 3]| std::array::from_fn(|t| x[(c + t).min(2)]);
        dot::<FUSED>(from_c(column(l, c)), from_c(v), 3 - c)
    })
}
