//! [`RodSystem`]: a rod, its pins, its energies and its grabs; the facade's
//! implementation of the integrators' [`System`] view (the sum of all energies and of
//! the active grabs' springs).
//!
//! **One path for knot changes.** Energies may cache data that follow the rod's basis
//! (a rest metric at the quadrature points, multipliers per tension function), so every
//! insertion, removal or cut must reach them with its exact [`KnotMap`]. All of them go
//! through [`RodSystem::change_knots`] (or its shorthands [`RodSystem::insert_knot`],
//! [`RodSystem::remove_knot`], [`RodSystem::cut`]), which notifies every energy of
//! every map and records the rod's topology epoch. A change made behind its back — a
//! bare `rod.cut(..)`, or another rod put in its place — leaves a different epoch, and
//! the next step, solve or estimate refuses to run on it
//! ([`crate::Error::KnotsChangedUnheard`]) instead of reading stale caches.

use crate::world::bodies::Bodies;
use crate::world::gripper::Gripper;
use crate::world::path::Path;
use crate::{Error, Grab};

/// A force at a material point, constant or following a keyframed path of forces.
#[derive(Debug, Clone, PartialEq)]
pub struct Load {
    /// The force now (the energy term).
    pub force: PointForce,
    /// Keyframes of the force (`[t, Fx, Fy, Fz]` as positions of a [`Path`]); `None`:
    /// constant.
    pub path: Option<Path>,
}

/// A pin (by index in [`RodSystem::pins`]) whose position follows a keyframed path.
#[derive(Debug, Clone, PartialEq)]
pub struct PinDriver {
    /// Index of the pin.
    pub pin: usize,
    /// Its positions over time.
    pub path: Path,
}
use nalgebra::Vector3;
use splinerod_core::{
    Attachment, BlockBanded, Cancel, CoreError, HessianKind, KnotMap, Pin, Real, RigidBody, Rod,
};
use splinerod_energies::{Energy, EnergySummary, PointForce};
#[cfg(doc)]
use splinerod_energies::{Interaction, Lifecycle, Summary};
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
    /// Pins moved along keyframed paths ([`RodSystem::drive`]).
    pub drivers: Vec<PinDriver>,
    /// Point loads (their forces follow their paths, [`RodSystem::drive`]).
    pub loads: Vec<Load>,
    /// Grippers holding exact clamps ([`crate::world::gripper`]), moved along their pose
    /// paths by [`RodSystem::drive`] or between steps by [`RodSystem::set_gripper_pose`].
    pub grippers: Vec<Gripper>,
    /// Rigid bodies the pins hold ([`crate::world::bodies`]).
    pub bodies: Bodies,
    /// The rod's topology epoch when the energies last heard of its knots.
    heard_epoch: u64,
    /// Every knot change so far, in order (checkpoints replay them).
    pub(crate) knot_changes: Vec<crate::world::saved::KnotChange>,
    /// The first energy found returning a non-finite value or gradient since the last
    /// [`RodSystem::take_non_finite_energy`] (`what`, name).
    non_finite: std::sync::Mutex<Option<(&'static str, String)>>,
    /// A stop asked from outside (a signal): the solvers poll it
    /// ([`System::interrupted`]) and abandon the step under way. Default: none.
    pub cancel: Cancel,
}

impl RodSystem {
    /// A system without pins or energies.
    pub fn new(rod: Rod) -> Self {
        Self {
            heard_epoch: rod.topology_epoch(),
            knot_changes: Vec::new(),
            rod,
            pins: Vec::new(),
            energies: Vec::new(),
            grabs: Vec::new(),
            time: 0.0,
            drivers: Vec::new(),
            loads: Vec::new(),
            grippers: Vec::new(),
            bodies: Bodies::default(),
            non_finite: std::sync::Mutex::new(None),
            cancel: Cancel::none(),
        }
    }

    /// The energy that returned a non-finite energy or gradient since the last call
    /// (what it returned, its name), cleared. A step that failed on a non-finite value
    /// names its culprit with it.
    pub fn take_non_finite_energy(&self) -> Option<(&'static str, String)> {
        self.non_finite
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
    }

