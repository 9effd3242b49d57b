//! The contact barrier (issue #46): a potential of the gap `g` that is zero beyond the
//! tolerance `τ` and grows without bound as the gap closes, so that a contact rests at
//! a gap inside \\((0, \tau)\\) whatever its load — no stiffness to guess for the rest
//! geometry. It is the log barrier of incremental potential contact (Li et al. 2020),
//!
//! \\[ b(g) = -\kappa\, (g - \tau)^2 \ln\frac{g}{\tau} \quad (0 < g < \tau), \qquad
//! b(g) = 0 \quad (g \ge \tau), \\]
//!
//! with \\(x = g/\tau\\) and the unit barrier \\(\tilde b(x) = -(x - 1)^2 \ln x\\):
//! \\(b = \kappa \tau^2 \tilde b\\), \\(b' = \kappa \tau \tilde b'\\),
//! \\(b'' = \kappa \tilde b''\\), where
//!
//! \\[ \tilde b'(x) = -2 (x - 1) \ln x - \frac{(x - 1)^2}{x}, \qquad
//! \tilde b''(x) = -2 \ln x - \frac{4 (x - 1)}{x} + \frac{(x - 1)^2}{x^2}. \\]
//!
//! All three vanish at \\(x = 1\\) (the barrier is \\(C^2\\) where it starts), it is
//! convex and non-increasing on \\((0, 1)\\), and near contact \\(-b' \approx \kappa
//! \tau^2 / g\\): a load `F` rests at the gap \\(g \approx \kappa \tau^2 / F\\) — any
//! load finds a gap inside the tolerance, a heavier one a smaller gap.
//!
//! **Below** \\(x_c = \\)[`EXTENSION`] the barrier continues as its second-order Taylor
//! polynomial at \\(x_c\\) (a stiff quadratic penalty, still \\(C^2\\)), so the energy
//! is finite at every state a Newton step may try — an overlapping start, a trial step
//! past a strand — and Newton's line search needs no special domain. A contact reaches
//! it only under a load about \\(1/x_c\\) times the one that rests at \\(\tau / 2\\)
//! (see [`super::stiffness`] for how `κ` is chosen and raised before a contact gets
//! there).
//!
//! **Units.** `κ` is in N/m like the penalty stiffness: `b` takes the place of the
//! penalty \\(\phi\\) in every contact term with the same weights (a sample pair's
//! \\(w_a w_b/(r_a + r_b)^2\\), a surface point's \\(w/(2r)\\)).

use splinerod_core::Real;

/// Where the barrier turns into its quadratic continuation, as a fraction of the
/// tolerance (`x_c`, module docs).
pub const EXTENSION: Real = 1e-2;

/// \\(-\tilde b'(1/2) = \ln 2 + 1/2\\): the unit barrier's force at half the tolerance.
/// A contact carrying `F` rests at half the tolerance when \\(\kappa \tau\\) times this
/// equals `F`.
pub const HALF_TOLERANCE_FORCE: Real = std::f64::consts::LN_2 + 0.5;

/// The unit barrier \\(\tilde b\\) and its first two derivatives at `x` in
/// \\([x_c, 1)\\) (module docs).
fn unit(x: Real) -> [Real; 3] {
    let (ln, y) = (x.ln(), x - 1.0);
    [
        -y * y * ln,
        -2.0 * y * ln - y * y / x,
        -2.0 * ln - 4.0 * y / x + y * y / (x * x),
    ]
}

/// The unit barrier and its first two derivatives at any `x`: zero from 1 on, the
/// barrier on \\([x_c, 1)\\), its Taylor polynomial at \\(x_c\\) below.
fn unit_extended(x: Real) -> [Real; 3] {
    if x >= 1.0 {
        return [0.0; 3];
    }
    if x >= EXTENSION {
        return unit(x);
    }
    let [b, b1, b2] = unit(EXTENSION);
    let h = x - EXTENSION;
    [b + h * (b1 + 0.5 * h * b2), b1 + h * b2, b2]
}

/// The unit barrier's slope \\(\tilde b'(x)\\) at any `x` (its continuation below
/// \\(x_c\\)): the force of a contact at the gap `x τ` is `κ τ` times its negative.
pub(crate) fn unit_slope(x: Real) -> Real {
    unit_extended(x)[1]
}

/// The barrier of stiffness `kappa` (N/m) and tolerance `tau` (m) at the gap `g` (m):
/// \\([b, b', b'']\\) in J, N and N/m.
pub(crate) fn barrier(kappa: Real, tau: Real, g: Real) -> [Real; 3] {
    let [b, b1, b2] = unit_extended(g / tau);
    [kappa * tau * tau * b, kappa * tau * b1, kappa * b2]
}

#[cfg(test)]
mod tests {
    use super::{barrier, unit, EXTENSION, HALF_TOLERANCE_FORCE};

    #[test]
    fn derivatives_match_finite_differences_and_join_smoothly() {
        let (kappa, tau) = (3e2, 2e-4);
        let h = 1e-11;
        for x in [-0.5, 1e-3, 0.5 * EXTENSION, 0.02, 0.1, 0.5, 0.9, 0.999, 1.2] {
            let g = x * tau;
            let [_, s, c] = barrier(kappa, tau, g);
            let [lo, slo, _] = barrier(kappa, tau, g - h);
            let [hi, shi, _] = barrier(kappa, tau, g + h);
            let (ds, dc) = ((hi - lo) / (2.0 * h), (shi - slo) / (2.0 * h));
            assert!((ds - s).abs() <= 1e-5 * (1.0 + s.abs()), "x {x}: {ds} {s}");
            assert!((dc - c).abs() <= 1e-4 * (1.0 + c.abs()), "x {x}: {dc} {c}");
        }
        // C² at the tolerance and at the continuation.
        assert_eq!(barrier(kappa, tau, tau), [0.0; 3]);
        let below = barrier(kappa, tau, tau * (1.0 - 1e-9));
        assert!(below.iter().all(|v| v.abs() < 1e-6 * kappa));
        let [a, b] = [EXTENSION * (1.0 - 1e-12), EXTENSION * (1.0 + 1e-12)];
        let (l, r) = (barrier(kappa, tau, a * tau), barrier(kappa, tau, b * tau));
        for k in 0..3 {
            assert!((l[k] - r[k]).abs() <= 1e-8 * l[k].abs(), "{k}: {l:?} {r:?}");
        }
    }

    #[test]
    fn convex_and_pushing_everywhere_inside_the_tolerance() {
        let mut last = f64::NEG_INFINITY;
        for k in 0..1000 {
            let x = -0.5 + 1.5 * k as f64 / 1000.0;
            let [_, s, c] = barrier(1.0, 1.0, x);
            assert!(s <= 0.0 && c >= 0.0, "x {x}");
            assert!(s >= last, "the force must fall as the gap opens, x {x}");
            last = s;
        }
        let [_, s, _] = unit(0.5);
        assert!((-s - HALF_TOLERANCE_FORCE).abs() < 1e-15);
    }
}
