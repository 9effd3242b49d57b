//! What a run reports about twist: the clamps' torques (`pin_torques`) and the twist
//! state (`twist`), from the twisting energy's summary.

use crate::{Error, RodSystem, Scene};
use nalgebra::Vector3;
use serde::Serialize;
use splinerod_core::Real;

/// The twist between the end clamps.
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct TwistOutput {
    /// Total twist Tw of the material frame, rad.
    pub twist: Real,
    /// Turn of the end clamp relative to the start clamp, rad.
    pub turn: Real,
    /// Twisting moment the clamps hold, N·m.
    pub moment: Real,
    /// Writhe of the centreline closed along the clamp axes ([`crate::knot::writhe`]), turns.
    pub writhe: Real,
    /// Link `twist / 2π + writhe`, turns: by Călugăreanu's theorem the clamps' relative
    /// turn in turns (plus the link the rod started with).
    pub link: Real,
}

/// Samples of the centreline for the writhe.
const WRITHE_SAMPLES: usize = 401;

/// The twist state, if the rod has a twisting energy.
pub(crate) fn twist(system: &RodSystem) -> Result<Option<TwistOutput>, Error> {
    let Some(t) = system.summary()?.twist else {
        return Ok(None);
    };
    let axes = t.axes.map(Vector3::from);
    let writhe = crate::knot::writhe::writhe(&system.rod, WRITHE_SAMPLES, axes)?;
    Ok(Some(TwistOutput {
        twist: t.twist,
        turn: t.turn,
        moment: t.moment,
        writhe,
        link: t.twist / (2.0 * std::f64::consts::PI) + writhe,
    }))
}

/// Per pin, the torque it exerts on the rod (N·m): `−M` about the start clamp's axis,
/// `+M` about the end clamp's, zero for the other pins; empty without twist.
pub(crate) fn pin_torques(scene: &Scene, system: &RodSystem) -> Result<Vec<[Real; 3]>, Error> {
    let Some(t) = system.summary()?.twist else {
        return Ok(Vec::new());
    };
    let mut torques = vec![[0.0; 3]; scene.pins.len()];
    let [start, end] = scene.twist_clamps();
    for (pin, sign, axis) in [(start, -1.0, t.axes[0]), (end, 1.0, t.axes[1])] {
        if let Some(i) = pin {
            torques[i] = (Vector3::from(axis) * (sign * t.moment)).into();
        }
    }
    Ok(torques)
}
