//! The rule behind a scene's `"auto"` stretching: which mixed form a rod needs.

use super::StretchFormulation;
use nalgebra::Vector3;
use splinerod_core::{Real, Rod};

/// The lumped form's extra error on a rod whose strain varies on the scale `ε` is about
/// this times `ε L / n²` (m; measured on the catenary, L = 1 m, EA = 100 N: 2.7e-6 m at
/// 32 points above the consistent form's error).
pub const AUTO_LUMPING_ERROR: Real = 0.27;

/// The discretisation error left at O(h⁴) is about this times `L / n⁴` (m; the same
/// measurements, four catenary shapes, EA 10² – 10⁹ N, 16 – 64 points:
/// `cargo run --release --example form_study`).
pub const AUTO_RESOLUTION_ERROR: Real = 0.011;

/// Compression (strain) of the start beyond which [`StretchFormulation::auto`] takes
/// the consistent form whatever the errors: the lumped projection leaves the shortest
/// axial waves a stiffness of about an eighth of the pointwise one, which a compressive
/// strain beyond about 12 % turns negative (a spurious zig-zag mode grows); the
/// consistent form is stable down to the Green–Lagrange material's own limit (stretch
/// 1/√3).
pub const AUTO_COMPRESSION: Real = 0.05;

/// What [`StretchFormulation::auto`] decides from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AutoInputs {
    /// The strain scale the loads, the pins and the start put on the rod (≥ 0).
    pub strain: Real,
    /// The largest compression of the start (≥ 0).
    pub compression: Real,
    /// The most control points the rod will have.
    pub control_points: usize,
    /// Rest length, m.
    pub length: Real,
    /// The error the rest of the model allows anyway, m (a contact's onset layer, an
    /// adaptive run's tolerance; 0 if none).
    pub model_error: Real,
}

impl StretchFormulation {
    /// The form a scene's `"auto"` resolves to: [`Self::MixedConsistent`] where the
    /// lumped form's extra error, [`AUTO_LUMPING_ERROR`]` · ε L / n²`, would pass half
    /// of what the run allows anyway — the larger of the resolution's own error
    /// ([`AUTO_RESOLUTION_ERROR`]` · L / n⁴`) and `model_error` — or where the start is
    /// compressed beyond [`AUTO_COMPRESSION`]; else [`Self::Mixed`]. On stiff rods the
    /// two agree (the lumped Gram matrix enters only the constitutive relation, which
    /// the constraints make irrelevant there) and the lumped form needs no conjugate
    /// gradients. The pointwise form is never chosen: it locks on stiff rods and is at
    /// best as accurate as the consistent form on stretchy ones.
    pub fn auto(inputs: AutoInputs) -> Self {
        let n = inputs.control_points.max(1) as Real;
        let lumping = AUTO_LUMPING_ERROR * inputs.strain * inputs.length / (n * n);
        let resolution = AUTO_RESOLUTION_ERROR * inputs.length / (n * n * n * n);
        let allowed = resolution.max(inputs.model_error);
        if lumping > 0.5 * allowed || inputs.compression > AUTO_COMPRESSION {
            Self::MixedConsistent
        } else {
            Self::Mixed
        }
    }
}

impl AutoInputs {
    /// The largest tensile and compressive Green–Lagrange strain of `rod`'s current
    /// curve against arclength at its quadrature points, `(tension, compression)`, both
    /// ≥ 0: what the start puts on a rod at rest when `s` is arclength.
    pub fn start_strains(rod: &Rod) -> (Real, Real) {
        let (mut tension, mut compression): (Real, Real) = (0.0, 0.0);
        for qp in rod.quadrature().walk() {
            let c1 = qp
                .d1
                .iter()
                .enumerate()
                .fold(Vector3::zeros(), |acc, (a, &w)| {
                    acc + rod.positions[qp.first + a] * w
                });
            let strain = 0.5 * (c1.norm_squared() - 1.0);
            tension = tension.max(strain);
            compression = compression.max(-strain);
        }
        (tension, compression)
    }

    /// The largest stretch held points impose on the rod between them, ≥ 0: `held` lists
    /// each point's material coordinate (m) with every place it is held at (its start
    /// and keyframes); for consecutive points along the rod, the largest distance
    /// between their places over their rest distance, minus one.
    pub fn held_strain(held: &mut [(Real, Vec<Vector3<Real>>)]) -> Real {
        held.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut strain: Real = 0.0;
        for pair in held.windows(2) {
            let rest = pair[1].0 - pair[0].0;
            if rest <= 0.0 {
                continue;
            }
            for p in &pair[0].1 {
                for q in &pair[1].1 {
                    strain = strain.max((p - q).norm() / rest - 1.0);
                }
            }
        }
        strain
    }
}
