//! Contact detection between parts of one rod, on *contact segments*: the rest arclength
//! of each piece (between cuts) is divided at the multiples of a length `ℓ`, whatever
//! the knots, so the segments — and the contact energy — do not change when knots are
//! inserted or removed.
//!
//! **Broad phase.** Each segment lies in a box: the speed of the curve is bounded on a
//! knot span by the derivative's control points,
//! \\(|C'| \le V = \max_i d\, |q_i - q_{i-1}| / (t_{i+d} - t_i)\\) (convex-hull property
//! of the derivative curve), so with samples `h` apart the segment lies within `V h/2`
//! of its samples: the box of its samples widened by that. The boxes are sorted along
//! the axis of widest spread and swept; two segments are candidates when their boxes
//! come within the reach `2r + δ` on every axis and they are
//! at least `exclusion` apart along the rod (closer segments are neighbours: their
//! closest points would be where they join; across a cut too, so the two new ends of a
//! cut separate freely; on a closed rod, also around the seam). Cost O(m log m) for `m` segments, plus the candidates.
//!
//! **Sample pairs.** Each segment carries material sample points (midpoint rule, at most
//! `spacing` apart, with their basis rows cached per basis); the contact energy sums a
//! penalty over every pair of samples of candidate segments closer than the reach — a
//! quadrature of the double integral over both strands, so crossing strands and strands
//! lying alongside each other are treated alike and the energy is as smooth as the
//! penalty. The samples move with the material, not with the knots, so knot insertion
//! does not change the energy.
//!
//! **Closest points** between candidate segments ([`closest_points_between`], on the
//! curve) are computed on request only, for reporting distances and for refinement.
//!
//! The detection is cached on the positions and the basis epoch: the energy, gradient
//! and Hessian of one Newton iterate detect once. Between iterates and steps, a
//! **Verlet list** (the `Skin` of `contact/skin.rs`) spares the broad phase and the far
//! sample pairs: a full detection lists every sample pair closer than `reach + margin`
//! (margin `SKIN · reach`), and until some control point has moved by `margin / 2`
//! since, a detection re-measures only those pairs — the same pairs closer than the reach as a
//! full detection would find (possibly listed in another order, which changes sums by
//! round-off only). No allocation once the buffers have grown.

use super::assemble::GroupHessian;
use super::sample_sums::SampleSums;
use super::skin::{Skin, SKIN};
use nalgebra::Vector3;
use splinerod_core::proximity::{closest_points_between, BoxSweep};
use splinerod_core::segments::just_below;
use splinerod_core::{BasisValues, CoreError, Real, Rod, SavedState, StateReader};

/// Closest points `C(s)` and `C(t)` of two contact segments closer than the reach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPoint {
    /// Material coordinate on the first part, m of rest arclength.
    pub s: Real,
    /// Material coordinate on the second part, m of rest arclength.
    pub t: Real,
    /// Distance \\(|C(s) - C(t)|\\) between the centre lines, m.
    pub distance: Real,
    /// Unit vector from `C(t)` to `C(s)`.
    pub normal: Vector3<Real>,
}

/// Two samples closer than the reach: indices, distance and unit vector from `t` to `s`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SamplePair {
    pub a: u32,
    pub b: u32,
    pub distance: Real,
    pub normal: Vector3<Real>,
}

/// Material sample points with their quadrature weights and cached basis rows.
#[derive(Debug, Clone, Default)]
pub(crate) struct Samples {
    pub s: Vec<Real>,
    pub weight: Vec<Real>,
    pub first: Vec<u32>,
    pub values: Vec<Real>,
    pub order: usize,
    pub position: Vec<Vector3<Real>>,
}

impl Samples {
    /// Basis values of sample `k`, for control points `first[k]..`.
    pub fn row(&self, k: usize) -> &[Real] {
        &self.values[k * self.order..(k + 1) * self.order]
    }

