//! Parameter derivatives (the [`Parameters`] capability, issue #48): with the energy
//! `E(q; p)` of a scalar parameter `p` (a stiffness, a density, a component of gravity),
//! the mixed derivative \\(\partial^2 E / \partial q\, \partial p\\) at the rod's
//! positions — what the sensitivity of an equilibrium needs: from
//! \\(\nabla E(q(p); p) = f\\), \\(K\, \mathrm{d}q/\mathrm{d}p = -\partial \nabla E / \partial p\\).
//!
//! The built-in energies are linear in their stiffness, density and gravity parameters,
//! `E = p Ê(q)`, so the derivative is `∇E / p` ([`add_linear`]); an energy that is not
//! says so by implementing [`Parameters::add_gradient_derivative`] itself. Every
//! built-in energy also has the rest length, [`REST_LENGTH`] (`"rest_length"`): the
//! derivative at fixed control points of a domain `[0, L]` scaled with every material
//! coordinate at a fixed fraction ([`crate::rest_length`] derives each energy's).

use crate::rest_length::{add_homogeneous, add_power, REST_LENGTH};
use crate::Energy;
use nalgebra::Vector3;
use splinerod_core::{CoreError, Real, Rod};

/// An energy's scalar parameters and the derivative of its gradient by each.
pub trait Parameters: Send + Sync {
    /// The parameters' names, as the scene calls them (`"bending_stiffness"`).
    fn parameter_names(&self) -> &[&'static str];

    /// Adds \\(\partial \nabla E / \partial p\\) for the parameter `name` at the rod's
    /// positions to `out` (one entry per control point); `Ok(false)` if the energy has no
    /// parameter of that name.
    fn add_gradient_derivative(
        &self,
        rod: &Rod,
        name: &str,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError>;
}

/// `out += ∇E / value` for an energy linear in its parameter of value `value`
/// (`E = value · Ê`); an error if `value` is zero or not finite (the energy then has no
/// gradient to scale: its derivative is `∇Ê`, which the energy must give itself). The
/// gradient goes through a scratch buffer of the thread, sized once (a run's forward
/// sensitivities call this every step).
pub fn add_linear(
    energy: &dyn Energy,
    rod: &Rod,
    value: Real,
    out: &mut [Vector3<Real>],
) -> Result<bool, CoreError> {
    if !(value.is_finite() && value != 0.0) {
        return Err(CoreError::InvalidParameter {
            name: "parameter",
            value,
            reason: "a derivative by a parameter needs its value finite and non-zero",
        });
    }
    SCRATCH.with(|cell| {
        let mut gradient = cell.borrow_mut();
        gradient.clear();
        gradient.resize(rod.len(), Vector3::zeros());
        energy.add_gradient(rod, &mut gradient);
        for (o, g) in out.iter_mut().zip(gradient.iter()) {
            *o += g / value;
        }
    });
    Ok(true)
}

thread_local! {
    /// [`add_linear`]'s gradient buffer.
    static SCRATCH: std::cell::RefCell<Vec<Vector3<Real>>> = const { std::cell::RefCell::new(Vec::new()) };
}

impl Parameters for crate::Bending {
    /// `EI` and the rest length (bending is homogeneous of degree −1 in the lengths).
    fn parameter_names(&self) -> &[&'static str] {
        &["bending_stiffness", REST_LENGTH]
    }

    fn add_gradient_derivative(
        &self,
        rod: &Rod,
        name: &str,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError> {
        match name {
            "bending_stiffness" => add_linear(self, rod, self.stiffness, out),
            REST_LENGTH => add_homogeneous(self, rod, -1, out),
            _ => Ok(false),
        }
    }
}

impl Parameters for crate::Twisting {
    /// `GJ` and the rest length (\\(E = GJ\,\mathrm{Tw}^2/(2L)\\)).
    fn parameter_names(&self) -> &[&'static str] {
        &["twist_stiffness", REST_LENGTH]
    }

    fn add_gradient_derivative(
        &self,
        rod: &Rod,
        name: &str,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError> {
        match name {
            "twist_stiffness" => add_linear(self, rod, self.stiffness, out),
            REST_LENGTH => add_power(self, rod, -1.0, out),
            _ => Ok(false),
        }
    }
}

impl Parameters for crate::Stretching {
    /// `EA` and the rest length (homogeneous of degree 1 in the lengths); none for an
    /// inextensible rod (its stretching is a constraint), no rest length with a rest
    /// shape (the rest metric is the initial curve's, not the domain's).
    fn parameter_names(&self) -> &[&'static str] {
        match (&self.multipliers, self.has_rest_shape()) {
            (Some(_), _) => &[],
            (None, true) => &["stretch_stiffness"],
            (None, false) => &["stretch_stiffness", REST_LENGTH],
        }
    }

    fn add_gradient_derivative(
        &self,
        rod: &Rod,
        name: &str,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError> {
        match name {
            "stretch_stiffness" if self.multipliers.is_none() => {
                add_linear(self, rod, self.stiffness, out)
            }
            REST_LENGTH if self.multipliers.is_none() && !self.has_rest_shape() => {
                add_homogeneous(self, rod, 1, out)
            }
            _ => Ok(false),
        }
    }
}

impl Parameters for crate::Gravity {
    /// The rod's linear density (its weight `g ρ` per unit length), the components of
    /// `g` and the rest length (the weight is \\(\propto L\\)).
    fn parameter_names(&self) -> &[&'static str] {
        &[
            "linear_density",
            "gravity[0]",
            "gravity[1]",
            "gravity[2]",
            REST_LENGTH,
        ]
    }

    fn add_gradient_derivative(
        &self,
        rod: &Rod,
        name: &str,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError> {
        let density = rod.material().linear_density;
        let direction = match name {
            "linear_density" => return add_linear(self, rod, density, out),
            REST_LENGTH => return add_power(self, rod, 1.0, out),
            "gravity[0]" => Vector3::x(),
            "gravity[1]" => Vector3::y(),
            "gravity[2]" => Vector3::z(),
            _ => return Ok(false),
        };
        // ∇E = −g m_i: its derivative by g_c is −e_c m_i.
        for (o, m) in out.iter_mut().zip(rod.lumped_masses()) {
            *o -= direction * *m;
        }
        Ok(true)
    }
}

impl Parameters for crate::Clamp {
    /// The rest length: \\(C'(s) = C_u/L\\) at a fixed fraction, so at a fixed penalty
    /// \\(\partial_L\nabla E = -2\nabla E/L\\) (a stiffness that follows `L` is its
    /// caller's to add).
    fn parameter_names(&self) -> &[&'static str] {
        &[REST_LENGTH]
    }

    fn add_gradient_derivative(
        &self,
        rod: &Rod,
        name: &str,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError> {
        match name {
            REST_LENGTH => add_power(self, rod, -2.0, out),
            _ => Ok(false),
        }
    }
}

/// [`Parameters`] of an energy acting at one material point at a fixed fraction of the
/// rod, with no length of its own: the rest length leaves its gradient as it is.
macro_rules! at_a_point {
    ($energy:ty) => {
        impl Parameters for $energy {
            /// The rest length, whose derivative is zero (the point's basis row
            /// \\(b_i(uL; L) = B_i(u)\\) does not change).
            fn parameter_names(&self) -> &[&'static str] {
                &[REST_LENGTH]
            }

            fn add_gradient_derivative(
                &self,
                _rod: &Rod,
                name: &str,
                _out: &mut [Vector3<Real>],
            ) -> Result<bool, CoreError> {
                Ok(name == REST_LENGTH)
            }
        }
    };
}

at_a_point!(crate::PointForce);
at_a_point!(crate::PointSpring);
