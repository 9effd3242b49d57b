//! Closed rods (#20): rings on a periodic basis, against known answers.

use splinerod::prelude::*;
use std::f64::consts::TAU;

/// A free ring of rest radius `r0` (μ = 0.1 kg/m, EA = 10 N), `m` cubic control points,
/// stretched uniformly by `strain` and released; only stretching acts.
fn free_ring(m: usize, r0: Real, strain: Real, formulation: StretchFormulation) -> RodSystem {
    let material = Material {
        rest_length: TAU * r0,
        linear_density: 0.1,
    };
    let space = PeriodicBSplineSpace::uniform(3, m, material.rest_length).expect("space");
    let (center, normal) = (Vector3::new(0.1, 0.2, 0.3), Vector3::new(0.0, 0.3, 1.0));
    let rod = Rod::ring(
        material,
        Box::new(space),
        center,
        normal,
        r0 * (1.0 + strain),
    )
    .expect("ring")
    .with_quadrature_points(formulation.points_per_span(3))
    .expect("quadrature");
    let mut stretching = Stretching::new(10.0).expect("stretching");
    stretching.formulation = formulation;
    RodSystem::new(rod).with_energy(stretching)
}

/// Mean distance of the curve from the ring's centre of mass.
fn mean_radius(rod: &Rod) -> Real {
    let c = rod.centre_of_mass();
    let l = rod.material().rest_length;
    let samples = 64;
    (0..samples)
        .map(|k| (rod.point(l * k as Real / samples as Real).expect("point") - c).norm())
        .sum::<Real>()
        / samples as Real
}

/// Angular frequency of `y` from its upward crossings of its mid-range.
fn angular_frequency(t: &[Real], y: &[Real]) -> Real {
    let mid = 0.5
        * (y.iter().cloned().fold(Real::INFINITY, Real::min)
            + y.iter().cloned().fold(Real::NEG_INFINITY, Real::max));
    let crossings: Vec<Real> = (1..y.len())
        .filter(|&k| y[k - 1] < mid && y[k] >= mid)
        .map(|k| t[k - 1] + (t[k] - t[k - 1]) * (mid - y[k - 1]) / (y[k] - y[k - 1]))
        .collect();
    assert!(crossings.len() >= 3, "too few oscillations");
    TAU * (crossings.len() - 1) as Real / (crossings[crossings.len() - 1] - crossings[0])
}

#[test]
fn a_free_ring_breathes_at_the_exact_frequency() {
    let (r0, ea, mu) = (0.2, 10.0, 0.1);
    let exact = (ea / mu as Real).sqrt() / r0;
    let period = TAU / exact;
    for formulation in [
        StretchFormulation::Pointwise,
        StretchFormulation::Mixed,
        StretchFormulation::MixedConsistent,
    ] {
        let system = free_ring(32, r0, 1e-3, formulation);
        let momentum = system.rod.linear_momentum();
        let mut sim = Simulation::new(
            system,
            Box::new(ImplicitMidpoint::new(NewtonParams::default()).expect("midpoint")),
        );
        let dt = period / 800.0;
        let (mut t, mut r) = (vec![0.0], vec![mean_radius(&sim.system.rod)]);
        while sim.time < 5.0 * period {
            sim.step(dt).expect("step");
            t.push(sim.time);
            r.push(mean_radius(&sim.system.rod));
        }
        let omega = angular_frequency(&t, &r);
        let error = (omega / exact - 1.0).abs();
        println!(
            "{formulation:?}: ω = {omega:.6} rad/s (exact {exact:.6}), relative error {error:.2e}"
        );
        assert!(error <= 1e-4);
        assert!((sim.system.rod.linear_momentum() - momentum).norm() < 1e-12);
        let m = sim.system.rod.basis().periodic_count().expect("closed");
        for i in m..sim.system.rod.len() {
            assert_eq!(sim.system.rod.positions[i], sim.system.rod.positions[i - m]);
        }
    }
}

/// Breakpoints of the wobbly ring (period 1.3 m).
const BREAKS: [Real; 14] = [
    0.0, 0.07, 0.2, 0.26, 0.41, 0.5, 0.62, 0.7, 0.83, 0.9, 1.02, 1.1, 1.19, 1.25,
];

