//! The material frame made visible: a stripe painted along the rod, offset from the
//! centreline along the material director, so twist shows as the stripe winding around
//! the rod.
//!
//! The twist is quasi-static and uniform (see `energies::Twisting`), so the material
//! director at `s` is the start clamp's director carried along the centreline by
//! parallel transport and turned about the tangent by \\(\theta(s) = \mathrm{Tw}\, s/L\\).

use crate::Error;
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};
use splinerod_energies::{parallel_transport, TwistSummary};

/// Points of the stripe: \\(C(s_k) + \text{offset}\cdot d(s_k)\\) at `samples` evenly
/// spaced material points, with `d` the material director.
pub fn stripe(
    rod: &Rod,
    twist: &TwistSummary,
    offset: Real,
    samples: usize,
) -> Result<Vec<Vector3<Real>>, Error> {
    let l = rod.material().rest_length;
    let s: Vec<Real> = (0..samples)
        .map(|k| l * k as Real / (samples - 1).max(1) as Real)
        .collect();
    let directors = directors(rod, twist, &s)?;
    s.iter()
        .zip(directors)
        .map(|(&s, d)| Ok(rod.point(s)? + d * offset))
        .collect()
}

/// The material director \\(d(s_k)\\) at the increasing material coordinates `s` (m),
/// transported from sample to sample.
pub fn directors(rod: &Rod, twist: &TwistSummary, s: &[Real]) -> Result<Vec<Vector3<Real>>, Error> {
    let l = rod.material().rest_length;
    let mut director = Vector3::from(twist.start_director);
    let mut previous = Vector3::from(twist.axes[0]);
    let mut out = Vec::with_capacity(s.len());
    for &s in s {
        let t = rod.tangent(s)?.normalize();
        director = parallel_transport(&previous, &t, &director);
        previous = t;
        let theta = twist.twist * s / l;
        out.push(director * theta.cos() + t.cross(&director) * theta.sin());
    }
    Ok(out)
}
