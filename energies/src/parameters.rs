//! Parameter derivatives (the [`Parameters`] capability, issue #48): with the energy
//! `E(q; p)` of a scalar parameter `p` (a stiffness, a density, a component of gravity),
//! the mixed derivative \\(\partial^2 E / \partial q\, \partial p\\) at the rod's
//! positions — what the sensitivity of an equilibrium needs: from
//! \\(\nabla E(q(p); p) = f\\), \\(K\, \mathrm{d}q/\mathrm{d}p = -\partial \nabla E / \partial p\\).
//!
//! The built-in energies are linear in their parameters, `E = p Ê(q)`, so the
//! derivative is `∇E / p` ([`add_linear`]); an energy that is not says so by
//! implementing [`Parameters::add_gradient_derivative`] itself.

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

/// [`Parameters`] for an energy with one parameter `$name` it is linear in, of value
/// `self.$field`.
macro_rules! linear_parameter {
    ($energy:ty, $name:literal, $field:ident) => {
        impl Parameters for $energy {
            fn parameter_names(&self) -> &[&'static str] {
                &[$name]
            }

            fn add_gradient_derivative(
                &self,
                rod: &Rod,
                name: &str,
                out: &mut [Vector3<Real>],
            ) -> Result<bool, CoreError> {
                match name {
                    $name => add_linear(self, rod, self.$field, out),
                    _ => Ok(false),
                }
            }
        }
    };
}

linear_parameter!(crate::Bending, "bending_stiffness", stiffness);
linear_parameter!(crate::Twisting, "twist_stiffness", stiffness);

impl Parameters for crate::Stretching {
    /// `EA`; none for an inextensible rod (its stretching is a constraint).
    fn parameter_names(&self) -> &[&'static str] {
        match self.multipliers {
            Some(_) => &[],
            None => &["stretch_stiffness"],
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
            _ => Ok(false),
        }
    }
}

impl Parameters for crate::Gravity {
    /// The rod's linear density (its weight `g ρ` per unit length) and the components of
    /// `g`.
    fn parameter_names(&self) -> &[&'static str] {
        &["linear_density", "gravity[0]", "gravity[1]", "gravity[2]"]
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
