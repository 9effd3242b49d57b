//! The twist of a closed rod: no clamps, the material frame closes on itself.
//!
//! Carried by parallel transport once around the loop, a director comes back turned by
//! the holonomy ψ of the loop (the same for every starting director: for a closed
//! curve it is 2π times the writhe, mod 2π — Fuller, Călugăreanu). The material frame
//! closes, so its total twist is \\(\mathrm{Tw} = \psi - \psi_0 + \Phi\\) with ψ₀ the
//! holonomy of the initial loop and Φ the twist it starts with ([`Twisting::around_loop`]):
//! the link is fixed, and writhe trades with twist. The polygons of the tangent samples
//! close (the last sample's neighbour is the first), so the local gradient and Hessian
//! of the open rod's holonomy hold unchanged, with one more pair across the seam (a far
//! coupling, folded by the closed rod's Newton solve). Michell's instability follows:
//! an isotropic ring twisted past \\(\Phi_c = 2\pi\sqrt3\, B/C\\) buckles out of plane.

use super::holonomy::{signed_angle, transport, Samples};
use super::{Frame, Twisting};
use nalgebra::Vector3;
use splinerod_core::{CoreError, Real, Rod};

impl Twisting {
    /// The twist of the closed `rod` with torsional stiffness `GJ > 0`, starting with
    /// total twist `twist` (rad) in its present shape. The twist stays in the rod (its
    /// link is fixed) until a cut releases it.
    pub fn around_loop(stiffness: Real, rod: &Rod, twist: Real) -> Result<Self, CoreError> {
        if !rod.is_closed() {
            return Err(CoreError::InvalidParameter {
                name: "twist",
                value: twist,
                reason: "the twist of a loop needs a closed rod",
            });
        }
        if !twist.is_finite() {
            return Err(CoreError::InvalidParameter {
                name: "twist",
                value: twist,
                reason: "must be finite",
            });
        }
        let frame = Frame::along(rod.tangent(0.0)?)?;
        Self::starting(stiffness, rod, [frame, frame], twist, true)
    }

    /// Whether this is the twist of a closed rod.
    pub fn is_loop(&self) -> bool {
        self.closed
    }
}

/// The holonomy of closed polygon `p`, in (−π, π]: the angle about the first tangent by
/// which a director transported once around comes back turned.
pub(super) fn loop_holonomy(samples: &Samples, p: usize) -> Real {
    let polygon = &samples.polygons[p];
    let first = samples.t[polygon[0]];
    let helper = if first.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let start = (helper - first * first.dot(&helper)).normalize();
    let mut director = start;
    let mut previous = first;
    for &k in &polygon[1..] {
        let t = &samples.t[k];
        director = transport(&previous, t, &director);
        previous = *t;
    }
    director = transport(&previous, &first, &director);
    signed_angle(&director, &start, &first)
}
