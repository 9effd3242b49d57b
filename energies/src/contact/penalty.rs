//! The contact penalty \\(\phi(g)\\) of a gap `g` (m): zero for \\(g \ge \delta\\), a
//! cubic onset on \\([0, \delta)\\) and a quadratic below zero,
//!
//! \\[ \phi(g) = \begin{cases} 0 & g \ge \delta \\\\
//! \dfrac{k\,(\delta - g)^3}{6\delta} & 0 \le g < \delta \\\\
//! \dfrac{k}{2} g^2 - \dfrac{k\delta}{2} g + \dfrac{k\delta^2}{6} & g < 0 \end{cases} \\]
//!
//! so \\(\phi'' = k(\delta - g)/\delta\\) rises continuously from 0 to `k` across the
//! onset layer and stays `k` in penetration: \\(\phi\\) is \\(C^2\\), convex and
//! non-increasing, which keeps Newton's method well behaved as contacts appear and vanish.
//! A contact pushing with force `F` settles at the gap \\(\delta - \sqrt{2\delta F/k}\\)
//! while \\(F < k\delta/2\\), i.e. before the surfaces touch.
//!
//! With `barrier` set, [`Penalty`] is instead the barrier of the `barrier` module, of
//! stiffness `k` and tolerance `delta` (the gap where it starts).

use super::barrier::barrier;
use splinerod_core::Real;

/// The penalty of stiffness `k` (N/m) and onset thickness `delta` (m), or with
/// `barrier` the barrier of stiffness `k` and tolerance `delta`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Penalty {
    pub k: Real,
    pub delta: Real,
    pub barrier: bool,
}

impl Penalty {
    /// \\(\phi(g)\\), J.
    pub fn value(&self, g: Real) -> Real {
        if self.barrier {
            return barrier(self.k, self.delta, g)[0];
        }
        let (k, d) = (self.k, self.delta);
        if g >= d {
            0.0
        } else if g >= 0.0 {
            k * (d - g).powi(3) / (6.0 * d)
        } else {
            0.5 * k * g * g - 0.5 * k * d * g + k * d * d / 6.0
        }
    }

    /// \\(\phi'(g)\\), N (non-positive: the force pushes the gap open).
    pub fn slope(&self, g: Real) -> Real {
        if self.barrier {
            return barrier(self.k, self.delta, g)[1];
        }
        let (k, d) = (self.k, self.delta);
        if g >= d {
            0.0
        } else if g >= 0.0 {
            -k * (d - g).powi(2) / (2.0 * d)
        } else {
            k * g - 0.5 * k * d
        }
    }

    /// \\(\phi''(g)\\), N/m (non-negative).
    pub fn curvature(&self, g: Real) -> Real {
        if self.barrier {
            return barrier(self.k, self.delta, g)[2];
        }
        let (k, d) = (self.k, self.delta);
        if g >= d {
            0.0
        } else if g >= 0.0 {
            k * (d - g) / d
        } else {
            k
        }
    }
}

#[cfg(test)]
mod tests {
    use super::Penalty;

    #[test]
    fn derivatives_match_finite_differences_and_join_smoothly() {
        let p = Penalty {
            k: 1e4,
            delta: 2e-4,
            barrier: false,
        };
        let h = 1e-9;
        for g in [-1e-3, -1e-4, -1e-12, 0.0, 1e-12, 5e-5, 1.9e-4, 2e-4, 3e-4] {
            let dv = (p.value(g + h) - p.value(g - h)) / (2.0 * h);
            let ds = (p.slope(g + h) - p.slope(g - h)) / (2.0 * h);
            assert!(
                (dv - p.slope(g)).abs() <= 1e-6 * (1.0 + p.slope(g).abs()),
                "{g}"
            );
            assert!((ds - p.curvature(g)).abs() <= 1e-3 * p.k, "{g}");
        }
        assert!(p.value(2e-4) == 0.0 && p.slope(2e-4) == 0.0 && p.curvature(2e-4) == 0.0);
        assert!((p.curvature(0.0) - p.k).abs() < 1e-9);
    }
}
