//! [`RodSystem`]: a rod, its pins and its energies; the facade's implementation of the
//! integrators' [`System`] view (the sum of all energies).

use nalgebra::Vector3;
use splinerod_core::{BlockBanded, HessianKind, Pin, Real, Rod};
use splinerod_energies::Energy;
use splinerod_integrators::System;

/// A rod with pins and a list of energies. All fields are public state.
pub struct RodSystem {
    /// The rod.
    pub rod: Rod,
    /// Pins (positions are the targets for the next step).
    pub pins: Vec<Pin>,
    /// Potential energies (stretching, gravity, ...), summed.
    pub energies: Vec<Box<dyn Energy>>,
}

impl RodSystem {
    /// A system without pins or energies.
    pub fn new(rod: Rod) -> Self {
        Self {
            rod,
            pins: Vec::new(),
            energies: Vec::new(),
        }
    }

    /// Adds an energy (builder style).
    pub fn with_energy(mut self, energy: impl Energy + 'static) -> Self {
        self.energies.push(Box::new(energy));
        self
    }

    /// Adds a pin (builder style).
    pub fn with_pin(mut self, pin: Pin) -> Self {
        self.pins.push(pin);
        self
    }

    /// Each energy's name and value, in order.
    pub fn energy_breakdown(&self) -> Vec<(String, Real)> {
        self.energies
            .iter()
            .map(|e| (e.name().to_string(), e.energy(&self.rod)))
            .collect()
    }
}

impl std::fmt::Debug for RodSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = self.energies.iter().map(|e| e.name()).collect();
        f.debug_struct("RodSystem")
            .field("rod", &self.rod)
            .field("pins", &self.pins)
            .field("energies", &names)
            .finish()
    }
}

impl System for RodSystem {
    fn rod(&self) -> &Rod {
        &self.rod
    }
    fn rod_mut(&mut self) -> &mut Rod {
        &mut self.rod
    }
    fn pins(&self) -> &[Pin] {
        &self.pins
    }
    fn potential_energy(&self) -> Real {
        self.energies.iter().map(|e| e.energy(&self.rod)).sum()
    }
    fn add_potential_gradient(&self, gradient: &mut [Vector3<Real>]) {
        for e in &self.energies {
            e.add_gradient(&self.rod, gradient);
        }
    }
    fn add_potential_hessian(&self, kind: HessianKind, hessian: &mut BlockBanded) {
        for e in &self.energies {
            e.add_hessian(&self.rod, kind, hessian);
        }
    }
}
