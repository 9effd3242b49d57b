//! Turning a validated [`Scene`] into library objects: the basis, the rod, its energies
//! (only those the scene needs: no gravity energy when gravity is zero) and its pins.

use crate::scene::{KnotsSpec, LinearSolverSpec, Method, RestShape, Scene};
use crate::world::gripper::{Gripper, PosePath};
use crate::world::path::Path;
use crate::{Error, Grab, RodSystem, Simulation};
use nalgebra::Vector3;
use splinerod_adaptivity::{Adapter, Continuity};
use splinerod_core::{BSplineSpace, BasisSpace, Keyframes, Material, Pin, Real, Rod};
use splinerod_energies::{
    Bending, Clamp, Frame, Gravity, StretchFormulation, Stretching, Twisting,
};
use splinerod_integrators::{
    Bdf2, ImplicitEuler, ImplicitMidpoint, Integrator, LinearSolverKind, NewtonParams,
    StaticParams, StaticSolver,
};

impl Method {
    /// Every method with its name in scene files.
    pub const NAMES: [(Method, &'static str); 4] = [
        (Method::ImplicitEuler, "implicit-euler"),
        (Method::ImplicitMidpoint, "implicit-midpoint"),
        (Method::Bdf2, "bdf2"),
        (Method::Static, "static"),
    ];

    /// The method's name in scene files.
    pub fn name(self) -> &'static str {
        let found = Self::NAMES.iter().find(|(m, _)| *m == self);
        found.map_or("static", |(_, name)| name)
    }

    /// The method called `name` in scene files; an unknown name is an error naming it.
    pub fn from_name(name: &str) -> Result<Method, Error> {
        let found = Self::NAMES.iter().find(|(_, n)| *n == name);
        found.map(|(m, _)| *m).ok_or_else(|| {
            let known: Vec<_> = Self::NAMES.iter().map(|(_, n)| *n).collect();
            let reason = format!("unknown method; expected one of {}", known.join(", "));
            Error::field("solver.method", format!("\"{name}\""), reason)
        })
    }

    /// The integrator of this method: a time integrator with `newton`, or the static
    /// solver with `statics`.
    pub fn integrator(
        self,
        newton: NewtonParams,
        statics: StaticParams,
    ) -> Result<Box<dyn Integrator>, Error> {
        Ok(match self {
            Method::ImplicitEuler => Box::new(ImplicitEuler::new(newton)?),
            Method::ImplicitMidpoint => Box::new(ImplicitMidpoint::new(newton)?),
            Method::Bdf2 => Box::new(Bdf2::new(newton)?),
            Method::Static => Box::new(StaticSolver::new(statics)?),
        })
    }
}

/// Smallest clearance ratio (centre-line distance over the contact distance) a scene
/// may start with ([`Scene::build`]).
pub const MIN_START_CLEARANCE: Real = 0.5;

impl Scene {
    /// The basis space on `[0, L]` described by `rod.knots`.
    pub fn basis(&self) -> Result<BSplineSpace, Error> {
        let r = &self.rod;
        let layout = r.knot_layout();
        let given = match &layout {
            KnotsSpec::Named(name) => format!("\"{name}\""),
            KnotsSpec::Explicit(k) => format!("{k:?}"),
        };
        let wrap = |e: splinerod_core::CoreError| Error::field("rod.knots", &given, e.to_string());
        match &layout {
            KnotsSpec::Named(name) if name == "uniform" => {
                BSplineSpace::uniform(r.degree, r.control_points, r.rest_length).map_err(wrap)
            }
            KnotsSpec::Named(_) => {
                BSplineSpace::clamped_uniform(r.degree, r.control_points, r.rest_length)
                    .map_err(wrap)
            }
            KnotsSpec::Explicit(raw) => {
                // Check the user's numbers first, so errors quote them; then map the domain to [0, L].
                let given = BSplineSpace::new(r.degree, raw.clone()).map_err(wrap)?;
                let (a, b) = given.domain();
                let mapped = raw
                    .iter()
                    .map(|t| (t - a) / (b - a) * r.rest_length)
                    .collect();
                BSplineSpace::new(r.degree, mapped).map_err(wrap)
            }
        }
    }

