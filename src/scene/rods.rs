//! Several rods in one scene: `[[rods]]` tables (each the fields of `[rod]` plus a
//! `name`), and pins, grabs, loads and cuts naming their rod (`rod = "upper"`).
//!
//! Each rod is read, resolved and validated as the one-rod scene it would be alone
//! (its entries only), with errors renamed to the file's own paths (`rods[1].damping`,
//! `pins[3].at`). It is built the same way — its energies, pins, grabs and loads — and
//! the rods are then joined into one system ([`Rod::join`]: end to end in parameter
//! space, separated by cuts), each energy put on its rod by [`OnSegment`], every
//! material coordinate moved to the joined parameter ([`Scene::coordinate`]). Contact
//! (between rods, with the floor and obstacles) acts on the joined rod, in the same
//! Newton matrix as everything else.
//!
//! Limits, checked with a clear error: one degree for all rods, no `[ensemble]`. Rods
//! of different radii keep their centre lines `r₁ + r₂` apart
//! ([`splinerod_energies::Contact::with_segment_radii`]).

use crate::scene::{LoadSpec, RodSpec, Scene};
use crate::world::gripper::Gripper;
use crate::{Error, PinDriver, RodSystem};
use splinerod_core::{Cancel, Pin, Real, Rod};
use splinerod_energies::OnSegment;

/// Where the entries of one rod's scene come from in the file.
#[derive(Debug, Default)]
pub(crate) struct Origins {
    pins: Vec<usize>,
    grabs: Vec<usize>,
    loads: Vec<usize>,
    cuts: Vec<usize>,
}

impl RodSpec {
    /// The placeholder for a scene without `[rod]` (one with `[[rods]]`).
    pub(crate) fn absent() -> Self {
        Self {
            name: None,
            absent: true,
            rest_length: 0.0,
            given_rest_length: None,
            linear_density: 0.0,
            stretch_stiffness: 0.0,
            bending_stiffness: None,
            twist_stiffness: None,
            twist: None,
            damping: 0.0,
            control_points: 0,
            degree: 3,
            knots: None,
            closed: false,
            ring: None,
            start: None,
            end: None,
            initial_control_points: None,
            radius: None,
            friction: None,
            overhand: None,
            rest_shape: Default::default(),
            stretch_formulation: Default::default(),
        }
    }
}

impl Scene {
    /// Number of rods (1 for a `[rod]` scene).
    pub fn rod_count(&self) -> usize {
        self.rods.len().max(1)
    }

    /// The table of rod `k` (`[rod]` for a one-rod scene).
    pub fn rod_spec(&self, k: usize) -> &RodSpec {
        self.rods.get(k).unwrap_or(&self.rod)
    }

    /// Control points of all rods at the start.
    pub fn total_control_points(&self) -> usize {
        (0..self.rod_count())
            .map(|k| self.rod_spec(k).control_points)
            .sum()
    }

    /// The system's material coordinate (m) of `fraction` of rod `k`: rods follow each
    /// other in parameter space; the end of a rod that another follows is the largest
    /// float below the junction ([`Rod::joined_coordinate`]).
    pub fn coordinate(&self, k: usize, fraction: Real) -> Real {
        if self.rods.is_empty() {
            return fraction * self.rod.rest_length;
        }
        let start = self.rods[..k].iter().fold(0.0, |o, r| o + r.rest_length);
        let length = self.rods[k].rest_length;
        let follows = k + 1 < self.rods.len();
        splinerod_core::segments::on_segment(start, start + length, fraction * length, follows)
    }

    /// [`Scene::coordinate`] of an entry naming rod `name`; an unknown name (or none in a
    /// scene of several rods) is an error naming `rod`.
    pub fn entry_coordinate(&self, name: Option<&str>, fraction: Real) -> Result<Real, Error> {
        let k = self.rod_index("rod", name)?;
        Ok(self.coordinate(k, fraction))
    }

    /// Index of the rod named `name` (`None`: the only rod); errors name `field`.
    pub fn rod_index(&self, field: &str, name: Option<&str>) -> Result<usize, Error> {
        let names: Vec<&str> = (0..self.rod_count())
            .map(|k| self.rod_spec(k).name.as_deref().unwrap_or(""))
            .collect();
        match name {
            None if self.rods.len() > 1 => {
                let reason = format!("required when the scene has several rods ({names:?})");
                Err(Error::field(field, "absent", reason))
            }
            None => Ok(0),
            Some(n) => names.iter().position(|m| *m == n).ok_or_else(|| {
                let reason = format!("no rod of that name (rods: {names:?})");
                Error::field(field, format!("\"{n}\""), reason)
            }),
        }
    }

