//! Rods as `BasisCurves`: where each rod lies in the (joined) rod's arrays
//! ([`Layout`]), its curves between cuts ([`Piece`]), and the time samples of every
//! attribute of its prim ([`RodStreams`]), written frame by frame.
//!
//! Every curve is an ordinary B-spline of the rod's degree `d`: `n` control points and
//! `n + d + 1` knots, its domain `[t_d, t_n]`. An open rod's pieces are clamped (their
//! ends are the rod's ends or cuts, knots of multiplicity `d + 1`). A closed rod without
//! cuts is its periodic curve written in the unclamped form the core keeps
//! ([`splinerod_core::PeriodicBSplineSpace`]): `m + d` control points of which the last
//! `d` repeat the first `d`, and `m + 2d + 1` knots. A closed rod's cuts open it: its
//! pieces run from cut to cut, the one across the seam with knots past the period
//! (`c + L`). Knots are the rod's own material coordinate, m (from 0 at its start).

use super::text::{close_sample, open_sample, separator, tuple, Float, Num};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};
use splinerod_core::{Real, Rod};
use std::fmt::{self, Write};

/// How one rod lies in the joined rod's arrays.
#[derive(Debug, Clone, Copy)]
pub(super) enum Layout {
    /// An open rod: control points `first .. first + len` of the joined rod, its knots
    /// `first .. first + len + d + 1` less `offset` (where it starts).
    Open {
        /// Its first control point.
        first: usize,
        /// Its number of control points.
        len: usize,
        /// The joined parameter of its material point 0.
        offset: Real,
    },
    /// A closed rod of `m` distinct control points (coefficient `j` of the
    /// bi-infinite periodic sequence is `positions[d + j mod m]`, knot `j` is
    /// `knots[d + j mod m] + period ⌊j/m⌋`).
    Closed {
        /// Distinct control points.
        m: usize,
        /// Rest length.
        period: Real,
    },
}

/// One curve of a rod: coefficients `start .. start + count` of its [`Layout`] (and
/// knots `start .. start + count + d + 1`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Piece {
    start: isize,
    count: usize,
}

impl Layout {
    /// Rod `k` of `rod` (the whole rod when it has no segments).
    pub(super) fn of(rod: &Rod, k: usize) -> Layout {
        if let Some(m) = rod.basis().periodic_count() {
            let (start, end) = rod.basis().domain();
            return Layout::Closed {
                m,
                period: end - start,
            };
        }
        let range = rod.segment_points(k);
        Layout::Open {
            first: range.start,
            len: range.len(),
            offset: rod.segments().get(k).map_or(0.0, |g| g.start),
        }
    }

    /// Coefficient `j`.
    fn point<'a>(&self, rod: &'a Rod, j: isize) -> &'a Vector3<Real> {
        match *self {
            Layout::Open { first, .. } => &rod.positions[first + j as usize],
            Layout::Closed { m, .. } => {
                let d = rod.basis().degree();
                &rod.positions[d + j.rem_euclid(m as isize) as usize]
            }
        }
    }

    /// Knot `j`, in the rod's material coordinate.
    fn knot(&self, rod: &Rod, j: isize) -> Real {
        let knots = rod.basis().knots();
        match *self {
            Layout::Open { first, offset, .. } => knots[first + j as usize] - offset,
            Layout::Closed { m, period } => {
                let d = rod.basis().degree();
                let (i, turns) = (j.rem_euclid(m as isize), j.div_euclid(m as isize));
                knots[d + i as usize] + period * turns as Real
            }
        }
    }

    /// The rod's curves, in order of their start, into `out` (emptied first).
    pub(super) fn pieces(&self, rod: &Rod, out: &mut Vec<Piece>) {
        out.clear();
        let knots = rod.basis().knots();
        let d = rod.basis().degree();
        match *self {
            Layout::Open { first, len, .. } => {
                let (lo, hi) = (knots[first + d], knots[first + len]);
                let mut start = 0;
                for c in rod.cut_points().filter(|&c| c > lo && c < hi) {
                    let run = (knots.partition_point(|&t| t < c) - first) as isize;
                    out.push(Piece {
                        start,
                        count: (run - start) as usize,
                    });
                    start = run;
                }
                let count = len - start as usize;
                out.push(Piece { start, count });
            }
            Layout::Closed { m, .. } => {
                let breaks = &knots[d..d + m];
                let seam = rod.is_cut_at_seam().then_some(0.0);
                let runs = seam.into_iter().chain(rod.cut_points());
                for c in runs {
                    let start = breaks.partition_point(|&t| t < c) as isize;
                    out.push(Piece { start, count: 0 });
                }
                if out.is_empty() {
                    out.push(Piece {
                        start: -(d as isize),
                        count: m + d,
                    });
                    return;
                }
                let first = out[0].start + m as isize;
                for i in 0..out.len() {
                    let next = out.get(i + 1).map_or(first, |p| p.start);
                    out[i].count = (next - out[i].start) as usize;
                }
            }
        }
    }
}

