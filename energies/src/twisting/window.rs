//! A window of `d + 1` consecutive control points whose Hessian blocks are summed
//! locally before going into the [`BlockBanded`] matrix: the holonomy's Hessian is a sum
//! over pairs of neighbouring samples, and all samples of a span share its `d + 1` basis
//! functions, so a span's pairs touch the same `(d + 1)(d + 2)/2` blocks. Summing them
//! here and adding each block once per span costs a fraction of adding every pair's
//! blocks to the matrix.

use crate::twisting::holonomy::Row;
use nalgebra::Matrix3;
use splinerod_core::{basis::MAX_ORDER, BlockBanded};

/// Upper blocks `(base + i, base + j)`, `i ≤ j < width`, summed locally.
pub(crate) struct Window {
    base: usize,
    width: usize,
    used: bool,
    blocks: [[Matrix3<f64>; MAX_ORDER]; MAX_ORDER],
}

impl Window {
    /// An empty window of `width ≤ MAX_ORDER` control points.
    pub fn new(width: usize) -> Self {
        Self {
            base: 0,
            width: width.min(MAX_ORDER),
            used: false,
            blocks: [[Matrix3::zeros(); MAX_ORDER]; MAX_ORDER],
        }
    }

    /// Adds \\(R_a^T H R_b + R_b^T H^T R_a\\) (just \\(R_a^T H R_a\\), `H` symmetric, if
    /// `b` is `None`), with \\(R\\) the rows \\(a = \sum_i b_i'(s) q_i\\); pairs wider than
    /// the window go straight to `hessian`.
    pub fn add(&mut self, hessian: &mut BlockBanded, a: &Row, b: Option<&Row>, h: &Matrix3<f64>) {
        let other = b.unwrap_or(a);
        let lo = a.first.min(other.first);
        let hi = a.last().max(other.last());
        if hi - lo >= self.width {
            return add_direct(hessian, a, b, h);
        }
        if self.used && (lo < self.base || hi >= self.base + self.width) {
            self.flush(hessian);
        }
        if !self.used {
            self.base = lo;
            self.used = true;
        }
        let (ht, hs) = (h.transpose(), h + h.transpose());
        for i in 0..a.len {
            let ii = a.first + i - self.base;
            if b.is_none() {
                for j in i..a.len {
                    self.blocks[ii][a.first + j - self.base] += h * (a.d1[i] * a.d1[j]);
                }
                continue;
            }
            for j in 0..other.len {
                let jj = other.first + j - self.base;
                let w = a.d1[i] * other.d1[j];
                match ii.cmp(&jj) {
                    std::cmp::Ordering::Less => self.blocks[ii][jj] += h * w,
                    std::cmp::Ordering::Greater => self.blocks[jj][ii] += ht * w,
                    std::cmp::Ordering::Equal => self.blocks[ii][ii] += hs * w,
                }
            }
        }
    }

    /// Adds the summed blocks to `hessian` and empties the window.
    pub fn flush(&mut self, hessian: &mut BlockBanded) {
        if !self.used {
            return;
        }
        let n = hessian.dim();
        for i in 0..self.width {
            for j in i..self.width {
                let block = std::mem::replace(&mut self.blocks[i][j], Matrix3::zeros());
                if self.base + j < n {
                    hessian.add_block(self.base + i, self.base + j, &block);
                }
            }
        }
        self.used = false;
    }
}

/// [`Window::add`] straight into the matrix.
fn add_direct(hessian: &mut BlockBanded, a: &Row, b: Option<&Row>, h: &Matrix3<f64>) {
    let same = b.is_none();
    let b = b.unwrap_or(a);
    for i in 0..a.len {
        let range = if same { i..a.len } else { 0..b.len };
        for j in range {
            let (row, col) = (a.first + i, b.first + j);
            let w = a.d1[i] * b.d1[j];
            if !same && row == col {
                hessian.add_block(row, col, &((h + h.transpose()) * w));
            } else {
                // A closed rod's last and first samples couple across the seam.
                hessian.add_coupling(row, col, &(h * w));
            }
        }
    }
}
