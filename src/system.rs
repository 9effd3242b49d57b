//! [`RodSystem`]: a rod, its pins, its energies and its grabs; the facade's
//! implementation of the integrators' [`System`] view (the sum of all energies and of
//! the active grabs' springs and contact).

use crate::Grab;
use nalgebra::Vector3;
use splinerod_core::{BlockBanded, HessianKind, Pin, Real, Rod};
use splinerod_energies::{Contact, Energy};
use splinerod_integrators::System;

/// A rod with pins and a list of energies. All fields are public state.
pub struct RodSystem {
    /// The rod.
    pub rod: Rod,
    /// Pins (positions are the targets for the next step).
    pub pins: Vec<Pin>,
    /// Potential energies (stretching, gravity, ...), summed.
    pub energies: Vec<Box<dyn Energy>>,
    /// Grabs; only the active ones (see [`Grab::active`]) pull.
    pub grabs: Vec<Grab>,
    /// Simulated time the grabs are evaluated at (the end of the step being solved).
    pub time: Real,
    /// Contact (self, between cut pieces, floor), if the scene has it.
    pub contact: Option<Contact>,
}

impl RodSystem {
    /// A system without pins or energies.
    pub fn new(rod: Rod) -> Self {
        Self {
            rod,
            pins: Vec::new(),
            energies: Vec::new(),
            grabs: Vec::new(),
            time: 0.0,
            contact: None,
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

    /// Adds contact (builder style).
    pub fn with_contact(mut self, contact: Contact) -> Self {
        self.contact = Some(contact);
        self
    }

    /// Adds a grab (builder style).
    pub fn with_grab(mut self, grab: Grab) -> Self {
        self.grabs.push(grab);
        self
    }

    /// The springs of the grabs active at [`time`](Self::time).
    pub fn active_grabs(&self) -> impl Iterator<Item = &dyn Energy> + '_ {
        self.grabs
            .iter()
            .filter(|g| g.active(self.time))
            .map(|g| &g.spring as &dyn Energy)
    }

    /// Every energy acting now: the energies, the active grabs, then contact.
    fn acting(&self) -> impl Iterator<Item = &dyn Energy> + '_ {
        self.energies
            .iter()
            .map(|e| e.as_ref())
            .chain(self.active_grabs())
            .chain(self.contact.iter().map(|c| c as &dyn Energy))
    }

    /// One multiplier update of every energy holding constraints (the inextensible
    /// rod; see [`Energy::update_multipliers`] for `stiffen`); the largest violation
    /// before it (0 without constraints).
    pub fn update_multipliers(&mut self, stiffen: bool) -> Real {
        let rod = &self.rod;
        self.energies
            .iter_mut()
            .map(|e| e.update_multipliers(rod, stiffen))
            .fold(0.0, Real::max)
    }

    /// Axial tension (N) at the material coordinates `s` from the energies that carry
    /// one (stretching); empty if none does.
    pub fn tension(&self, s: &[Real]) -> Vec<Real> {
        let mut out = vec![0.0; s.len()];
        let mut any = false;
        for e in self.acting() {
            any |= e.add_tension(&self.rod, s, &mut out);
        }
        if any {
            out
        } else {
            Vec::new()
        }
    }

    /// Each acting energy's name and value, in order; terms sharing a name (several
    /// grabs) are summed.
    pub fn energy_breakdown(&self) -> Vec<(String, Real)> {
        let mut out: Vec<(String, Real)> = Vec::new();
        for e in self.acting() {
            let value = e.energy(&self.rod);
            match out.iter_mut().find(|(name, _)| name == e.name()) {
                Some((_, total)) => *total += value,
                None => out.push((e.name().to_string(), value)),
            }
        }
        out
    }
}

impl std::fmt::Debug for RodSystem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let names: Vec<&str> = self.energies.iter().map(|e| e.name()).collect();
        f.debug_struct("RodSystem")
            .field("rod", &self.rod)
            .field("pins", &self.pins)
            .field("energies", &names)
            .field("grabs", &self.grabs)
            .field("contact", &self.contact.as_ref().map(|c| c.params()))
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
        self.acting().map(|e| e.energy(&self.rod)).sum()
    }
    fn add_potential_gradient(&self, gradient: &mut [Vector3<Real>]) {
        for e in self.acting() {
            e.add_gradient(&self.rod, gradient);
        }
    }
    fn add_potential_hessian(&self, kind: HessianKind, hessian: &mut BlockBanded) {
        for e in self.acting() {
            e.add_hessian(&self.rod, kind, hessian);
        }
    }
    fn hessian_bandwidth(&self) -> usize {
        let d = self.rod.basis().degree();
        self.acting()
            .map(|e| e.bandwidth(&self.rod))
            .fold(d, usize::max)
    }
    fn admissible(&self) -> bool {
        self.contact
            .as_ref()
            .is_none_or(|c| c.admissible(&self.rod))
    }
}
