//! The pins of the batched step: each holds one control point whole, eliminated from the
//! Newton system as in `point_pins.rs` (\\(A_{jk} \to 0\\), \\(A_{kk} \to I\\),
//! \\(b_j \to b_j - A_{jk}\delta_k\\), \\(b_k \to \delta_k\\) with
//! \\(\delta_k = c - x_k\\)), and its multiplier recovered from the saved column,
//! \\(\mu_k = r_k + (A\Delta x)_k\\).

use super::{LaneEuler, LaneFallback};
use splinerod_core::lanes::{mul_add, ZERO};
use splinerod_core::{Lanes, Pin, Real, Rod, LANES};

impl LaneEuler {
    /// The pins: each must hold one control point whole, the same in every lane; their
    /// targets for the velocity unknown are \\((p - q_{0,k})/h\\).
    #[inline(always)]
    pub(super) fn place_pins(
        &mut self,
        rods: [&Rod; LANES],
        pins: [&[Pin]; LANES],
        dt: Real,
    ) -> Result<(), LaneFallback> {
        let count = pins[0].len();
        if pins.iter().any(|p| p.len() != count) {
            return Err(LaneFallback("pins"));
        }
        self.pins.clear();
        self.targets.clear();
        for p in 0..count {
            // The rods share their knots: a pin at the same place holds the same point.
            let lead = &pins[0][p];
            let k = self.pin_point(rods[0], lead).ok_or(LaneFallback("pins"))?;
            if self.pins.contains(&k) {
                return Err(LaneFallback("pins"));
            }
            let mut target = [ZERO; 3];
            for (l, lane) in pins.iter().enumerate() {
                let pin = &lane[p];
                let alike = pin.at.to_bits() == lead.at.to_bits()
                    && pin.slides_along.is_none()
                    && !pin.tangent;
                if !alike {
                    return Err(LaneFallback("pins"));
                }
                if !pin.position.iter().all(|x| x.is_finite()) {
                    self.fail(l, "non-finite pin");
                }
                for (c, t) in target.iter_mut().enumerate() {
                    t[l] = (pin.position[c] - self.q0[3 * k + c][l]) / dt;
                }
            }
            self.pins.push(k);
            self.targets.push(target);
        }
        self.multipliers.resize(count, [ZERO; 3]);
        Ok(())
    }

    /// The control point `pin` holds alone and whole on `rod` ([`single_point`]),
    /// remembered for the knots it was found on (an ensemble's groups share them).
    fn pin_point(&mut self, rod: &Rod, pin: &Pin) -> Option<usize> {
        let knots = rod.basis().knots();
        let same = self.pin_knots.len() == knots.len()
            && self
                .pin_knots
                .iter()
                .zip(knots)
                .all(|(a, b)| a.to_bits() == b.to_bits());
        if !same {
            self.pin_knots.clear();
            self.pin_knots.extend_from_slice(knots);
            self.pin_points.clear();
        }
        let key = (pin.at.to_bits(), pin.tangent, pin.slides_along.is_some());
        if let Some(&(_, k)) = self.pin_points.iter().find(|(p, _)| *p == key) {
            return k;
        }
        let k = single_point(rod, pin);
        self.pin_points.push((key, k));
        k
    }

    /// Saves the pinned columns of `A` and decouples them (identity on the diagonal).
    #[inline(always)]
    pub(super) fn eliminate_pins(&mut self) {
        let (n, bw) = (self.n, self.bw);
        let width = 2 * bw + 1;
        self.saved.resize(self.pins.len() * width, [ZERO; 9]);
        for (e, &k) in self.pins.iter().enumerate() {
            for j in k.saturating_sub(bw)..(k + bw + 1).min(n) {
                let saved = &mut self.saved[e * width + j + bw - k];
                // Entry by entry, the lower blocks transposed (no block copied whole
                // through a temporary: a library call each).
                let (stored, transposed) = match j <= k {
                    true => (&self.a.row(j)[k - j], false),
                    false => (&self.a.row(k)[j - k], true),
                };
                for (e, entry) in saved.iter_mut().enumerate() {
                    let (r, c) = (e % 3, e / 3);
                    *entry = stored[if transposed { 3 * r + c } else { e }];
                }
            }
        }
        let mut identity = [ZERO; 9];
        for e in [0, 4, 8] {
            identity[e] = [1.0; LANES];
        }
        for &k in &self.pins {
            for j in k.saturating_sub(bw)..k {
                self.a.row_mut(j)[k - j] = [ZERO; 9];
            }
            let row = self.a.row_mut(k);
            row.iter_mut().for_each(|b| *b = [ZERO; 9]);
            row[0] = identity;
        }
    }