    /// Position of sample `k` for control points `q`: \(\sum_a b_a q_{first + a}\),
    /// summed in order (the cubic case written out, same operations).
    #[inline(always)]
    fn at(&self, k: usize, q: &[Vector3<Real>]) -> Vector3<Real> {
        let first = self.first[k] as usize;
        // The row's control points, sliced once (no bounds check per term).
        let q = &q[first..first + self.order];
        let row = self.row(k);
        if let (Ok(q), Ok(b)) = (<&[_; 4]>::try_from(q), <&[Real; 4]>::try_from(row)) {
            return Vector3::from_fn(|c, _| {
                let term = |a: usize| q[a][c] * b[a];
                (((0.0 + term(0)) + term(1)) + term(2)) + term(3)
            });
        }
        q.iter()
            .zip(row)
            .fold(Vector3::zeros(), |acc, (qa, &b)| acc + qa * b)
    }
}

/// A contact segment: its rest-arclength range and its samples.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Segment {
    pub lo: Real,
    pub hi: Real,
    /// Its samples: `samples[first..end]`.
    pub first: usize,
    pub end: usize,
}

/// Buffers and cache of the detection.
#[derive(Debug, Clone, Default)]
pub(crate) struct Detector {
    segments: Vec<Segment>,
    /// Boxes of the segments' curves: their samples' boxes widened by half the speed
    /// bound times the sample spacing.
    lower: Vec<Vector3<Real>>,
    /// Per segment: how far its curve may stray from its samples, `V h / 2`.
    widen: Vec<Real>,
    upper: Vec<Vector3<Real>>,
    /// Speed bound of each non-empty span `k` (index `k`; 0 for empty spans).
    span_speed: Vec<Real>,
    sweep: BoxSweep,
    breaks: Vec<Real>,
    /// The samples of every segment.
    pub samples: Samples,
    /// Sample pairs closer than the reach, from the last detection.
    pub pairs: Vec<SamplePair>,
    /// `pairs[start..end]` of each candidate segment pair with touching samples.
    pub groups: Vec<(usize, usize)>,
    /// Scratch for assembling one group's Hessian.
    pub group_hessian: GroupHessian,
    /// Scratch: the pairs' one-sample terms, summed per sample.
    pub sums: SampleSums,
    /// Candidate segment pairs of the last broad phase.
    candidates: Vec<(u32, u32)>,
    /// Segment pairs the last closest-point search examined.
    examined: Vec<(u32, u32)>,
    /// Closest points of touching candidates (filled by [`Detector::closest`]).
    pub closest: Vec<ContactPoint>,
    closest_done: bool,
    /// Whether `candidates` are for the exact reach (else for the skin's wider one).
    candidates_exact: bool,
    /// Whether every sample's position is current (else only the skin's samples').
    placed_all: bool,
    layout: Option<(u64, [Real; 2])>,
    cached: Option<(u64, [Real; 4])>,
    positions: Vec<Vector3<Real>>,
    /// The Verlet list of the last full detection (see [`Skin`]).
    skin: Skin,
}

impl Detector {
    /// Appends the Verlet list (see [`Skin::save`]) and the sample positions as they
    /// stand (a warm list updates only its own samples; the others keep the positions of
    /// the last full placement, which the closest-point prefilter reads).
    pub fn save_state(&self, out: &mut SavedState) {
        self.skin.save(out);
        out.vectors(&self.samples.position);
        out.int(u64::from(self.placed_all));
    }

    /// Forgets what was made for the rod's former knots (sample layout, Verlet list,
    /// sample positions, cached detection) after a knot change. The next detection
    /// rebuilds them anyway (they are keyed on the old topology); a checkpoint taken
    /// before it then saves no list laid out for pieces the restored rod lacks.
    pub fn forget_topology(&mut self) {
        self.layout = None;
        self.cached = None;
        self.skin.forget();
        self.samples.position.clear();
        self.placed_all = false;
    }

