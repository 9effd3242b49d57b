//! Cost of the adapt stage (error estimate, marks, maps) for `splinerod bench`: the
//! step of [`crate::bench`]'s cable with a tolerance-driven adapter whose tolerance is
//! never reached (so the resolution stays and only the stage's cost is measured). The
//! stage is timed inside each step ([`crate::StepReport::stages`]) and summed, so
//! the figures do not depend on two separate runs agreeing on the machine's speed.

use crate::bench::one_iteration;
use crate::problems::pinned_cable;
use crate::world::estimate::MAX_INTERVAL;
use crate::{Error, Simulation};
use splinerod_adaptivity::{AdaptParams, Adapter, ToleranceCriterion};
use splinerod_core::Real;
use std::time::Instant;

/// Over `reps` steps of an `n`-point cable with the adapt stage: (stage seconds, whole
/// step seconds), summed. Estimates come every few steps once the rod is steady, so the
/// sums cover several of them.
fn stage_and_step(n: usize, reps: usize) -> Result<(Real, Real), Error> {
    let params = AdaptParams {
        max_control_points: n,
        min_control_points: n,
        ..AdaptParams::default()
    };
    let adapter = Adapter::new(params)?.with(ToleranceCriterion::new(1.0)?);
    let system = pinned_cable(n, 1.05, 100.0)?;
    let mut sim = Simulation::new(system, one_iteration()?).with_adapter(adapter);
    // Past the schedule's start-up (estimates every step until the rod is steady).
    for _ in 0..3 * MAX_INTERVAL {
        sim.step(1e-3)?;
    }
    let (mut stage, mut whole) = (0.0, 0.0);
    for _ in 0..reps {
        let t = Instant::now();
        let report = sim.step(1e-3)?;
        whole += t.elapsed().as_secs_f64();
        stage += report.stages.adapt;
    }
    Ok((stage, whole))
}

/// The adapt stage's share of a step at 16 control points: stage time over the rest of
/// the step's time.
pub fn adapt_fraction_16(reps: usize) -> Result<Real, Error> {
    let (stage, whole) = stage_and_step(16, reps)?;
    Ok(stage / (whole - stage))
}

/// The adapt stage's mean time per step and control point (ns) at `n` control points.
pub fn adapt_ns_per_cp(n: usize, reps: usize) -> Result<Real, Error> {
    let (stage, _) = stage_and_step(n, reps)?;
    Ok(stage * 1e9 / (reps * n) as Real)
}
