//! The `[ensemble]` scene table: `count` copies of the scene's rod, each with its own
//! material values drawn uniformly from the given ranges and its interior control points
//! displaced by a random amount, reproducibly from `seed` (member `i` draws from stream
//! `i` of a ChaCha8 generator, so it gets the same values whatever the thread count).

use crate::scene::{non_negative, positive};
use crate::{Error, Scene, Simulation};
use nalgebra::Vector3;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use serde::Deserialize;

/// `[ensemble]`.
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnsembleSpec {
    /// Number of rods (≥ 1).
    pub count: usize,
    /// Seed of the random variations. Default 0.
    #[serde(default)]
    pub seed: u64,
    /// `[min, max]` of `rod.stretch_stiffness`, N.
    pub stretch_stiffness: Option<[f64; 2]>,
    /// `[min, max]` of `rod.linear_density`, kg/m.
    pub linear_density: Option<[f64; 2]>,
    /// `[min, max]` of `rod.damping`, 1/s.
    pub damping: Option<[f64; 2]>,
    /// Largest random displacement of each coordinate of the control points that no pin
    /// holds, m. Default 0.
    #[serde(default)]
    pub perturbation: f64,
    /// Solve the steps of members that share a shape four at a time
    /// ([`crate::Ensemble::batched`]; the same results up to round-off). Default true.
    #[serde(default = "batched_default")]
    pub batched: bool,
}

fn batched_default() -> bool {
    true
}

fn range(field: &str, r: Option<[f64; 2]>, zero_allowed: bool) -> Result<(), Error> {
    let Some([lo, hi]) = r else {
        return Ok(());
    };
    let check = if zero_allowed { non_negative } else { positive };
    check(&format!("{field}[0]"), lo)?;
    check(&format!("{field}[1]"), hi)?;
    if lo > hi {
        return Err(Error::field(
            field,
            format!("[{lo}, {hi}]"),
            "min must not exceed max",
        ));
    }
    Ok(())
}

impl EnsembleSpec {
    /// Range checks; errors name the field.
    pub fn validate(&self) -> Result<(), Error> {
        if self.count == 0 {
            return Err(Error::field("ensemble.count", 0, "must be at least 1"));
        }
        range("ensemble.stretch_stiffness", self.stretch_stiffness, false)?;
        range("ensemble.linear_density", self.linear_density, false)?;
        range("ensemble.damping", self.damping, true)?;
        non_negative("ensemble.perturbation", self.perturbation)
    }

    /// Member `index`'s scene and its random perturbation generator.
    fn member_scene(&self, scene: &Scene, index: usize) -> (Scene, ChaCha8Rng) {
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed);
        rng.set_stream(index as u64);
        let mut draw = |r: Option<[f64; 2]>, default: f64| match r {
            Some([lo, hi]) if hi > lo => rng.random_range(lo..=hi),
            Some([lo, _]) => lo,
            None => default,
        };
        let mut member = scene.clone();
        member.ensemble = None;
        let rod = &mut member.rod;
        rod.stretch_stiffness = draw(self.stretch_stiffness, rod.stretch_stiffness);
        rod.linear_density = draw(self.linear_density, rod.linear_density);
        rod.damping = draw(self.damping, rod.damping);
        (member, rng)
    }

    /// Builds member `index`: its simulation and its scene.
    pub fn member(&self, scene: &Scene, index: usize) -> Result<(Scene, Simulation), Error> {
        let (member, mut rng) = self.member_scene(scene, index);
        let mut sim = member.build()?;
        let a = self.perturbation;
        if a > 0.0 {
            let held = held_control_points(&sim)?;
            for (i, q) in sim.system.rod.positions.iter_mut().enumerate() {
                let shift = Vector3::from_fn(|_, _| rng.random_range(-a..=a));
                if !held[i] {
                    *q += shift;
                }
            }
        }
        Ok((member, sim))
    }
}

/// Control points a pin depends on (moving them would make a pin jump).
fn held_control_points(sim: &Simulation) -> Result<Vec<bool>, Error> {
    let rod = &sim.system.rod;
    let mut held = vec![false; rod.len()];
    for pin in &sim.system.pins {
        let row = pin.row(rod)?;
        for k in 0..row.order {
            held[row.first + k] |= row.value[k] != 0.0;
        }
    }
    Ok(held)
}
