//! Parameter paths: what a scene path such as `rods[1].bending_stiffness` or
//! `pins[0].position[2]` names (`Target`), its value in a scene and how to set it.
//!
//! The paths with sensitivities: `rod.{stretch,bending,twist}_stiffness`,
//! `rod.linear_density`, `rod.damping` (runs), the same on `rods[k].…`,
//! `world.gravity[c]`, `loads[i].force[c]`, `pins[i].position[c]` and
//! `contact.friction` (runs). A pin's position is the held position at `t = 0` (where
//! the point starts, plus the [`offset`](crate::scene::PinSpec::offset) the parameter
//! sets); setting it translates the target — of a driven pin its whole `path`, of an
//! exact clamp its tangent pin too. `rod.rest_length` scales the rod's domain with every
//! material coordinate at its fraction (`sensitivity/rest_length.rs`, which refuses
//! what it cannot follow). Refused with the reason: `rods[k].rest_length` (see
//! `REST_LENGTH`), per-surface friction (`rod.friction`, `obstacles[i].friction`, and
//! `contact.friction` while one is set).

use crate::{Error, Scene};
use nalgebra::Vector3;
use splinerod_core::Real;
use splinerod_energies::rest_length::REST_LENGTH as REST_LENGTH_NAME;

/// Why a `[[rods]]` entry's rest length has no sensitivities.
pub(crate) const REST_LENGTH: &str = "not built for one rod of several: it would scale \
    its segment of the joined rod's domain alone (rod.rest_length of a single rod is)";

/// What a parameter path names.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Target {
    /// An energy parameter: its name and the segment (`None`: any energy of the rod).
    Energy(&'static str, Option<usize>),
    /// Component `c` of load `i`'s force.
    Load(usize, usize),
    /// The mass-proportional damping rate of the rod (`None`) or of `[[rods]]` entry `k`:
    /// a parameter of dynamic runs only.
    Damping(Option<usize>),
    /// Component `component` of `[[pins]]` entry `pin`'s held position; `start`: that
    /// component where the point starts (the position without offset), m.
    Pin {
        /// The `[[pins]]` entry.
        pin: usize,
        /// The component, 0 … 2.
        component: usize,
        /// Where the point starts, m.
        start: Real,
    },
    /// `contact.friction`, the Coulomb coefficient of every contact: a parameter of runs.
    Friction,
}

/// Sets the parameter at scene path `path` (as
/// [`static_sensitivities`](crate::sensitivity::static_sensitivities) reads it) of
/// `scene` to `value`.
pub fn set_parameter(scene: &mut Scene, path: &str, value: Real) -> Result<(), Error> {
    let target = target(scene, path)?;
    set(scene, &target, value);
    Ok(())
}

/// The value of the parameter at scene path `path` (as [`set_parameter`] names it) in
/// `scene`.
pub fn parameter_value(scene: &Scene, path: &str) -> Result<Real, Error> {
    Ok(target_value(scene, &target(scene, path)?))
}

/// An error naming the parameter `path` with `reason`.
fn bad(path: &str, reason: impl Into<String>) -> Error {
    Error::field("params", format!("\"{path}\""), reason.into())
}

/// What the parameter `path` names in `scene`, or an error naming it.
pub(crate) fn target(scene: &Scene, path: &str) -> Result<Target, Error> {
    if let Some(field) = path.strip_prefix("rod.") {
        if !scene.rods.is_empty() {
            return Err(bad(path, "the scene has [[rods]]: name the rod as rods[k]"));
        }
        if field == "rest_length" {
            super::rest_length::check_scene(scene, path)?;
            return Ok(Target::Energy(REST_LENGTH_NAME, None));
        }
        return rod_target(path, field, None);
    }
    if let Some((k, field)) =
        indexed(path, "rods[").and_then(|(k, rest)| Some((k, rest.strip_prefix('.')?)))
    {
        if k >= scene.rods.len() {
            let reason = format!("the scene has {} [[rods]] entries", scene.rods.len());
            return Err(bad(path, reason));
        }
        return rod_target(path, field, Some(k));
    }
    if let Some((c, "")) = indexed(path, "world.gravity[") {
        return match c {
            0 => Ok(Target::Energy("gravity[0]", None)),
            1 => Ok(Target::Energy("gravity[1]", None)),
            2 => Ok(Target::Energy("gravity[2]", None)),
            _ => Err(bad(path, "gravity has the components 0, 1, 2")),
        };
    }
    if let Some((i, rest)) = indexed(path, "loads[") {
        if let Some((c, "")) = indexed(rest, ".force[") {
            return load_target(scene, path, i, c);
        }
    }
    if let Some((i, rest)) = indexed(path, "pins[") {
        if let Some((c, "")) = indexed(rest, ".position[") {
            return pin_target(scene, path, i, c);
        }
    }
    if path == "contact.friction" {
        return friction_target(scene, path);
    }
    if indexed(path, "obstacles[").is_some_and(|(_, rest)| rest == ".friction") {
        let reason = "per-surface friction has no sensitivities yet (a contact's \
                      coefficient is the smaller of its two surfaces'; only the scene-wide \
                      contact.friction is differentiated)";
        return Err(bad(path, reason));
    }
    Err(bad(
        path,
        "not a scalar parameter with sensitivities (rod.<stiffness, linear_density, \
         rest_length or damping>, rods[k].…, world.gravity[c], loads[i].force[c], pins[i].position[c], \
         contact.friction)",
    ))
}

