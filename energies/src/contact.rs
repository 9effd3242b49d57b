//! [`Contact`]: a smooth penalty keeping a rod of radius `r` off itself, off the other
//! pieces of its cuts, and above a floor plane (paper §3.2: collision detection and
//! response before the forces; the paper's response is a penalty too).
//!
//! **Self-contact.** For each contact between parts of the rod (see [`detect`]: broad
//! phase over span boxes, closest points between spans on the curve), with centre-line
//! distance \\(d = |C(s) - C(t)|\\) and gap \\(g = d - 2r\\),
//!
//! \\[ E = \sum_{\text{contacts}} \phi(g), \qquad
//! \frac{\partial E}{\partial q_i} = \phi'(g)\, w_i\, n, \qquad
//! w_i = b_i(s) - b_i(t), \quad n = \frac{C(s) - C(t)}{d}, \\]
//!
//! with the penalty \\(\phi\\) of [`penalty`] (stiffness `k`, onset layer `δ`). The
//! gradient is exact: the closest points minimise the distance, so their motion does
//! not change it to first order. The Hessian used for both [`HessianKind`]s is
//! \\(\phi''(g)\, w w^T \otimes n n^T\\), the exact Hessian of the distance between two
//! crossing straight segments; it is positive semi-definite and drops the curvature
//! term \\(\phi'/d\, (I - n n^T)\\), which is negative and, for crossing strands,
//! cancelled by the sliding of the closest points. It couples control points far apart
//! on the rod, so it is assembled with [`BlockBanded::add_coupling`].
//!
//! **Floor.** A plane \\(n_f \cdot x = h\\) pushes on the rod's quadrature points with
//! the gap \\(g(s) = n_f \cdot C(s) - h - r\\) and the energy per unit rest length
//! \\(\tfrac{1}{2r}\, \phi(g(s))\\): a length of rod equal to its diameter pressed into
//! the floor resists like one self-contact.
//!
//! **What is not modelled:** friction; contacts between points less than `exclusion`
//! apart in rest arclength (they are neighbours: a rod bent to radius `r` first touches
//! itself at \\(\pi r\\), the default); and contacts within two adjacent spans, which the
//! broad phase skips (refinement keeps spans short where the rod touches itself).

pub mod detect;
mod penalty;

use crate::Energy;
use detect::{ContactPoint, Detector};
use nalgebra::{Matrix3, Vector3};
use penalty::Penalty;
use splinerod_core::basis::MAX_ORDER;
use splinerod_core::rod::{non_negative, positive};
use splinerod_core::{BlockBanded, CoreError, HessianKind, Real, Rod};
use std::sync::{Mutex, MutexGuard};

/// Settings of [`Contact`]. All lengths in m.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Rod radius `r` (> 0): centre lines are kept `2r` apart.
    pub radius: Real,
    /// Penalty stiffness `k`, N/m (> 0).
    pub stiffness: Real,
    /// Onset layer `δ` (> 0): the penalty starts at gap `δ` and reaches stiffness `k` at
    /// gap 0. Default `0.1 r`.
    pub onset: Real,
    /// Points closer than this in rest arclength never touch (≥ 0). Default `π r`.
    pub exclusion: Real,
    /// Floor plane `(n_f, h)`: unit normal and height, the rod staying on the `+n_f` side.
    pub floor: Option<(Vector3<Real>, Real)>,
}

impl ContactParams {
    /// Self-contact only, for radius `r` and stiffness `k`, with the default onset and
    /// exclusion.
    pub fn new(radius: Real, stiffness: Real) -> Result<Self, CoreError> {
        positive("radius", radius)?;
        positive("stiffness", stiffness)?;
        Ok(Self {
            radius,
            stiffness,
            onset: 0.1 * radius,
            exclusion: std::f64::consts::PI * radius,
            floor: None,
        })
    }

