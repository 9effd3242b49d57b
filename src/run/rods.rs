//! The per-rod results of a `[[rods]]` scene (JSON `rods[i]`): each rod's name, control
//! points, knots, samples along it, its own energies (kinetic and every energy placed on
//! it; contact acts between rods and stays in the top-level `energy`) and the forces of
//! its pins.

use crate::{Error, RodSystem, Scene};
use serde::Serialize;
use splinerod_core::Real;
use std::collections::BTreeMap;

/// Positions of evenly spaced material points at the end.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Samples {
    /// Material coordinates, fractions of the rest length.
    pub s: Vec<Real>,
    /// Their positions, m.
    pub positions: Vec<[Real; 3]>,
    /// Axial tension there, N (the stretching energy's tension field; absent without one).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub tension: Vec<Real>,
}

/// One rod of a `[[rods]]` scene at the end of a run.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct RodOutput {
    /// Its `name`.
    pub name: String,
    /// Its control points now.
    pub control_points: usize,
    /// Its knot vector now, fractions of its rest length.
    pub knots: Vec<Real>,
    /// Evenly spaced points along it (`output.samples` of them).
    pub samples: Samples,
    /// Its energies, J, by name (`kinetic` included).
    pub energy: BTreeMap<String, Real>,
    /// The forces it puts on the supports of the `[[pins]]` entries naming it, in file
    /// order, N (as the run's `pin_forces`).
    pub pin_forces: Vec<[Real; 3]>,
    /// The stretching form it used (see [`crate::run::result::RodModel`]).
    pub stretch_formulation_used: String,
}

/// Every rod's results; empty for a one-rod scene.
/// `pin_forces`: one per `[[pins]]` entry, in file order; `forms`: each rod's stretching
/// form.
pub fn rods(
    scene: &Scene,
    system: &RodSystem,
    pin_forces: &[[Real; 3]],
    forms: &[splinerod_energies::StretchFormulation],
) -> Result<Vec<RodOutput>, Error> {
    let rod = &system.rod;
    let m = scene.output.samples;
    let s: Vec<Real> = (0..m).map(|k| k as Real / (m - 1) as Real).collect();
    let mut out = Vec::with_capacity(scene.rods.len());
    for (k, spec) in scene.rods.iter().enumerate() {
        let positions = s
            .iter()
            .map(|&f| rod.point(scene.coordinate(k, f)).map(Into::into))
            .collect::<Result<_, _>>()?;
        let part = rod.segment_rod(k)?;
        let mut energy = BTreeMap::from([("kinetic".to_string(), part.kinetic_energy())]);
        for e in system
            .energies
            .iter()
            .filter(|e| e.capabilities().segment == Some(k))
        {
            *energy.entry(e.name().to_string()).or_insert(0.0) += e.energy(rod);
        }
        let mine =
            |p: &&crate::scene::PinSpec| scene.rod_index("", p.rod.as_deref()).ok() == Some(k);
        let forces = scene.pins.iter().zip(pin_forces).filter(|(p, _)| mine(p));
        let l = part.material().rest_length;
        out.push(RodOutput {
            name: spec.name.clone().unwrap_or_default(),
            control_points: part.len(),
            knots: part.basis().knots().iter().map(|t| t / l).collect(),
            pin_forces: forces.map(|(_, f)| *f).collect(),
            stretch_formulation_used: forms.get(k).map_or("", |f| f.name()).to_string(),
            samples: Samples {
                s: s.clone(),
                positions,
                tension: Vec::new(),
            },
            energy,
        });
    }
    Ok(out)
}
