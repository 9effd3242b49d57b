//! How a [`Simulation`] takes its steps: how many reach a time, and the steps taken
//! with the GIL released and Ctrl-C heard.

use crate::driver::Driver;
use crate::errors::{guard, scene_error};
use crate::interrupt::Interrupt;
use crate::simulation::Simulation;
use pyo3::prelude::*;
use splinerod::Real;

impl Simulation {
    /// Steps a dynamic simulation needs to reach `until` (the scene's end by default).
    pub(crate) fn steps_until(&self, py: Python<'_>, until: Option<Real>) -> PyResult<usize> {
        let (done, scheduled, dt) = match &self.driver {
            Driver::Scene(run) => (run.stages_done(), Some(run.stage_count()), run.dt()),
            Driver::Code { dt, calls, .. } => (*calls, None, *dt),
        };
        if self.driver.is_static() {
            return Ok(usize::from(done == 0));
        }
        let Some(until) = until else {
            return scheduled.map(|n| n.saturating_sub(done)).ok_or_else(|| {
                scene_error(
                    py,
                    Some("until"),
                    "a simulation built in code needs `until`",
                )
            });
        };
        let until = crate::arrays::finite(py, "until", until)?;
        let left = (until - self.driver.sims()[0].time) / dt;
        Ok((left * (1.0 - 1e-12)).ceil().max(0.0) as usize)
    }

    /// Makes `n` steps with the GIL released; Ctrl-C raises `KeyboardInterrupt` within
    /// about a second, the state the one after the last completed step
    /// ([`crate::interrupt`]).
    pub(crate) fn advance(&mut self, py: Python<'_>, n: usize) -> PyResult<()> {
        let interrupt = Interrupt::new();
        let (driver, cancel) = (&mut self.driver, &interrupt.cancel);
        guard(&mut self.poisoned, || {
            let made = py.detach(|| driver.advance(n, cancel));
            interrupt.result(py, made)
        })
    }
}