    /// The right-hand side `b = −r` rewritten for the prescribed steps
    /// \\(\delta_k = c - x_k\\) of the pinned points.
    #[inline(always)]
    pub(super) fn apply_pin_targets(&mut self) {
        let (n, bw) = (self.n, self.bw);
        let width = 2 * bw + 1;
        for (e, &k) in self.pins.iter().enumerate() {
            let delta = self.delta(e, k);
            for j in k.saturating_sub(bw)..(k + bw + 1).min(n) {
                let block = &self.saved[e * width + j + bw - k];
                for r in 0..3 {
                    let mut acc = self.flat[3 * j + r];
                    for (c, d) in delta.iter().enumerate() {
                        let b = &block[3 * c + r];
                        for l in 0..LANES {
                            acc[l] -= b[l] * d[l];
                        }
                    }
                    self.flat[3 * j + r] = acc;
                }
            }
        }
        for (e, &k) in self.pins.iter().enumerate() {
            let delta = self.delta(e, k);
            self.flat[3 * k..3 * k + 3].copy_from_slice(&delta);
        }
    }

    /// \\(\delta_k = c - x_k\\) of pin `e` at control point `k`.
    #[inline(always)]
    fn delta(&self, e: usize, k: usize) -> [Lanes; 3] {
        std::array::from_fn(|c| {
            std::array::from_fn(|l| self.targets[e][c][l] - self.x[3 * k + c][l])
        })
    }

    /// Whether lane `l`'s iterate meets its pins (the line search runs only then).
    #[inline(always)]
    pub(super) fn feasible(&self, l: usize) -> bool {
        self.pins.iter().enumerate().all(|(e, &k)| {
            let t = &self.targets[e];
            let gap = (0..3).map(|c| (t[c][l] - self.x[3 * k + c][l]).abs());
            let size = (0..3).map(|c| t[c][l].abs()).fold(0.0, Real::max);
            gap.fold(0.0, Real::max) <= 1e-10 * (1.0 + size)
        })
    }

    /// The pins' multipliers \\(\mu_k = r_k + (A\Delta x)_k\\) from the saved columns;
    /// per lane the norm of \\(r - G^T\mu\\) and the slope \\((r - G^T\mu)\cdot\Delta x\\).
    #[inline(always)]
    pub(super) fn pin_multipliers_and_slope(&mut self) -> (Lanes, Lanes) {
        let (n, bw) = (self.n, self.bw);
        let width = 2 * bw + 1;
        for (e, &k) in self.pins.iter().enumerate() {
            let mut mu: [Lanes; 3] = std::array::from_fn(|c| self.r[3 * k + c]);
            for j in k.saturating_sub(bw)..(k + bw + 1).min(n) {
                let block = &self.saved[e * width + j + bw - k];
                for (c, m) in mu.iter_mut().enumerate() {
                    for r in 0..3 {
                        mul_add(m, block[3 * c + r], self.flat[3 * j + r]);
                    }
                }
            }
            self.multipliers[e] = mu;
        }
        // r − Gᵀμ into the gradient buffer (free until the next assembly).
        self.gradient.copy_from_slice(&self.r);
        for (e, &k) in self.pins.iter().enumerate() {
            for c in 0..3 {
                for l in 0..LANES {
                    self.gradient[3 * k + c][l] -= self.multipliers[e][c][l];
                }
            }
        }
        let (mut norm, mut slope) = (ZERO, ZERO);
        for (g, d) in self.gradient.iter().zip(&self.flat) {
            mul_add(&mut norm, *g, *g);
            mul_add(&mut slope, *g, *d);
        }
        (norm.map(Real::sqrt), slope)
    }
}

/// The control point a pin holds alone and whole (no sliding, not a tangent pin, its
/// row one 1 and zeros), if it does.
fn single_point(rod: &Rod, pin: &Pin) -> Option<usize> {
    if pin.slides_along.is_some() || pin.tangent {
        return None;
    }
    let row = pin.row(rod).ok()?;
    let mut nonzero = (0..row.order).filter(|&k| row.value[k] != 0.0);
    match (nonzero.next(), nonzero.next()) {
        (Some(k), None) if (row.value[k] - 1.0).abs() <= 1e-14 => Some(row.first + k),
        _ => None,
    }
}
