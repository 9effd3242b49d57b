//! [`Contact`] as an [`Energy`]: the energy, gradient and Hessian summed over sample
//! pairs and surface points, the step's lifecycle (stiffness update, then friction's
//! frozen forces), checkpoints and the finer copy for error estimates.

use super::{Contact, ContactLaw, SamplePair};
use crate::capabilities::{Capabilities, Interaction, Lifecycle, Summary};
use crate::{Energy, EnergySummary};
use nalgebra::Vector3;
use splinerod_core::rod::positive;
use splinerod_core::{
    BlockBanded, CoreError, HessianKind, KnotMap, Real, Rod, SavedState, StateReader,
};

impl Energy for Contact {
    fn name(&self) -> &str {
        "contact"
    }

    fn energy(&self, rod: &Rod) -> Real {
        let Ok(d) = self.detected(rod) else {
            return Real::NAN;
        };
        let e: Real = d
            .pairs
            .iter()
            .map(|c| self.pair_weight(&d, c) * self.penalty.value(self.gap(&d, c)))
            .sum();
        drop(d);
        let surfaces = self.surface_energy(rod).unwrap_or(Real::NAN);
        e + surfaces + self.friction_state().energy(rod)
    }

    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        if !self.add_pair_gradient(rod, gradient) {
            return;
        }
        if self.add_surface_gradient(rod, gradient).is_err() {
            gradient
                .iter_mut()
                .for_each(|g| *g = Vector3::repeat(Real::NAN));
            return;
        }
        self.friction_state().add_gradient(rod, gradient);
    }

    fn add_hessian(&self, rod: &Rod, kind: HessianKind, hessian: &mut BlockBanded) {
        let Ok(mut d) = self.detected(rod) else {
            hessian.scale(Real::NAN);
            return;
        };
        let mut local = std::mem::take(&mut d.group_hessian);
        let mut sums = std::mem::take(&mut d.sums);
        sums.clear(d.samples.s.len());
        let samples = &d.samples;
        let first = |k: u32| samples.first[k as usize] as usize;
        for &(start, end) in &d.groups {
            let pairs = &d.pairs[start..end];
            let order = samples.order;
            // Each strand's samples touch a run of consecutive control points.
            let run = |side: fn(&SamplePair) -> u32| {
                let firsts = pairs
                    .iter()
                    .map(|c| samples.first[side(c) as usize] as usize);
                let (lo, hi) = firsts.fold((usize::MAX, 0), |(lo, hi), f| (lo.min(f), hi.max(f)));
                lo..hi + order
            };
            local.start(run(|c| c.a), run(|c| c.b));
            for c in pairs {
                let m = self.pair_hessian(&d, c, kind);
                sums.add_block(c.a, &m);
                sums.add_block(c.b, &m);
                let a = (c.a, first(c.a), samples.row(c.a as usize));
                local.add_cross(a, (first(c.b), samples.row(c.b as usize)), &m);
            }
            local.finish(hessian);
        }
        sums.spread_blocks(samples, hessian);
        local.flush(hessian);
        d.group_hessian = local;
        d.sums = sums;
        drop(d);
        if self.add_surface_hessian(rod, kind, hessian).is_err() {
            hessian.scale(Real::NAN);
            return;
        }
        self.friction_state().add_hessian(rod, hessian);
    }

    fn capabilities(&self) -> Capabilities<'_> {
        Capabilities {
            lifecycle: Some(self),
            interaction: Some(self),
            summary: Some(self),
            parameters: Some(self),
            ..Capabilities::default()
        }
    }

    fn lifecycle_mut(&mut self) -> Option<&mut dyn Lifecycle> {
        Some(self)
    }
}

impl Contact {
    /// Adds the gradient of the sample pairs' sum (self-contact and contact between
    /// strands) to `gradient`; without a detection, sets it to NaN and returns false.
    pub(super) fn add_pair_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) -> bool {
        let Ok(mut d) = self.detected(rod) else {
            gradient
                .iter_mut()
                .for_each(|g| *g = Vector3::repeat(Real::NAN));
            return false;
        };
        // Each pair's force acts on its two samples (see `sample_sums`).
        let mut sums = std::mem::take(&mut d.sums);
        sums.clear(d.samples.s.len());
        for c in &d.pairs {
            let force = c.normal * (self.pair_weight(&d, c) * self.penalty.slope(self.gap(&d, c)));
            sums.add_force(c.a, &force);
            sums.add_force(c.b, &-force);
        }
        sums.spread_forces(&d.samples, gradient);
        d.sums = sums;
        true
    }
}

