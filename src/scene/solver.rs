//! Validation of `[solver]` and the sub-stepping settings it gives a simulation.

use crate::scene::{positive, Method, Scene};
use crate::world::substep::StepControl;
use crate::Error;

impl Scene {
    /// The sub-stepping settings of `[solver]` (`min_dt`, `time_tolerance`).
    pub fn step_control(&self) -> StepControl {
        StepControl {
            min_dt: self.solver.min_dt,
            time_tolerance: self.solver.time_tolerance,
        }
    }

    pub(crate) fn validate_solver(&self) -> Result<(), Error> {
        let s = &self.solver;
        if s.method != Method::Static {
            positive(
                "solver.dt",
                s.dt.ok_or_else(|| {
                    Error::field("solver.dt", "missing", "time stepping needs a time step")
                })?,
            )?;
            let duration = s.duration.ok_or_else(|| {
                Error::field(
                    "solver.duration",
                    "missing",
                    "time stepping needs a duration",
                )
            })?;
            positive("solver.duration", duration)?;
        } else {
            for (name, value) in [("solver.dt", s.dt), ("solver.duration", s.duration)] {
                if let Some(v) = value {
                    positive(name, v)?;
                }
            }
        }
        if let Some(m) = s.max_step {
            positive("solver.max_step", m)?;
        }
        if s.newton_iterations == Some(0) {
            return Err(Error::field(
                "solver.newton_iterations",
                0,
                "must be at least 1",
            ));
        }
        if let Some(t) = s.tolerance {
            positive("solver.tolerance", t)?;
        }
        if let Some(t) = s.time_tolerance {
            positive("solver.time_tolerance", t)?;
        }
        if let Some(m) = s.min_dt {
            positive("solver.min_dt", m)?;
            if let Some(dt) = s.dt.filter(|&dt| m > dt) {
                let reason = format!("must not exceed solver.dt = {dt}");
                return Err(Error::field("solver.min_dt", m, reason));
            }
        }
        Ok(())
    }
}