    /// Reads back the Verlet list for `rod`, laying out its samples.
    pub fn load_state(&mut self, rod: &Rod, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        *self = Self::default();
        let epoch = rod.topology_epoch();
        self.skin.load(input, epoch)?;
        if let Some([segment, spacing]) = self.skin.layout() {
            self.build_segments(rod, segment, spacing)?;
            self.layout = Some((epoch, [segment, spacing]));
            if !self.skin.fits(self.samples.s.len(), self.segments.len()) {
                self.skin = Skin::default();
                return Err(CoreError::StateMismatch("a contact list of another rod"));
            }
        }
        input.vectors_into(&mut self.samples.position)?;
        self.placed_all = input.int()? == 1;
        let placed = self.samples.position.len();
        if self.layout.is_some() && placed != self.samples.s.len() {
            *self = Self::default();
            return Err(CoreError::StateMismatch("contact samples of another rod"));
        }
        Ok(())
    }

    /// Detects sample pairs closer than `reach` (m) on segments of length `segment` (m)
    /// at least `exclusion` (m) apart along the rod, with samples at most `spacing` (m)
    /// apart, unless the rod is unchanged since the last call with the same settings.
    /// With `every_sample`, every sample's position is made current (obstacles visit
    /// them all); otherwise only those of sample pairs that may be within reach.
    pub fn detect(
        &mut self,
        rod: &Rod,
        reach: Real,
        exclusion: Real,
        [segment, spacing]: [Real; 2],
        every_sample: bool,
    ) -> Result<(), CoreError> {
        let epoch = rod.topology_epoch();
        let key = (epoch, [reach, exclusion, segment, spacing]);
        if self.cached == Some(key)
            && self.positions == rod.positions
            && (self.placed_all || !every_sample)
        {
            return Ok(());
        }
        self.cached = None;
        if self.layout != Some((epoch, [segment, spacing])) {
            self.layout = None;
            self.build_segments(rod, segment, spacing)?;
            self.layout = Some((epoch, [segment, spacing]));
        }
        if self.skin.holds(rod, key) {
            self.placed_all = every_sample;
            if every_sample {
                self.place_samples(rod);
            } else {
                self.place_skin_samples(rod);
            }
        } else {
            let margin = SKIN * reach;
            self.place_samples(rod);
            self.placed_all = true;
            self.segment_widths(rod);
            self.bound_segments();
            let period = rod.is_closed().then(|| rod.material().rest_length);
            self.sweep(reach + margin, exclusion, period);
            self.candidates_exact = false;
            let wide = reach + margin;
            let p = &self.samples.position;
            self.skin.build(
                &self.candidates,
                (&self.segments, [&self.lower, &self.upper]),
                p,
                wide,
                self.samples.s.len(),
            );
            self.skin.reference.clone_from(&rod.positions);
            (self.skin.key, self.skin.margin) = (Some(key), margin);
        }
        let p = &self.samples.position;
        self.skin
            .within(p, reach, &mut self.pairs, &mut self.groups);
        self.closest.clear();
        self.closest_done = false;
        self.positions.clone_from(&rod.positions);
        self.cached = Some(key);
        Ok(())
    }

    /// Fills [`closest`](Self::closest) with the closest points of every candidate
    /// segment pair closer than `reach` (after a [`detect`](Self::detect) at this state).
    ///
    /// The segment pairs examined are those with a sample pair closer than `reach`
    /// plus how far each curve strays from its samples (`V h / 2`): no other pair's
    /// curves come within `reach`. They are found in the skin's list when the skin
    /// certifies it holds them all ([`Skin::covers`]), else by a broad phase at `reach`.
    pub fn closest(&mut self, rod: &Rod, reach: Real) -> Result<(), CoreError> {
        if self.closest_done {
            return Ok(());
        }
        self.segment_widths(rod);
        let widest = self.widen.iter().copied().fold(0.0, Real::max);
        self.examined.clear();
        if self.skin.covers(rod, 2.0 * widest) {
            let p = &self.samples.position;
            let widen = &self.widen;
            let bound = |a: usize, b: usize| reach + widen[a] + widen[b];
            self.skin.pairs_within(p, bound, &mut self.examined);
        } else {
            if !self.candidates_exact {
                // The skin's candidates are for a wider reach: the exact ones.
                if !self.placed_all {
                    self.place_samples(rod);
                    self.placed_all = true;
                }
                let exclusion = self.skin.key.map_or(0.0, |(_, settings)| settings[1]);
                self.bound_segments();
                let period = rod.is_closed().then(|| rod.material().rest_length);
                self.sweep(reach, exclusion, period);
                self.candidates_exact = true;
            }
            for k in 0..self.candidates.len() {
                let (a, b) = self.candidates[k];
                if self.samples_within(a as usize, b as usize, reach) {
                    self.examined.push((a, b));
                }
            }
        }
        self.closest.clear();
        for &(a, b) in &self.examined {
            let (sa, sb) = (&self.segments[a as usize], &self.segments[b as usize]);
            let c = closest_points_between(
                rod,
                [sa.lo, just_below(sa.hi).max(sa.lo)],
                [sb.lo, just_below(sb.hi).max(sb.lo)],
            )?;
            if c.distance < reach {
                self.closest.push(ContactPoint {
                    s: c.s,
                    t: c.t,
                    distance: c.distance,
                    normal: c.normal,
                });
            }
        }
        self.closest_done = true;
        Ok(())
    }

