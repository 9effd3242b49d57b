//! Cost of the adapt stage (error estimate, marks, maps) for `splinerod bench`: the
//! step of [`crate::bench`]'s cable with a tolerance-driven adapter whose tolerance is
//! never reached (so the resolution stays and only the stage's cost is measured),
//! against the same step without adaptivity.

use crate::bench::one_iteration;
use crate::estimate::MAX_INTERVAL;
use crate::problems::pinned_cable;
use crate::{Error, Simulation};
use splinerod_adaptivity::{AdaptParams, Adapter, ToleranceCriterion};
use splinerod_core::Real;
use std::time::Instant;

/// Mean step time (s) of an `n`-point cable over `reps` steps, with the adapt stage if
/// `adapt` (a mean, since estimates are made every few steps once the rod is steady).
fn step_seconds(n: usize, reps: usize, adapt: bool) -> Result<Real, Error> {
    let mut sim = Simulation::new(pinned_cable(n, 1.05, 100.0)?, one_iteration()?);
    if adapt {
        let params = AdaptParams {
            max_control_points: n,
            min_control_points: n,
            ..AdaptParams::default()
        };
        let criterion = ToleranceCriterion::new(1.0)?;
        sim = sim.with_adapter(Adapter::new(params)?.with(criterion));
    }
    // Past the schedule's start-up (estimates every step until the rod is steady).
    for _ in 0..3 * MAX_INTERVAL {
        sim.step(1e-3)?;
    }
    let t = Instant::now();
    for _ in 0..reps {
        sim.step(1e-3)?;
    }
    Ok(t.elapsed().as_secs_f64() / reps as Real)
}

/// The adapt stage's time over the step's, at 16 control points.
pub fn adapt_fraction_16(reps: usize) -> Result<Real, Error> {
    let plain = step_seconds(16, reps, false)?;
    let adaptive = step_seconds(16, reps, true)?;
    Ok((adaptive - plain) / plain)
}

/// The adapt stage's time per control point (ns) at `n` control points.
pub fn adapt_ns_per_cp(n: usize, reps: usize) -> Result<Real, Error> {
    let plain = step_seconds(n, reps, false)?;
    let adaptive = step_seconds(n, reps, true)?;
    Ok((adaptive - plain) * 1e9 / n as Real)
}
