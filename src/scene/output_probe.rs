//! One entry of `output.probes`: a material point whose position is recorded at every
//! step, given as a fraction of the (first) rod's length (`0.5`) or, on any rod of a
//! `[[rods]]` scene, as a table naming the rod (`{ rod = "upper", at = 0.5 }`).

use crate::error::fraction;
use crate::{Error, Scene};
use serde::de::{self, MapAccess, Visitor};
use serde::{Deserialize, Deserializer};
use splinerod_core::Real;
use std::fmt;

/// A probed material point (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeSpec {
    /// The rod it is on (`None`: the first rod, or the only one).
    pub rod: Option<String>,
    /// Fraction of that rod's rest length, in `[0, 1]`.
    pub at: Real,
}

impl From<Real> for ProbeSpec {
    fn from(at: Real) -> Self {
        Self { rod: None, at }
    }
}

impl Scene {
    /// Checks probe `i` (field `output.probes[i]`): a fraction in `[0, 1]` on a rod the
    /// scene has.
    pub(crate) fn validate_probe(&self, i: usize) -> Result<(), Error> {
        let probe = &self.output.probes[i];
        if probe.rod.is_none() {
            return fraction(&format!("output.probes[{i}]"), probe.at);
        }
        fraction(&format!("output.probes[{i}].at"), probe.at)?;
        self.rod_index(&format!("output.probes[{i}].rod"), probe.rod.as_deref())?;
        Ok(())
    }

    /// The system's material coordinate (m) of `probe`: on the rod it names, else on the
    /// first rod (as every plain fraction of the scene).
    pub fn probe_coordinate(&self, probe: &ProbeSpec) -> Result<Real, Error> {
        let k = match probe.rod.as_deref() {
            None => 0,
            // Found without allocating (this runs at every step); the error path names
            // the rods.
            Some(name) => match (0..self.rod_count())
                .position(|k| self.rod_spec(k).name.as_deref().unwrap_or("") == name)
            {
                Some(k) => k,
                None => self.rod_index("output.probes.rod", Some(name))?,
            },
        };
        Ok(self.coordinate(k, probe.at))
    }
}

impl<'de> Deserialize<'de> for ProbeSpec {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ProbeVisitor)
    }
}

/// Reads a number or a `{ rod, at }` table.
struct ProbeVisitor;

impl<'de> Visitor<'de> for ProbeVisitor {
    type Value = ProbeSpec;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a fraction of the rod's length or a table { rod = \"name\", at = fraction }")
    }

    fn visit_f64<E: de::Error>(self, at: f64) -> Result<ProbeSpec, E> {
        Ok(at.into())
    }

    fn visit_i64<E: de::Error>(self, at: i64) -> Result<ProbeSpec, E> {
        Ok((at as Real).into())
    }

    fn visit_u64<E: de::Error>(self, at: u64) -> Result<ProbeSpec, E> {
        Ok((at as Real).into())
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<ProbeSpec, A::Error> {
        let (mut rod, mut at) = (None, None);
        while let Some(key) = map.next_key::<String>()? {
            match key.as_str() {
                "rod" => rod = Some(map.next_value::<String>()?),
                "at" => at = Some(map.next_value::<Real>()?),
                other => return Err(de::Error::unknown_field(other, &["rod", "at"])),
            }
        }
        let at = at.ok_or_else(|| de::Error::missing_field("at"))?;
        let rod = rod.ok_or_else(|| de::Error::missing_field("rod"))?;
        Ok(ProbeSpec { rod: Some(rod), at })
    }
}