    /// The segments of every piece and their samples with basis rows.
    fn build_segments(&mut self, rod: &Rod, length: Real, spacing: Real) -> Result<(), CoreError> {
        self.piece_breaks(rod);
        self.segments.clear();
        let samples = &mut self.samples;
        for v in [&mut samples.s, &mut samples.weight, &mut samples.values] {
            v.clear();
        }
        samples.first.clear();
        samples.order = rod.basis().degree() + 1;
        let mut row = BasisValues::default();
        for p in 1..self.breaks.len() {
            let (start, end) = (self.breaks[p - 1], self.breaks[p]);
            let count = ((end - start) / length).ceil().max(1.0) as usize;
            let h = (end - start) / count as Real;
            for k in 0..count {
                let lo = start + k as Real * h;
                let hi = if k + 1 == count { end } else { lo + h };
                let first = samples.s.len();
                let m = ((hi - lo) / spacing).ceil().max(1.0) as usize;
                for j in 0..m {
                    let s = lo + (j as Real + 0.5) * (hi - lo) / m as Real;
                    rod.basis().evaluate_values(s, &mut row)?;
                    samples.s.push(s);
                    samples.weight.push((hi - lo) / m as Real);
                    samples.first.push(row.first as u32);
                    samples
                        .values
                        .extend_from_slice(&row.value[..samples.order]);
                }
                self.segments.push(Segment {
                    lo,
                    hi,
                    first,
                    end: samples.s.len(),
                });
            }
        }
        Ok(())
    }

    /// Sample positions at the rod's current control points.
    fn place_samples(&mut self, rod: &Rod) {
        let samples = &mut self.samples;
        // Every entry is overwritten: no need to clear.
        samples.position.resize(samples.s.len(), Vector3::zeros());
        for k in 0..samples.s.len() {
            samples.position[k] = samples.at(k, &rod.positions);
        }
    }

    /// Positions of the skin's samples only.
    fn place_skin_samples(&mut self, rod: &Rod) {
        let samples = &mut self.samples;
        for &k in &self.skin.samples {
            let k = k as usize;
            samples.position[k] = samples.at(k, &rod.positions);
        }
    }

    /// Whether two segments' curves may come closer than `reach`: some pair of their
    /// samples is closer than `reach` plus how far each curve strays from its samples
    /// (else the closest points' distance is at least `reach`, and the closest-point
    /// iteration is skipped).
    fn samples_within(&self, a: usize, b: usize, reach: Real) -> bool {
        let (sa, sb) = (&self.segments[a], &self.segments[b]);
        let bound = reach + self.widen[a] + self.widen[b];
        let p = &self.samples.position;
        let bound2 = bound * bound * (1.0 + 1e-9);
        (sa.first..sa.end)
            .any(|i| (sb.first..sb.end).any(|j| (p[i] - p[j]).norm_squared() < bound2))
    }