impl Lifecycle for Contact {
    /// Updates an adapting stiffness ([`Contact::adapt_stiffness`]), then freezes
    /// friction.
    fn begin_step(&mut self, rod: &Rod, dt: Real) -> Result<(), CoreError> {
        positive("dt", dt)?;
        self.adapt_stiffness(rod)?;
        Contact::begin_step(self, rod, dt)
    }

    /// In a static solve (`stiffen`), raises an adapting stiffness where the tolerance
    /// is not met (see [`crate::contact::stiffness`]); between time steps nothing (their
    /// updates come at [`Lifecycle::begin_step`]).
    fn update_multipliers(&mut self, rod: &Rod, stiffen: bool) -> Real {
        if stiffen {
            self.stiffen_for_statics(rod)
        } else {
            0.0
        }
    }

    fn drive(&mut self, t: Real) {
        self.move_obstacles(t);
    }

    /// The friction lags' anchors and normal forces (the `friction` module): the slip
    /// is measured from the step's start.
    fn add_start_rate(&self, rod: &Rod, start_rate: &[Vector3<Real>], out: &mut [Vector3<Real>]) {
        self.friction_state().add_start_rate(rod, start_rate, out);
    }

    fn on_knot_change(&mut self, _rod: &Rod, _map: &KnotMap) {
        let detector = self.detector.get_mut().unwrap_or_else(|e| e.into_inner());
        detector.forget_topology();
    }

    fn save_state(&self, out: &mut SavedState) {
        let detector = self.detector.lock().unwrap_or_else(|e| e.into_inner());
        detector.save_state(out);
        if self.params.law != ContactLaw::Penalty {
            out.real(self.penalty.k);
            out.reals(&self.adapted_at.unwrap_or([Real::NAN; 2]));
        }
    }

    fn load_state(&mut self, rod: &Rod, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        let detector = self.detector.get_mut().unwrap_or_else(|e| e.into_inner());
        detector.load_state(rod, input)?;
        if self.params.law != ContactLaw::Penalty {
            self.set_stiffness(input.real()?)?;
            let mut at = Vec::new();
            input.reals_into(&mut at)?;
            self.adapted_at = match at[..] {
                [g, f] if !f.is_nan() => Some([g, f]),
                [_, _] => None,
                _ => return Err(CoreError::StateMismatch("a contact stiffness state")),
            };
        }
        Ok(())
    }

    fn time_dependent(&self) -> bool {
        self.motion.paths.iter().any(Option::is_some)
    }

    /// The same contact at its stiffness now, with its segments' radii and without
    /// friction (its frozen data belong to the coarse rod's step), for estimators
    /// evaluating the energies on a finer copy.
    fn for_finer_rod(&self, _fine: &Rod) -> Option<Box<dyn Energy>> {
        let mut params = self.params;
        params.friction = 0.0;
        let copy = Contact::new(params).and_then(|c| c.with_obstacles(self.obstacles.clone()));
        let mut copy = copy.ok()?;
        copy.penalty = self.penalty;
        copy.radii = self.radii.clone();
        Some(Box::new(copy) as Box<dyn Energy>)
    }
}

impl Interaction for Contact {
    fn interaction_points(&self, rod: &Rod, out: &mut Vec<Real>) -> Result<(), CoreError> {
        Contact::interaction_points(self, rod, out)
    }

    fn admissible(&self, rod: &Rod) -> bool {
        Contact::admissible(self, rod)
    }

    fn add_obstacle_forces(
        &self,
        rod: &Rod,
        out: &mut Vec<Vector3<Real>>,
    ) -> Result<(), CoreError> {
        out.extend(self.obstacle_forces(rod)?);
        Ok(())
    }
}

impl Summary for Contact {
    fn summary(&self, rod: &Rod) -> Result<EnergySummary, CoreError> {
        Ok(EnergySummary {
            contact: Some(Contact::summary(self, rod)?),
            ..EnergySummary::default()
        })
    }
}
