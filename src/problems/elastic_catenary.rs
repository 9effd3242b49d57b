//! The exact elastic catenary of the Green–Lagrange law, for any axial stiffness: the
//! reference the stiff-rod (locking) studies measure against.
//!
//! A rod of rest length `L` and weight `w = μ g` per rest length hangs from pins at the
//! same height `D` apart. With `s` the rest arclength, the horizontal tension `H` is
//! constant and the vertical force is \\(V(s) = w (s - L/2)\\) (symmetry), so the
//! tension is \\(T(s) = \sqrt{H^2 + V^2}\\). The stretch γ solves the constitutive law
//! \\(T = \tfrac{EA}{2}\gamma(\gamma^2 - 1)\\) (γ = 1 for an inextensible rod), and the
//! centre line follows the force:
//!
//! \\[ x(s) = \int_0^s \gamma \frac{H}{T}\, d\sigma, \qquad
//!     y(s) = \int_0^s \gamma \frac{V}{T}\, d\sigma. \\]
//!
//! `H` is found by bisection on \\(x(L) = D\\); the integrals by composite 8-point
//! Gauss–Legendre on 256 panels (the integrands are analytic: round-off accuracy).

use crate::Error;
use splinerod_core::quadrature::GaussLegendre;
use splinerod_core::Real;

/// An elastic catenary: geometry, load, stiffness and the tension that solves it.
#[derive(Debug, Clone, PartialEq)]
pub struct ElasticCatenary {
    /// Rest length `L`, m.
    pub length: Real,
    /// Weight per rest length `μ g`, N/m.
    pub weight: Real,
    /// Axial stiffness `EA`, N (`f64::INFINITY`: inextensible).
    pub stiffness: Real,
    /// Horizontal tension `H`, N.
    pub horizontal_tension: Real,
}

const PANELS: usize = 256;

impl ElasticCatenary {
    /// Solves for `H` with pins `span` apart (`0 < span < L` for an inextensible rod).
    pub fn new(length: Real, span: Real, weight: Real, stiffness: Real) -> Result<Self, Error> {
        let positive = |name: &str, v: Real| {
            if v > 0.0 && !v.is_nan() {
                Ok(())
            } else {
                Err(Error::field(name, v, "must be positive"))
            }
        };
        positive("length", length)?;
        positive("span", span)?;
        positive("weight", weight)?;
        positive("stiffness", stiffness)?;
        let mut c = Self {
            length,
            weight,
            stiffness,
            horizontal_tension: 0.0,
        };
        let (mut lo, mut hi) = (1e-12 * weight * length, weight * length);
        c.horizontal_tension = hi;
        while c.point(length)[0] < span {
            hi *= 2.0;
            c.horizontal_tension = hi;
            if hi > 1e30 {
                return Err(Error::field("span", span, "no catenary reaches it"));
            }
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            c.horizontal_tension = mid;
            if c.point(length)[0] < span {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        c.horizontal_tension = 0.5 * (lo + hi);
        Ok(c)
    }

    /// Stretch at tension `t`: the root γ ≥ 1 of \\(\tfrac{EA}{2}\gamma(\gamma^2-1) = t\\).
    pub fn stretch(&self, t: Real) -> Real {
        if self.stiffness.is_infinite() {
            return 1.0;
        }
        let k = 2.0 * t / self.stiffness;
        // Newton on γ³ − γ − k, from above the root (convex for γ ≥ 1).
        let mut g: Real = 1.0 + k.max(k.cbrt());
        for _ in 0..100 {
            let step = (g * g * g - g - k) / (3.0 * g * g - 1.0);
            g -= step;
            if step.abs() <= 1e-16 * g {
                break;
            }
        }
        g
    }

    /// Tension at rest arclength `s`, N.
    pub fn tension(&self, s: Real) -> Real {
        let v = self.weight * (s - 0.5 * self.length);
        self.horizontal_tension.hypot(v)
    }

    /// Largest relative difference between a run's tension samples (at the fractions
    /// `samples.s` of the rest length) and [`Self::tension`]; infinite without samples.
    pub fn tension_error(&self, samples: &crate::run::runner::Samples) -> Real {
        if samples.tension.len() != samples.s.len() || samples.s.is_empty() {
            return Real::INFINITY;
        }
        samples
            .s
            .iter()
            .zip(&samples.tension)
            .map(|(&f, &t)| {
                let exact = self.tension(f * self.length);
                (t - exact).abs() / exact
            })
            .fold(0.0, Real::max)
    }

    /// Position `[x, y]` of material point `s` (first pin at the origin), m.
    pub fn point(&self, s: Real) -> [Real; 2] {
        let rule = GaussLegendre::new(8);
        let panel = s / PANELS as Real;
        let mut xy = [0.0, 0.0];
        for k in 0..PANELS {
            let a = k as Real * panel;
            for (&u, &w) in rule.nodes.iter().zip(&rule.weights) {
                let sigma = a + u * panel;
                let v = self.weight * (sigma - 0.5 * self.length);
                let t = self.horizontal_tension.hypot(v);
                let f = w * panel * self.stretch(t) / t;
                xy[0] += f * self.horizontal_tension;
                xy[1] += f * v;
            }
        }
        xy
    }
}