/// A wobbly, spinning, falling ring on irregular knots, with its parameter origin at
/// breakpoint `origin` of the reference ring: bending, gravity and `formulation`.
fn wobbly_ring(origin: usize, formulation: StretchFormulation) -> RodSystem {
    let l = 1.3;
    let breaks = BREAKS;
    let m = breaks.len();
    let shift = breaks[origin];
    let rotated: Vec<Real> = (0..m)
        .map(|j| breaks[(j + origin) % m] - shift)
        .map(|u| if u < 0.0 { u + l } else { u })
        .collect();
    let space = PeriodicBSplineSpace::new(3, rotated, l).expect("space");
    let material = Material {
        rest_length: l,
        linear_density: 0.1,
    };
    let point = |j: usize| {
        let a = TAU * j as Real / m as Real;
        Vector3::new(
            0.2 * a.cos() * (1.0 + 0.1 * (3.0 * a).sin()),
            0.2 * a.sin(),
            0.03 * (2.0 * a).cos(),
        )
    };
    let spin = |j: usize| {
        let a = TAU * j as Real / m as Real;
        Vector3::new(-a.sin(), a.cos(), 0.5 * (5.0 * a).sin())
    };
    let count = space.count();
    let positions = (0..count).map(|i| point((i + origin) % m)).collect();
    let mut rod = Rod::new(material, Box::new(space), positions)
        .expect("rod")
        .with_quadrature_points(formulation.points_per_span(3))
        .expect("quadrature");
    rod.velocities = (0..count).map(|i| spin((i + origin) % m)).collect();
    let mut stretching = Stretching::new(50.0).expect("stretching");
    stretching.formulation = formulation;
    RodSystem::new(rod)
        .with_energy(stretching)
        .with_energy(Bending::new(1e-4).expect("bending"))
        .with_energy(Gravity::new(Vector3::new(0.0, 0.0, -9.81)).expect("gravity"))
}

#[test]
fn a_closed_rod_has_no_seam() {
    for formulation in [
        StretchFormulation::Pointwise,
        StretchFormulation::Mixed,
        StretchFormulation::MixedConsistent,
    ] {
        let run = |origin: usize| {
            let euler = ImplicitEuler::new(NewtonParams::default()).expect("euler");
            let mut sim = Simulation::new(wobbly_ring(origin, formulation), Box::new(euler));
            for _ in 0..50 {
                sim.step(2e-3).expect("step");
            }
            sim.system.rod
        };
        let reference = run(0);
        let l = reference.material().rest_length;
        for origin in [1, 5, 12] {
            let rotated = run(origin);
            let shift = BREAKS[origin];
            let mut worst: Real = 0.0;
            for k in 0..200 {
                let s = l * k as Real / 200.0;
                let s_rotated = (s - shift).rem_euclid(l);
                let a = reference.point(s).expect("point");
                let b = rotated.point(s_rotated).expect("point");
                worst = worst.max((a - b).norm());
            }
            println!(
                "{formulation:?}, origin at breakpoint {origin}: largest difference {worst:.2e} m"
            );
            assert!(worst < 1e-12, "{formulation:?}: {worst:e}");
        }
    }
}

