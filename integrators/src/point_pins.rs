//! Elimination of pins that hold a single control point (a pin at a clamped end: its row
//! of `G` is one 1 and zeros). For such a pin at control point `k` the constraint is
//! \\(\Delta x_k = \delta_k = c - x_k\\); instead of a Schur complement (three extra
//! back-substitutions per pin) the Newton system is rewritten
//!
//! \\[ A_{jk} \to 0,\ A_{kj} \to 0\ (j \ne k), \quad A_{kk} \to I, \quad
//! b_j \to b_j - A_{jk}\delta_k, \quad b_k \to \delta_k, \\]
//!
//! which keeps `A` symmetric positive definite and within its band. A pin sliding along
//! an axis holds only the directions of its projector `P` (and leaves `Q = I − P`
//! free): then \\(\Delta x_k = Q\Delta x_k + P\delta_k\\), so
//! \\(A_{jk} \to A_{jk} Q\\), \\(A_{kk} \to Q A_{kk} Q + P\\),
//! \\(b_j \to b_j - A_{jk} P\delta_k\\), \\(b_k \to Q b_k + P\delta_k\\) (the full
//! pin is `P = I`), and its multiplier is the `P` part of the row's residual. Far blocks
//! (self-contact couplings `A_jk` with `|j − k|` beyond the band) are treated alike: saved,
//! zeroed in place (so the sparsity pattern, and with it the symbolic analysis, is
//! unchanged) and moved to the right-hand side as \\(-A_{jk}\delta_k\\). The pin's
//! multiplier follows from the original row `k`: \\(\mu = (A \Delta x)_k - b_k -
//! (G^T\mu)_k\\) with the other pins' multipliers. Low-rank terms \\(c\,u u^T\\) alike:
//! saved whole, their entries at eliminated points zeroed, and \\(c\, u\, (u_k \cdot
//! \delta_k)\\) moved to the right-hand side.

use crate::IntegratorError;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BasisValues, BlockBanded, FarBlock, Real};

/// Pins eliminated from the Newton system, with what is needed to recover their forces.
#[derive(Debug, Default)]
pub(crate) struct PointPins {
    /// `(pin index, control point)` of each eliminated pin.
    pins: Vec<(usize, usize)>,
    /// The projector `P` onto the directions each eliminated pin holds.
    projectors: Vec<Matrix3<Real>>,
    /// Per eliminated pin: blocks \\(A_{jk}\\) for `j = k - bw ..= k + bw` before elimination.
    saved: Vec<Matrix3<Real>>,
    /// Far blocks touching an eliminated control point, before elimination:
    /// `(e, j, A_jk)` for eliminated pin `e` at control point `k` (duplicates kept: they sum).
    saved_far: Vec<(usize, usize, Matrix3<Real>)>,
    /// Low-rank terms `(c, u)` before elimination; the first `low_rank_used` are live.
    saved_low_rank: Vec<(Real, Vec<Vector3<Real>>)>,
    low_rank_used: usize,
    /// Per eliminated pin: the right-hand side `b_k` before elimination.
    rhs: Vec<Vector3<Real>>,
    bandwidth: usize,
}

/// The control point a pin's row holds alone with weight 1, if it does.
fn single_point(row: &BasisValues) -> Option<usize> {
    let mut nonzero = (0..row.order).filter(|&k| row.value[k] != 0.0);
    match (nonzero.next(), nonzero.next()) {
        (Some(k), None) if (row.value[k] - 1.0).abs() <= 1e-14 => Some(row.first + k),
        _ => None,
    }
}

impl PointPins {
    /// Finds the pins to eliminate among `rows` (with the pins' `projectors`), all but
    /// those `kept` for the Schur complement; two pins on one control point conflict.
    pub fn setup(
        &mut self,
        rows: &[BasisValues],
        projectors: &[Matrix3<Real>],
        kept: &[usize],
    ) -> Result<(), IntegratorError> {
        self.pins.clear();
        self.projectors.clear();
        for (p, row) in rows.iter().enumerate() {
            if let Some(k) = single_point(row).filter(|_| !kept.contains(&p)) {
                if self.pins.iter().any(|&(_, other)| other == k) {
                    return Err(IntegratorError::RedundantPins);
                }
                self.pins.push((p, k));
                self.projectors.push(projectors[p]);
            }
        }
        Ok(())
    }

