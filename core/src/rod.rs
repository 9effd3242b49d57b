//! [`Rod`]: a B-spline centreline whose control points are the degrees of freedom.
//!
//! The curve is \\(C(s,t) = \sum_i q_i(t)\, b_i(s)\\) with `s` the rest arclength in
//! `[0, L]` (so \\(\partial l_0/\partial s = 1\\)). Every physical quantity is an integral
//! over `s`, independent of the knots:
//!
//! * mass matrix (paper eq. 10) \\(M_{ij} = \int_0^L \mu\, b_i b_j\, ds\\),
//! * lumped masses \\(m_i = \int_0^L \mu\, b_i\, ds = \sum_j M_{ij}\\) (gravity's
//!   generalised force is \\(m_i g\\), momentum \\(\sum_i m_i \dot q_i\\)),
//! * kinetic energy \\(\tfrac12 \sum_{ij} M_{ij}\, \dot q_i \cdot \dot q_j\\).
//!
//! Knot insertion changes the basis but not the curve, its velocity, nor any of these.

use crate::banded::SymBanded;
use crate::basis::{greville, BasisSpace, BasisValues, MAX_DEGREE};
use crate::knot_map::KnotMap;
use crate::quadrature::{GaussLegendre, QuadratureTable};
use crate::refine::RefinementOperator;
use crate::segments::{Density, Segment};
use crate::{CoreError, Real};
use nalgebra::Vector3;
use std::sync::atomic::{AtomicU64, Ordering};

/// Material constants of a rod that the core needs (energies carry their own stiffness).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Material {
    /// Rest length `L`, m. The basis domain is `[0, L]`.
    pub rest_length: Real,
    /// Mass per unit rest length `μ`, kg/m.
    pub linear_density: Real,
}

impl Material {
    /// Checks that both constants are finite and positive.
    pub fn validate(&self) -> Result<(), CoreError> {
        positive("rest_length", self.rest_length)?;
        positive("linear_density", self.linear_density)
    }
}

pub use crate::check::{non_negative, positive};

/// A rod: state (`positions`, `velocities`) in public fields, and the basis with its
/// cached quadrature and mass matrix, which change only through knot operations.
#[derive(Debug, Clone)]
pub struct Rod {
    /// Control points `q_i`, m.
    pub positions: Vec<Vector3<Real>>,
    /// Control point velocities, m/s.
    pub velocities: Vec<Vector3<Real>>,
    /// Mass-proportional damping coefficient `α`, 1/s: force \\(-\alpha M \dot q\\).
    pub damping: Real,
    material: Material,
    basis: Box<dyn BasisSpace>,
    quadrature: QuadratureTable,
    mass: SymBanded,
    lumped: Vec<Real>,
    topology_epoch: u64,
    /// Rods joined into this one ([`Rod::join`]); empty for a rod on its own.
    pub(crate) segments: Vec<Segment>,
}

impl Rod {
    /// A rod at rest with the given control points on `basis` (domain `[0, L]`).
    pub fn new(
        material: Material,
        basis: Box<dyn BasisSpace>,
        positions: Vec<Vector3<Real>>,
    ) -> Result<Self, CoreError> {
        Self::with_segments(material, basis, positions, Vec::new())
    }

    /// [`Rod::new`] with the densities of joined rods ([`Rod::join`]).
    pub(crate) fn with_segments(
        material: Material,
        basis: Box<dyn BasisSpace>,
        positions: Vec<Vector3<Real>>,
        segments: Vec<Segment>,
    ) -> Result<Self, CoreError> {
        material.validate()?;
        let (start, end) = basis.domain();
        let l = material.rest_length;
        if start.abs() > 1e-12 * l || (end - l).abs() > 1e-12 * l {
            return Err(CoreError::DomainMismatch {
                start,
                end,
                rest_length: l,
            });
        }
        let n = basis.count();
        if positions.len() != n {
            let found = positions.len();
            return Err(CoreError::CountMismatch {
                what: "control points",
                expected: n,
                found,
            });
        }
        check_finite("control point", &positions)?;
        check_periodic_copies(basis.as_ref(), &positions)?;
        let mut rod = Self {
            velocities: vec![Vector3::zeros(); n],
            positions,
            damping: 0.0,
            material,
            basis,
            quadrature: QuadratureTable::default(),
            mass: SymBanded::default(),
            lumped: Vec::new(),
            topology_epoch: next_epoch(),
            segments,
        };
        rod.rebuild_caches(GaussLegendre::points_for_degree(rod.basis.degree()), true)?;
        Ok(rod)
    }