    /// The rod in its initial state.
    pub fn build_rod(&self) -> Result<Rod, Error> {
        let r = &self.rod;
        let material = Material {
            rest_length: r.rest_length,
            linear_density: r.linear_density,
        };
        let mut rod = match &r.initial_control_points {
            _ if self.closed() => self.build_closed_rod(material)?,
            Some(points) => Rod::new(
                material,
                Box::new(self.basis()?),
                points.iter().map(|p| Vector3::from(*p)).collect(),
            )?,
            None => {
                let start = Vector3::from(r.start.unwrap_or([0.0; 3]));
                let end = r
                    .end
                    .map(Vector3::from)
                    .unwrap_or(start + Vector3::new(r.rest_length, 0.0, 0.0));
                Rod::straight(material, Box::new(self.basis()?), start, end)?
            }
        };
        rod.damping = r.damping;
        // The mixed stretching needs fewer points than the default (cubic: 4, not 5);
        // bending's rational integrand and the floor's contact samples keep the default.
        if r.stretch_formulation.is_mixed()
            && r.bending_stiffness.is_none()
            && self.contact.is_none()
            && (!self.part_of_world || self.reduced_quadrature)
        {
            // Nothing reads the basis' second derivatives either (only bending does).
            let formulation = StretchFormulation::Mixed;
            rod = rod
                .with_quadrature_points(formulation.points_per_span(r.degree))?
                .without_second_derivatives();
        }
        Ok(rod)
    }

    /// The rod with its energies and pins; with `[[rods]]`, all rods joined in one
    /// system ([`Rod::join`]).
    pub fn build_system(&self) -> Result<RodSystem, Error> {
        if !self.rods.is_empty() {
            return self.build_world();
        }
        let rod = self.resolve_coarse_start(self.build_rod()?)?;
        let l = rod.material().rest_length;
        let ea = self.rod.stretch_stiffness;
        let mut stretching = match self.rod.rest_shape {
            RestShape::Arclength => Stretching::new(ea.min(Real::MAX))?,
            RestShape::Initial => {
                Stretching::with_rest_shape(ea.min(Real::MAX), &rod).map_err(|e| {
                    let reason = format!("the initial curve cannot be the rest shape: {e}");
                    Error::field("rod.rest_shape", "\"initial\"", reason)
                })?
            }
        };
        stretching.formulation = self.stretch_formulation_used(&rod)?;
        stretching.guard = self.contact.as_ref().is_some_and(|c| c.enabled);
        if ea == Real::INFINITY {
            stretching.make_inextensible(&rod);
        }
        let mut system = RodSystem::new(rod).with_energy(stretching);
        if let Some(ei) = self.rod.bending_stiffness {
            let bending = Bending::for_rod(ei, &system.rod)?;
            system = system.with_energy(bending);
        }
        let g = Vector3::from(self.world.gravity);
        if g != Vector3::zeros() {
            system = system.with_energy(Gravity::new(g)?);
        }
        system = self.add_pins(system)?;
        if let Some(twisting) = self.twisting(&system.rod)? {
            system = system.with_energy(twisting);
        }
        for g in &self.grabs {
            let times = (g.start_time, g.end_time);
            let grab = Grab::new(g.at * l, Vector3::from(g.to), times, g.stiffness)?;
            system = system.with_grab(grab);
        }
        for load in self.loads()? {
            system = system.with_load(load);
        }
        if let Some(contact) = self.contact()?.filter(|_| !self.part_of_world) {
            system = system.with_energy(contact);
        }
        if self.part_of_world {
            return Ok(system);
        }
        self.add_bodies(system)
    }

    /// The `[[pins]]`, in order, then the exact clamps' tangent pins (after them, so a
    /// scene pin's index is its place in the file): a clamp at an end of a rod with
    /// clamped knots holds its tangent exactly (a pin on the next control point sliding
    /// along the tangent or `direction`, driven with the end) and gets a gripper
    /// ([`crate::world::gripper`], following its `pose`), elsewhere by the penalty
    /// [`Clamp`] (no `pose` there).
    fn add_pins(&self, mut system: RodSystem) -> Result<RodSystem, Error> {
        let l = self.rod.rest_length;
        let mut tangents = Vec::new();
        for (i, spec) in self.pins.iter().enumerate() {
            let mut pin = Pin::here(&system.rod, spec.at * l)?;
            if let Some(p) = spec.position {
                agrees(&format!("pins[{i}].position"), p, pin.position, l)?;
            }
            if let Some(axis) = spec.slides_along {
                pin = pin.sliding(Vector3::from(axis))?;
            }
            let mut path = None;
            if let Some(keyframes) = &spec.path {
                let field = format!("pins[{i}].path");
                // Times and values were checked by `Scene::validate`.
                let p = Path::new(keyframes, spec.interpolation, &field)?;
                agrees(&format!("{field}[0]"), p.start().1.into(), pin.position, l)?;
                system = system.with_driver(i, p.clone());
                path = Some(p);
            }
            if let (true, Some(ei)) = (spec.clamp, self.rod.bending_stiffness) {
                let direction = match spec.direction {
                    Some(d) => Vector3::from(d),
                    None => system.rod.tangent(spec.at * l)?,
                };
                match Pin::tangent_at(&system.rod, spec.at * l) {
                    Ok(tangent) => {
                        // Re-normalising the start tangent could move it by an ulp.
                        let tangent = match spec.direction {
                            Some(_) => tangent.sliding(direction)?,
                            None => tangent,
                        };
                        tangents.push((i, tangent, path));
                    }
                    Err(_) if spec.pose.is_some() => {
                        let reason = "a gripper needs an exact clamp: an end of a rod with clamped knots (rod.knots)";
                        return Err(Error::field(format!("pins[{i}].pose"), "given", reason));
                    }
                    Err(_) => {
                        let stiffness = Clamp::stiffness_for(ei, l);
                        let clamp = Clamp::new(spec.at * l, direction, stiffness)?;
                        system = system.with_energy(clamp);
                    }
                }
            }
            system = system.with_pin(pin);
        }
        for (i, tangent, path) in tangents {
            let index = system.pins.len();
            if let Some(path) = path {
                system = system.with_driver(index, path);
            }
            system = system.with_pin(tangent);
            system = self.with_gripper(system, i, index)?;
        }
        Ok(system)
    }