    /// Rod `k` as a one-rod scene: its table, and the pins, grabs, loads and cuts naming
    /// it; and where they come from in the file.
    pub(crate) fn rod_scene(&self, k: usize) -> Result<(Scene, Origins), Error> {
        let mut origins = Origins::default();
        let mut sub = self.clone();
        sub.rod = self.rods[k].clone();
        sub.rods.clear();
        (sub.pins, origins.pins) = self.entries_of(k, "pins", &self.pins, |p| Some(&p.rod))?;
        (sub.grabs, origins.grabs) = self.entries_of(k, "grabs", &self.grabs, |g| Some(&g.rod))?;
        // A body's load names no rod (`add_bodies` takes it).
        (sub.loads, origins.loads) = self.entries_of(k, "loads", &self.loads, rod_of_load)?;
        (sub.cuts, origins.cuts) = self.entries_of(k, "cuts", &self.cuts, |c| Some(&c.rod))?;
        // Probes may name any rod: the whole scene checks them (`resolve_rods`).
        sub.output.probes.clear();
        Ok((sub, origins))
    }

    /// The entries of `list` (called `label` in the file) naming rod `k`, and their
    /// indices in the file.
    fn entries_of<T: Clone>(
        &self,
        k: usize,
        label: &str,
        list: &[T],
        rod: impl Fn(&T) -> Option<&Option<String>>,
    ) -> Result<(Vec<T>, Vec<usize>), Error> {
        let (mut mine, mut origins) = (Vec::new(), Vec::new());
        for (i, entry) in list.iter().enumerate() {
            let field = format!("{label}[{i}].rod");
            let Some(name) = rod(entry) else { continue };
            if self.rod_index(&field, name.as_deref())? == k {
                mine.push(entry.clone());
                origins.push(i);
            }
        }
        Ok((mine, origins))
    }

    /// For a scene with `[[rods]]`: resolves and validates every rod as its one-rod scene
    /// (errors renamed to the file's paths) and the rods together; `Ok(false)` for a
    /// one-rod scene, which the caller resolves as before.
    pub(crate) fn resolve_rods(&mut self, cancel: &Cancel) -> Result<bool, Error> {
        if self.rods.is_empty() {
            if self.rod.absent {
                let problems = vec![crate::scene::Problem::Missing {
                    field: "rod".into(),
                    table: true,
                    note: Some("or [[rods]]".into()),
                }];
                return Err(Error::Format {
                    file: None,
                    problems,
                });
            }
            return Ok(false);
        }
        if !self.rod.absent {
            let reason = "give one [rod] table or [[rods]] tables, not both";
            return Err(Error::field("rods", "given with [rod]", reason));
        }
        if self.ensemble.is_some() {
            let reason = "ensembles of scenes with several rods are not supported yet";
            return Err(Error::field("ensemble", "given with [[rods]]", reason));
        }
        self.check_names()?;
        for k in 0..self.rods.len() {
            let (mut sub, origins) = self.rod_scene(k)?;
            let rename = |e| renamed(e, k, &origins);
            sub.resolve_shape_with(cancel).map_err(rename)?;
            sub.validate().map_err(|e| renamed(e, k, &origins))?;
            self.rods[k] = sub.rod;
        }
        self.rod = self.rods[0].clone();
        self.check_together()?;
        for i in 0..self.output.probes.len() {
            self.validate_probe(i)?;
        }
        Ok(true)
    }

    /// Every rod has a name, unique and not empty.
    fn check_names(&self) -> Result<(), Error> {
        for (k, r) in self.rods.iter().enumerate() {
            let field = format!("rods[{k}].name");
            let Some(name) = r.name.as_deref().filter(|n| !n.is_empty()) else {
                let reason = "every rod of [[rods]] needs a name (pins, grabs, loads and cuts name their rod)";
                return Err(Error::field(field, "absent", reason));
            };
            if self.rods[..k]
                .iter()
                .any(|o| o.name.as_deref() == Some(name))
            {
                return Err(Error::field(
                    field,
                    format!("\"{name}\""),
                    "names must differ",
                ));
            }
        }
        Ok(())
    }

    /// What the rods must share: the degree, and room for all of them under
    /// `adaptivity.max_control_points`.
    fn check_together(&self) -> Result<(), Error> {
        let first = &self.rods[0];
        for (k, r) in self.rods.iter().enumerate().skip(1) {
            if r.degree != first.degree {
                let reason = format!(
                    "rods in one system share one degree (rods[0] has {})",
                    first.degree
                );
                return Err(Error::field(format!("rods[{k}].degree"), r.degree, reason));
            }
        }
        if let Some(a) = self.adaptivity.as_ref().filter(|a| a.enabled) {
            let total = self.total_control_points();
            if a.max_control_points < total {
                let reason = format!("below the rods' {total} control points at the start");
                let field = "adaptivity.max_control_points";
                return Err(Error::field(field, a.max_control_points, reason));
            }
        }
        Ok(())
    }