    /// A straight rod at rest from `start` to `end`, uniformly parametrised (control
    /// points at the Greville abscissae, which reproduce the line exactly).
    pub fn straight(
        material: Material,
        basis: Box<dyn BasisSpace>,
        start: Vector3<Real>,
        end: Vector3<Real>,
    ) -> Result<Self, CoreError> {
        material.validate()?;
        let l = material.rest_length;
        let positions = (0..basis.count())
            .map(|i| start + (end - start) * (greville(basis.as_ref(), i) / l))
            .collect();
        Self::new(material, basis, positions)
    }

    /// The rod with `points` Gauss points per knot span instead of the default
    /// [`GaussLegendre::points_for_degree`] (knot changes keep the count). At least
    /// `degree + 1`, which the mass matrix needs to be exact; energies whose integrands
    /// need more must be given more. Build energies with cached per-point data after this.
    pub fn with_quadrature_points(mut self, points: usize) -> Result<Self, CoreError> {
        let d = self.basis.degree();
        if !(d + 1..=4 * (MAX_DEGREE + 1)).contains(&points) {
            return Err(CoreError::InvalidParameter {
                name: "quadrature points per span",
                value: points as Real,
                reason: "must be at least degree + 1 (the mass matrix is integrated exactly)",
            });
        }
        let second = self.quadrature.has_second_derivatives();
        self.rebuild_caches(points, second)?;
        Ok(self)
    }

    /// This rod without the basis' second derivatives in its quadrature table (kept
    /// through every later change of knots and refined copy): for rods no bending acts
    /// on, 128 bytes less per span of a cubic rod at 4 points per span. Bending refuses
    /// such a rod ([`QuadratureTable::has_second_derivatives`]).
    pub fn without_second_derivatives(mut self) -> Self {
        self.quadrature = std::mem::take(&mut self.quadrature).without_second_derivatives();
        self
    }

    /// A copy of this rod with every value of `values` (non-decreasing, strictly inside
    /// the domain) inserted as a knot at once: the same curve and motion on a finer basis
    /// (same quadrature points per span), and the old→new map in `op`. O(n); see
    /// [`BasisSpace::refined`].
    pub fn refined(&self, values: &[Real], op: &mut RefinementOperator) -> Result<Rod, CoreError> {
        let basis = self.basis.refined(values, op)?;
        let mut rod = Self {
            positions: Vec::new(),
            velocities: Vec::new(),
            damping: self.damping,
            material: self.material,
            basis,
            quadrature: QuadratureTable::default(),
            mass: SymBanded::default(),
            lumped: Vec::new(),
            topology_epoch: next_epoch(),
            segments: self.segments.clone(),
        };
        op.apply(&self.positions, &mut rod.positions);
        op.apply(&self.velocities, &mut rod.velocities);
        let second = self.quadrature.has_second_derivatives();
        rod.rebuild_caches(self.quadrature.points_per_span(), second)?;
        Ok(rod)
    }

    /// Recomputes quadrature (`points` per span, second derivatives if `second`), mass
    /// matrix and lumped masses from the basis.
    fn rebuild_caches(&mut self, points: usize, second: bool) -> Result<(), CoreError> {
        let d = self.basis.degree();
        self.quadrature = QuadratureTable::tabulate(self.basis.as_ref(), points, second)?;
        let n = self.basis.count();
        let density = self.density();
        let mut mass = SymBanded::zeros(n, d);
        let mut lumped = vec![0.0; n];
        for qp in self.quadrature.points() {
            let mu = density.at(qp.s);
            for a in 0..qp.value.len() {
                let wa = mu * qp.weight * qp.value[a];
                lumped[qp.first + a] += wa;
                for b in a..qp.value.len() {
                    mass.add(qp.first + a, qp.first + b, wa * qp.value[b]);
                }
            }
        }
        self.mass = mass;
        self.lumped = lumped;
        Ok(())
    }

