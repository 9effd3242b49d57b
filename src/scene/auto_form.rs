//! `rod.stretch_formulation = "auto"` (the default): the stretching form chosen from
//! the strain the scene puts on the rod ([`StretchFormulation::auto`]).
//!
//! The strain scale is the largest of
//!
//! * the loads against the axial stiffness, \\((\mu |g| L + \sum |F_{load}| + \sum k_{grab}
//!   d_{grab}) / EA\\), with each keyframed load at its largest and each grab's force
//!   bounded by its spring stretched from where its point starts to its target;
//! * the stretch the pins impose: for consecutive pins along the rod, the largest
//!   distance their positions (start and keyframes) put between them over their rest
//!   distance, minus one (sliding pins impose none);
//! * the tension of the start, the largest Green–Lagrange strain at the rod's
//!   quadrature points (`0` for `rest_shape = "initial"`);
//!
//! and the start's compression is the largest negative strain there. The number of
//! control points is the rod's, or the adapter's cap. What the run allows anyway is a
//! contact's onset layer (its rest geometry is off by that much) and a tolerance-driven
//! adapter's tolerance (it aims at no better). An inextensible
//! rod (`stretch_stiffness = "inextensible"`) holds its constraints on the lumped
//! tension space.

use crate::scene::{RestShape, Scene, StretchFormulationSpec};
use crate::Error;
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};
use splinerod_energies::{AutoInputs, StretchFormulation};

impl Scene {
    /// The stretching form of every rod of the scene, in order (one for a `[rod]`
    /// scene), as [`Scene::stretch_formulation_used`] resolves it.
    pub fn stretch_formulations_used(&self) -> Result<Vec<StretchFormulation>, Error> {
        if self.rods.is_empty() {
            return Ok(vec![self.stretch_formulation_used(&self.build_rod()?)?]);
        }
        (0..self.rods.len())
            .map(|k| {
                let (sub, _) = self.rod_scene(k)?;
                sub.stretch_formulation_used(&sub.build_rod()?)
            })
            .collect()
    }

    /// The stretching form of this (one-rod) scene's rod, `rod` built from it: the one
    /// asked for, or the `"auto"` choice (module docs).
    pub fn stretch_formulation_used(&self, rod: &Rod) -> Result<StretchFormulation, Error> {
        let ea = self.rod.stretch_stiffness;
        let form = match self.rod.stretch_formulation {
            StretchFormulationSpec::Auto if ea == Real::INFINITY => StretchFormulation::Mixed,
            StretchFormulationSpec::Auto => {
                let (tension, compression) = self.start_strain(rod);
                let strain = tension
                    .max(self.load_strain(rod)?)
                    .max(self.pin_strain(rod)?);
                let control_points = match &self.adaptivity {
                    Some(a) => a.max_control_points.max(rod.len()),
                    None => rod.len(),
                };
                StretchFormulation::auto(AutoInputs {
                    strain,
                    compression,
                    control_points,
                    length: self.rod.rest_length,
                    model_error: self.model_error(),
                })
            }
            StretchFormulationSpec::Mixed => StretchFormulation::Mixed,
            StretchFormulationSpec::Pointwise => StretchFormulation::Pointwise,
            StretchFormulationSpec::MixedConsistent => StretchFormulation::MixedConsistent,
        };
        Ok(form)
    }

    /// The error the model allows whatever the stretching (m): the contact's onset layer
    /// (default a tenth of the thinnest radius) and a tolerance-driven adapter's
    /// tolerance, the larger; 0 without either.
    fn model_error(&self) -> Real {
        let contact = self.contact_layer().unwrap_or(0.0);
        let adaptive = match &self.adaptivity {
            Some(a) => a.aimed_error(self.rod.rest_length),
            None => 0.0,
        };
        contact.max(adaptive)
    }

    /// The largest tensile and compressive Green–Lagrange strain of the start
    /// ([`AutoInputs::start_strains`]; zero for an initial curve taken as the rest shape).
    pub(crate) fn start_strain(&self, rod: &Rod) -> (Real, Real) {
        match self.rod.rest_shape {
            RestShape::Initial => (0.0, 0.0),
            _ => AutoInputs::start_strains(rod),
        }
    }

    /// The loads' strain scale: weight, loads and grabs over `EA` (module docs).
    fn load_strain(&self, rod: &Rod) -> Result<Real, Error> {
        Ok(self.load_tension(rod)? / self.rod.stretch_stiffness)
    }

    /// The loads' tension scale, N: weight, loads and grabs (module docs).
    pub(crate) fn load_tension(&self, rod: &Rod) -> Result<Real, Error> {
        let r = &self.rod;
        let weight = r.linear_density * Vector3::from(self.world.gravity).norm() * r.rest_length;
        let loads: Real = self
            .loads
            .iter()
            .map(|l| match (&l.force, &l.path) {
                (Some(f), _) => Vector3::from(*f).norm(),
                (None, Some(keys)) => keys
                    .iter()
                    .map(|k| Vector3::new(k[1], k[2], k[3]).norm())
                    .fold(0.0, Real::max),
                (None, None) => 0.0,
            })
            .sum();
        let mut grabs = 0.0;
        for g in &self.grabs {
            let from = rod.point(g.at * r.rest_length)?;
            grabs += g.stiffness * (Vector3::from(g.to) - from).norm();
        }
        Ok(weight + loads + grabs)
    }

    /// The largest stretch consecutive fixed pins impose (module docs), ≥ 0.
    pub(crate) fn pin_strain(&self, rod: &Rod) -> Result<Real, Error> {
        let l = self.rod.rest_length;
        let mut pins = Vec::new();
        for spec in self.pins.iter().filter(|p| p.slides_along.is_none()) {
            let mut places = vec![rod.point(spec.at * l)?];
            if let Some(keys) = &spec.path {
                places.extend(keys.iter().map(|k| Vector3::new(k[1], k[2], k[3])));
            }
            pins.push((spec.at * l, places));
        }
        Ok(AutoInputs::held_strain(&mut pins))
    }
}
