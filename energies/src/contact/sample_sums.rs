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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::contact::assemble::GroupHessian;
    use nalgebra::DMatrix;

    /// Samples with rows of `order` weights starting at `firsts`.
    fn samples(firsts: &[u32], order: usize) -> Samples {
        let values = (0..firsts.len() * order)
            .map(|k| 0.1 + ((k * 7) % 11) as Real / 13.0)
            .collect();
        Samples {
            s: vec![0.0; firsts.len()],
            weight: vec![1.0; firsts.len()],
            first: firsts.to_vec(),
            values,
            order,
            position: Vec::new(),
        }
    }

    /// A symmetric block from a seed.
    fn sym(seed: usize) -> SymBlock {
        std::array::from_fn(|e| ((seed * 5 + e * 3) % 7) as Real - 2.5)
    }

    /// \(u u^T \otimes M\) summed over the pairs, `u = B_a − B_b`, densely.
    fn dense_reference(s: &Samples, pairs: &[(u32, u32)], n: usize) -> DMatrix<Real> {
        let mut h = DMatrix::zeros(3 * n, 3 * n);
        for (p, &(a, b)) in pairs.iter().enumerate() {
            let mut u = vec![0.0; n];
            for (k, sign) in [(a, 1.0), (b, -1.0)] {
                let first = s.first[k as usize] as usize;
                for (i, w) in s.row(k as usize).iter().enumerate() {
                    u[first + i] += sign * w;
                }
            }
            let m = block(&sym(p));
            for i in 0..n {
                for j in 0..n {
                    let mut v = h.fixed_view_mut::<3, 3>(3 * i, 3 * j);
                    v += m * (u[i] * u[j]);
                }
            }
        }
        h
    }

    #[test]
    fn per_sample_assembly_equals_the_pairwise_sum() {
        let n = 24;
        // Samples 0..3 on one strand, 4..7 on another far along it, 8..9 overlapping
        // the first strand's control points (a pair sharing control points).
        let s = samples(&[2, 2, 3, 4, 15, 16, 16, 17, 3, 4], 4);
        let groups: [&[(u32, u32)]; 2] = [
            &[(0, 4), (0, 5), (1, 5), (2, 6), (2, 7), (3, 7)],
            &[(1, 8), (2, 8), (2, 9), (3, 9)],
        ];
        let mut hessian = BlockBanded::zeros(n, 3);
        let (mut sums, mut local) = (SampleSums::default(), GroupHessian::default());
        sums.clear(s.s.len());
        let mut p = 0;
        for pairs in groups {
            let run = |side: fn(&(u32, u32)) -> u32| {
                let firsts = pairs.iter().map(|c| s.first[side(c) as usize] as usize);
                firsts.clone().min().unwrap_or(0)..firsts.max().unwrap_or(0) + s.order
            };
            local.start(run(|c| c.0), run(|c| c.1));
            for &(a, b) in pairs {
                let m = sym(p);
                p += 1;
                sums.add_block(a, &m);
                sums.add_block(b, &m);
                let first = |k: u32| s.first[k as usize] as usize;
                let row_a = (a, first(a), s.row(a as usize));
                local.add_cross(row_a, (first(b), s.row(b as usize)), &m);
            }
            local.finish(&mut hessian);
        }
        local.flush(&mut hessian);
        sums.spread_blocks(&s, &mut hessian);
        let all: Vec<_> = groups.concat();
        let expected = dense_reference(&s, &all, n);
        let error = (hessian.to_dense() - &expected).amax();
        assert!(error <= 1e-12 * expected.amax(), "error {error}");
        assert!(hessian.has_far_blocks());
    }

    #[test]
    fn forces_spread_over_each_samples_row() {
        let s = samples(&[0, 1, 5], 4);
        let mut sums = SampleSums::default();
        sums.clear(3);
        let f = Vector3::new(1.0, -2.0, 0.5);
        sums.add_force(0, &f);
        sums.add_force(2, &-f);
        sums.add_force(0, &f);
        let mut g = vec![Vector3::zeros(); 9];
        sums.spread_forces(&s, &mut g);
        for (k, scale) in [(0usize, 2.0), (2, -1.0)] {
            let first = s.first[k] as usize;
            for (i, w) in s.row(k).iter().enumerate() {
                assert_eq!(g[first + i], f * (scale * w));
            }
        }
        // Cleared between uses, also for another sample count.
        sums.clear(3);
        let mut h = vec![Vector3::zeros(); 9];
        sums.spread_forces(&s, &mut h);
        assert!(h.iter().all(|v| *v == Vector3::zeros()));
    }
}
