//! Validation of bending against beam theory, through the public API:
//!
//! * a cantilever (pin + [`Clamp`] at s = 0) under self weight and under a small tip
//!   load vs Euler–Bernoulli, \\(qL^4/(8EI)\\) and \\(PL^3/(3EI)\\);
//! * the same cantilever under a large tip load vs the elastica, computed here by
//!   shooting on \\(EI\,\theta'' = P\cos\theta\\), \\(\theta(0) = 0\\), \\(\theta'(L) = 0\\);
//! * Euler buckling of a pinned–pinned rod: the compression at which the lowest
//!   transverse \\(\omega^2\\) of the modal analysis crosses zero, converted to a force,
//!   vs \\(\pi^2 EI/L^2\\).
//!
//! Stretching is present with a large `EA` (the rod is then nearly inextensible, as beam
//! theory assumes); the figures are printed (`cargo test --release --test integration bending:: -- --nocapture`).

use splinerod::core::BlockBanded;
use splinerod::energies::{Bending, Clamp};
use splinerod::integrators::modal;
use splinerod::prelude::*;

const L: Real = 1.0;
const MU: Real = 0.1;
const G: Real = 9.81;

/// A dead load `force` at the free end s = L (energy \\(-F\cdot C(L)\\)).
struct TipLoad {
    force: Vector3<Real>,
}

impl Energy for TipLoad {
    fn energy(&self, rod: &Rod) -> Real {
        rod.point(L).map_or(Real::NAN, |p| -self.force.dot(&p))
    }
    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let b = rod.basis_at(L).expect("tip inside the rod");
        for k in 0..b.order {
            gradient[b.first + k] -= self.force * b.value[k];
        }
    }
    fn add_hessian(&self, _: &Rod, _: splinerod::core::HessianKind, _: &mut BlockBanded) {}
}

/// A horizontal cantilever along x, built in at s = 0, with `n` cubic control points.
fn cantilever(n: usize, ei: Real, ea: Real, clamp_stiffness: Real) -> RodSystem {
    let material = Material {
        rest_length: L,
        linear_density: MU,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, L).expect("basis");
    let end = Vector3::new(L, 0.0, 0.0);
    let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
    let pin = Pin::here(&rod, 0.0).expect("pin");
    let clamp = Clamp::here(&rod, 0.0, clamp_stiffness).expect("clamp");
    let bending = Bending::for_rod(ei, &rod).expect("bending");
    RodSystem::new(rod)
        .with_energy(Stretching::new(ea).expect("EA"))
        .with_energy(bending)
        .with_energy(clamp)
        .with_pin(pin)
}

fn solve(system: &mut RodSystem) {
    let stats = StaticSolver::new(StaticParams::default())
        .expect("params")
        .solve(system)
        .expect("static solve");
    assert!(stats.converged);
}

/// A round rod of slenderness L/r = 10⁴ has EA/EI = 4/r² = 4·10⁸/L²: membrane locking
/// would make the cantilever far too stiff. The default (mixed) stretching does not lock:
/// the self-weight and large-deflection answers hold as for a stubby rod.
#[test]
fn slender_cantilever_does_not_lock() {
    let ei = 100.0;
    let ea = 4e8 / (L * L) * ei;
    let k = Clamp::stiffness_for(ei, L);
    let mut sys =
        cantilever(16, ei, ea, k).with_energy(Gravity::new(Vector3::new(0.0, -G, 0.0)).expect("g"));
    solve(&mut sys);
    let got = -sys.rod.point(L).expect("tip").y;
    let want = MU * G * L.powi(4) / (8.0 * ei);
    let error = (got - want).abs() / want;
    println!("L/r = 1e4, EA = {ea:.1e} N: tip {got:.6e} m vs qL⁴/8EI = {want:.6e} m, rel err {error:.2e}");
    assert!(error < 1e-2);
    let (ei, ea, p) = (1.0, 4e8 / (L * L), 3.0);
    let tip = loaded_tip(ei, ea, p);
    let error = (tip - elastica_tip(p / ei)).norm() / L;
    println!(
        "L/r = 1e4 elastica PL²/EI = {}: |Δ|/L = {error:.2e}",
        p * L * L / ei
    );
    assert!(error < 1e-3);
}