    /// Whether pin `p` is eliminated.
    pub fn contains(&self, p: usize) -> bool {
        self.pins.iter().any(|&(q, _)| q == p)
    }

    /// The projector onto the directions of control point `k` left free by the
    /// eliminated pins (`I` if none holds it, 0 if one holds it fully).
    pub fn free_directions(&self, k: usize) -> Matrix3<Real> {
        let held = self.pins.iter().position(|&(_, q)| q == k);
        held.map_or(Matrix3::identity(), |e| {
            Matrix3::identity() - self.projectors[e]
        })
    }

    /// Saves the eliminated columns of `a` (band and far blocks), then decouples them
    /// (identity on the diagonal, zero far blocks).
    pub fn eliminate_matrix(&mut self, a: &mut BlockBanded) {
        let (n, bw) = (a.dim(), a.bandwidth());
        self.bandwidth = bw;
        let width = 2 * bw + 1;
        self.saved.clear();
        self.saved.resize(self.pins.len() * width, Matrix3::zeros());
        for (e, &(_, k)) in self.pins.iter().enumerate() {
            // Block (j, k) of the band: stored as (j, k) above the diagonal, as the
            // transpose of (k, j) below it.
            for j in k.saturating_sub(bw)..(k + bw + 1).min(n) {
                self.saved[e * width + j + bw - k] = if j <= k {
                    *a.upper(j, k - j)
                } else {
                    a.upper(k, j - k).transpose()
                };
            }
        }
        self.save_far(a.far_blocks());
        self.save_low_rank(a);
        for (&(_, k), p) in self.pins.iter().zip(&self.projectors) {
            let q = Matrix3::identity() - p;
            for f in a.far_blocks_mut() {
                if f.col == k {
                    f.block *= q;
                }
                if f.row == k {
                    f.block = q * f.block;
                }
            }
            // A point held in every direction (q = 0, the usual pin): its row and
            // column are the identity's, written straight into the band.
            if q == Matrix3::zeros() {
                let row = a.band_row_mut(k);
                row[0] = *p;
                row[1..].fill(Matrix3::zeros());
                for j in k.saturating_sub(bw)..k {
                    a.band_row_mut(j)[k - j] = Matrix3::zeros();
                }
                continue;
            }
            for j in k.saturating_sub(bw)..(k + bw + 1).min(n) {
                let value = if j == k {
                    q * a.block(k, k) * q + p
                } else {
                    a.block(j, k) * q
                };
                a.set_block(j, k, &value);
            }
        }
    }

    /// Saves the low-rank terms and zeroes their entries at eliminated points.
    fn save_low_rank(&mut self, a: &mut BlockBanded) {
        self.low_rank_used = 0;
        if self.pins.is_empty() {
            return;
        }
        for term in a.low_rank_mut() {
            if self.low_rank_used == self.saved_low_rank.len() {
                self.saved_low_rank.push((0.0, Vec::new()));
            }
            let saved = &mut self.saved_low_rank[self.low_rank_used];
            saved.0 = term.coefficient;
            saved.1.clear();
            saved.1.extend_from_slice(&term.vector);
            self.low_rank_used += 1;
            for (&(_, k), p) in self.pins.iter().zip(&self.projectors) {
                let held = p * term.vector[k];
                term.vector[k] -= held;
            }
        }
    }

    /// The saved low-rank terms.
    fn low_rank(&self) -> &[(Real, Vec<Vector3<Real>>)] {
        &self.saved_low_rank[..self.low_rank_used]
    }

    /// Saves, per eliminated pin at `k`, the far blocks `A_jk` of column `k`.
    fn save_far(&mut self, far: &[FarBlock]) {
        self.saved_far.clear();
        for (e, &(_, k)) in self.pins.iter().enumerate() {
            for f in far {
                if f.col == k {
                    self.saved_far.push((e, f.row, f.block));
                } else if f.row == k {
                    self.saved_far.push((e, f.col, f.block.transpose()));
                }
            }
        }
    }

