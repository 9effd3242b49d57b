//! The detection's Verlet list ([`Skin`]): sample pairs that may come within the reach
//! while the rod moves a little.
//!
//! A full detection lists every sample pair of its candidate segment pairs closer than
//! `reach + margin` (margin [`SKIN`]` · reach`), with the control points then. Samples
//! are convex combinations of control points (B-spline values are non-negative and sum
//! to one), so a sample moves no more than the farthest-moved control point, `m`. While
//! `2m < margin`, a pair now closer than `reach` was closer than `reach + margin` then:
//! it is listed. A detection re-measures only the listed pairs — the same pairs within
//! reach as a full detection, listed perhaps in another order (sums change by round-off
//! only).
//!
//! The same argument certifies closest-point searches: a pair now closer than
//! `reach + w` was listed if `w + 2m ≤ margin` ([`Skin::covers`]).

use super::detect::{SamplePair, Segment};
use nalgebra::Vector3;
use splinerod_core::{CoreError, Real, Rod, SavedState, StateReader};

/// Width of the skin, in reaches: a wider skin lists more pairs and is rebuilt less often.
pub(crate) const SKIN: Real = 0.25;

/// A Verlet list of sample pairs (see the module docs).
#[derive(Debug, Clone, Default)]
pub(crate) struct Skin {
    /// The detection settings and topology epoch it was made for.
    pub key: Option<(u64, [Real; 4])>,
    /// Its margin, m.
    pub margin: Real,
    /// The control points when it was made.
    pub reference: Vec<Vector3<Real>>,
    /// Sample pairs, grouped by candidate segment pair (`near[start..end]`).
    near: Vec<(u32, u32)>,
    groups: Vec<(usize, usize)>,
    /// The segment pair of each group.
    segments: Vec<(u32, u32)>,
    /// The samples of `near`, each once, in increasing order.
    pub samples: Vec<u32>,
    /// Scratch: which samples are listed.
    listed: Vec<bool>,
}

impl Skin {
    /// Appends the list (checkpoints: which pairs a warm list re-measures decides the
    /// rounding of the results, so a resumed run needs the same list).
    pub fn save(&self, out: &mut SavedState) {
        out.int(u64::from(self.key.is_some()));
        if let Some((_, settings)) = self.key {
            out.reals(&settings);
        }
        out.real(self.margin);
        out.vectors(&self.reference);
        let flat = |pairs: &[(u32, u32)]| {
            pairs
                .iter()
                .flat_map(|&(a, b)| [u64::from(a), u64::from(b)])
                .collect::<Vec<_>>()
        };
        out.ints(flat(&self.near).into_iter());
        out.ints(flat(&self.segments).into_iter());
        let groups = self.groups.iter().flat_map(|&(a, b)| [a as u64, b as u64]);
        out.ints(groups.collect::<Vec<_>>().into_iter());
        out.ints(self.samples.iter().map(|&k| u64::from(k)));
    }

    /// Reads back what [`save`](Self::save) wrote, for a rod of topology epoch `epoch`;
    /// check it with [`fits`](Self::fits) once the samples are laid out.
    pub fn load(&mut self, input: &mut StateReader<'_>, epoch: u64) -> Result<(), CoreError> {
        let bad = || CoreError::StateMismatch("a contact list entry out of range");
        self.key = None;
        let keyed = input.int()? == 1;
        let mut settings = Vec::new();
        if keyed {
            input.reals_into(&mut settings)?;
        }
        self.margin = input.real()?;
        input.vectors_into(&mut self.reference)?;
        let small = |x: u64| u32::try_from(x).map_err(|_| bad());
        for out in [&mut self.near, &mut self.segments] {
            out.clear();
            for c in input.ints()?.chunks_exact(2) {
                out.push((small(c[0])?, small(c[1])?));
            }
        }
        self.groups.clear();
        for c in input.ints()?.chunks_exact(2) {
            let (a, b) = (c[0] as usize, c[1] as usize);
            if a > b || b > self.near.len() {
                return Err(bad());
            }
            self.groups.push((a, b));
        }
        self.samples.clear();
        for &k in input.ints()? {
            self.samples.push(small(k)?);
        }
        if keyed {
            let s: [Real; 4] = settings.try_into().map_err(|_| bad())?;
            self.key = Some((epoch, s));
        }
        Ok(())
    }

    /// Empties the list (its samples and segments belong to former knots; see
    /// [`Detector::forget_topology`](super::detect::Detector::forget_topology)).
    pub fn forget(&mut self) {
        self.key = None;
        self.margin = 0.0;
        self.reference.clear();
        self.near.clear();
        self.groups.clear();
        self.segments.clear();
        self.samples.clear();
    }

    /// The `[segment, spacing]` of the detection the list was made for, if any.
    pub fn layout(&self) -> Option<[Real; 2]> {
        self.key.map(|(_, s)| [s[2], s[3]])
    }