    /// `system` with a gripper on the exact clamp of `[[pins]]` entry `i` (its tangent
    /// pin `tangent`), following the entry's `pose`.
    fn with_gripper(
        &self,
        system: RodSystem,
        i: usize,
        tangent: usize,
    ) -> Result<RodSystem, Error> {
        let spec = &self.pins[i];
        let rod = &system.rod;
        let at = spec.at * self.rod.rest_length;
        let next = system.pins[tangent].row(rod)?.first;
        let end = usize::from(rod.segment_end(at) != Some(true));
        let lever = (rod.positions[next] - rod.point(at)?).norm();
        let Some(mut gripper) = Gripper::new(&system.pins, i, tangent, end, lever) else {
            return Ok(system);
        };
        if let Some(keyframes) = &spec.pose {
            let field = format!("pins[{i}].pose");
            gripper = gripper.with_path(PosePath::new(keyframes, spec.interpolation, &field)?);
        }
        Ok(system.with_gripper(gripper))
    }

    /// The twisting energy of `rod.twist_stiffness` between the end clamps, with their
    /// `turn` schedules (the start frame's axis is the rod's tangent there as it
    /// starts), or around a closed rod, which starts with the total twist `rod.twist`.
    fn twisting(&self, rod: &Rod) -> Result<Option<Twisting>, Error> {
        if let (Some(gj), true) = (self.rod.twist_stiffness, self.closed()) {
            let twist = self.rod.twist.unwrap_or(0.0);
            return Ok(Some(Twisting::around_loop(gj, rod, twist)?));
        }
        let (Some(gj), [Some(first), Some(last)]) = (self.rod.twist_stiffness, self.twist_clamps())
        else {
            return Ok(None);
        };
        // The clamps' axes: their `direction`s, or the rod's tangents as it starts.
        let axis = |i: usize, s: Real| match self.pins[i].direction {
            Some(d) => Ok(Vector3::from(d)),
            None => rod.tangent(s),
        };
        let frame = Frame::along(axis(first, 0.0)?)?;
        let end_axis = axis(last, rod.material().rest_length)?;
        let schedule = |i: usize| -> Result<Option<Keyframes<Real>>, Error> {
            let pin = &self.pins[i];
            let field = format!("pins[{i}].turn");
            pin.turn
                .as_ref()
                .map(|k| crate::world::path::schedule(k, pin.interpolation, &field))
                .transpose()
        };
        let twisting = Twisting::between_axes(gj, rod, frame, end_axis)?
            .with_turns(schedule(first)?, schedule(last)?);
        Ok(Some(twisting))
    }

    /// The adapt step of `[adaptivity]`, if enabled ([`crate::scene::AdaptivitySpec::adapter`]).
    pub fn adapter(&self) -> Result<Option<Adapter>, Error> {
        let Some(a) = self.adaptivity.as_ref().filter(|a| a.enabled) else {
            return Ok(None);
        };
        let initial = self.total_control_points();
        let adapter = a.adapter(self.rod.rest_length, initial)?;
        Ok(Some(adapter.with_continuity(self.continuity())))
    }

    /// Where adaptivity may make corners: the rods (segments) with neither bending nor
    /// twist stiffness ([`Continuity`]; on the others knots stop at multiplicity `d − 1`).
    pub fn continuity(&self) -> Continuity {
        let mut start = 0.0;
        let mut corners_allowed = Vec::new();
        for k in 0..self.rod_count() {
            let spec = self.rod_spec(k);
            let end = start + spec.rest_length;
            if spec.bending_stiffness.is_none() && spec.twist_stiffness.is_none() {
                corners_allowed.push((start, end));
            }
            start = end;
        }
        Continuity { corners_allowed }
    }

