//! The mixed form on closed rods: tension functions split by the seam.
//!
//! On a periodic basis ([`splinerod_core::PeriodicBSplineSpace`], `m` distinct control
//! points, `n = m + d` stored) the tension functions `j` and `j + m`, `1 ≤ j < d`, are the
//! two halves of one periodic function: one straddles `s = 0` from the right, the other
//! `s = L` from the left. The periodic tension space has one coefficient for both, so
//! the pair is one function with moment and weight
//!
//! \\[ b = b_j + b_{j+m}, \qquad w = m_j + m_{j+m}, \qquad \lambda = \hat\lambda + EA\, b/w, \\]
//!
//! the energy \\(\tfrac{EA}{2} b^2/w\\) and the material Hessian
//! \\(\tfrac{EA}{w} (\partial b_j + \partial b_{j+m})(\partial b_j + \partial b_{j+m})^T\\):
//! each half's own outer product with the pair's stiffness, plus the cross term between
//! the halves, which couples control points on both sides of the seam
//! ([`add_cross_term`]; the Newton solve folds them, `splinerod_integrators`). Without
//! the merge the tension could jump at the seam and results would depend on where it
//! is (measured: 1.9e-2 m on a wobbly ring after 0.2 s); with it they do not (to
//! round-off, `tests/closed_rings.rs`).

use super::table::MAX_WIDTH;
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BlockBanded, Real, Rod, MAX_DEGREE};

/// The other half of tension function `index` (`1 ..= n − 1`) of a closed rod, if the
/// seam splits it.
#[inline]
pub(super) fn partner(rod: &Rod, index: usize) -> Option<usize> {
    let m = rod.basis().periodic_count()?;
    let last = rod.len() - 1;
    if index >= 1 && index + m <= last {
        Some(index + m)
    } else if index > m && index <= last {
        Some(index - m)
    } else {
        None
    }
}

/// The merged `(b, w)` of the split pairs of a closed rod, from each function's own.
#[derive(Debug, Clone, Copy)]
pub(super) struct Merged {
    /// Per pair `j = 1 .. d`, at `j − 1`.
    pairs: [(Real, Real); MAX_DEGREE],
    /// Number of distinct control points (0 for an open rod: nothing merged).
    m: usize,
    /// The degree `d` (pairs `1 .. d`).
    d: usize,
}

impl Merged {
    /// The pairs of `rod` with per-function `(b, w)` from `own` (nothing for an open rod).
    pub fn of(rod: &Rod, own: impl Fn(usize) -> (Real, Real)) -> Self {
        let mut merged = Self {
            pairs: [(0.0, 0.0); MAX_DEGREE],
            m: 0,
            d: rod.basis().degree(),
        };
        if let Some(m) = rod.basis().periodic_count() {
            merged.m = m;
            for j in 1..rod.basis().degree() {
                let ((b1, w1), (b2, w2)) = (own(j), own(j + m));
                merged.pairs[j - 1] = (b1 + b2, w1 + w2);
            }
        }
        merged
    }

    /// `(b, w)` of the periodic function that function `index` is part of, if it is split.
    #[inline]
    pub fn get(&self, index: usize) -> Option<(Real, Real)> {
        if self.m == 0 {
            return None;
        }
        let head = if index > self.m {
            index - self.m
        } else {
            index
        };
        (head >= 1 && head < self.d).then(|| self.pairs[head - 1])
    }
}

/// The first halves' derivative blocks, kept until their second halves come.
#[derive(Debug)]
pub(super) struct Heads {
    blocks: [(usize, usize, [Vector3<Real>; MAX_WIDTH]); MAX_DEGREE],
}

impl Default for Heads {
    fn default() -> Self {
        Self {
            blocks: [(0, 0, [Vector3::zeros(); MAX_WIDTH]); MAX_DEGREE],
        }
    }
}

impl Heads {
    /// Keeps the block of head function `index` (`1 ≤ index < d`).
    pub fn keep(&mut self, index: usize, first: usize, db: &[Vector3<Real>]) {
        let slot = &mut self.blocks[index - 1];
        slot.0 = first;
        slot.1 = db.len();
        slot.2[..db.len()].copy_from_slice(db);
    }

    /// The kept block of head function `index`: first control point and derivatives.
    pub fn get(&self, index: usize) -> (usize, &[Vector3<Real>]) {
        let (first, width, db) = &self.blocks[index - 1];
        (*first, &db[..*width])
    }
}

/// Adds the cross term \\(c\,(u v^T + v u^T)\\) between the halves' derivative blocks `u`
/// (control points from `first_u`) and `v` (from `first_v`), in the band or as far
/// blocks.
pub(super) fn add_cross_term(
    hessian: &mut BlockBanded,
    c: Real,
    (first_u, u): (usize, &[Vector3<Real>]),
    (first_v, v): (usize, &[Vector3<Real>]),
) {
    for (a, ua) in u.iter().enumerate() {
        for (b, vb) in v.iter().enumerate() {
            let block: Matrix3<Real> = ua * vb.transpose() * c;
            let (i, j) = (first_u + a, first_v + b);
            if i == j {
                hessian.add_block(i, i, &(block + block.transpose()));
            } else {
                hessian.add_coupling(i, j, &block);
            }
        }
    }
}
