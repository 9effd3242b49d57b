//! The summary of each member of an ensemble run (JSON `ensemble[i]`).

use crate::run::tally::Tally;
use crate::run::totals::ContactStats;
use crate::{Error, Scene, Simulation};
use serde::Serialize;
use splinerod_core::Real;
use std::collections::BTreeMap;

/// What one member ended with.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct MemberSummary {
    /// Member index.
    pub index: usize,
    /// Its axial stiffness, N.
    pub stretch_stiffness: Real,
    /// Its linear density, kg/m.
    pub linear_density: Real,
    /// Its damping, 1/s.
    pub damping: Real,
    /// Final sag: height of the chord between the rod's ends at mid-length minus the
    /// height of the material midpoint (along y), m.
    pub sag: Real,
    /// Final energies, J (as the run's `energy`).
    pub energy: BTreeMap<String, Real>,
    /// Final control points.
    pub control_points: usize,
    /// Its contact statistics over the run (absent without `[contact]`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<ContactStats>,
    /// Its last error estimate, m (absent without an estimator).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub estimated_error: Option<Real>,
}

/// The summary of a finished member (its scene, simulation and what it accumulated).
pub(crate) fn summarize(
    index: usize,
    scene: &Scene,
    sim: &Simulation,
    tally: &Tally,
) -> Result<MemberSummary, Error> {
    let rod = &sim.system.rod;
    let l = rod.material().rest_length;
    let (a, b, m) = (rod.point(0.0)?, rod.point(l)?, rod.point(0.5 * l)?);
    let mut energy = BTreeMap::from([("kinetic".to_string(), rod.kinetic_energy())]);
    energy.extend(sim.system.energy_breakdown());
    Ok(MemberSummary {
        index,
        stretch_stiffness: scene.rod.stretch_stiffness,
        linear_density: scene.rod.linear_density,
        damping: scene.rod.damping,
        sag: 0.5 * (a.y + b.y) - m.y,
        energy,
        control_points: rod.distinct_len(),
        contact: tally.contact,
        estimated_error: tally.estimates.as_ref().map(|e| e.estimated_error),
    })
}