    /// Linear density per parameter value.
    fn density(&self) -> Density<'_> {
        Density {
            uniform: self.material.linear_density,
            segments: &self.segments,
        }
    }

    /// Material constants (of the joined whole for a joined rod: its density is the
    /// first segment's; see [`Rod::segments`]).
    pub fn material(&self) -> &Material {
        &self.material
    }
    /// The basis space.
    pub fn basis(&self) -> &dyn BasisSpace {
        self.basis.as_ref()
    }
    /// Whether the rod is closed (its basis is periodic: the last `degree` control
    /// points are copies of the first, see [`BasisSpace::periodic_count`]).
    pub fn is_closed(&self) -> bool {
        self.basis.periodic_count().is_some()
    }
    /// Number of control points (for a closed rod, with the copies across the seam).
    pub fn len(&self) -> usize {
        self.positions.len()
    }
    /// Number of distinct control points: [`len`](Self::len) for an open rod, without
    /// the copies across the seam for a closed one (what outputs report).
    pub fn distinct_len(&self) -> usize {
        self.basis.periodic_count().unwrap_or(self.positions.len())
    }
    /// Whether the rod has no control points (never true for a constructed rod).
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }
    /// Basis tabulated at the quadrature points.
    pub fn quadrature(&self) -> &QuadratureTable {
        &self.quadrature
    }
    /// Mass matrix `M` (scalar; acts on each coordinate).
    pub fn mass_matrix(&self) -> &SymBanded {
        &self.mass
    }
    /// Lumped masses \\(m_i = \int \mu b_i\\).
    pub fn lumped_masses(&self) -> &[Real] {
        &self.lumped
    }
    /// Identifies the rod's basis: a new value, unique in the process, at every change
    /// of knots (and for every new rod or refined copy); caches keyed on it (solvers'
    /// symbolic analyses, contact samples) know when to rebuild.
    pub fn topology_epoch(&self) -> u64 {
        self.topology_epoch
    }
    /// Total mass \\(\int \mu\, ds\\).
    pub fn total_mass(&self) -> Real {
        self.lumped.iter().sum()
    }

    /// Kinetic energy \\(\tfrac12 \dot q^T M \dot q\\).
    pub fn kinetic_energy(&self) -> Real {
        0.5 * self.mass.bilinear_vec3(&self.velocities, &self.velocities)
    }

    /// Largest control-point speed, m/s: a bound on the speed of every material point
    /// (the basis is a non-negative partition of unity).
    pub fn max_speed(&self) -> Real {
        self.velocities
            .iter()
            .map(|v| v.norm())
            .fold(0.0, Real::max)
    }

    /// Linear momentum \\(\int \mu \dot C\, ds = \sum_i m_i \dot q_i\\).
    pub fn linear_momentum(&self) -> Vector3<Real> {
        self.lumped
            .iter()
            .zip(&self.velocities)
            .map(|(m, v)| v * *m)
            .sum()
    }

    /// Centre of mass \\(\frac{1}{\mu L}\int \mu C\, ds\\).
    pub fn centre_of_mass(&self) -> Vector3<Real> {
        let p: Vector3<Real> = self
            .lumped
            .iter()
            .zip(&self.positions)
            .map(|(m, q)| q * *m)
            .sum();
        p / self.total_mass()
    }

    /// Evaluates the basis at material coordinate `s`.
    pub fn basis_at(&self, s: Real) -> Result<BasisValues, CoreError> {
        let mut b = BasisValues::default();
        self.basis.evaluate(s, &mut b)?;
        Ok(b)
    }

    /// Position \\(C(s)\\) of material point `s`.
    pub fn point(&self, s: Real) -> Result<Vector3<Real>, CoreError> {
        let b = self.basis_at(s)?;
        Ok(b.combine(&b.value, &self.positions))
    }

    /// Velocity \\(\dot C(s)\\) of material point `s`.
    pub fn velocity(&self, s: Real) -> Result<Vector3<Real>, CoreError> {
        let b = self.basis_at(s)?;
        Ok(b.combine(&b.value, &self.velocities))
    }

    /// Tangent \\(C'(s)\\); its length is the stretch `γ`.
    pub fn tangent(&self, s: Real) -> Result<Vector3<Real>, CoreError> {
        let b = self.basis_at(s)?;
        Ok(b.combine(&b.d1, &self.positions))
    }

    /// Error naming the first non-finite position or velocity, if any.
    pub fn check_finite(&self) -> Result<(), CoreError> {
        check_finite("control point", &self.positions)?;
        check_finite("velocity", &self.velocities)
    }

    /// Inserts knot `s` (strictly inside `(0, L)`): positions and velocities go through
    /// the exact map, so the curve, its motion and every energy are unchanged.
    pub fn insert_knot(&mut self, s: Real) -> Result<KnotMap, CoreError> {
        let map = self.basis.insert_knot(s)?;
        self.after_knot_change(map)
    }

    /// Removes knot `index` if that moves the curve by at most `tolerance` (m); otherwise
    /// returns [`CoreError::RemovalNotWithinTolerance`] and changes nothing.
    pub fn remove_knot(&mut self, index: usize, tolerance: Real) -> Result<KnotMap, CoreError> {
        non_negative("tolerance", tolerance)?;
        let candidate = self.basis.removal(index)?;
        let error = candidate.shape_error(&self.positions);
        if error.is_nan() || error > tolerance {
            return Err(CoreError::RemovalNotWithinTolerance {
                index,
                error,
                tolerance,
            });
        }
        let map = self.basis.remove_knot(index)?;
        self.after_knot_change(map)
    }

    fn after_knot_change(&mut self, map: KnotMap) -> Result<KnotMap, CoreError> {
        map.apply_in_place(&mut self.positions);
        map.apply_in_place(&mut self.velocities);
        self.topology_epoch = next_epoch();
        if map.wraps() {
            // Changed functions on both sides of a closed rod's seam: not one region.
            let second = self.quadrature.has_second_derivatives();
            self.rebuild_caches(self.quadrature.points_per_span(), second)?;
            return Ok(map);
        }
        let density = Density {
            uniform: self.material.linear_density,
            segments: &self.segments,
        };
        crate::local_update::update_caches(
            &map,
            self.basis.as_ref(),
            density,
            &mut self.quadrature,
            &mut self.mass,
            &mut self.lumped,
        )?;
        Ok(map)
    }
}

