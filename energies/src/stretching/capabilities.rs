//! [`Stretching`]'s capabilities besides the mechanical core: its lifecycle (tables,
//! knot changes, continuation, multipliers, checkpoints, finer copies), the Hessian
//! remainder of the consistent mixed form, the axial tension and the lane form.

use super::{StretchFormulation, Stretching};
use crate::capabilities::{HessianRemainder, LaneForm, Lifecycle, Tension};
use crate::Energy;
use nalgebra::Vector3;
use splinerod_core::{BasisValues, CoreError, KnotMap, Real, Rod, SavedState, StateReader};

impl Lifecycle for Stretching {
    /// The axial stiffness `EA` (an inextensible rod's penalty has its own continuation:
    /// not scaled).
    fn set_stiffness_scale(&mut self, scale: Real) -> bool {
        if self.multipliers.is_some() {
            return false;
        }
        let own = *self.unscaled.get_or_insert(self.stiffness);
        self.stiffness = if scale == 1.0 { own } else { own * scale };
        if scale == 1.0 {
            self.unscaled = None;
        }
        true
    }

    fn on_knot_change(&mut self, rod: &Rod, _map: &KnotMap) {
        self.follow(rod);
    }

    fn begin_step(&mut self, rod: &Rod, _dt: Real) -> Result<(), CoreError> {
        if !self.table.matches(rod) || (self.consistent() && !self.gram.matches(rod)) {
            self.tabulate(rod);
        }
        Ok(())
    }

    fn for_finer_rod(&self, fine: &Rod) -> Option<Box<dyn Energy>> {
        if self.rest.is_none() && self.multipliers.is_none() {
            return None;
        }
        let mut copy = self.clone();
        copy.follow(fine);
        Some(Box::new(copy))
    }

    fn save_state(&self, out: &mut SavedState) {
        if let Some(m) = &self.multipliers {
            m.save(out);
        }
    }

    fn load_state(&mut self, _rod: &Rod, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        match &mut self.multipliers {
            Some(m) => m.load(input),
            None => Ok(()),
        }
    }

    fn update_multipliers(&mut self, rod: &Rod, stiffen: bool) -> Real {
        if self.multipliers.is_none() {
            return 0.0;
        }
        let tensions: Vec<(Real, Real)> = self.with_tensions(rod, |t| t.to_vec());
        self.multipliers
            .as_mut()
            .map_or(0.0, |m| m.update(&tensions, stiffen))
    }
}

impl HessianRemainder for Stretching {
    fn has_remainder(&self, _rod: &Rod) -> bool {
        self.consistent()
    }

    fn add_remainder(
        &self,
        rod: &Rod,
        v: &[Vector3<Real>],
        scale: Real,
        out: &mut [Vector3<Real>],
    ) {
        self.mixed_remainder(rod, v, scale, out);
    }
}

impl Tension for Stretching {
    fn add_tension(&self, rod: &Rod, s: &[Real], out: &mut [Real]) -> bool {
        if self.formulation != StretchFormulation::Pointwise {
            self.mixed_tension(rod, s, out);
            return true;
        }
        let mut b = BasisValues::default();
        for (&s, t) in s.iter().zip(out) {
            if rod.basis().evaluate(s, &mut b).is_ok() {
                let c1 = b.combine(&b.d1, &rod.positions);
                let g0 = self.rest_metric_at(s);
                let eps = 0.5 * (c1.norm_squared() - g0) / g0;
                *t += self.stiffness * eps * c1.norm() / g0.sqrt();
            }
        }
        true
    }
}

impl LaneForm for Stretching {
    fn lane_term<'a>(&'a self, rod: &'a Rod) -> Option<crate::LaneTerm<'a>> {
        self.moment_term(rod)
    }
}

impl Stretching {
    /// Whether the rest metric is an initial curve's ([`Stretching::with_rest_shape`])
    /// rather than the parametrisation's: then the rest length does not enter the
    /// energy as the domain's length (its parameter derivative is not given).
    pub(crate) fn has_rest_shape(&self) -> bool {
        self.rest.is_some()
    }
}