    /// Newton settings of `[solver]` for time stepping.
    pub fn newton_params(&self) -> NewtonParams {
        let d = NewtonParams::default();
        NewtonParams {
            max_iterations: self.solver.newton_iterations.unwrap_or(d.max_iterations),
            tolerance: self.solver.tolerance.unwrap_or(d.tolerance),
            line_search: self.solver.line_search,
            linear_solver: self.linear_solver(),
            max_step: self.max_step(),
            accept_unconverged: self.solver.accept_unconverged,
        }
    }

    /// The factorisation named by `solver.linear_solver`.
    pub fn linear_solver(&self) -> LinearSolverKind {
        match self.solver.linear_solver {
            LinearSolverSpec::Banded => LinearSolverKind::Banded,
            LinearSolverSpec::Sparse => LinearSolverKind::Sparse,
        }
    }

    /// Settings of `[solver]` for `method = "static"`.
    pub fn static_params(&self) -> StaticParams {
        let d = StaticParams::default();
        StaticParams {
            max_iterations: self.solver.newton_iterations.unwrap_or(d.max_iterations),
            tolerance: self.solver.tolerance.unwrap_or(d.tolerance),
            linear_solver: self.linear_solver(),
            ..d
        }
    }

    /// The integrator named by `solver.method` (the static solver for `static`).
    pub fn integrator(&self) -> Result<Box<dyn Integrator>, Error> {
        let method = self.solver.method;
        method.integrator(self.newton_params(), self.static_params())
    }

    /// The simulation of the scene (for `method = "static"`, with the static solver:
    /// [`Simulation::settle`] solves the equilibrium).
    pub fn build(&self) -> Result<Simulation, Error> {
        let integrator = self.integrator()?;
        let system = self.offset_pins(self.build_system()?)?;
        self.check_start_above_floor(&system.rod)?;
        self.check_start_clearance(&system)?;
        let mut sim = Simulation::new(system, integrator);
        if let Some(adapter) = self.adapter()? {
            sim = sim.with_adapter(adapter);
        }
        if self.output.error_estimate {
            sim = sim.estimate_errors();
        }
        sim.control = self.step_control();
        Ok(sim)
    }

    /// Refuses a start in deep contact: parts of the rods (or a rod and an obstacle)
    /// closer than [`MIN_START_CLEARANCE`] of their contact distance. The penalty would
    /// then push them apart with forces the steps can only follow by tiny sub-steps (a
    /// radius mistyped tenfold made a six-step run take minutes).
    fn check_start_clearance(&self, system: &RodSystem) -> Result<(), Error> {
        let contact = system.summary()?.contact;
        let Some(ratio) = contact.and_then(|c| c.min_clearance_ratio) else {
            return Ok(());
        };
        if ratio >= MIN_START_CLEARANCE {
            return Ok(());
        }
        let (field, radius) = match self.rods.is_empty() {
            true => ("rod.radius".to_string(), self.rod.radius),
            false => ("rods[].radius".to_string(), None),
        };
        let value = radius.map_or("as given".to_string(), |r| r.to_string());
        let reason = format!(
            "the rods start in deep contact (clearance {ratio:.3} of the contact distance, at least {MIN_START_CLEARANCE} needed): lay them out apart or use a smaller radius"
        );
        Err(Error::field(field, value, reason))
    }

    /// Number of steps of `dt` covering `duration` (the last step ends at or just past it).
    pub fn step_count(&self) -> usize {
        match (self.solver.method, self.solver.dt, self.solver.duration) {
            (m, Some(dt), Some(t)) if m != Method::Static => {
                ((t / dt) * (1.0 - 1e-12)).ceil().max(1.0) as usize
            }
            _ => 0,
        }
    }

    /// Material coordinate (m) of a scene fraction (of the first rod, with `[[rods]]`:
    /// see [`Scene::coordinate`]).
    pub fn material_coordinate(&self, fraction: Real) -> Real {
        self.coordinate(0, fraction)
    }
}

/// An error naming `field` unless the position `given` for a pin agrees with where the
/// rod starts there (`actual`), to 1e-9 of the rod's length `l`: a pin never makes the
/// rod jump.
fn agrees(field: &str, given: [Real; 3], actual: Vector3<Real>, l: Real) -> Result<(), Error> {
    let gap = (Vector3::from(given) - actual).norm();
    if gap > 1e-9 * l.max(1.0) {
        let reason = format!(
            "the rod starts at {:?} there ({gap:.3e} m away); pins must agree with the initial shape",
            actual.as_slice()
        );
        return Err(Error::field(field, format!("{given:?}"), reason));
    }
    Ok(())
}