    /// Adds the floor `y = height` (normal `+y`).
    pub fn with_floor(mut self, height: Real) -> Result<Self, CoreError> {
        if !height.is_finite() {
            return Err(CoreError::InvalidParameter {
                name: "floor",
                value: height,
                reason: "must be finite",
            });
        }
        self.floor = Some((Vector3::y(), height));
        Ok(self)
    }

    /// Checks every setting.
    pub fn validate(&self) -> Result<(), CoreError> {
        positive("radius", self.radius)?;
        positive("stiffness", self.stiffness)?;
        positive("onset", self.onset)?;
        non_negative("exclusion", self.exclusion)?;
        if let Some((normal, height)) = self.floor {
            let unit = (normal.norm() - 1.0).abs() < 1e-12;
            if !unit || !height.is_finite() {
                return Err(CoreError::InvalidParameter {
                    name: "floor",
                    value: normal.norm(),
                    reason: "needs a unit normal and a finite height",
                });
            }
        }
        Ok(())
    }

    /// Centre-line distance at which the penalty starts, `2r + δ`.
    pub fn reach(&self) -> Real {
        2.0 * self.radius + self.onset
    }
}

/// The contact energy (module docs). Detection buffers sit behind a mutex so that the
/// `&self` energy methods can reuse them; one rod is never evaluated from two threads at
/// once, so the lock is uncontended.
#[derive(Debug)]
pub struct Contact {
    params: ContactParams,
    penalty: Penalty,
    detector: Mutex<Detector>,
}

impl Clone for Contact {
    fn clone(&self) -> Self {
        Self {
            params: self.params,
            penalty: self.penalty,
            detector: Mutex::new(Detector::default()),
        }
    }
}

/// What the detection found at the rod's current positions.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactSummary {
    /// Contacts (pairs closer than the reach `2r + δ`).
    pub pairs: usize,
    /// Candidate span pairs of the broad phase.
    pub candidates: usize,
    /// Smallest centre-line distance among the contacts, m (`None` without contacts).
    pub min_distance: Option<Real>,
}

impl Contact {
    /// A contact energy with validated `params`.
    pub fn new(params: ContactParams) -> Result<Self, CoreError> {
        params.validate()?;
        Ok(Self {
            params,
            penalty: Penalty {
                k: params.stiffness,
                delta: params.onset,
            },
            detector: Mutex::new(Detector::default()),
        })
    }

    /// The settings.
    pub fn params(&self) -> &ContactParams {
        &self.params
    }

    fn detected(&self, rod: &Rod) -> Result<MutexGuard<'_, Detector>, CoreError> {
        let mut detector = self.detector.lock().unwrap_or_else(|e| e.into_inner());
        detector.detect(rod, self.params.reach(), self.params.exclusion)?;
        Ok(detector)
    }

    /// Runs `f` on each contact at the rod's positions.
    pub fn for_each_contact(
        &self,
        rod: &Rod,
        mut f: impl FnMut(&ContactPoint),
    ) -> Result<(), CoreError> {
        self.detected(rod)?.contacts.iter().for_each(&mut f);
        Ok(())
    }

    /// Counts and closest distance of the contacts at the rod's positions.
    pub fn summary(&self, rod: &Rod) -> Result<ContactSummary, CoreError> {
        let d = self.detected(rod)?;
        let min_distance = d.contacts.iter().map(|c| c.distance).reduce(Real::min);
        Ok(ContactSummary {
            pairs: d.contacts.len(),
            candidates: d.candidates,
            min_distance,
        })
    }

    /// Appends the material coordinates of both sides of every contact (for the
    /// interaction refinement criterion).
    pub fn interaction_points(&self, rod: &Rod, out: &mut Vec<Real>) -> Result<(), CoreError> {
        self.for_each_contact(rod, |c| out.extend([c.s, c.t]))
    }

    fn gap(&self, c: &ContactPoint) -> Real {
        c.distance - 2.0 * self.params.radius
    }

    /// Calls `f(point, weight, basis row)` at every quadrature point with the floor gap.
    fn for_each_floor_point(&self, rod: &Rod, mut f: impl FnMut(Real, Real, usize, &[Real])) {
        let Some((normal, height)) = self.params.floor else {
            return;
        };
        let table = rod.quadrature();
        for p in 0..table.len() {
            let q = table.point(p);
            let x: Vector3<Real> = (0..q.value.len())
                .map(|k| rod.positions[q.first + k] * q.value[k])
                .sum();
            let gap = normal.dot(&x) - height - self.params.radius;
            if gap < self.params.onset {
                f(gap, q.weight / (2.0 * self.params.radius), q.first, q.value);
            }
        }
    }
}