    /// Rewrites the flat right-hand side `b` for prescribed steps `δ_k = c_p − x_k`
    /// (`targets` `None`: homogeneous constraints, `δ_k = 0`).
    pub fn eliminate_rhs(
        &mut self,
        x: &[Vector3<Real>],
        targets: Option<&[Vector3<Real>]>,
        b: &mut [Real],
    ) {
        let (bw, n) = (self.bandwidth, x.len());
        let width = 2 * bw + 1;
        self.rhs.clear();
        for &(_, k) in &self.pins {
            self.rhs.push(flat3(b, k));
        }
        if targets.is_none() {
            // Zero gaps: only the pinned rows change.
            for (e, &(_, k)) in self.pins.iter().enumerate() {
                let value = (Matrix3::identity() - self.projectors[e]) * flat3(b, k);
                b[3 * k..3 * k + 3].copy_from_slice(value.as_slice());
            }
            return;
        }
        let held = |e: usize| {
            let (p, k) = self.pins[e];
            targets.map_or(Vector3::zeros(), |t| self.projectors[e] * (t[p] - x[k]))
        };
        for (e, &(_, k)) in self.pins.iter().enumerate() {
            let delta = held(e);
            for j in k.saturating_sub(bw)..(k + bw + 1).min(n) {
                let change = self.saved[e * width + j + bw - k] * delta;
                sub3(b, j, &change);
            }
        }
        for &(e, j, block) in &self.saved_far {
            sub3(b, j, &(block * held(e)));
        }
        for (c, u) in self.low_rank() {
            let s: Real = (0..self.pins.len())
                .map(|e| u[self.pins[e].1].dot(&held(e)))
                .sum();
            for (j, u) in u.iter().enumerate() {
                sub3(b, j, &(u * (c * s)));
            }
        }
        for (e, &(_, k)) in self.pins.iter().enumerate() {
            let q = Matrix3::identity() - self.projectors[e];
            let value = q * flat3(b, k) + held(e);
            b[3 * k..3 * k + 3].copy_from_slice(value.as_slice());
        }
    }

    /// The eliminated control points, in pin order.
    pub fn control_points(&self) -> impl Iterator<Item = usize> + '_ {
        self.pins.iter().map(|&(_, k)| k)
    }

    /// Multipliers of the eliminated pins from the solved step `dx` (flat) and `others[e]`
    /// \(= (G^T\mu)_k\) of the remaining pins at each eliminated control point.
    pub fn multipliers(&self, dx: &[Real], others: &[Vector3<Real>], mu: &mut [Vector3<Real>]) {
        self.multipliers_from(dx, others, |e, _| -self.rhs[e], mu);
    }

    /// [`Self::multipliers`] with each row's part other than the banded product given by
    /// `rest(e, k)` for pin `e` at control point `k` (instead of the saved right-hand
    /// side), e.g. with a remainder's product added.
    pub fn multipliers_from(
        &self,
        dx: &[Real],
        others: &[Vector3<Real>],
        rest: impl Fn(usize, usize) -> Vector3<Real>,
        mu: &mut [Vector3<Real>],
    ) {
        let (bw, n) = (self.bandwidth, dx.len() / 3);
        let width = 2 * bw + 1;
        for (e, &(p, k)) in self.pins.iter().enumerate() {
            let mut row = rest(e, k) - others[e];
            for j in k.saturating_sub(bw)..(k + bw + 1).min(n) {
                // A_kj = A_jkᵀ.
                row += self.saved[e * width + j + bw - k].tr_mul(&flat3(dx, j));
            }
            for &(_, j, block) in self.saved_far.iter().filter(|s| s.0 == e) {
                row += block.tr_mul(&flat3(dx, j));
            }
            for (c, u) in self.low_rank() {
                let s: Real = (0..n).map(|j| u[j].dot(&flat3(dx, j))).sum();
                row += u[k] * (c * s);
            }
            mu[p] = self.projectors[e] * row;
        }
    }
}

fn flat3(v: &[Real], k: usize) -> Vector3<Real> {
    Vector3::new(v[3 * k], v[3 * k + 1], v[3 * k + 2])
}

/// `v[3k..3k + 3] −= d`.
fn sub3(v: &mut [Real], k: usize, d: &Vector3<Real>) {
    v[3 * k..3 * k + 3]
        .iter_mut()
        .zip(d.iter())
        .for_each(|(x, d)| *x -= d);
}