    /// Records the first energy whose value (`what = "energy"`) or gradient is not
    /// finite: called only once the sum is found non-finite, so it costs nothing on a
    /// finite evaluation.
    fn find_non_finite(&self, what: &'static str) {
        let culprit = self.acting().find(|e| match what {
            "energy" => !e.energy(&self.rod).is_finite(),
            _ => {
                let mut g = vec![Vector3::zeros(); self.rod.len()];
                e.add_gradient(&self.rod, &mut g);
                g.iter().any(|v| !v.iter().all(|c| c.is_finite()))
            }
        });
        let mut slot = self.non_finite.lock().unwrap_or_else(|e| e.into_inner());
        if let (None, Some(e)) = (slot.as_ref(), culprit) {
            *slot = Some((what, e.name().to_string()));
        }
    }

    /// [`Self::find_non_finite`] for the gradient if `gradient` has a non-finite entry.
    fn check_gradient(&self, gradient: &[Vector3<Real>]) {
        if gradient.iter().any(|v| !v.iter().all(|c| c.is_finite())) {
            self.find_non_finite("gradient");
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

    /// Adds a grab (builder style).
    pub fn with_grab(mut self, grab: Grab) -> Self {
        self.grabs.push(grab);
        self
    }

    /// Drives pin `pin` along `path` (builder style).
    pub fn with_driver(mut self, pin: usize, path: Path) -> Self {
        self.drivers.push(PinDriver { pin, path });
        self
    }

    /// Adds a load (builder style).
    pub fn with_load(mut self, load: Load) -> Self {
        self.loads.push(load);
        self
    }

    /// Adds a gripper (builder style).
    pub fn with_gripper(mut self, gripper: Gripper) -> Self {
        self.grippers.push(gripper);
        self
    }

    /// Whether anything in the system moves with time: driven pins, keyframed loads,
    /// grabs, posed grippers or time-dependent energies (else [`Self::drive`] changes
    /// nothing).
    pub fn is_driven(&self) -> bool {
        !self.drivers.is_empty()
            || self.has_posed_grippers()
            || !self.grabs.is_empty()
            || self.loads.iter().any(|l| l.path.is_some())
            || self.bodies.loads.iter().any(|l| l.path.is_some())
            || self.energies.iter().any(|e| {
                let lifecycle = e.capabilities().lifecycle;
                lifecycle.is_some_and(|l| l.time_dependent())
            })
    }

    /// Moves every driven pin to its path's position at time `t`, sets every keyframed
    /// load's force, turns the time-dependent energies and moves the posed grippers.
    pub fn drive(&mut self, t: Real) {
        for d in &self.drivers {
            if let Some(pin) = self.pins.get_mut(d.pin) {
                pin.position = d.path.at(t);
            }
        }
        for load in &mut self.loads {
            if let Some(path) = &load.path {
                load.force.force = path.at(t);
            }
        }
        for energy in &mut self.energies {
            if let Some(l) = energy.lifecycle_mut() {
                l.drive(t);
            }
        }
        self.drive_grippers(t);
        if !self.bodies.loads.is_empty() {
            self.drive_bodies(t);
        }
    }

    /// The springs of the grabs active at [`time`](Self::time).
    pub fn active_grabs(&self) -> impl Iterator<Item = &dyn Energy> + '_ {
        self.grabs
            .iter()
            .filter(|g| g.active(self.time))
            .map(|g| &g.spring as &dyn Energy)
    }

    /// Every energy acting now: the energies, the active grabs, then the loads.
    pub fn acting(&self) -> impl Iterator<Item = &dyn Energy> + '_ {
        self.energies
            .iter()
            .map(|e| e.as_ref())
            .chain(self.active_grabs())
            .chain(self.loads.iter().map(|l| &l.force as &dyn Energy))
    }

    /// Changes the rod's knots through `change`, which receives the rod and a listener
    /// to call with every [`KnotMap`] it applies (as [`Rod::cut_with`] and the adapter
    /// do); every energy hears of every map. The one way knots change (module docs).
    pub fn change_knots<R, E>(
        &mut self,
        change: impl FnOnce(&mut Rod, &mut dyn FnMut(&Rod, &KnotMap)) -> Result<R, E>,
    ) -> Result<R, E> {
        let Self {
            rod,
            energies,
            knot_changes,
            ..
        } = self;
        let mut listener = |rod: &Rod, map: &KnotMap| {
            knot_changes.push(crate::world::saved::change_of(map));
            for l in energies.iter_mut().filter_map(|e| e.lifecycle_mut()) {
                l.on_knot_change(rod, map);
            }
        };
        let result = change(rod, &mut listener);
        self.heard_epoch = self.rod.topology_epoch();
        result
    }