/// The target of the rod field `field` (of `[[rods]]` entry `segment`).
fn rod_target(path: &str, field: &str, segment: Option<usize>) -> Result<Target, Error> {
    const FIELDS: [&str; 4] = [
        "stretch_stiffness",
        "bending_stiffness",
        "twist_stiffness",
        "linear_density",
    ];
    match field {
        "damping" => Ok(Target::Damping(segment)),
        "rest_length" => Err(bad(path, REST_LENGTH)),
        "friction" => Err(bad(
            path,
            "per-rod friction has no sensitivities yet (only the scene-wide contact.friction)",
        )),
        _ => FIELDS
            .iter()
            .find(|f| **f == field)
            .map(|n| Target::Energy(n, segment))
            .ok_or_else(|| {
                let reason = format!(
                    "not a rod parameter with sensitivities ({}, damping)",
                    FIELDS.join(", ")
                );
                bad(path, reason)
            }),
    }
}

/// Component `c` of load `i`'s force, checked.
fn load_target(scene: &Scene, path: &str, i: usize, c: usize) -> Result<Target, Error> {
    if scene.loads.get(i).is_some_and(|l| l.force.is_none()) {
        return Err(bad(path, "a keyframed load (path) has no one force value"));
    }
    if i < scene.loads.len() && c < 3 {
        return Ok(Target::Load(i, c));
    }
    let reason = format!(
        "the scene has {} [[loads]]; a force has 3 components",
        scene.loads.len()
    );
    Err(bad(path, reason))
}

/// Component `c` of `[[pins]]` entry `i`'s held position, checked, with where it
/// starts.
fn pin_target(scene: &Scene, path: &str, i: usize, c: usize) -> Result<Target, Error> {
    if i >= scene.pins.len() || c >= 3 {
        let reason = format!(
            "the scene has {} [[pins]]; a position has 3 components",
            scene.pins.len()
        );
        return Err(bad(path, reason));
    }
    let start = pin_start(scene, i)?[c];
    Ok(Target::Pin {
        pin: i,
        component: c,
        start,
    })
}

/// Where `[[pins]]` entry `i`'s point starts: its `position`, its path's first
/// keyframe, or the rod's point there (the rods built).
fn pin_start(scene: &Scene, i: usize) -> Result<Vector3<Real>, Error> {
    let spec = &scene.pins[i];
    if let Some(p) = spec.position {
        return Ok(Vector3::from(p));
    }
    if let Some(k) = spec.path.as_ref().and_then(|p| p.first()) {
        return Ok(Vector3::new(k[1], k[2], k[3]));
    }
    Ok(scene.build_system()?.pins[i].position)
}

/// `contact.friction`, checked: contact on, a positive coefficient (at 0 no step froze
/// a normal force to scale), no surface with its own.
fn friction_target(scene: &Scene, path: &str) -> Result<Target, Error> {
    let Some(contact) = scene.contact.as_ref().filter(|c| c.enabled) else {
        return Err(bad(path, "the scene has no [contact]"));
    };
    if contact.friction <= 0.0 {
        let reason = "friction = 0 froze no contact's normal force: its derivative at 0 \
                      is not built (start from a positive coefficient)";
        return Err(bad(path, reason));
    }
    let own = (0..scene.rod_count()).find(|&k| scene.rod_spec(k).friction.is_some());
    if let Some(k) = own {
        let field = if scene.rods.is_empty() {
            "rod.friction".to_string()
        } else {
            format!("rods[{k}].friction")
        };
        let reason = format!("{field} is set: contacts with per-surface friction take the smaller coefficient, not differentiated yet");
        return Err(bad(path, reason));
    }
    if let Some(i) = scene.obstacles.iter().position(|o| o.friction().is_some()) {
        let reason = format!("obstacles[{i}].friction is set: contacts with per-surface friction take the smaller coefficient, not differentiated yet");
        return Err(bad(path, reason));
    }
    Ok(Target::Friction)
}

