//! Cutting (paper §5.1): raising the multiplicity of an interior knot `s` to `d + 1`
//! makes the curve discontinuous there; no basis function straddles `s`, so the mass
//! matrix, every energy integrated span by span and every Newton matrix decouple into
//! independent pieces with no other special treatment.

use crate::{CoreError, KnotMap, Real, Rod};

impl Rod {
    /// Cuts the rod at material coordinate `s` (strictly inside `(0, L)`; on a closed rod
    /// also `0` or `L`, its seam) by exact knot insertions until `s` has multiplicity
    /// `degree + 1`; returns the number of insertions. Errors, changing nothing, if `s`
    /// is outside the rod or already a cut.
    pub fn cut(&mut self, s: Real) -> Result<usize, CoreError> {
        self.cut_with(s, &mut |_, _| {})
    }

    /// [`cut`](Self::cut), calling `on_change` with the rod after each insertion's map
    /// (for data that must follow the basis, e.g. energies' caches).
    pub fn cut_with(
        &mut self,
        s: Real,
        on_change: &mut dyn FnMut(&Rod, &KnotMap),
    ) -> Result<usize, CoreError> {
        let d = self.basis().degree();
        let (start, end) = self.basis().domain();
        // A closed rod may also be cut at its seam (s = 0, the same point as s = L).
        let seam = self.is_closed() && (s == start || s == end);
        let s = if seam { start } else { s };
        let inside = s > start && s < end;
        if !(inside || seam) {
            return Err(CoreError::OutsideDomain { s, start, end });
        }
        let present = self.knot_multiplicity(s);
        if present > d {
            return Err(CoreError::MultiplicityTooHigh {
                value: s,
                multiplicity: present + 1,
                max: d + 1,
            });
        }
        for _ in present..=d {
            let map = self.insert_knot(s)?;
            on_change(self, &map);
        }
        Ok(d + 1 - present)
    }

    /// Multiplicity of the value `s` in the knot vector (O(log n): knots are sorted).
    pub fn knot_multiplicity(&self, s: Real) -> usize {
        let knots = self.basis().knots();
        knots.partition_point(|&t| t <= s) - knots.partition_point(|&t| t < s)
    }

    /// Material coordinates of the cuts (interior knots of multiplicity `degree + 1`),
    /// increasing, without allocating. One pass over the knots.
    pub fn cut_points(&self) -> impl Iterator<Item = Real> + '_ {
        let d = self.basis().degree();
        let (start, end) = self.basis().domain();
        let knots = self.basis().knots();
        let mut run = 0;
        knots.iter().enumerate().filter_map(move |(i, &t)| {
            run = if i > 0 && knots[i - 1] == t {
                run + 1
            } else {
                1
            };
            (run == d + 1 && t > start && t < end).then_some(t)
        })
    }

    /// [`cut_points`](Self::cut_points), collected.
    pub fn cuts(&self) -> Vec<Real> {
        self.cut_points().collect()
    }

    /// Number of mechanically independent pieces: one more than the number of cuts, or
    /// for a closed rod as many as its cuts (the first cut opens the loop; a cut at the
    /// seam counts), at least one.
    pub fn pieces(&self) -> usize {
        let cuts = self.cut_points().count();
        match self.is_closed() {
            true => (cuts + usize::from(self.is_cut_at_seam())).max(1),
            false => cuts + 1,
        }
    }

    /// Whether a closed rod is cut at its seam (the knot `0` of multiplicity
    /// `degree + 1`); never for an open rod, whose ends are no cut.
    pub fn is_cut_at_seam(&self) -> bool {
        self.is_closed() && self.knot_multiplicity(0.0) > self.basis().degree()
    }

    /// Whether knot `index` belongs to a cut (removing it would reconnect two pieces).
    pub fn is_cut_knot(&self, index: usize) -> bool {
        let d = self.basis().degree();
        self.basis()
            .knots()
            .get(index)
            .is_some_and(|&t| self.knot_multiplicity(t) > d)
    }
}