/// What stays the same for a rod's prim over the run.
#[derive(Debug, Clone)]
pub(super) struct Style {
    /// The rod's `name` in the scene (empty without one).
    pub name: String,
    /// Its prim's name (unique, an identifier).
    pub prim: String,
    /// Its degree.
    pub degree: usize,
    /// Whether it is closed.
    pub closed: bool,
    /// `wrap = "periodic"`: the float points leave out the last `degree` exact ones
    /// (copies of the first).
    pub periodic: bool,
    /// Drawn width (`widths`), m.
    pub width: Real,
    /// Rest length, m.
    pub rest_length: Real,
}

impl Style {
    /// `linear` for degree 1, `cubic` otherwise.
    pub(super) fn curve_type(&self) -> &'static str {
        if self.degree == 1 {
            "linear"
        } else {
            "cubic"
        }
    }

    /// `periodic`, `nonperiodic` (degree 1, or a closed rod the scene cuts), or `pinned`
    /// (an open rod of degree ≥ 2: drawn through its end points).
    pub(super) fn wrap(&self) -> &'static str {
        if self.periodic {
            "periodic"
        } else if self.closed || self.degree == 1 {
            "nonperiodic"
        } else {
            "pinned"
        }
    }
}

/// The time samples of one rod's attributes so far: each a run of lines
/// `CODE: [ … ],` (module docs of [`super`]).
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
pub(super) struct RodStreams {
    /// `curveVertexCounts`.
    pub counts: String,
    /// `points` (float).
    pub points: String,
    /// `widths`, one per point.
    pub widths: String,
    /// `extent`.
    pub extent: String,
    /// `splinerod:curveVertexCounts`.
    pub exact_counts: String,
    /// `splinerod:controlPoints` (double).
    pub control_points: String,
    /// `splinerod:knots`.
    pub knots: String,
}

impl RodStreams {
    /// Appends the samples at time code `code` of the rod `layout` places in `rod`
    /// (`pieces`: scratch).
    pub(super) fn record(
        &mut self,
        style: &Style,
        rod: &Rod,
        layout: Layout,
        code: i64,
        pieces: &mut Vec<Piece>,
    ) -> fmt::Result {
        layout.pieces(rod, pieces);
        let d = rod.basis().degree();
        // The float points: all but the last d of a periodic curve (copies).
        let drawn = |p: &Piece| p.count - if style.periodic { d } else { 0 };
        counts(&mut self.counts, code, pieces.iter().map(drawn))?;
        counts(&mut self.exact_counts, code, pieces.iter().map(|p| p.count))?;
        let mut all = pieces
            .iter()
            .flat_map(|p| (0..drawn(p)).map(|i| p.start + i as isize));
        self.float_points(style, rod, layout, code, &mut all)?;
        let exact = pieces
            .iter()
            .flat_map(|p| (0..p.count).map(|i| p.start + i as isize));
        open_sample(&mut self.control_points, code)?;
        for (i, j) in exact.enumerate() {
            separator(&mut self.control_points, i);
            tuple(&mut self.control_points, layout.point(rod, j), Num)?;
        }
        close_sample(&mut self.control_points);
        let knots = pieces
            .iter()
            .flat_map(|p| (0..p.count + d + 1).map(|i| p.start + i as isize));
        open_sample(&mut self.knots, code)?;
        for (i, j) in knots.enumerate() {
            separator(&mut self.knots, i);
            write!(self.knots, "{}", Num(layout.knot(rod, j)))?;
        }
        close_sample(&mut self.knots);
        Ok(())
    }

    /// `points`, `widths` and `extent` (the points' box grown by half the width, as
    /// `UsdGeomBasisCurves::ComputeExtent` has it) at `code`.
    fn float_points(
        &mut self,
        style: &Style,
        rod: &Rod,
        layout: Layout,
        code: i64,
        indices: &mut dyn Iterator<Item = isize>,
    ) -> fmt::Result {
        let mut lo = [f32::INFINITY; 3];
        let mut hi = [f32::NEG_INFINITY; 3];
        open_sample(&mut self.points, code)?;
        open_sample(&mut self.widths, code)?;
        for (i, j) in indices.enumerate() {
            let p = layout.point(rod, j);
            separator(&mut self.points, i);
            tuple(&mut self.points, p, Float)?;
            separator(&mut self.widths, i);
            write!(self.widths, "{}", Float(style.width))?;
            for k in 0..3 {
                lo[k] = lo[k].min(p[k] as f32);
                hi[k] = hi[k].max(p[k] as f32);
            }
        }
        close_sample(&mut self.points);
        close_sample(&mut self.widths);
        let half = 0.5 * style.width as f32;
        let (lo, hi) = (lo.map(|x| x - half), hi.map(|x| x + half));
        open_sample(&mut self.extent, code)?;
        write!(
            self.extent,
            "({}, {}, {}), ({}, {}, {})",
            lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
        )?;
        close_sample(&mut self.extent);
        Ok(())
    }
}

/// One `int[]` sample of `values` at `code`.
fn counts(out: &mut String, code: i64, values: impl Iterator<Item = usize>) -> fmt::Result {
    open_sample(out, code)?;
    for (i, n) in values.enumerate() {
        separator(out, i);
        write!(out, "{n}")?;
    }
    close_sample(out);
    Ok(())
}
