//! Pins held away from where they start: a `[[pins]]` entry's
//! [`offset`](crate::scene::PinSpec::offset) `δ` (never read from a scene file; set by
//! [`crate::sensitivity::set_parameter`] for the parameter `pins[i].position[c]`)
//! moves its target \\(c \to c + \delta\\) — a held pin's position, every keyframe of a
//! driven pin's `path`, and an exact clamp's tangent pin with it (the line it slides
//! on is translated, its direction kept). The rod still starts where its shape puts it:
//! a run reaches the moved target in its first step, a static solve at equilibrium.

use crate::scene::Scene;
use crate::world::path::Path;
use crate::{Error, RodSystem};
use nalgebra::Vector3;

impl Scene {
    /// `system` (as built from this scene) with every `[[pins]]` entry's offset applied
    /// to its pin, its driver's path and its clamp's tangent pin.
    pub(crate) fn offset_pins(&self, mut system: RodSystem) -> Result<RodSystem, Error> {
        for (i, spec) in self.pins.iter().enumerate() {
            let offset = Vector3::from(spec.offset);
            if offset == Vector3::zeros() {
                continue;
            }
            let moved = self.moved_pins(&system.pins, i);
            for &p in &moved {
                system.pins[p].position += offset;
            }
            let Some(keyframes) = &spec.path else {
                continue;
            };
            let shifted: Vec<[f64; 4]> = keyframes
                .iter()
                .map(|k| [k[0], k[1] + offset.x, k[2] + offset.y, k[3] + offset.z])
                .collect();
            let path = Path::new(&shifted, spec.interpolation, &format!("pins[{i}].path"))?;
            for driver in system.drivers.iter_mut().filter(|d| moved.contains(&d.pin)) {
                driver.path = path.clone();
            }
        }
        Ok(system)
    }

    /// The system's pins that `[[pins]]` entry `i` moves: its own (index `i`) and an
    /// exact clamp's tangent pin.
    pub(crate) fn moved_pins(&self, pins: &[splinerod_core::Pin], i: usize) -> Vec<usize> {
        let tangents = crate::run::pins::clamp_tangents(self, pins, pins.len());
        let tangents = tangents.filter(|&(_, j)| j == i).map(|(t, _)| t);
        std::iter::once(i).chain(tangents).collect()
    }
}