    /// Inserts a knot at material coordinate `s` (m), telling the energies.
    pub fn insert_knot(&mut self, s: Real) -> Result<(), CoreError> {
        self.change_knots(|rod, heard| {
            let map = rod.insert_knot(s)?;
            heard(rod, &map);
            Ok(())
        })
    }

    /// Removes knot `index` if the curve moves by at most `tolerance` (m; see
    /// [`Rod::remove_knot`]), telling the energies.
    pub fn remove_knot(&mut self, index: usize, tolerance: Real) -> Result<(), CoreError> {
        self.change_knots(|rod, heard| {
            let map = rod.remove_knot(index, tolerance)?;
            heard(rod, &map);
            Ok(())
        })
    }

    /// Cuts the rod at material coordinate `s` (m; see [`Rod::cut`]), telling the
    /// energies; returns the knots inserted. A cut just beside a simple knot also
    /// removes that knot, merging the sliver span it would leave at the new end
    /// ([`crate::sliver`]).
    pub fn cut(&mut self, s: Real) -> Result<usize, CoreError> {
        let sliver = self.sliver_knot(s);
        let inserted = self.change_knots(|rod, heard| rod.cut_with(s, heard))?;
        if let Some(t) = sliver {
            self.merge_sliver(t)?;
        }
        Ok(inserted)
    }

    /// An error if the rod's knots changed (or the rod was replaced) without going
    /// through [`RodSystem::change_knots`]: the energies' caches may be stale.
    pub fn check_knots_heard(&self) -> Result<(), Error> {
        if self.rod.topology_epoch() == self.heard_epoch {
            Ok(())
        } else {
            Err(Error::KnotsChangedUnheard)
        }
    }

    /// Starts an integrator step of `dt` seconds: every energy's
    /// [`Lifecycle::begin_step`], and the bodies' friction
    /// ([`crate::world::body_friction`]).
    pub fn begin_step(&mut self, dt: Real) -> Result<(), CoreError> {
        if !self.bodies.contact.shapes.is_empty() {
            self.bodies.contact.begin_step(&self.bodies.bodies, dt);
        }
        let rod = &self.rod;
        self.energies
            .iter_mut()
            .filter_map(|e| e.lifecycle_mut())
            .try_for_each(|l| l.begin_step(rod, dt))
    }

    /// Appends the material coordinates (m) where something acts locally now: the
    /// active grabs, then every energy's [`Interaction::interaction_points`].
    pub fn interaction_points(&self, out: &mut Vec<Real>) -> Result<(), CoreError> {
        let t = self.time;
        let grabs = self.grabs.iter().filter(|g| g.active(t));
        out.extend(grabs.map(|g| g.spring.at));
        self.energies
            .iter()
            .filter_map(|e| e.capabilities().interaction)
            .try_for_each(|i| i.interaction_points(&self.rod, out))
    }

    /// The force the rod exerts on each rigid obstacle, N, in the order they were given
    /// ([`Interaction::add_obstacle_forces`]); empty without obstacles.
    pub fn obstacle_forces(&self) -> Result<Vec<Vector3<Real>>, CoreError> {
        let mut out = Vec::new();
        for i in self.acting().filter_map(|e| e.capabilities().interaction) {
            i.add_obstacle_forces(&self.rod, &mut out)?;
        }
        Ok(out)
    }

    /// The merged [`Summary::summary`] of every acting energy.
    pub fn summary(&self) -> Result<EnergySummary, CoreError> {
        let mut total = EnergySummary::default();
        for e in self.acting().filter_map(|e| e.capabilities().summary) {
            total.merge(&e.summary(&self.rod)?);
        }
        Ok(total)
    }

