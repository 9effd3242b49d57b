//! The CLI's short human summary of a [`RunResult`]: a line for what acts, none for
//! what does not (an energy that is exactly zero at the end, contact that never
//! touched).

use crate::run::ensemble::MemberSummary;
use crate::run::result::RunResult;
use crate::run::totals::ContactStats;

impl RunResult {
    /// A short human summary: steps, control points, wall time, final energies.
    pub fn summary(&self) -> String {
        let mut out = format!(
            "{} steps to t = {:.4} s, {} control points, {:.3} s wall ({} Newton iterations)\n",
            self.steps,
            self.time,
            self.control_points,
            self.wall_seconds,
            self.solver.newton_iterations
        );
        if self.steps > 0 {
            let us = self.median_step_seconds * 1e6;
            out.push_str(&format!("median step: {us:.1} µs\n"));
        }
        out.push_str(&self.energy_line());
        out.push_str(&self.ensemble_line());
        if self.control_points_history.len() > 1 {
            let counts = self.control_points_history.iter().map(|h| h[1] as usize);
            let (lo, hi) = counts.fold((usize::MAX, 0), |(a, b), n| (a.min(n), b.max(n)));
            out.push_str(&format!(
                "resolution: {} changes, {lo} to {hi} control points\n",
                self.control_points_history.len() - 1
            ));
        }
        if let Some(a) = &self.adaptivity {
            let e = a.estimated_error;
            out.push_str(&format!("estimated error: {e:.2e} m\n"));
        }
        if self.pieces > self.rods.len().max(1) {
            out.push_str(&format!("{} pieces after cutting\n", self.pieces));
        }
        if let Some(k) = &self.knot {
            let last = k.knot_length.last().copied().flatten();
            let first = k.knot_length.first().copied().flatten();
            if let (Some(a), Some(b)) = (first, last) {
                out.push_str(&format!("knot length: {a:.4} m -> {b:.4} m of rod\n"));
            }
        }
        if let Some(c) = &self.contact {
            out.push_str(&self.contact_line(c));
        }
        if self.solver.unconverged_steps > 0 {
            out.push_str(&format!(
                "note: {} steps stopped at the Newton iteration limit\n",
                self.solver.unconverged_steps
            ));
        }
        let s = &self.solver;
        if s.rejected_steps > 0 {
            let h = s.smallest_dt.unwrap_or_default();
            out.push_str(&format!(
                "sub-stepping: {} rejected sub-steps retried shorter, shortest {h:.3e} s\n",
                s.rejected_steps
            ));
        }
        if s.continuation_steps > 0 {
            out.push_str(&format!(
                "static solve: Newton needed {} continuation steps\n",
                s.continuation_steps
            ));
        }
        out
    }

    /// The final energies that are not exactly zero (a term that does nothing at the end,
    /// such as a load ramped to zero, is left out), naming the member they belong to in
    /// an ensemble.
    fn energy_line(&self) -> String {
        let acting: Vec<String> = self
            .energy
            .iter()
            .filter(|(_, v)| **v != 0.0)
            .map(|(k, v)| format!("{k} {v:.6e}"))
            .collect();
        let whose = match self.ensemble.first() {
            Some(m) => format!(" of member {}", m.index),
            None => String::new(),
        };
        match acting.is_empty() {
            true => format!("energy (J){whose}: every term 0\n"),
            false => format!("energy (J){whose}: {}\n", acting.join(", ")),
        }
    }

    /// For an ensemble: how many members ran and the spread of their final sag and total
    /// energy (the JSON's `ensemble` has each member's); empty otherwise.
    fn ensemble_line(&self) -> String {
        let (Some(first), Some(last)) = (self.ensemble.first(), self.ensemble.last()) else {
            return String::new();
        };
        let range = |f: &dyn Fn(&MemberSummary) -> f64| {
            let values = self.ensemble.iter().map(f);
            values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            })
        };
        let (sag_lo, sag_hi) = range(&|m| m.sag);
        let (e_lo, e_hi) = range(&|m| m.energy.values().sum());
        format!(
            "ensemble: {} members ({} to {}), sag {sag_lo:.4e} to {sag_hi:.4e} m, \
             total energy {e_lo:.6e} to {e_hi:.6e} J\n",
            self.ensemble.len(),
            first.index,
            last.index,
        )
    }

    /// What touched: pairs of strands, and points against the floor or obstacles, then
    /// the stiffness used and the smallest gap at the end against the tolerance; empty
    /// when nothing came within the contact's reach.
    fn contact_line(&self, c: &ContactStats) -> String {
        let mut parts = Vec::new();
        if let Some(r) = c.min_clearance_ratio {
            parts.push(format!("min clearance ratio {r:.4}"));
        }
        if c.max_pairs > 0 {
            parts.push(format!("at most {} pairs of strands", c.max_pairs));
        }
        if c.max_obstacle_contacts > 0 {
            let what = match self.obstacle_forces.is_empty() {
                true => "the floor",
                false => "the floor or an obstacle",
            };
            let n = c.max_obstacle_contacts;
            parts.push(format!("at most {n} points against {what}"));
        }
        if parts.is_empty() {
            return String::new();
        }
        if let Some(k) = c.stiffness_used {
            parts.push(format!("stiffness {k:.3e} N/m"));
        }
        if let (Some(g), Some(t)) = (c.end_gap, c.tolerance) {
            parts.push(format!("end gap {g:.3e} m (tolerance {t:.3e} m)"));
        }
        match parts.is_empty() {
            true => String::new(),
            false => format!("contact: {}\n", parts.join(", ")),
        }
    }
}
