//! A conformance suite that every [`Integrator`] must pass, run on each implementation
//! (adding an integrator = one line in `integrators/tests/conformance.rs`):
//!
//! * **free flight** under gravity, no internal energy: velocities are exactly
//!   \\(v_0 + g t\\) and positions \\(q_0 + v_0 t + \tfrac12 g t^2 + c\, h\, t\, g\\), with
//!   the lag `c` the integrator declares (½ for implicit Euler, 0 for schemes exact on
//!   constant accelerations);
//! * **momentum**: internal forces conserve linear momentum (1e-12 relative);
//! * **order** of convergence on a linear oscillator: the pinned string of
//!   [`TestString`] started in its first mode, whose exact semi-discrete solution is
//!   \\(q(t) = q_r + A\cos(\omega t)\,\phi\\) (ω, φ from [`crate::modal::modes`]); the
//!   phase-space error \\(\max_i |q_i - q_i(T)| + |v_i - v_i(T)|/\omega\\) after one period
//!   at 40, 80, 160 steps per period gives the observed order;
//! * **energy** per period on the same oscillator at 40 steps per period: conserved
//!   (conserving schemes, 1e-10 relative) or never increasing (dissipative schemes);
//! * **pins** hold at the end of every step, also while they move (1e-12 m);
//! * **rollback**: a step whose forces become NaN fails with
//!   [`IntegratorError::NonFinite`] and leaves the state bitwise unchanged.
//!
//! The test system is a string with the quadratic energy
//! \\(E = \tfrac{k}{2}\int |C'|^2 ds - \int \mu g\cdot C\, ds\\) (no dependency on the
//! energies crate).

use crate::{modal, Integrator, IntegratorError, System};
use nalgebra::{Matrix3, Vector3};
use splinerod_core::{BSplineSpace, BlockBanded, HessianKind, Material, Pin, Real, Rod};

/// A cubic string of rest length 2 m, μ = 0.5 kg/m, with the quadratic energy
/// \\(\tfrac{k}{2}\int |C'|^2 ds\\) and gravity `g`: linear equations of motion whose
/// pinned modes are \\(\omega_j \approx j\pi/L\,\sqrt{k/\mu}\\).
#[derive(Debug, Clone)]
pub struct TestString {
    /// The rod.
    pub rod: Rod,
    /// Pins.
    pub pins: Vec<Pin>,
    /// Stiffness `k`, N.
    pub k: Real,
    /// Gravity, m/s².
    pub g: Vector3<Real>,
    /// Makes the gradient NaN (to test rollback).
    pub poison: bool,
}

impl TestString {
    /// A straight string along x with `n ≥ 4` control points, unpinned.
    pub fn new(n: usize, k: Real, g: Vector3<Real>) -> Result<Self, IntegratorError> {
        let material = Material {
            rest_length: 2.0,
            linear_density: 0.5,
        };
        let basis = BSplineSpace::clamped_uniform(3, n, 2.0)?;
        let end = Vector3::new(2.0, 0.0, 0.0);
        let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end)?;
        Ok(Self {
            rod,
            pins: Vec::new(),
            k,
            g,
            poison: false,
        })
    }

    /// Pins both ends where they are.
    pub fn pin_ends(mut self) -> Result<Self, IntegratorError> {
        self.pins = vec![Pin::here(&self.rod, 0.0)?, Pin::here(&self.rod, 2.0)?];
        Ok(self)
    }

    /// Kinetic plus potential energy.
    pub fn total_energy(&self) -> Real {
        self.rod.kinetic_energy() + self.potential_energy()
    }
}

/// \\(C'\\) at a quadrature point.
fn tangent(p: &splinerod_core::QuadPoint<'_>, q: &[Vector3<Real>]) -> Vector3<Real> {
    p.d1.iter()
        .enumerate()
        .map(|(a, w)| q[p.first + a] * *w)
        .sum()
}

impl System for TestString {
    fn rod(&self) -> &Rod {
        &self.rod
    }
    fn rod_mut(&mut self) -> &mut Rod {
        &mut self.rod
    }
    fn pins(&self) -> &[Pin] {
        &self.pins
    }
    fn potential_energy(&self) -> Real {
        let q = &self.rod.positions;
        let elastic: Real = (self.rod.quadrature().points())
            .map(|p| 0.5 * self.k * p.weight * tangent(&p, q).norm_squared())
            .sum();
        let m = self.rod.lumped_masses();
        let gravity: Real = m.iter().zip(q).map(|(m, x)| m * self.g.dot(x)).sum();
        elastic - gravity
    }
    fn add_potential_gradient(&self, g: &mut [Vector3<Real>]) {
        let q = &self.rod.positions;
        for p in self.rod.quadrature().points() {
            let c1 = tangent(&p, q);
            for (a, w) in p.d1.iter().enumerate() {
                g[p.first + a] += c1 * (self.k * p.weight * w);
            }
        }
        for (gi, m) in g.iter_mut().zip(self.rod.lumped_masses()) {
            *gi -= self.g * *m;
        }
        if self.poison {
            g[1].x = Real::NAN;
        }
    }
    fn add_potential_hessian(&self, _kind: HessianKind, h: &mut BlockBanded) {
        for p in self.rod.quadrature().points() {
            for (a, wa) in p.d1.iter().enumerate() {
                for (b, wb) in p.d1.iter().enumerate().skip(a) {
                    let block = Matrix3::from_diagonal_element(self.k * p.weight * wa * wb);
                    h.add_block(p.first + a, p.first + b, &block);
                }
            }
        }
    }
}