/// A ring spinning about its axis at the radius where its tension holds it: with the
/// Green–Lagrange law the axial force is \\(N(γ) = EA\\,γ(γ^2 - 1)/2\\), and steady
/// rotation needs \\(N(γ) = μ ω^2 R R_0\\) (`γ = R/R_0`, μ per rest length). Implicit
/// midpoint holds a radius to O((ω dt)²) (measured with 64 control points over 3 turns:
/// 9.5e-4 at 100 steps per turn, 6.0e-5 at 400, 4.0e-6 at 1 600), so the test takes
/// 3 200 steps per turn; 16 control points resolve the ring (its mean radius is exact by
/// construction, `Rod::ring`).
#[test]
fn a_spinning_ring_keeps_its_radius_for_a_hundred_turns() {
    let (r0, ea, mu, gamma): (Real, Real, Real, Real) = (0.2, 10.0, 0.1, 1.01);
    let radius = gamma * r0;
    let force = ea * gamma * (gamma * gamma - 1.0) / 2.0;
    let omega = (force / (mu * radius * r0)).sqrt();
    let turn = TAU / omega;
    let material = Material {
        rest_length: TAU * r0,
        linear_density: mu,
    };
    let space = PeriodicBSplineSpace::uniform(3, 16, material.rest_length).expect("space");
    let (center, axis) = (Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.0, 0.0, 1.0));
    let mut rod = Rod::ring(material, Box::new(space), center, axis, radius).expect("ring");
    rod.velocities = rod
        .positions
        .iter()
        .map(|q| (axis * omega).cross(&(q - center)))
        .collect();
    let system = RodSystem::new(rod).with_energy(Stretching::new(ea).expect("stretching"));
    let midpoint = ImplicitMidpoint::new(NewtonParams::default()).expect("midpoint");
    let mut sim = Simulation::new(system, Box::new(midpoint));
    let dt = turn / 3200.0;
    let curve_radius = |rod: &Rod| {
        let samples = 199;
        let l = rod.material().rest_length;
        let sum: Real = (0..samples)
            .map(|k| {
                (rod.point(l * (k as Real + 0.5) / samples as Real)
                    .expect("point")
                    - center)
                    .norm()
            })
            .sum();
        sum / samples as Real / radius - 1.0
    };
    // The control polygon's mean radius follows the curve's (the ring keeps its shape).
    let polygon = |rod: &Rod| {
        rod.positions
            .iter()
            .map(|q| (q - center).norm())
            .sum::<Real>()
    };
    let (start, polygon_start) = (curve_radius(&sim.system.rod), polygon(&sim.system.rod));
    let (mut worst_curve, mut worst_polygon): (Real, Real) = (start.abs(), 0.0);
    while sim.time < 100.0 * turn {
        sim.step(dt).expect("step");
        worst_polygon = worst_polygon.max((polygon(&sim.system.rod) / polygon_start - 1.0).abs());
        if sim.steps % 400 == 0 {
            worst_curve = worst_curve.max(curve_radius(&sim.system.rod).abs());
        }
    }
    println!(
        "ω = {omega:.4} rad/s, 100 turns in {} steps: mean radius off by {start:.1e} at the start, at most {worst_curve:.2e} (sampled every 1/8 turn); control polygon within {worst_polygon:.2e} of its start",
        sim.steps
    );
    assert!(worst_curve <= 1e-6 && worst_polygon <= 1e-6);
}

/// Cutting a closed rod is exact (knot insertion to full multiplicity): the curve, the
/// velocities, the stretching (pointwise: a polynomial the quadrature integrates
/// exactly), gravity and kinetic energies are unchanged to round-off; bending's
/// rational integrand changes by its quadrature error (measured 1.9e-7 relative). The
/// first cut opens the loop into one piece, the second makes two.
#[test]
fn cutting_a_ring_changes_nothing_but_its_topology() {
    let system = wobbly_ring(0, StretchFormulation::Pointwise);
    let mut rod = system.rod.clone();
    let energies: Vec<Box<dyn Energy>> = vec![
        Box::new(
            Stretching::new(50.0)
                .map(|mut s| {
                    s.formulation = StretchFormulation::Pointwise;
                    s
                })
                .expect("stretching"),
        ),
        Box::new(Bending::new(1e-4).expect("bending")),
        Box::new(Gravity::new(Vector3::new(0.0, 0.0, -9.81)).expect("gravity")),
    ];
    let measure = |rod: &Rod| {
        let mut values: Vec<Real> = energies.iter().map(|e| e.energy(rod)).collect();
        values.push(rod.kinetic_energy());
        values
    };
    let l = rod.material().rest_length;
    let samples: Vec<Real> = (0..=300).map(|k| l * k as Real / 300.0).collect();
    let before = (
        measure(&rod),
        samples
            .iter()
            .map(|&s| (rod.point(s).expect("p"), rod.velocity(s).expect("v")))
            .collect::<Vec<_>>(),
    );
    assert_eq!(rod.pieces(), 1);
    for (cut, pieces) in [(0.03, 1), (0.71, 2), (1.2999, 3)] {
        rod.cut(cut).expect("cut");
        assert_eq!(rod.pieces(), pieces, "after cutting at {cut}");
        for (k, &s) in samples.iter().enumerate() {
            let (p, v) = before.1[k];
            assert!((rod.point(s).expect("p") - p).norm() < 1e-12);
            assert!((rod.velocity(s).expect("v") - v).norm() < 1e-12);
        }
        for (k, (e0, e1)) in before.0.iter().zip(measure(&rod)).enumerate() {
            let tolerance = if k == 1 { 1e-6 } else { 1e-12 };
            assert!(
                (e1 - e0).abs() <= tolerance * e0.abs().max(1e-3),
                "{k}: {e0} -> {e1}"
            );
        }
        let m = rod.distinct_len();
        assert!((m..rod.len()).all(|i| rod.positions[i] == rod.positions[i - m]));
    }
}