/// Source of topology epochs: unique across all rods of the process, so a cache keyed on
/// an epoch never mistakes one basis for another (a scratch copy refined from a rod gets
/// its own). Only equality of epochs means anything; their values do not enter results.
static NEXT_EPOCH: AtomicU64 = AtomicU64::new(1);

fn next_epoch() -> u64 {
    NEXT_EPOCH.fetch_add(1, Ordering::Relaxed)
}

/// Error naming the first control point of a closed rod that differs from the one it
/// copies across the seam (`positions[i + m]` must equal `positions[i]`).
fn check_periodic_copies(
    basis: &dyn BasisSpace,
    positions: &[Vector3<Real>],
) -> Result<(), CoreError> {
    let Some(m) = basis.periodic_count() else {
        return Ok(());
    };
    match (m..positions.len()).find(|&i| positions[i] != positions[i - m]) {
        Some(index) => Err(CoreError::InvalidParameter {
            name: "control point copy across the seam",
            value: index as Real,
            reason: "a closed rod's last `degree` control points must equal its first",
        }),
        None => Ok(()),
    }
}

/// Error naming the first non-finite vector of `field`.
pub fn check_finite(what: &'static str, field: &[Vector3<Real>]) -> Result<(), CoreError> {
    match field.iter().position(|v| !v.iter().all(|x| x.is_finite())) {
        Some(index) => Err(CoreError::NonFiniteState { what, index }),
        None => Ok(()),
    }
}
