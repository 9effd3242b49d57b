//! The CLI's short human summary of a [`RunResult`].

use crate::RunResult;

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
        let energies: Vec<String> = self
            .energy
            .iter()
            .map(|(k, v)| format!("{k} {v:.6e}"))
            .collect();
        out.push_str(&format!("energy (J): {}\n", energies.join(", ")));
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
            let ratio = c
                .min_clearance_ratio
                .map_or("-".into(), |r| format!("{r:.4}"));
            out.push_str(&format!(
                "contact: min clearance {ratio}, at most {} pairs",
                c.max_pairs
            ));
            if c.max_obstacle_contacts > 0 {
                let n = c.max_obstacle_contacts;
                out.push_str(&format!(", {n} points on the floor and obstacles"));
            }
            if let Some(k) = c.stiffness_used {
                out.push_str(&format!(", stiffness {k:.3e} N/m"));
            }
            if let (Some(g), Some(t)) = (c.end_gap, c.tolerance) {
                out.push_str(&format!(", end gap {g:.3e} m (tolerance {t:.3e} m)"));
            }
            out.push('\n');
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
}
