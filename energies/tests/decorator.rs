//! A decorator keeps every capability of the energy it wraps: [`OnSegment`] around an
//! energy that has all of them has all of them too, and each answers through it on the
//! segment (its rod, its control points, its material coordinates).
mod common;

use common::part;
use nalgebra::Vector3;
use splinerod_core::{CoreError, KnotMap, Real, Rod, SavedState, StateReader};
use splinerod_energies::{
    Capabilities, Energy, EnergySummary, HessianRemainder, Interaction, LaneForm, LaneTerm,
    Lifecycle, OnSegment, Parameters, Summary, Tension, TwistSummary,
};
use std::sync::{Arc, Mutex};

/// What the wrapped energy heard, and on rods of how many control points.
#[derive(Debug, Default)]
struct Heard {
    begin_step: Option<(usize, Real)>,
    knot_change: Option<usize>,
    drive: Option<Real>,
    stiffness: Option<Real>,
    loaded: Option<Real>,
}

/// `½ k |q|²`, with every capability: each answer names the rod it was given.
#[derive(Clone)]
struct Everything {
    k: Real,
    heard: Arc<Mutex<Heard>>,
}

impl Everything {
    fn heard(&self) -> std::sync::MutexGuard<'_, Heard> {
        self.heard.lock().expect("lock")
    }
}

impl Energy for Everything {
    fn energy(&self, rod: &Rod) -> Real {
        0.5 * self.k * rod.positions.iter().map(|q| q.norm_squared()).sum::<Real>()
    }
    fn add_gradient(&self, rod: &Rod, g: &mut [Vector3<Real>]) {
        g.iter_mut()
            .zip(&rod.positions)
            .for_each(|(g, q)| *g += q * self.k);
    }
    fn capabilities(&self) -> Capabilities<'_> {
        Capabilities {
            lifecycle: Some(self),
            interaction: Some(self),
            remainder: Some(self),
            tension: Some(self),
            lanes: Some(self),
            summary: Some(self),
            parameters: Some(self),
            segment: None,
        }
    }
    fn lifecycle_mut(&mut self) -> Option<&mut dyn Lifecycle> {
        Some(self)
    }
}

impl Lifecycle for Everything {
    fn begin_step(&mut self, rod: &Rod, dt: Real) -> Result<(), CoreError> {
        self.heard().begin_step = Some((rod.len(), dt));
        Ok(())
    }
    fn on_knot_change(&mut self, rod: &Rod, _map: &KnotMap) {
        self.heard().knot_change = Some(rod.len());
    }
    fn drive(&mut self, t: Real) {
        self.heard().drive = Some(t);
    }
    fn add_start_rate(&self, _: &Rod, start_rate: &[Vector3<Real>], out: &mut [Vector3<Real>]) {
        for (o, r) in out.iter_mut().zip(start_rate) {
            *o += r * self.k;
        }
    }
    fn time_dependent(&self) -> bool {
        true
    }
    fn update_multipliers(&mut self, rod: &Rod, _stiffen: bool) -> Real {
        rod.len() as Real
    }
    fn set_stiffness_scale(&mut self, scale: Real) -> bool {
        self.heard().stiffness = Some(scale);
        true
    }
    fn save_state(&self, out: &mut SavedState) {
        out.real(self.k);
    }
    fn load_state(&mut self, rod: &Rod, input: &mut StateReader<'_>) -> Result<(), CoreError> {
        self.heard().loaded = Some(input.real()? + rod.len() as Real);
        Ok(())
    }
    fn for_finer_rod(&self, fine: &Rod) -> Option<Box<dyn Energy>> {
        let k = self.k * fine.len() as Real;
        Some(Box::new(Everything { k, ..self.clone() }))
    }
    fn supports(&self, rod: &Rod) -> Result<(), CoreError> {
        match rod.segments().len() {
            0 => Ok(()),
            _ => Err(CoreError::StateMismatch("a joined rod")),
        }
    }
}