    /// The system of a `[[rods]]` scene (module docs).
    pub(crate) fn build_world(&self) -> Result<RodSystem, Error> {
        let mut parts = Vec::with_capacity(self.rods.len());
        // One quadrature for all: the mixed stretching's smaller one only if every rod
        // can use it (see `Scene::build_rod`).
        let reduced = self.contact.is_none()
            && self
                .rods
                .iter()
                .all(|r| r.stretch_formulation.is_mixed() && r.bending_stiffness.is_none());
        for k in 0..self.rods.len() {
            let (mut sub, origins) = self.rod_scene(k)?;
            sub.part_of_world = true;
            sub.reduced_quadrature = reduced;
            let part = sub.build_system().map_err(|e| renamed(e, k, &origins))?;
            parts.push((part, origins));
        }
        let rods: Vec<Rod> = parts.iter().map(|(p, _)| p.rod.clone()).collect();
        let mut system = RodSystem::new(Rod::join(&rods)?);
        let mut scene_pins: Vec<Option<Pin>> = vec![None; self.pins.len()];
        let mut tangents = Vec::new();
        let mut drivers = Vec::new();
        let mut grippers = Vec::new();
        let mut grabs = vec![None; self.grabs.len()];
        let mut loads = vec![None; self.loads.len()];
        for (k, (part, origins)) in parts.into_iter().enumerate() {
            let joined = &system.rod;
            let at = |s: Real| joined.joined_coordinate(k, s);
            let mut index = Vec::with_capacity(part.pins.len());
            for (i, pin) in part.pins.iter().enumerate() {
                let pin = Pin {
                    at: at(pin.at),
                    ..*pin
                };
                if let Some(&file) = origins.pins.get(i) {
                    scene_pins[file] = Some(pin);
                    index.push(file);
                } else {
                    index.push(self.pins.len() + tangents.len());
                    tangents.push(pin);
                }
            }
            drivers.extend(part.drivers.into_iter().map(|d| PinDriver {
                pin: index[d.pin],
                path: d.path,
            }));
            grippers.extend(part.grippers.into_iter().map(|g| Gripper {
                pin: index[g.pin],
                tangent: index[g.tangent],
                segment: Some(k),
                ..g
            }));
            for (mut grab, &file) in part.grabs.into_iter().zip(&origins.grabs) {
                grab.spring.at = at(grab.spring.at);
                grabs[file] = Some(grab);
            }
            for (mut load, &file) in part.loads.into_iter().zip(&origins.loads) {
                load.force.at = at(load.force.at);
                loads[file] = Some(load);
            }
            for energy in part.energies {
                let placed = OnSegment::new(&system.rod, k, energy)?;
                system.energies.push(Box::new(placed));
            }
        }
        system.pins = scene_pins.into_iter().flatten().chain(tangents).collect();
        system.drivers = drivers;
        system.grippers = grippers;
        system.grabs = grabs.into_iter().flatten().collect();
        system.loads = loads.into_iter().flatten().collect();
        if let Some(contact) = self.contact()? {
            let starts: Vec<Real> = system.rod.segments().iter().map(|g| g.start).collect();
            let radii: Vec<Real> = self.rods.iter().map(|r| r.radius.unwrap_or(0.0)).collect();
            let mut contact = contact.with_segment_radii(&starts, &radii)?;
            if self.rods.iter().any(|r| r.friction.is_some()) {
                let default = self.contact.as_ref().map_or(0.0, |c| c.friction);
                let mu: Vec<Real> = self
                    .rods
                    .iter()
                    .map(|r| r.friction.unwrap_or(default))
                    .collect();
                contact = contact.with_segment_friction(&starts, &mu)?;
            }
            system = system.with_energy(contact);
        }
        self.add_bodies(system)
    }
}

/// The rod a load names; `None` for a body's load (no rod's).
fn rod_of_load(load: &LoadSpec) -> Option<&Option<String>> {
    load.body.is_none().then_some(&load.rod)
}

/// `e` with the field paths of rod `k`'s scene renamed to the file's: `rod.x` to
/// `rods[k].x`, `pins[j]` to the file's index of that pin (grabs, loads, cuts alike).
fn renamed(e: Error, k: usize, origins: &Origins) -> Error {
    let rename = |field: String| -> String {
        if let Some(rest) = field.strip_prefix("rod.") {
            return format!("rods[{k}].{rest}");
        }
        let lists = [
            ("pins[", &origins.pins),
            ("grabs[", &origins.grabs),
            ("loads[", &origins.loads),
            ("cuts[", &origins.cuts),
        ];
        for (list, map) in lists {
            let Some(rest) = field.strip_prefix(list) else {
                continue;
            };
            let Some((j, after)) = rest.split_once(']') else {
                continue;
            };
            if let Some(file) = j.parse::<usize>().ok().and_then(|j| map.get(j)) {
                return format!("{list}{file}]{after}");
            }
        }
        field
    };
    match e {
        Error::InvalidField {
            field,
            value,
            reason,
        } => Error::InvalidField {
            field: rename(field),
            value,
            reason,
        },
        Error::MissingField { field, reason } => Error::MissingField {
            field: rename(field),
            reason,
        },
        other => other,
    }
}
