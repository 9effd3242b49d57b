//! Plausibility checks of a scene: values each in range that together describe no thin
//! rod, or a start no rod can have (each made a fuzzed run that could not finish).

use crate::scene::build::MIN_START_CLEARANCE;
use crate::scene::{PinSpec, Scene};
use crate::world::gripper::PosePath;
use crate::world::path::Path;
use crate::Error;
use nalgebra::Vector3;
use splinerod_core::Rod;

/// Smallest stretch (initial length over rest length) a scene may start a rod with.
pub const MIN_START_STRETCH: f64 = 0.1;

impl Scene {
    /// A bending or twisting stiffness `k` (N·m²) of a thin rod: at most EA·L² (its
    /// ratio to EA is a radius of gyration squared, which cannot exceed the length).
    /// Beyond it the stiffnesses differ by more than a double resolves in one Newton
    /// matrix (the fuzzer's EI = 9.2e18 made a run that could not finish).
    pub(crate) fn validate_against_stretch(
        &self,
        field: &str,
        k: Option<f64>,
    ) -> Result<(), Error> {
        let r = &self.rod;
        let bound = r.stretch_stiffness * r.rest_length * r.rest_length;
        match k {
            Some(k) if k.is_finite() && bound.is_finite() && k > bound => {
                let reason = format!(
                    "must be at most stretch_stiffness × rest_length² = {bound:e} N·m² for a thin rod"
                );
                Err(Error::field(field, k, reason))
            }
            _ => Ok(()),
        }
    }

    /// The initial curve (the straight `start`–`end` line, or the control polygon, which
    /// is at least as long as the curve) may not be squeezed to less than
    /// [`MIN_START_STRETCH`] of the rest length: a rod cannot be, and with contact such a
    /// start puts thousands of samples within reach of each other.
    pub(crate) fn validate_start_length(&self) -> Result<(), Error> {
        let r = &self.rod;
        let to_vector = |p: [f64; 3]| nalgebra::Vector3::from(p);
        let (field, value, length) = match (&r.initial_control_points, r.start, r.end) {
            (Some(points), ..) => {
                let pairs = points.windows(2);
                let length: f64 = pairs
                    .map(|w| (to_vector(w[1]) - to_vector(w[0])).norm())
                    .sum();
                let value = format!("{} points", points.len());
                ("rod.initial_control_points", value, length)
            }
            (None, Some(a), Some(b)) => {
                let value = format!("{b:?}");
                ("rod.end", value, (to_vector(b) - to_vector(a)).norm())
            }
            _ => return Ok(()),
        };
        let stretch = length / r.rest_length;
        // A relative 1e-12 of slack: `end = 0.1 · L` written as 1 − 0.9 is still allowed.
        if stretch < MIN_START_STRETCH * (1.0 - 1e-12) {
            let reason = format!(
                "the initial curve is at most {length:.4e} m long for a rest length of {} m (stretch {stretch:.3e}, at least {MIN_START_STRETCH} allowed)",
                r.rest_length
            );
            return Err(Error::field(field, value, reason));
        }
        Ok(())
    }
}

/// Largest rest length, knot size or span a scene may give, m: beyond it lengths, knots
/// and samples stop being representable together (a fuzzed `rest_length = 1e308` made
/// every knot infinite).
pub const MAX_LENGTH: f64 = 1e9;

/// Smallest distance between two cuts of one rod, as a fraction of its rest length:
/// closer cuts meet in one knot of multiplicity above `degree + 1`.
pub const MIN_CUT_SEPARATION: f64 = 1e-6;

/// A length field: positive and at most [`MAX_LENGTH`].
pub(crate) fn length(field: &str, v: f64) -> Result<(), Error> {
    crate::error::positive(field, v)?;
    if v > MAX_LENGTH {
        return Err(Error::field(
            field,
            v,
            format!("must be at most {MAX_LENGTH:e} m"),
        ));
    }
    Ok(())
}

impl Scene {
    /// Cross-field checks of values each in range: the cuts apart, an inextensible rod's pins within its reach.
    pub(crate) fn validate_plausible(&self) -> Result<(), Error> {
        self.validate_cuts_apart()?;
        if self.rod.stretch_stiffness == f64::INFINITY {
            self.validate_inextensible_pins()?;
        }
        Ok(())
    }

    /// No two cuts of one rod at the same point (on a closed rod, 0 and 1 are one point).
    fn validate_cuts_apart(&self) -> Result<(), Error> {
        for (j, b) in self.cuts.iter().enumerate() {
            for (i, a) in self.cuts[..j].iter().enumerate() {
                if a.rod != b.rod {
                    continue;
                }
                let mut apart = (a.at - b.at).abs();
                if self.closed() {
                    apart = apart.min(1.0 - apart);
                }
                if apart < MIN_CUT_SEPARATION {
                    let reason = format!(
                        "meets cuts[{i}] (at = {}): cuts of one rod must be at least {MIN_CUT_SEPARATION:e} of its length apart{}",
                        a.at,
                        if self.closed() { " (0 and 1 are the same point of a closed rod)" } else { "" }
                    );
                    return Err(Error::field(format!("cuts[{j}].at"), b.at, reason));
                }
            }
        }
        Ok(())
    }

