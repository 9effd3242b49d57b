//! Per-sample sums of the sample pairs' terms. A pair `(a, b)` acts on the control
//! points through \\(u = B_a - B_b\\) (`B_k` the basis row of sample `k`), so its
//! gradient \\(u \otimes f\\) and Hessian \\(u u^T \otimes M\\) split into terms of
//! one sample each,
//!
//! \\[ B_a \otimes f,\quad -B_b \otimes f,\quad B_a B_a^T \otimes M,\quad
//! B_b B_b^T \otimes M, \\]
//!
//! and the cross terms \\(-(B_a B_b^T + B_b B_a^T) \otimes M\\) (assembled per segment
//! pair, see [`super::assemble`]). The one-sample terms of every pair that touches a
//! sample are summed first — a force and a symmetric block per sample — and spread over
//! its control points once: `order` products per sample for the gradient instead of
//! `2 · order` per pair, `order (order + 1) / 2` blocks per sample for the Hessian
//! instead of `order (2 order + 1)` per pair. (A sample takes part in several pairs
//! wherever strands touch along a line or cross at a shallow angle.)

use super::assemble::{block, SymBlock};
use super::detect::Samples;
use nalgebra::Vector3;
use splinerod_core::{BlockBanded, Real};

/// Marks a sample without a slot.
const NONE: u32 = u32::MAX;

/// The sums, over the samples touched since the last [`SampleSums::clear`].
#[derive(Debug, Clone, Default)]
pub(crate) struct SampleSums {
    /// Per sample: its slot in `touched`, or [`NONE`].
    slot: Vec<u32>,
    /// The touched samples in order of first touch.
    touched: Vec<u32>,
    /// Per slot: the summed force.
    force: Vec<Vector3<Real>>,
    /// Per slot: the summed symmetric block.
    block: Vec<SymBlock>,
}

impl SampleSums {
    /// Empties the sums, for `samples` samples in all.
    pub fn clear(&mut self, samples: usize) {
        if self.slot.len() == samples {
            for &k in &self.touched {
                self.slot[k as usize] = NONE;
            }
        } else {
            self.slot.clear();
            self.slot.resize(samples, NONE);
        }
        self.touched.clear();
        self.force.clear();
        self.block.clear();
    }

    /// The slot of sample `k`, made (with zero sums) on first touch.
    #[inline]
    fn slot(&mut self, k: u32) -> usize {
        let s = &mut self.slot[k as usize];
        if *s == NONE {
            *s = self.touched.len() as u32;
            self.touched.push(k);
            self.force.push(Vector3::zeros());
            self.block.push([0.0; 6]);
        }
        *s as usize
    }

    /// Adds `f` to sample `k`'s force.
    #[inline]
    pub fn add_force(&mut self, k: u32, f: &Vector3<Real>) {
        let s = self.slot(k);
        self.force[s] += f;
    }

    /// Adds `m` to sample `k`'s block.
    #[inline]
    pub fn add_block(&mut self, k: u32, m: &SymBlock) {
        let s = self.slot(k);
        for (t, x) in self.block[s].iter_mut().zip(m) {
            *t += x;
        }
    }

    /// Adds each touched sample's force times its basis row to `gradient`.
    pub fn spread_forces(&self, samples: &Samples, gradient: &mut [Vector3<Real>]) {
        for (&k, f) in self.touched.iter().zip(&self.force) {
            let first = samples.first[k as usize] as usize;
            let rows = &mut gradient[first..first + samples.order];
            for (g, &b) in rows.iter_mut().zip(samples.row(k as usize)) {
                *g += f * b;
            }
        }
    }

    /// Adds each touched sample's \\(B B^T \otimes M\\) to `hessian` (band blocks: a
    /// sample's control points are consecutive).
    pub fn spread_blocks(&self, samples: &Samples, hessian: &mut BlockBanded) {
        let order = samples.order;
        for (&k, m) in self.touched.iter().zip(&self.block) {
            let first = samples.first[k as usize] as usize;
            let row = samples.row(k as usize);
            for (i, &wi) in row.iter().enumerate() {
                let mi = m.map(|x| x * wi);
                let blocks = hessian.band_row_mut(first + i);
                for (j, &wj) in row.iter().enumerate().skip(i) {
                    blocks[j - i] += block(&mi.map(|x| x * wj));
                }
            }
            debug_assert!(first + order <= hessian.dim());
        }
    }
}
