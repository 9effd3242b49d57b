//! Closed rods in scenes: `[rod] closed = true` with `initial_control_points` (the curve
//! wraps from the last point back to the first), or `[rod.ring]`, a circle fitted by
//! [`Rod::ring`] (which makes the rod closed by itself).
//!
//! ```toml
//! [rod]
//! rest_length = 1.0
//! control_points = 16      # distinct control points around the loop
//! [rod.ring]
//! radius = 0.15915         # 2π · radius = rest_length: at rest
//! center = [0.0, 0.0, 0.5]
//! normal = [0.0, 0.0, 1.0]
//! ```
//!
//! `twist_stiffness` with `twist` (rad) gives a closed rod the twist of a loop
//! ([`splinerod_energies::Twisting::around_loop`]). The knots are periodic: `"uniform"` (the default for a closed rod) or an explicit list
//! of `control_points + 1` breakpoints, the first being the seam and the last one period
//! after it (any units: mapped to `[0, L]`).

use crate::scene::{KnotsSpec, Scene};
use crate::Error;
use nalgebra::Vector3;
use serde::Deserialize;
use splinerod_core::{BasisSpace, Material, PeriodicBSplineSpace, Real, Rod};

/// `[rod.ring]`: the initial shape of a closed rod, a circle.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct RingSpec {
    /// Radius, m (> 0). At rest when `2π · radius = rest_length`, uniformly stretched
    /// otherwise.
    pub radius: f64,
    /// Centre, m. Default the origin.
    #[serde(default)]
    pub center: [f64; 3],
    /// Normal of the circle's plane (any length but zero). Default `[0, 0, 1]`.
    #[serde(default = "default_normal")]
    pub normal: [f64; 3],
}

fn default_normal() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

impl Scene {
    /// Whether the scene's rod is closed (`rod.closed` or `[rod.ring]`).
    pub fn closed(&self) -> bool {
        self.rod.closed || self.rod.ring.is_some()
    }

    /// Checks what a closed rod needs and refuses what it cannot have; nothing for an
    /// open rod.
    pub(crate) fn validate_closed(&self) -> Result<(), Error> {
        let r = &self.rod;
        if !self.closed() {
            return Ok(());
        }
        let refuse = |field: &str, value: String, reason: &str| {
            Err(Error::field(field, value, reason.to_string()))
        };
        let no_ends = "a closed rod has no ends: its shape comes from [rod.ring] or rod.initial_control_points";
        if let Some(s) = r.start {
            return refuse("rod.start", format!("{s:?}"), no_ends);
        }
        if let Some(e) = r.end {
            return refuse("rod.end", format!("{e:?}"), no_ends);
        }
        if r.overhand.is_some() {
            return refuse(
                "rod.overhand",
                "given".into(),
                "an overhand knot is an open rod",
            );
        }
        match (&r.ring, &r.initial_control_points) {
            (None, None) => {
                let reason = "a closed rod needs [rod.ring] or rod.initial_control_points";
                return refuse("rod.closed", "true".into(), reason);
            }
            (Some(_), Some(_)) => {
                let reason = "give either [rod.ring] or initial_control_points, not both";
                return refuse("rod.initial_control_points", "given".into(), reason);
            }
            (Some(ring), None) => validate_ring(ring)?,
            (None, Some(_)) => {}
        }
        if let Some((i, _)) = self.pins.iter().enumerate().find(|(_, p)| p.clamp) {
            let reason = "a closed rod has no ends to clamp";
            return refuse(&format!("pins[{i}].clamp"), "true".into(), reason);
        }
        self.periodic_basis().map(|_| ())
    }

    /// The periodic basis of a closed rod on `[0, L]` described by `rod.knots`.
    pub fn periodic_basis(&self) -> Result<PeriodicBSplineSpace, Error> {
        let r = &self.rod;
        let (m, l) = (r.control_points, r.rest_length);
        let periodic = "a closed rod has periodic knots: \"uniform\" or control_points + 1 breakpoints (the seam, then one period later)";
        let wrap = |given: String| {
            move |e: splinerod_core::CoreError| Error::field("rod.knots", given, e.to_string())
        };
        match &r.knots {
            None => PeriodicBSplineSpace::uniform(r.degree, m, l).map_err(wrap("default".into())),
            Some(KnotsSpec::Named(name)) if name == "uniform" => {
                PeriodicBSplineSpace::uniform(r.degree, m, l).map_err(wrap(format!("\"{name}\"")))
            }
            Some(KnotsSpec::Named(name)) => {
                Err(Error::field("rod.knots", format!("\"{name}\""), periodic))
            }
            Some(KnotsSpec::Explicit(k)) => {
                let given = format!("{k:?}");
                let (Some(&a), Some(&b)) = (k.first(), k.last()) else {
                    return Err(Error::field("rod.knots", given, periodic));
                };
                let ordered = a.is_finite() && b.is_finite() && b > a;
                if k.len() != m + 1 || !ordered {
                    return Err(Error::field("rod.knots", given, periodic));
                }
                let breaks = k[..m].iter().map(|t| (t - a) / (b - a) * l).collect();
                PeriodicBSplineSpace::new(r.degree, breaks, l).map_err(wrap(given))
            }
        }
    }

    /// The closed rod in its initial state: the ring, or the given control points with
    /// the copies across the seam appended.
    pub(crate) fn build_closed_rod(&self, material: Material) -> Result<Rod, Error> {
        let basis = self.periodic_basis()?;
        let copies = basis.count() - basis.breaks().len();
        match (&self.rod.ring, &self.rod.initial_control_points) {
            (Some(ring), _) => {
                let (center, normal) = (Vector3::from(ring.center), Vector3::from(ring.normal));
                Ok(Rod::ring(
                    material,
                    Box::new(basis),
                    center,
                    normal,
                    ring.radius,
                )?)
            }
            (None, Some(points)) => {
                let mut positions: Vec<Vector3<Real>> =
                    points.iter().map(|p| Vector3::from(*p)).collect();
                positions.extend_from_within(..copies);
                Ok(Rod::new(material, Box::new(basis), positions)?)
            }
            (None, None) => Err(Error::field(
                "rod.closed",
                "true",
                "a closed rod needs [rod.ring] or rod.initial_control_points",
            )),
        }
    }
}

fn validate_ring(ring: &RingSpec) -> Result<(), Error> {
    if !(ring.radius.is_finite() && ring.radius > 0.0) {
        return Err(Error::field(
            "rod.ring.radius",
            ring.radius,
            "must be finite and positive",
        ));
    }
    crate::scene::finite_vec("rod.ring.center", ring.center)?;
    crate::scene::finite_vec("rod.ring.normal", ring.normal)?;
    let n = Vector3::from(ring.normal).norm();
    if !(n.is_finite() && n > 0.0) {
        let value = format!("{:?}", ring.normal);
        return Err(Error::field(
            "rod.ring.normal",
            value,
            "must be a non-zero vector",
        ));
    }
    Ok(())
}