    /// Whether every sample and segment the list names exists (`samples` samples,
    /// `segments` segments).
    pub fn fits(&self, samples: usize, segments: usize) -> bool {
        let pair_ok = |&(a, b): &(u32, u32), n: usize| (a as usize) < n && (b as usize) < n;
        self.near.iter().all(|p| pair_ok(p, samples))
            && self.segments.iter().all(|p| pair_ok(p, segments))
            && self.samples.iter().all(|&k| (k as usize) < samples)
    }

    /// Whether the list still holds every pair within reach at `rod`'s positions, for
    /// the detection `key`.
    pub fn holds(&self, rod: &Rod, key: (u64, [Real; 4])) -> bool {
        self.key == Some(key) && 2.0 * self.displacement(rod) < self.margin
    }

    /// Whether every sample pair now closer than `reach + extra` is listed.
    pub fn covers(&self, rod: &Rod, extra: Real) -> bool {
        self.key.is_some() && extra + 2.0 * self.displacement(rod) <= self.margin
    }

    /// The largest distance a control point moved since the list was made (infinite
    /// for another rod size).
    fn displacement(&self, rod: &Rod) -> Real {
        if self.reference.len() != rod.positions.len() {
            return Real::INFINITY;
        }
        let moved = rod.positions.iter().zip(&self.reference);
        moved
            .map(|(q, r)| (q - r).norm_squared())
            .fold(0.0, Real::max)
            .sqrt()
    }

    /// Lists the sample pairs of the candidate segment pairs closer than `wide`, at the
    /// sample positions `p` (`count` samples in all), given the segments and boxes
    /// holding their samples. A sample of the first segment farther than `wide` from
    /// the second's box along some axis has no partner there and is skipped.
    pub fn build(
        &mut self,
        candidates: &[(u32, u32)],
        (segments, [lower, upper]): (&[Segment], [&[Vector3<Real>]; 2]),
        p: &[Vector3<Real>],
        wide: Real,
        count: usize,
    ) {
        self.near.clear();
        self.groups.clear();
        self.segments.clear();
        let filter = wide * wide * (1.0 + 1e-9);
        // Generous: the distance test below decides.
        let reach = wide * (1.0 + 1e-6);
        for &(a, b) in candidates {
            let start = self.near.len();
            let (sa, sb) = (&segments[a as usize], &segments[b as usize]);
            let (lo, hi) = (
                lower[b as usize].add_scalar(-reach),
                upper[b as usize].add_scalar(reach),
            );
            for i in sa.first..sa.end {
                let x = &p[i];
                if (0..3).any(|k| x[k] < lo[k] || x[k] > hi[k]) {
                    continue;
                }
                for j in sb.first..sb.end {
                    if (p[i] - p[j]).norm_squared() < filter {
                        self.near.push((i as u32, j as u32));
                    }
                }
            }
            if self.near.len() > start {
                self.groups.push((start, self.near.len()));
                self.segments.push((a, b));
            }
        }
        self.listed.clear();
        self.listed.resize(count, false);
        for &(i, j) in &self.near {
            self.listed[i as usize] = true;
            self.listed[j as usize] = true;
        }
        self.samples.clear();
        let listed = self.listed.iter().enumerate().filter(|(_, &l)| l);
        self.samples.extend(listed.map(|(k, _)| k as u32));
    }

    /// The listed pairs closer than `reach` at the sample positions `p`, into `pairs`,
    /// grouped by segment pair in `groups`.
    pub fn within(
        &self,
        p: &[Vector3<Real>],
        reach: Real,
        pairs: &mut Vec<SamplePair>,
        groups: &mut Vec<(usize, usize)>,
    ) {
        pairs.clear();
        groups.clear();
        // A cheap squared-distance filter, slightly generous so that the exact test
        // below decides every pair (no square root for far samples).
        let filter = reach * reach * (1.0 + 1e-9);
        for &(start, end) in &self.groups {
            let first = pairs.len();
            for &(i, j) in &self.near[start..end] {
                let r = p[i as usize] - p[j as usize];
                if r.norm_squared() >= filter {
                    continue;
                }
                let distance = r.norm();
                if distance < reach {
                    let normal = r / distance;
                    pairs.push(SamplePair {
                        a: i,
                        b: j,
                        distance,
                        normal,
                    });
                }
            }
            if pairs.len() > first {
                groups.push((first, pairs.len()));
            }
        }
    }

    /// The segment pairs `(a, b)` with a listed sample pair closer than `bound(a, b)` at
    /// the sample positions `p`, into `out`.
    pub fn pairs_within(
        &self,
        p: &[Vector3<Real>],
        bound: impl Fn(usize, usize) -> Real,
        out: &mut Vec<(u32, u32)>,
    ) {
        for (&(start, end), &(a, b)) in self.groups.iter().zip(&self.segments) {
            let limit = bound(a as usize, b as usize);
            let limit2 = limit * limit * (1.0 + 1e-9);
            let near = &self.near[start..end];
            let close =
                |&(i, j): &(u32, u32)| (p[i as usize] - p[j as usize]).norm_squared() < limit2;
            if near.iter().any(close) {
                out.push((a, b));
            }
        }
    }
}
