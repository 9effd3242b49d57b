//! Initial shapes and rest states of `[rod]` (documented in `scenes/README.md`):
//! `rod.rest_shape` and the `[rod.overhand]` knot, which sets the rest length and the
//! control points before validation.

use crate::scene::{KnotsSpec, Scene};
use crate::Error;
use serde::Deserialize;
use splinerod_core::Cancel;

/// `rod.rest_shape`.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum RestShape {
    /// The material coordinate is rest arclength: unit speed is unstrained.
    #[default]
    Arclength,
    /// The initial curve is unstrained (rest metric \\(|I_0'(s)|^2\\)).
    Initial,
}

/// `rod.stretch_formulation`.
#[derive(Debug, Clone, Copy, Default, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "kebab-case")]
pub enum StretchFormulationSpec {
    /// Chosen from the strain the scene puts on the rod (the default; see
    /// `scene/auto_form.rs`): the consistent mixed form on stretchy rods, the lumped
    /// one on stiff ones.
    #[default]
    Auto,
    /// The strain projected onto the degree-`d − 1` splines with the lumped Gram matrix
    /// (locking-free; second order where the strain varies).
    Mixed,
    /// The strain at every quadrature point (order `d + 1` on stretchy rods; locks on
    /// stiff ones).
    Pointwise,
    /// Mixed, with the tension from the consistent Gram matrix (locking-free and order
    /// `d + 1` on stretchy rods; Newton steps corrected by conjugate gradients).
    MixedConsistent,
}

impl StretchFormulationSpec {
    /// Whether the strain is projected onto the tension space (every form but the
    /// pointwise one; `"auto"` only chooses mixed forms).
    pub fn is_mixed(self) -> bool {
        self != Self::Pointwise
    }
}

/// `[rod.overhand]`: the initial shape of [`crate::knot::overhand_knot`].
#[derive(Debug, Clone, Copy, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct OverhandShape {
    /// Outer diameter of the knot seen from above, m (> 0).
    pub size: f64,
    /// Distance between the two ends, which lie at `(±span/2, 0, 0)`, m.
    pub span: f64,
}

impl Scene {
    /// Sets `rod.rest_length` from the file, or it and `rod.initial_control_points` from
    /// `rod.overhand`; errors if the scene gives both, or neither.
    pub fn resolve_shape(&mut self) -> Result<(), Error> {
        self.resolve_shape_with(&Cancel::none())
    }

    /// [`Scene::resolve_shape`], polling `cancel` during the knot's fit.
    pub(crate) fn resolve_shape_with(&mut self, cancel: &Cancel) -> Result<(), Error> {
        let r = &mut self.rod;
        let Some(shape) = r.overhand else {
            let Some(length) = r.given_rest_length else {
                return Err(Error::MissingField {
                    field: "rod.rest_length".into(),
                    reason: "required unless rod.overhand gives the shape".into(),
                });
            };
            r.rest_length = length;
            return Ok(());
        };
        let given = [
            ("rod.rest_length", r.given_rest_length.is_some()),
            (
                "rod.initial_control_points",
                r.initial_control_points.is_some(),
            ),
            ("rod.start", r.start.is_some()),
            ("rod.end", r.end.is_some()),
            // The default knots spelled out are no conflict.
            (
                "rod.knots",
                r.knots.as_ref().is_some_and(|k| *k != KnotsSpec::default()),
            ),
            ("rod.closed", r.closed || r.ring.is_some()),
        ];
        if let Some((field, _)) = given.iter().find(|g| g.1) {
            let reason = "rod.overhand sets the shape and the rest length: remove one of them";
            return Err(Error::field(*field, "given", reason));
        }
        let spec = crate::knot::OverhandSpec {
            size: shape.size,
            span: shape.span,
            control_points: r.control_points,
            degree: r.degree,
        };
        let knot = crate::knot::overhand_knot_cancellable(&spec, cancel).map_err(|e| match e {
            Error::InvalidField {
                field,
                value,
                reason,
            } => Error::InvalidField {
                field: match field.as_str() {
                    "control_points" | "degree" => format!("rod.{field}"),
                    _ => format!("rod.overhand.{field}"),
                },
                value,
                reason,
            },
            other => other,
        })?;
        r.rest_length = knot.rest_length;
        r.initial_control_points = Some(knot.control_points.iter().map(|p| (*p).into()).collect());
        Ok(())
    }
}

/// `rod.stretch_stiffness`: a number, or the string `"inextensible"` as `+∞`.
pub(crate) fn stiffness_or_inextensible<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<f64, D::Error> {
    struct Stiffness;
    impl serde::de::Visitor<'_> for Stiffness {
        type Value = f64;
        fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            f.write_str("a number (N) or \"inextensible\"")
        }
        fn visit_f64<E: serde::de::Error>(self, x: f64) -> Result<f64, E> {
            match x.is_infinite() {
                // "= value: reason": worded as a scene field out of range.
                true => Err(E::custom(format!(
                    "= {x}: must be finite and positive (or \"inextensible\")"
                ))),
                false => Ok(x),
            }
        }
        fn visit_i64<E: serde::de::Error>(self, x: i64) -> Result<f64, E> {
            Ok(x as f64)
        }
        fn visit_u64<E: serde::de::Error>(self, x: u64) -> Result<f64, E> {
            Ok(x as f64)
        }
        fn visit_str<E: serde::de::Error>(self, w: &str) -> Result<f64, E> {
            match w {
                "inextensible" => Ok(f64::INFINITY),
                _ => Err(E::invalid_value(serde::de::Unexpected::Str(w), &self)),
            }
        }
    }
    d.deserialize_any(Stiffness)
}

pub(crate) fn default_degree() -> usize {
    3
}
