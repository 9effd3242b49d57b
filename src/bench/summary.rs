//! The bench's results as the command line prints them, one line per figure.

use crate::bench::BenchResult;

impl BenchResult {
    /// The figures in words, one line each (what `splinerod bench` prints).
    pub fn summary(&self) -> Vec<String> {
        let mut lines = Vec::new();
        lines.push(format!(
        "one implicit Euler step, 16 control points: {:.2} µs ({:.2} µs with the consistent stretching)",
        self.step_us_16, self.step_us_16_consistent
    ));
        lines.push(format!(
            "one static Newton iteration, 16 control points: {:.2} µs",
            self.static_newton_us_16
        ));
        lines.push(format!(
            "8 independent 16-point rods in one system: {:.3} × eight single-rod steps",
            self.world_overhead_8
        ));
        lines.push(format!(
            "knot tying with contact (knot_tying_adaptive.toml, first 0.5 s): {:.0} µs median step",
            self.knot_step_us
        ));
        for (n, ns) in &self.per_cp_ns {
            lines.push(format!("per control point per step at {n}: {ns:.0} ns"));
        }
        lines.push(format!(
            "flatness (max/min per control point): {:.3}",
            self.per_cp_flatness
        ));
        lines.push(format!(
        "ensemble of 16-point rods: {:.0} rod-steps/s on 1 thread, {:.0} on {} ({:.0} % efficiency)",
        self.ensemble_rod_steps_per_s_1,
        self.ensemble_rod_steps_per_s_all,
        self.threads,
        100.0 * self.parallel_efficiency
    ));
        lines.push(format!(
            "  batched four at a time: {:.2} times the {:.0} rod-steps/s of members stepped alone",
            self.batched_speedup, self.ensemble_rod_steps_per_s_alone_1
        ));
        lines.push(format!(
            "memory: {:.0} bytes per control point",
            self.bytes_per_cp
        ));
        lines.push(format!(
            "checkpoint of the default scene after 100 steps: {:.0} bytes, written in {:.0} µs",
            self.checkpoint_bytes_16, self.checkpoint_us_16
        ));
        lines.push(format!(
        "stiff catenary (EA = 1e4) settled to {:.2e} m with {} control points in {} steps, {:.3} s",
        self.stiff_catenary.1,
        self.stiff_catenary.0,
        self.stiff_catenary.2,
        self.stiff_catenary_settle_s
    ));
        let converged = self
            .hard_cases_converged
            .map_or("not run with --quick".into(), |n| {
                format!("{n} of {}", self.hard_cases_total)
            });
        lines.push(format!(
            "hard cases converged: {converged}; default scene: {:.3} Newton iterations per step",
            self.newton_per_step_default
        ));
        lines
    }
}