#[test]
fn cantilever_small_deflection_matches_euler_bernoulli() {
    let (ei, ea) = (100.0, 1e6);
    let k = Clamp::stiffness_for(ei, L);
    // Self weight: δ = q L⁴ / (8 EI).
    let weight = |clamp: Real| {
        let mut sys = cantilever(16, ei, ea, clamp)
            .with_energy(Gravity::new(Vector3::new(0.0, -G, 0.0)).expect("g"));
        solve(&mut sys);
        -sys.rod.point(L).expect("tip").y
    };
    let want = MU * G * L.powi(4) / (8.0 * ei);
    let (got, stiffer) = (weight(k), weight(100.0 * k));
    let error = (got - want).abs() / want;
    println!(
        "self weight: tip {got:.6e} m vs qL⁴/8EI = {want:.6e} m, rel err {error:.2e}; \
         clamp penalty effect (k vs 100k) {:.2e}",
        (got - stiffer).abs() / want
    );
    assert!(error < 1e-2);
    assert!((got - stiffer).abs() < 1e-4 * want);
    // Tip load: δ = P L³ / (3 EI).
    let p = 0.3;
    let mut sys = cantilever(16, ei, ea, k).with_energy(TipLoad {
        force: Vector3::new(0.0, -p, 0.0),
    });
    solve(&mut sys);
    let got = -sys.rod.point(L).expect("tip").y;
    let want = p * L.powi(3) / (3.0 * ei);
    let error = (got - want).abs() / want;
    println!("tip load: tip {got:.6e} m vs PL³/3EI = {want:.6e} m, rel err {error:.2e}");
    assert!(error < 1e-2);
}

/// The inextensible elastica under a dead tip load: tip position, by shooting on θ'(0).
fn elastica_tip(load: Real) -> Vector3<Real> {
    // y = (θ, θ', x, y); θ'' = load cos θ with load = P/EI.
    let rhs = |y: [Real; 4]| [y[1], load * y[0].cos(), y[0].cos(), y[0].sin()];
    let integrate = |c: Real| {
        let steps = 4000;
        let h = L / steps as Real;
        let mut y = [0.0, c, 0.0, 0.0];
        let add = |y: [Real; 4], k: [Real; 4], f: Real| std::array::from_fn(|i| y[i] + f * k[i]);
        for _ in 0..steps {
            let k1 = rhs(y);
            let k2 = rhs(add(y, k1, h / 2.0));
            let k3 = rhs(add(y, k2, h / 2.0));
            let k4 = rhs(add(y, k3, h));
            y = std::array::from_fn(|i| {
                y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])
            });
        }
        y
    };
    // θ'(L) rises monotonically with c; bisect on θ'(L) = 0 with θ'(0) ∈ [-load L, 0].
    let (mut lo, mut hi) = (-load * L, 0.0);
    for _ in 0..80 {
        let mid = 0.5 * (lo + hi);
        if integrate(mid)[1] < 0.0 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let y = integrate(0.5 * (lo + hi));
    Vector3::new(y[2], y[3], 0.0)
}

/// Tip of the 16-point cantilever under a dead tip load `p`, loaded in four increments
/// (continuation), each solve starting from the last equilibrium.
fn loaded_tip(ei: Real, ea: Real, p: Real) -> Vector3<Real> {
    let k = Clamp::stiffness_for(ei, L);
    let mut sys = cantilever(16, ei, ea, k);
    sys.energies.push(Box::new(TipLoad {
        force: Vector3::zeros(),
    }));
    for step in 1..=4 {
        let force = Vector3::new(0.0, -p * step as Real / 4.0, 0.0);
        if let Some(last) = sys.energies.last_mut() {
            *last = Box::new(TipLoad { force });
        }
        solve(&mut sys);
    }
    sys.rod.point(L).expect("tip")
}