impl Interaction for Everything {
    fn interaction_points(&self, rod: &Rod, out: &mut Vec<Real>) -> Result<(), CoreError> {
        out.push(0.25 * rod.material().rest_length);
        Ok(())
    }
    fn admissible(&self, rod: &Rod) -> bool {
        rod.len() < 10
    }
    fn add_obstacle_forces(
        &self,
        rod: &Rod,
        out: &mut Vec<Vector3<Real>>,
    ) -> Result<(), CoreError> {
        out.push(Vector3::new(rod.len() as Real, 0.0, 0.0));
        Ok(())
    }
}

/// `R = k I`.
impl HessianRemainder for Everything {
    fn has_remainder(&self, rod: &Rod) -> bool {
        rod.segments().is_empty()
    }
    fn add_remainder(&self, _: &Rod, v: &[Vector3<Real>], scale: Real, out: &mut [Vector3<Real>]) {
        out.iter_mut()
            .zip(v)
            .for_each(|(o, v)| *o += v * (scale * self.k));
    }
}

/// A tension of `100 + s` at the rod's own coordinate `s`.
impl Tension for Everything {
    fn add_tension(&self, _: &Rod, s: &[Real], out: &mut [Real]) -> bool {
        out.iter_mut().zip(s).for_each(|(t, s)| *t += 100.0 + s);
        true
    }
}

impl LaneForm for Everything {
    fn lane_term<'a>(&'a self, rod: &'a Rod) -> Option<LaneTerm<'a>> {
        let g = Vector3::zeros();
        let masses = rod.lumped_masses();
        Some(LaneTerm::Gravity { g, masses })
    }
}

impl Parameters for Everything {
    fn parameter_names(&self) -> &[&'static str] {
        &["k"]
    }
    fn add_gradient_derivative(
        &self,
        rod: &Rod,
        name: &str,
        out: &mut [Vector3<Real>],
    ) -> Result<bool, CoreError> {
        if name != "k" {
            return Ok(false);
        }
        splinerod_energies::parameters::add_linear(self, rod, self.k, out)
    }
}

impl Summary for Everything {
    fn summary(&self, rod: &Rod) -> Result<EnergySummary, CoreError> {
        let twist = TwistSummary {
            twist: rod.len() as Real,
            ..TwistSummary::default()
        };
        Ok(EnergySummary {
            twist: Some(twist),
            ..EnergySummary::default()
        })
    }
}