    /// The domain's ends and the cuts, in order.
    fn piece_breaks(&mut self, rod: &Rod) {
        let (start, end) = rod.basis().domain();
        self.breaks.clear();
        self.breaks.push(start);
        self.breaks.extend(rod.cut_points());
        self.breaks.push(end);
    }

    /// Per segment, how far its curve may stray from its samples, `V h / 2`: `V` the
    /// speed bound of the spans it meets and `h` its sample spacing (the curve between
    /// two samples, or between an end and its sample, stays that close to a sample).
    fn segment_widths(&mut self, rod: &Rod) {
        let d = rod.basis().degree();
        let knots = rod.basis().knots();
        let q = &rod.positions;
        let speed = |first: usize| {
            (first + 1..=first + d)
                .map(|i| d as Real * (q[i] - q[i - 1]).norm() / (knots[i + d] - knots[i]))
                .fold(0.0, Real::max)
        };
        // Each span's bound once (segments are shorter than spans and share them).
        self.span_speed.clear();
        self.span_speed.resize(knots.len(), 0.0);
        for j in d..knots.len().saturating_sub(d + 1) {
            if knots[j + 1] > knots[j] {
                self.span_speed[j] = speed(j - d);
            }
        }
        // Non-empty spans [knots[k], knots[k + 1]], k = first + d, in order.
        let mut k = d;
        self.widen.clear();
        for seg in &self.segments {
            while knots[k + 1] <= seg.lo {
                k += 1;
            }
            let mut v: Real = 0.0;
            let mut j = k;
            while j + 1 < knots.len() && knots[j] < seg.hi {
                if knots[j + 1] > knots[j] {
                    v = v.max(self.span_speed[j]);
                }
                j += 1;
            }
            let h = (seg.hi - seg.lo) / (seg.end - seg.first) as Real;
            self.widen.push(0.5 * v * h);
        }
    }

    /// Boxes of the segments: the box of the samples widened by
    /// [`segment_widths`](Self::segment_widths) (computed already).
    fn bound_segments(&mut self) {
        let p = &self.samples.position;
        self.lower.clear();
        self.upper.clear();
        for (seg, &w) in self.segments.iter().zip(&self.widen) {
            let widen = Vector3::repeat(w);
            // Plain comparisons (positions are finite): a min/max instruction each.
            let (mut lo, mut hi) = ([Real::INFINITY; 3], [Real::NEG_INFINITY; 3]);
            for x in &p[seg.first..seg.end] {
                for c in 0..3 {
                    lo[c] = if x[c] < lo[c] { x[c] } else { lo[c] };
                    hi[c] = if x[c] > hi[c] { x[c] } else { hi[c] };
                }
            }
            self.lower.push(Vector3::from(lo) - widen);
            self.upper.push(Vector3::from(hi) + widen);
        }
    }

    /// Sort and sweep over the segment boxes ([`BoxSweep`]): candidate segment pairs,
    /// boxes closer than `reach` on every axis and segments at least `exclusion` apart
    /// along the rod.
    /// Candidate segment pairs: boxes within `reach`, segments at least `exclusion`
    /// apart along the rod — around the loop either way for a closed rod of length
    /// `period`.
    fn sweep(&mut self, reach: Real, exclusion: Real, period: Option<Real>) {
        self.candidates.clear();
        self.sweep.sort(&self.lower, &self.upper);
        let (segments, candidates) = (&self.segments, &mut self.candidates);
        self.sweep.pairs(&self.lower, &self.upper, reach, |i, j| {
            let (first, second) = if segments[i].lo < segments[j].lo {
                (i, j)
            } else {
                (j, i)
            };
            let apart = segments[second].lo - segments[first].hi;
            let around = period.map_or(Real::INFINITY, |l| {
                l - segments[second].hi + segments[first].lo
            });
            if apart.min(around) >= exclusion {
                candidates.push((first as u32, second as u32));
            }
        });
    }

    /// Number of segment pairs the last closest-point search examined (those whose
    /// curves may come within the reach, see [`Detector::closest`]).
    pub fn candidate_count(&self) -> usize {
        self.examined.len()
    }
}
