//! Forward sensitivities ([`splinerod_integrators::forward`]) of a swinging test string
//! (pinned at one end, released horizontally under gravity, damped) against central
//! differences of runs, for implicit Euler and BDF2 (its midpoint start included): by
//! the string's stiffness, a component of gravity and the damping rate; no allocation
//! per step once sized.

use nalgebra::Vector3;
use splinerod_core::{Pin, Real};
use splinerod_integrators::conformance::TestString;
use splinerod_integrators::{
    Bdf2, ForwardState, ImplicitEuler, ImplicitMidpoint, Integrator, IntegratorError, NewtonParams,
    ParameterRates, System,
};

#[path = "common/counting.rs"]
mod counting;
use counting::allocations_during;

/// The parameters: stiffness `k`, gravity's `y`, damping `α`.
#[derive(Debug, Clone, Copy)]
struct Parameters {
    k: Real,
    gy: Real,
    alpha: Real,
}

impl Parameters {
    /// With parameter `i` moved by `h`.
    fn moved(mut self, i: usize, h: Real) -> Self {
        match i {
            0 => self.k += h,
            1 => self.gy += h,
            _ => self.alpha += h,
        }
        self
    }
}

/// The rates of the three parameters on the test string.
struct Rates(Parameters);

impl ParameterRates for Rates {
    fn gradient_rate(
        &mut self,
        system: &dyn System,
        k: usize,
        out: &mut [Vector3<Real>],
    ) -> Result<(), IntegratorError> {
        out.iter_mut().for_each(|o| *o = Vector3::zeros());
        let masses = system.rod().lumped_masses();
        match k {
            0 => {
                // The elastic part of the gradient, over k (the energy is linear in k).
                system.add_potential_gradient(out);
                let g = Vector3::new(0.3, self.0.gy, 0.0);
                for (o, m) in out.iter_mut().zip(masses) {
                    *o = (*o + g * *m) / self.0.k;
                }
            }
            1 => {
                for (o, m) in out.iter_mut().zip(masses) {
                    o.y = -m;
                }
            }
            _ => {}
        }
        Ok(())
    }

    fn mass_rate(&self, _k: usize) -> Real {
        0.0
    }

    fn damping_rate(&self, k: usize) -> Real {
        if k == 2 {
            1.0
        } else {
            0.0
        }
    }
}

/// A scheme by name, with a tight Newton tolerance.
fn scheme(name: &str) -> Box<dyn Integrator> {
    let params = NewtonParams {
        tolerance: 1e-14,
        ..NewtonParams::default()
    };
    match name {
        "bdf2" => Box::new(Bdf2::new(params).unwrap()),
        _ => Box::new(ImplicitEuler::new(params).unwrap()),
    }
}

/// Runs the string for `steps` steps of 10 ms by `name`; the end positions and, with
/// `forward`, the states of the three parameters.
fn run(name: &str, p: Parameters, forward: bool) -> (Vec<Vector3<Real>>, Vec<ForwardState>) {
    let mut string = TestString::new(10, p.k, Vector3::new(0.3, p.gy, 0.0)).unwrap();
    string.pins = vec![Pin::here(&string.rod, 0.0).unwrap()];
    string.rod.damping = p.alpha;
    let mut integrator = scheme(name);
    let n = string.rod.len();
    let mut states = vec![ForwardState::new(n); if forward { 3 } else { 0 }];
    let mut rates = Rates(p);
    for _ in 0..60 {
        integrator.step(&mut string, 0.01).expect("step");
        if forward {
            let f = integrator.forward().expect("a forward form");
            f.propagate(&mut string, &mut rates, &mut states)
                .expect("propagate");
        }
    }
    (string.rod.positions.clone(), states)
}

/// The largest relative error of the forward sensitivities of `name` against central
/// differences (relative 1e-4, extrapolated from h and h/2).
fn worst_error(name: &str) -> Real {
    let p = Parameters {
        k: 4.0,
        gy: -9.81,
        alpha: 0.5,
    };
    let (_, states) = run(name, p, true);
    let values = [p.k, p.gy, p.alpha];
    let mut worst: Real = 0.0;
    for (i, state) in states.iter().enumerate() {
        let central = |h: Real| -> Vec<Vector3<Real>> {
            let (up, _) = run(name, p.moved(i, h), false);
            let (down, _) = run(name, p.moved(i, -h), false);
            up.iter()
                .zip(&down)
                .map(|(a, b)| (a - b) / (2.0 * h))
                .collect()
        };
        let h = 1e-4 * values[i].abs();
        let (coarse, fine) = (central(h), central(h / 2.0));
        let largest = state
            .positions
            .iter()
            .map(|v| v.amax())
            .fold(0.0, Real::max);
        assert!(largest > 1e-6, "parameter {i} moves the string");
        for ((d, c), f) in state.positions.iter().zip(&coarse).zip(&fine) {
            let extrapolated = (f * 4.0 - c) / 3.0;
            worst = worst.max((d - extrapolated).amax() / largest);
        }
    }
    worst
}

#[test]
fn implicit_euler_s_forward_sensitivities_match_finite_differences() {
    let error = worst_error("implicit-euler");
    assert!(error < 1e-6, "relative error {error:e}");
}

#[test]
fn bdf2_s_forward_sensitivities_match_finite_differences() {
    let error = worst_error("bdf2");
    assert!(error < 1e-6, "relative error {error:e}");
}

#[test]
fn other_schemes_have_no_forward_form_and_a_forward_step_needs_a_step() {
    let mut midpoint = ImplicitMidpoint::new(NewtonParams::default()).unwrap();
    assert!(midpoint.forward().is_none());
    let mut euler = ImplicitEuler::new(NewtonParams::default()).unwrap();
    let mut string = TestString::new(6, 1.0, Vector3::zeros()).unwrap();
    let mut states = vec![ForwardState::new(string.rod.len())];
    let mut rates = Rates(Parameters {
        k: 1.0,
        gy: 0.0,
        alpha: 0.0,
    });
    let forward = euler.forward().expect("implicit Euler has one");
    let e = forward.propagate(&mut string, &mut rates, &mut states);
    assert!(e.is_err(), "no step taken yet");
}

#[test]
fn forward_steps_do_not_allocate_after_warm_up() {
    for name in ["implicit-euler", "bdf2"] {
        let p = Parameters {
            k: 4.0,
            gy: -9.81,
            alpha: 0.5,
        };
        let mut string = TestString::new(10, p.k, Vector3::new(0.3, p.gy, 0.0)).unwrap();
        string.pins = vec![Pin::here(&string.rod, 0.0).unwrap()];
        let mut integrator = scheme(name);
        let mut states = vec![ForwardState::new(string.rod.len()); 3];
        let mut rates = Rates(p);
        let mut step = |string: &mut TestString| {
            integrator.step(string, 0.01).expect("step");
            let f = integrator.forward().expect("a forward form");
            f.propagate(string, &mut rates, &mut states)
                .expect("propagate");
        };
        for _ in 0..3 {
            step(&mut string);
        }
        let count = allocations_during(|| {
            for _ in 0..20 {
                step(&mut string);
            }
        });
        assert_eq!(count, 0, "{name}: {count} allocations in 20 forward steps");
    }
}