    /// One multiplier update of every energy holding constraints (the inextensible
    /// rod; see [`Lifecycle::update_multipliers`] for `stiffen`); the largest violation
    /// before it (0 without constraints).
    pub fn update_multipliers(&mut self, stiffen: bool) -> Real {
        let rod = &self.rod;
        self.energies
            .iter_mut()
            .map(|e| {
                let lifecycle = e.lifecycle_mut();
                lifecycle.map_or(0.0, |l| l.update_multipliers(rod, stiffen))
            })
            .fold(0.0, Real::max)
    }

    /// Axial tension (N) at the material coordinates `s` from the energies that carry
    /// one (stretching); empty if none does.
    pub fn tension(&self, s: &[Real]) -> Vec<Real> {
        let mut out = vec![0.0; s.len()];
        let mut any = false;
        for t in self.acting().filter_map(|e| e.capabilities().tension) {
            any |= t.add_tension(&self.rod, s, &mut out);
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
            .field("drivers", &self.drivers)
            .field("loads", &self.loads)
            .field("grippers", &self.grippers)
            .finish()
    }
}

impl System for RodSystem {
    fn rod(&self) -> &Rod {
        &self.rod
    }
    fn as_any(&self) -> Option<&dyn std::any::Any> {
        Some(self)
    }
    fn rod_mut(&mut self) -> &mut Rod {
        &mut self.rod
    }
    fn pins(&self) -> &[Pin] {
        &self.pins
    }
    fn bodies(&self) -> &[RigidBody] {
        &self.bodies.bodies
    }
    fn bodies_mut(&mut self) -> &mut [RigidBody] {
        &mut self.bodies.bodies
    }
    fn attachments(&self) -> &[Attachment] {
        &self.bodies.attachments
    }
    fn add_body_potential(
        &self,
        body: usize,
        pose: (&Vector3<Real>, &nalgebra::UnitQuaternion<Real>),
        grad: &mut nalgebra::Vector6<Real>,
        hess: &mut nalgebra::Matrix6<Real>,
    ) -> Real {
        self.body_contact(body, pose, grad, hess) + self.body_friction(body, pose, grad, hess)
    }
    fn potential_energy(&self) -> Real {
        let total: Real = self.acting().map(|e| e.energy(&self.rod)).sum();
        if !total.is_finite() {
            self.find_non_finite("energy");
        }
        total
    }
    fn add_potential_gradient(&self, gradient: &mut [Vector3<Real>]) {
        for e in self.acting() {
            e.add_gradient(&self.rod, gradient);
        }
        self.check_gradient(gradient);
    }
    fn add_potential_hessian(&self, kind: HessianKind, hessian: &mut BlockBanded) {
        for e in self.acting() {
            e.add_hessian(&self.rod, kind, hessian);
        }
    }
    fn add_potential_gradient_and_hessian(
        &self,
        kind: HessianKind,
        gradient: &mut [Vector3<Real>],
        hessian: &mut BlockBanded,
    ) {
        for e in self.acting() {
            e.add_gradient_and_hessian(&self.rod, kind, gradient, hessian);
        }
        self.check_gradient(gradient);
    }
    fn has_hessian_remainder(&self) -> bool {
        let mut remainders = self.acting().filter_map(|e| e.capabilities().remainder);
        remainders.any(|r| r.has_remainder(&self.rod))
    }
    fn add_hessian_remainder(&self, v: &[Vector3<Real>], scale: Real, out: &mut [Vector3<Real>]) {
        for r in self.acting().filter_map(|e| e.capabilities().remainder) {
            r.add_remainder(&self.rod, v, scale, out);
        }
    }
    fn hessian_bandwidth(&self) -> usize {
        let d = self.rod.basis().degree();
        self.acting()
            .map(|e| e.bandwidth(&self.rod))
            .fold(d, usize::max)
    }
    fn admissible(&self) -> bool {
        let mut barriers = self.acting().filter_map(|e| e.capabilities().interaction);
        barriers.all(|i| i.admissible(&self.rod))
    }
    fn update_multipliers(&mut self, stiffen: bool) -> Real {
        RodSystem::update_multipliers(self, stiffen)
    }
    fn interrupted(&self) -> bool {
        self.cancel.abandon()
    }
    fn set_stiffness_scale(&mut self, scale: Real) -> bool {
        let mut any = false;
        for l in self.energies.iter_mut().filter_map(|e| e.lifecycle_mut()) {
            any |= l.set_stiffness_scale(scale);
        }
        any
    }
}