#[test]
fn on_segment_keeps_every_capability_of_what_it_wraps() {
    let parts = [part(7, 1.0, 0.0), part(6, 0.5, 1.0)];
    let joined = Rod::join(&parts).expect("join");
    let heard = Arc::new(Mutex::new(Heard::default()));
    let k = 3.0;
    let inner = Everything {
        k,
        heard: heard.clone(),
    };
    let own = inner.capabilities();
    assert!(own.lanes.is_some() && own.segment.is_none());
    let mut wrapped = OnSegment::new(&joined, 1, Box::new(inner.clone())).expect("wrap");
    let (points, start) = (joined.segment_points(1), joined.segments()[1].start);
    let (n, first) = (points.len(), points.start);
    assert_eq!(n, 6);

    // Every capability is there, and the segment is named.
    let caps = wrapped.capabilities();
    let Capabilities {
        lifecycle: Some(lifecycle),
        interaction: Some(interaction),
        remainder: Some(remainder),
        tension: Some(tension),
        lanes: Some(lanes),
        summary: Some(summary),
        parameters: Some(parameters),
        segment: Some(1),
    } = caps
    else {
        panic!("a capability was lost through OnSegment");
    };

    // Lifecycle, read side: time dependence, state, finer copies, support — on the part.
    assert!(lifecycle.time_dependent());
    let mut saved = SavedState::default();
    lifecycle.save_state(&mut saved);
    assert!(lifecycle.supports(&joined).is_ok(), "asked on the part");
    let finer = lifecycle.for_finer_rod(&joined).expect("a finer copy");
    assert_eq!(finer.capabilities().segment, Some(1));
    let finer_energy = finer.energy(&joined);
    assert!((finer_energy - n as Real * wrapped.energy(&joined)).abs() < 1e-12);

    // Interaction: coordinates shifted to the joined rod, barrier and forces on the part.
    let mut at = Vec::new();
    interaction
        .interaction_points(&joined, &mut at)
        .expect("points");
    assert_eq!(at, vec![start + 0.25 * 0.5]);
    assert!(
        interaction.admissible(&joined),
        "the part has 6 < 10 points"
    );
    let mut forces = Vec::new();
    interaction
        .add_obstacle_forces(&joined, &mut forces)
        .expect("forces");
    assert_eq!(forces, vec![Vector3::new(n as Real, 0.0, 0.0)]);

    // The start rate: applied on the part's control points only.
    let rate = vec![Vector3::new(1.0, 2.0, 3.0); joined.len()];
    let mut out = vec![Vector3::zeros(); joined.len()];
    lifecycle.add_start_rate(&joined, &rate, &mut out);
    for (i, o) in out.iter().enumerate() {
        let expected = if points.contains(&i) {
            rate[i] * k
        } else {
            Vector3::zeros()
        };
        assert_eq!(*o, expected, "start rate at {i}");
    }

    // Hessian remainder: asked and applied on the part's control points only.
    assert!(remainder.has_remainder(&joined));
    let v = vec![Vector3::new(1.0, 2.0, 3.0); joined.len()];
    let mut out = vec![Vector3::zeros(); joined.len()];
    remainder.add_remainder(&joined, &v, 0.5, &mut out);
    for (i, o) in out.iter().enumerate() {
        let expected = if points.contains(&i) {
            v[i] * (0.5 * k)
        } else {
            Vector3::zeros()
        };
        assert_eq!(*o, expected, "remainder at {i}");
    }

    // Tension: at the part's own coordinates, only inside it.
    let s = [0.5 * start, start + 0.2];
    let mut t = [0.0; 2];
    assert!(tension.add_tension(&joined, &s, &mut t));
    assert_eq!(t[0], 0.0);
    assert!((t[1] - 100.2).abs() < 1e-12);

    // Lanes: the capability is kept, and a segment has no whole-rod lane form
    // (crate::decorate); on the part alone the inner energy has one.
    assert!(lanes.lane_term(&joined).is_none());
    assert!(inner.lane_term(&parts[1]).is_some());

    // Summary: of the part.
    let twist = summary
        .summary(&joined)
        .expect("summary")
        .twist
        .expect("twist");
    assert_eq!(twist.twist, n as Real);

    // Parameters: named as inside, the derivative on the part's control points only
    // (E = k/2 |q|², so ∂∇E/∂k = q there).
    assert_eq!(parameters.parameter_names(), &["k"]);
    let mut d = vec![Vector3::zeros(); joined.len()];
    assert!(parameters
        .add_gradient_derivative(&joined, "k", &mut d)
        .expect("k"));
    assert!(!parameters
        .add_gradient_derivative(&joined, "m", &mut d)
        .expect("m"));
    for (i, di) in d.iter().enumerate() {
        let expected = if points.contains(&i) {
            joined.positions[i]
        } else {
            Vector3::zeros()
        };
        assert!((di - expected).norm() < 1e-12, "derivative at {i}: {di:?}");
    }

    // Lifecycle, mutable side: every hook reaches the inner energy with the part.
    let lifecycle = wrapped.lifecycle_mut().expect("a lifecycle");
    lifecycle.begin_step(&joined, 1e-3).expect("begin");
    lifecycle.drive(0.7);
    assert!(lifecycle.set_stiffness_scale(0.5));
    assert_eq!(lifecycle.update_multipliers(&joined, false), n as Real);
    lifecycle
        .load_state(&joined, &mut saved.reader())
        .expect("load");
    {
        let heard = heard.lock().expect("lock");
        assert_eq!(heard.begin_step, Some((n, 1e-3)));
        assert_eq!(heard.drive, Some(0.7));
        assert_eq!(heard.stiffness, Some(0.5));
        assert_eq!(heard.loaded, Some(k + n as Real));
    }
    let mut changed = joined.clone();
    let map = changed.insert_knot(start + 0.21).expect("insert");
    lifecycle.on_knot_change(&changed, &map);
    assert_eq!(heard.lock().expect("lock").knot_change, Some(n + 1));
    assert_eq!(first, changed.segment_points(1).start);
}