/// `(n, rest)` for `path = prefix + "n]" + rest`.
fn indexed<'a>(path: &'a str, prefix: &str) -> Option<(usize, &'a str)> {
    let rest = path.strip_prefix(prefix)?;
    let (n, rest) = rest.split_once(']')?;
    Some((n.parse().ok()?, rest))
}

/// Sets the parameter `target` of `scene` to `v`.
pub(crate) fn set(scene: &mut Scene, target: &Target, v: Real) {
    match *target {
        Target::Damping(Some(k)) => scene.rods[k].damping = v,
        Target::Damping(None) => scene.rod.damping = v,
        Target::Load(i, c) => {
            if let Some(f) = scene.loads[i].force.as_mut() {
                f[c] = v;
            }
        }
        Target::Pin {
            pin,
            component,
            start,
        } => scene.pins[pin].offset[component] = v - start,
        Target::Friction => {
            if let Some(c) = scene.contact.as_mut() {
                c.friction = v;
            }
        }
        Target::Energy(name, segment) => {
            let rod = match segment {
                Some(k) => &mut scene.rods[k],
                None => &mut scene.rod,
            };
            match name {
                "stretch_stiffness" => rod.stretch_stiffness = v,
                "bending_stiffness" => rod.bending_stiffness = Some(v),
                "twist_stiffness" => rod.twist_stiffness = Some(v),
                "linear_density" => rod.linear_density = v,
                REST_LENGTH_NAME => {
                    rod.rest_length = v;
                    rod.given_rest_length = Some(v);
                }
                "gravity[0]" => scene.world.gravity[0] = v,
                "gravity[1]" => scene.world.gravity[1] = v,
                _ => scene.world.gravity[2] = v,
            }
        }
    }
}

/// The scene value of the parameter `target`.
pub(crate) fn target_value(scene: &Scene, target: &Target) -> Real {
    match *target {
        Target::Energy(name, segment) => value(scene, name, segment),
        Target::Load(i, c) => scene.loads[i].force.map_or(0.0, |f| f[c]),
        Target::Damping(segment) => scene.rod_spec(segment.unwrap_or(0)).damping,
        Target::Pin {
            pin,
            component,
            start,
        } => start + scene.pins[pin].offset[component],
        Target::Friction => scene.contact.as_ref().map_or(0.0, |c| c.friction),
    }
}

/// The scene value of the energy parameter `name` (on rod `segment`).
pub(crate) fn value(scene: &Scene, name: &str, segment: Option<usize>) -> Real {
    let rod = scene.rod_spec(segment.unwrap_or(0));
    match name {
        "stretch_stiffness" => rod.stretch_stiffness,
        "bending_stiffness" => rod.bending_stiffness.unwrap_or(0.0),
        "twist_stiffness" => rod.twist_stiffness.unwrap_or(0.0),
        "linear_density" => rod.linear_density,
        REST_LENGTH_NAME => rod.rest_length,
        "gravity[0]" => scene.world.gravity[0],
        "gravity[1]" => scene.world.gravity[1],
        _ => scene.world.gravity[2],
    }
}

/// Per pin of `pins` (the system's), the derivative of its target by the parameter
/// `target`: \\(e_c\\) on the pins `[[pins]]` entry `i` moves
/// ([`Scene::moved_pins`]: its own and an exact clamp's tangent pin) for
/// `pins[i].position[c]`; for `rod.rest_length`, the initial shape's (zero unless the
/// rod's end follows it); zero otherwise (into `out`, resized).
pub(crate) fn target_rates(
    scene: &Scene,
    pins: &[splinerod_core::Pin],
    target: &Target,
    out: &mut Vec<Vector3<Real>>,
) {
    out.clear();
    out.resize(pins.len(), Vector3::zeros());
    match *target {
        Target::Pin { pin, component, .. } => {
            for p in scene.moved_pins(pins, pin) {
                out[p][component] = 1.0;
            }
        }
        Target::Energy(REST_LENGTH_NAME, None) => {
            super::rest_length::pin_rates(scene, pins, out);
        }
        _ => {}
    }
}