/// How an integrator treats the energy of an undamped linear oscillator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EnergyBehaviour {
    /// Conserved to 1e-10 relative over the test (implicit midpoint, trapezoidal).
    Conserving,
    /// Never increases (implicit Euler, BDF2).
    Dissipating,
}

/// What the suite should expect of an integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Expectations {
    /// Order of convergence; the observed one must be within ±0.2.
    pub order: Real,
    /// Free-flight position lag coefficient `c` (see the module docs).
    pub free_flight_lag: Real,
    /// Energy behaviour on the oscillator.
    pub energy: EnergyBehaviour,
}

/// Figures the suite measured.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Report {
    /// Free flight: largest position or velocity deviation, relative to the motion's scale.
    pub free_flight: Real,
    /// Momentum change under internal forces, relative.
    pub momentum: Real,
    /// Oscillator phase-space errors after one period (relative to the amplitude) at 40,
    /// 80, 160 steps per period.
    pub errors: [Real; 3],
    /// Observed order, from the last two errors.
    pub order: Real,
    /// Relative energy change per period at 40 steps per period (negative: loss).
    pub energy_per_period: Real,
    /// Largest pin violation at the end of a step, m.
    pub pins: Real,
}

/// Builds a fresh integrator for each check.
pub type Constructor<'a> = &'a dyn Fn() -> Result<Box<dyn Integrator>, IntegratorError>;

/// Runs every check and returns the measured figures, or a message naming the first
/// failed check with its figures.
pub fn check_integrator(make: Constructor<'_>, expect: Expectations) -> Result<Report, String> {
    let name = make().map_err(|e| e.to_string())?.name().to_string();
    let fail = |what: &str, value: Real| Err(format!("{name}: {what} = {value:e}"));
    let mut report = Report {
        free_flight: free_flight(make, expect.free_flight_lag)?,
        momentum: momentum(make)?,
        pins: pins(make)?,
        ..Report::default()
    };
    if report.free_flight > 1e-12 {
        return fail("free-flight error", report.free_flight);
    }
    if report.momentum > 1e-12 {
        return fail("momentum change", report.momentum);
    }
    if report.pins > 1e-12 {
        return fail("pin violation", report.pins);
    }
    for (k, steps) in [40, 80, 160].into_iter().enumerate() {
        report.errors[k] = oscillator(make, steps, 1)?.0;
    }
    report.order = (report.errors[1] / report.errors[2]).log2();
    if (report.order - expect.order).abs() > 0.2 {
        return fail("observed order", report.order);
    }
    let (_, energies) = oscillator(make, 40, 10)?;
    report.energy_per_period = energy_per_period(&energies, 40);
    let (first, last) = (energies[0], energies[energies.len() - 1]);
    let worst_rise = energies
        .windows(2)
        .map(|w| (w[1] - w[0]) / first)
        .fold(Real::NEG_INFINITY, Real::max);
    match expect.energy {
        EnergyBehaviour::Conserving if ((last - first) / first).abs() > 1e-10 => {
            return fail("energy drift over 10 periods", (last - first) / first)
        }
        EnergyBehaviour::Dissipating if worst_rise > 1e-12 => {
            return fail("energy rise in one step", worst_rise)
        }
        _ => {}
    }
    rollback(make).map_err(|e| format!("{name}: {e}"))?;
    Ok(report)
}

fn steps(
    integrator: &mut dyn Integrator,
    system: &mut TestString,
    dt: Real,
    count: usize,
) -> Result<(), String> {
    for _ in 0..count {
        integrator.step(system, dt).map_err(|e| e.to_string())?;
    }
    Ok(())
}

fn free_flight(make: Constructor<'_>, lag: Real) -> Result<Real, String> {
    let g = Vector3::new(0.3, -9.81, 0.1);
    let mut sys = TestString::new(7, 0.0, g).map_err(|e| e.to_string())?;
    let v0 = Vector3::new(1.0, 2.0, -0.5);
    sys.rod.velocities.iter_mut().for_each(|v| *v = v0);
    let q0 = sys.rod.positions.clone();
    let mut integrator = make().map_err(|e| e.to_string())?;
    let (h, count) = (0.01, 50);
    steps(integrator.as_mut(), &mut sys, h, count)?;
    let t = h * count as Real;
    let scale = (v0 * t + g * (0.5 * t * t)).norm();
    let mut worst: Real = 0.0;
    for ((q, v), q0) in sys.rod.positions.iter().zip(&sys.rod.velocities).zip(&q0) {
        let exact = q0 + v0 * t + g * (0.5 * t * t + lag * h * t);
        worst = worst.max((q - exact).norm() / scale);
        worst = worst.max((v - (v0 + g * t)).norm() / (v0 + g * t).norm());
    }
    Ok(worst)
}