#[test]
fn cantilever_large_deflection_matches_the_elastica() {
    let (ei, ea, p) = (1.0, 1e5, 3.0);
    let tip = loaded_tip(ei, ea, p);
    let want = elastica_tip(p / ei);
    let error = (tip - want).norm() / L;
    println!(
        "elastica PL²/EI = {}: tip ({:.6}, {:.6}) vs shooting ({:.6}, {:.6}), |Δ|/L = {error:.2e}",
        p * L * L / ei,
        tip.x,
        tip.y,
        want.x,
        want.y
    );
    assert!(
        want.y < -0.5 * L,
        "the test must be in the large-deflection regime"
    );
    assert!(error < 1e-3);
}

/// Pinned–pinned rod compressed to `(1 − ε) L`: lowest transverse ω² and the axial force.
fn compressed(eps: Real, ei: Real, ea: Real) -> (Real, Real) {
    let material = Material {
        rest_length: L,
        linear_density: MU,
    };
    let basis = BSplineSpace::clamped_uniform(3, 16, L).expect("basis");
    let gamma = 1.0 - eps;
    let end = Vector3::new(gamma * L, 0.0, 0.0);
    let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
    let [start, finish] = [Pin::here(&rod, 0.0), Pin::here(&rod, L)];
    let bending = Bending::for_rod(ei, &rod).expect("bending");
    let stretching = Stretching::new(ea).expect("EA");
    let force = -stretching.tension(gamma);
    let sys = RodSystem::new(rod)
        .with_energy(stretching)
        .with_energy(bending)
        .with_pin(start.expect("pin"))
        .with_pin(finish.expect("pin"));
    let modes = modal::modes(&sys, 8).expect("modes");
    let transverse = modes
        .iter()
        .find(|m| {
            let axial: Real = m.shape.iter().map(|v| v.x * v.x).sum();
            let all: Real = m.shape.iter().map(|v| v.norm_squared()).sum();
            axial < 0.5 * all
        })
        .expect("a transverse mode");
    (transverse.omega * transverse.omega.abs(), force)
}

#[test]
fn euler_buckling_load_of_a_pinned_rod() {
    // The load is applied by compressing the pinned span: the straight rod at stretch
    // γ = 1 − ε is an equilibrium with axial force P = −T(γ) = (EA/2) γ (1 − γ²). Find ε
    // where the lowest transverse ω² crosses zero (secant), convert to P.
    // Linearised about that state, E_b = EI/2 ∫ |w''|²/γ⁴ ds and the stretching term is
    // −P/(2γ) ∫ |w'|² ds (rest arclength s), so the discrete model buckles at
    // P = π²EI/(γ³L²): 3ε ≈ 3·10⁻⁴ above π²EI/L², the ambiguity of an extensible rod's
    // bending modulus (per rest or deformed length); a larger EA shrinks it.
    let (ei, ea) = (1.0, 1e5);
    let euler = std::f64::consts::PI.powi(2) * ei / (L * L);
    let mut a = 0.5 * euler / ea;
    let mut b = 1.5 * euler / ea;
    let (mut fa, mut fb) = (compressed(a, ei, ea).0, compressed(b, ei, ea).0);
    for _ in 0..20 {
        let c = b - fb * (b - a) / (fb - fa);
        (a, fa) = (b, fb);
        b = c;
        fb = compressed(b, ei, ea).0;
        if (b - a).abs() < 1e-14 {
            break;
        }
    }
    let (w2, critical) = compressed(b, ei, ea);
    let error = (critical - euler).abs() / euler;
    println!(
        "buckling: ε = {b:.6e}, P_cr = {critical:.6} N vs π²EI/L² = {euler:.6} N, rel err {error:.2e} (ω² there {w2:.1e})"
    );
    assert!(error < 5e-3);
}