    /// An inextensible rod cannot span pins farther apart than the rod between them: at
    /// time 0 and over every driven pin's path, each pair of pins (fixed or driven, not
    /// sliding) must stay within the rest length between their material points.
    fn validate_inextensible_pins(&self) -> Result<(), Error> {
        let pins = &self.pins;
        for (j, b) in pins.iter().enumerate() {
            for (i, a) in pins[..j].iter().enumerate() {
                if a.rod != b.rod || a.slides_along.is_some() || b.slides_along.is_some() {
                    continue;
                }
                let reach = (a.at - b.at).abs() * self.rod.rest_length;
                for t in self.pin_check_times(a, b)? {
                    let (Some(pa), Some(pb)) = (self.pin_point(a, t)?, self.pin_point(b, t)?)
                    else {
                        continue;
                    };
                    let apart = (pa - pb).norm();
                    if apart > reach * (1.0 + 1e-9) + 1e-12 * self.rod.rest_length {
                        let field = Self::pin_field(j, b)
                            .or_else(|| Self::pin_field(i, a))
                            .unwrap_or_else(|| "rod.end".to_string());
                        let reason = format!(
                            "the rod is inextensible, but pins[{i}] and pins[{j}] are {apart:.6e} m apart at t = {t} s, farther than the {reach:.6e} m of rod between them"
                        );
                        return Err(Error::field(
                            field,
                            format!("{:?}", [pb.x, pb.y, pb.z]),
                            reason,
                        ));
                    }
                }
            }
        }
        Ok(())
    }

    /// The field that places pin `k` (`path` or `position`; `None`: on the start).
    fn pin_field(k: usize, pin: &PinSpec) -> Option<String> {
        match (&pin.path, pin.position) {
            (Some(_), _) => Some(format!("pins[{k}].path")),
            (None, Some(_)) => Some(format!("pins[{k}].position")),
            (None, None) => None,
        }
    }

    /// Times to compare two pins at: 0, every keyframe of their paths (and poses) and 64 instants
    /// along the longer path (smooth interpolation may pass between keyframes).
    fn pin_check_times(&self, a: &PinSpec, b: &PinSpec) -> Result<Vec<f64>, Error> {
        let mut times = vec![0.0];
        let mut end: f64 = 0.0;
        for pin in [a, b] {
            let path = pin.path.iter().flatten().map(|k| k[0]);
            let pose = pin.pose.iter().flatten().map(|k| k[0]);
            for time in path.chain(pose) {
                times.push(time);
                end = end.max(time);
            }
        }
        times.extend((1..=64).map(|k| end * k as f64 / 64.0));
        Ok(times)
    }

    /// Where pin `p` holds its point at time `t`: on its path, at its `position`, or on
    /// the straight start line; `None` where the start is no straight line.
    fn pin_point(&self, p: &PinSpec, t: f64) -> Result<Option<Vector3<f64>>, Error> {
        let start = self.pin_start(p, t)?;
        let Some(keyframes) = &p.pose else {
            return Ok(start);
        };
        let pose = PosePath::new(keyframes, p.interpolation, "pins[].pose")?;
        Ok(start.map(|x| x + pose.at(t).0))
    }

    /// [`Scene::pin_point`] without a gripper's translation.
    fn pin_start(&self, p: &PinSpec, t: f64) -> Result<Option<Vector3<f64>>, Error> {
        if let Some(keyframes) = &p.path {
            let path = Path::new(keyframes, p.interpolation, "pins[].path")?;
            return Ok(Some(path.at(t)));
        }
        if let Some(x) = p.position {
            return Ok(Some(Vector3::from(x)));
        }
        let r = &self.rod;
        match (r.start, r.end, &r.initial_control_points) {
            (Some(a), Some(b), None) if r.overhand.is_none() && !self.closed() => {
                let (a, b) = (Vector3::from(a), Vector3::from(b));
                Ok(Some(a + (b - a) * p.at))
            }
            _ => Ok(None),
        }
    }
}

impl Scene {
    /// Refuses a rod that starts below `contact.floor`: a centre line closer to the floor
    /// than [`MIN_START_CLEARANCE`] of the radius at a quadrature point (where the floor
    /// pushes). The penalty would launch it (a fuzzed start 0.5 m under the floor left
    /// with 32 kJ of kinetic energy).
    pub(crate) fn check_start_above_floor(&self, rod: &Rod) -> Result<(), Error> {
        let Some(floor) = self
            .contact
            .as_ref()
            .filter(|c| c.enabled)
            .and_then(|c| c.floor)
        else {
            return Ok(());
        };
        let table = rod.quadrature();
        for p in 0..table.len() {
            let q = table.point(p);
            let y: f64 = (0..q.value.len())
                .map(|k| rod.positions[q.first + k].y * q.value[k])
                .sum();
            let radius = self.radius_at(q.s);
            if y - floor < MIN_START_CLEARANCE * radius {
                let reason = format!(
                    "the rod starts with its centre line at y = {y:.6e} m, within {MIN_START_CLEARANCE} r (r = {radius} m) of the floor or below it: start it above floor + r"
                );
                return Err(Error::field("contact.floor", floor, reason));
            }
        }
        Ok(())
    }

    /// The contact radius of the rod at material coordinate `s` (m along the joined
    /// rods of `[[rods]]`).
    fn radius_at(&self, s: f64) -> f64 {
        let mut start = 0.0;
        for k in 0..self.rod_count() {
            let spec = self.rod_spec(k);
            start += spec.rest_length;
            if s <= start || k + 1 == self.rod_count() {
                return spec.radius.unwrap_or(0.0);
            }
        }
        0.0
    }
}