fn momentum(make: Constructor<'_>) -> Result<Real, String> {
    let mut sys = TestString::new(9, 50.0, Vector3::zeros()).map_err(|e| e.to_string())?;
    for (i, v) in sys.rod.velocities.iter_mut().enumerate() {
        *v = Vector3::new((i as Real).sin(), 0.5 * (i as Real).cos(), 0.2);
    }
    let p0 = sys.rod.linear_momentum();
    let mut integrator = make().map_err(|e| e.to_string())?;
    steps(integrator.as_mut(), &mut sys, 0.005, 300)?;
    Ok((sys.rod.linear_momentum() - p0).norm() / p0.norm())
}

fn pins(make: Constructor<'_>) -> Result<Real, String> {
    let g = Vector3::new(0.0, -9.81, 0.0);
    let mut sys = TestString::new(8, 10.0, g).map_err(|e| e.to_string())?;
    sys.pins = vec![
        Pin::here(&sys.rod, 0.0).map_err(|e| e.to_string())?,
        Pin::here(&sys.rod, 0.7).map_err(|e| e.to_string())?,
    ];
    let mut integrator = make().map_err(|e| e.to_string())?;
    let mut worst: Real = 0.0;
    for step in 0..20 {
        sys.pins[1].position = Vector3::new(0.7, 0.01 * step as Real, 0.0);
        steps(integrator.as_mut(), &mut sys, 0.01, 1)?;
        for pin in &sys.pins {
            worst = worst.max(pin.violation(&sys.rod).map_err(|e| e.to_string())?.norm());
        }
    }
    Ok(worst)
}

/// Runs the first mode of the pinned string (k = 4, 12 control points, amplitude 1 cm)
/// for `periods` periods of `per_period` steps. Returns the final error relative to the
/// amplitude and the oscillation energy after every step (first entry: initial).
fn oscillator(
    make: Constructor<'_>,
    per_period: usize,
    periods: usize,
) -> Result<(Real, Vec<Real>), String> {
    let string = TestString::new(12, 4.0, Vector3::zeros()).map_err(|e| e.to_string())?;
    let mut sys = string.pin_ends().map_err(|e| e.to_string())?;
    let rest = sys.rod.positions.clone();
    let rest_energy = sys.potential_energy();
    let mode = modal::modes(&sys, 1).map_err(|e| e.to_string())?;
    let mode = mode.first().ok_or("no mode")?;
    let biggest = mode.shape.iter().map(|v| v.norm()).fold(0.0, Real::max);
    let amplitude = 0.01 / biggest;
    for (q, phi) in sys.rod.positions.iter_mut().zip(&mode.shape) {
        *q += phi * amplitude;
    }
    let period = 2.0 * std::f64::consts::PI / mode.omega;
    let dt = period / per_period as Real;
    let mut integrator = make().map_err(|e| e.to_string())?;
    let mut energies = vec![sys.total_energy() - rest_energy];
    for _ in 0..per_period * periods {
        steps(integrator.as_mut(), &mut sys, dt, 1)?;
        energies.push(sys.total_energy() - rest_energy);
    }
    // After whole periods the exact solution is back at its start, at rest. The velocity
    // counts too (scaled by 1/ω): at a turning point the position alone sees the phase
    // error δ only at second order (A(1 − cos δ)).
    let omega = mode.omega;
    let error = (sys.rod.positions.iter().zip(&rest).zip(&mode.shape))
        .zip(&sys.rod.velocities)
        .map(|(((q, r), phi), v)| (q - r - phi * amplitude).norm() + v.norm() / omega)
        .fold(0.0, Real::max);
    Ok((error / 0.01, energies))
}

/// Relative energy change per period, from the first and last samples.
fn energy_per_period(energies: &[Real], per_period: usize) -> Real {
    let periods = (energies.len() - 1) as Real / per_period as Real;
    let ratio = energies[energies.len() - 1] / energies[0];
    ratio.powf(1.0 / periods) - 1.0
}

fn rollback(make: Constructor<'_>) -> Result<(), String> {
    let mut sys = TestString::new(8, 10.0, Vector3::zeros()).map_err(|e| e.to_string())?;
    sys.rod.velocities[3] = Vector3::new(0.0, 1.0, 0.0);
    let mut integrator = make().map_err(|e| e.to_string())?;
    // Two steps, so that multistep schemes use their history.
    steps(integrator.as_mut(), &mut sys, 0.01, 2)?;
    let (q, v) = (sys.rod.positions.clone(), sys.rod.velocities.clone());
    sys.poison = true;
    match integrator.step(&mut sys, 0.01) {
        Err(IntegratorError::NonFinite { .. }) => {}
        other => return Err(format!("a NaN force gave {other:?}, not NonFinite")),
    }
    if sys.rod.positions != q || sys.rod.velocities != v {
        return Err("state not restored after a failed step".into());
    }
    // The failed step must not have spoiled the next one.
    sys.poison = false;
    steps(integrator.as_mut(), &mut sys, 0.01, 1)
}