/// Merged weights \\(w_i = b_i(s) - b_i(t)\\) of a contact: at most `2 · MAX_ORDER`
/// control points.
fn contact_weights(c: &ContactPoint, out: &mut [(usize, Real); 2 * MAX_ORDER]) -> usize {
    let mut len = 0;
    let rows = [(&c.row_s, 1.0), (&c.row_t, -1.0)];
    for (row, sign) in rows {
        for k in 0..row.order {
            let i = row.first + k;
            let w = sign * row.value[k];
            match out[..len].iter_mut().find(|(j, _)| *j == i) {
                Some((_, total)) => *total += w,
                None => {
                    out[len] = (i, w);
                    len += 1;
                }
            }
        }
    }
    len
}

impl Energy for Contact {
    fn name(&self) -> &str {
        "contact"
    }

    fn energy(&self, rod: &Rod) -> Real {
        let Ok(d) = self.detected(rod) else {
            return Real::NAN;
        };
        let mut e: Real = d
            .contacts
            .iter()
            .map(|c| self.penalty.value(self.gap(c)))
            .sum();
        drop(d);
        self.for_each_floor_point(rod, |g, w, _, _| e += w * self.penalty.value(g));
        e
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let Ok(d) = self.detected(rod) else {
            gradient
                .iter_mut()
                .for_each(|g| *g = Vector3::repeat(Real::NAN));
            return;
        };
        let mut weights = [(0, 0.0); 2 * MAX_ORDER];
        for c in &d.contacts {
            let force = c.normal * self.penalty.slope(self.gap(c));
            let len = contact_weights(c, &mut weights);
            for &(i, w) in &weights[..len] {
                gradient[i] += force * w;
            }
        }
        drop(d);
        let normal = self.params.floor.map_or(Vector3::zeros(), |f| f.0);
        self.for_each_floor_point(rod, |g, w, first, value| {
            let force = normal * (w * self.penalty.slope(g));
            for (k, b) in value.iter().enumerate() {
                gradient[first + k] += force * *b;
            }
        });
    }

    fn add_hessian(&self, rod: &Rod, _kind: HessianKind, hessian: &mut BlockBanded) {
        let Ok(d) = self.detected(rod) else {
            hessian.scale(Real::NAN);
            return;
        };
        let mut weights = [(0, 0.0); 2 * MAX_ORDER];
        for c in &d.contacts {
            let nn = c.normal * c.normal.transpose() * self.penalty.curvature(self.gap(c));
            let len = contact_weights(c, &mut weights);
            for (a, &(i, wi)) in weights[..len].iter().enumerate() {
                for &(j, wj) in &weights[a..len] {
                    hessian.add_coupling(i, j, &(nn * (wi * wj)));
                }
            }
        }
        drop(d);
        let nn: Matrix3<Real> = self
            .params
            .floor
            .map_or(Matrix3::zeros(), |f| f.0 * f.0.transpose());
        self.for_each_floor_point(rod, |g, w, first, value| {
            let c = w * self.penalty.curvature(g);
            for (a, ba) in value.iter().enumerate() {
                for (b, bb) in value.iter().enumerate().skip(a) {
                    hessian.add_block(first + a, first + b, &(nn * (c * ba * bb)));
                }
            }
        });
    }
}
