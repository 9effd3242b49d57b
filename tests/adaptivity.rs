//! Adaptive resolution end to end: refinement invariance over long random sequences,
//! no energy jump when the adapt step inserts during a simulation, and the payoff on a
//! grabbed cable against a fine reference.

use proptest::prelude::*;
use splinerod::adaptivity::{AdaptParams, Adapter, CurvatureCriterion};
use splinerod::prelude::*;
use splinerod::{run, RunResult};

fn rod(n: usize) -> Rod {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, 1.0).expect("basis");
    let end = Vector3::new(0.9, 0.0, 0.0);
    let mut rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), end).expect("rod");
    for (i, (q, v)) in rod
        .positions
        .iter_mut()
        .zip(rod.velocities.iter_mut())
        .enumerate()
    {
        let x = i as Real;
        q.y += 0.05 * (1.7 * x).sin();
        q.z += 0.02 * (0.6 * x).cos();
        *v = Vector3::new(0.3 * (0.4 * x).cos(), -0.1 * x, 0.2);
    }
    rod
}

fn pointwise(ea: Real) -> Stretching {
    let mut s = Stretching::new(ea).expect("stiffness");
    s.formulation = StretchFormulation::Pointwise;
    s
}

fn energies(rod: &Rod) -> [Real; 3] {
    let stretch = pointwise(100.0);
    let gravity = Gravity::new(Vector3::new(0.0, -9.81, 0.0)).expect("gravity");
    [
        rod.kinetic_energy(),
        stretch.energy(rod),
        gravity.energy(rod),
    ]
}

fn assert_energies_match(a: [Real; 3], b: [Real; 3], tol: Real) {
    for (x, y) in a.iter().zip(&b) {
        assert!((x - y).abs() <= tol * x.abs().max(1e-300), "{a:?} vs {b:?}");
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(4))]

    /// 10 000 random insertions and exact removals (of knots inserted before, in any
    /// order) leave the curve, its motion and its energies unchanged.
    #[test]
    fn ten_thousand_knot_operations_change_nothing(seed in any::<u64>()) {
        let mut rod = rod(10);
        let (original, velocities, e0) = (rod.positions.clone(), rod.velocities.clone(), energies(&rod));
        let mut inserted: Vec<Real> = Vec::new();
        let mut state = seed | 1;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as Real / (1u64 << 53) as Real
        };
        for op in 0..10_000 {
            let remove = !inserted.is_empty() && (next() < 0.5 || rod.len() > 60);
            if remove {
                let k = ((next() * inserted.len() as Real) as usize).min(inserted.len() - 1);
                let value = inserted.swap_remove(k);
                let index = rod.basis().knots().iter().position(|&t| t == value).expect("knot");
                rod.remove_knot(index, 1e-9).expect("exact removal");
            } else {
                let s = 0.001 + 0.998 * next();
                if rod.knot_multiplicity(s) == 0 {
                    rod.insert_knot(s).expect("insertion");
                    inserted.push(s);
                }
            }
            if op % 1000 == 999 {
                assert_energies_match(e0, energies(&rod), 1e-10);
            }
        }
        for value in inserted.drain(..) {
            let index = rod.basis().knots().iter().position(|&t| t == value).expect("knot");
            rod.remove_knot(index, 1e-9).expect("exact removal");
        }
        prop_assert_eq!(rod.len(), original.len());
        for (a, b) in original.iter().zip(&rod.positions).chain(velocities.iter().zip(&rod.velocities)) {
            prop_assert!((a - b).amax() <= 1e-10 * (1.0 + a.amax()), "{} -> {}", a, b);
        }
    }
}

#[test]
fn insertions_during_a_simulation_cause_no_energy_jump() {
    let pins = |r: &Rod| {
        [
            Pin::here(r, 0.0).expect("pin"),
            Pin::here(r, 1.0).expect("pin"),
        ]
    };
    let r = rod(8);
    let [left, right] = pins(&r);
    let system = RodSystem::new(r)
        .with_energy(pointwise(100.0))
        .with_energy(Gravity::new(Vector3::new(0.0, -9.81, 0.0)).expect("gravity"))
        .with_pin(left)
        .with_pin(right);
    let euler = ImplicitEuler::new(NewtonParams::default()).expect("params");
    let mut sim = Simulation::new(system, Box::new(euler));
    // Insertion only (no removal threshold): every change must be exact.
    let criterion = CurvatureCriterion::new(0.002, 0.0).expect("criterion");
    let params = AdaptParams {
        max_control_points: 40,
        ..AdaptParams::default()
    };
    let mut adapter = Adapter::new(params).expect("params").with(criterion);
    let mut inserted = 0;
    for _ in 0..200 {
        sim.step(0.002).expect("step");
        let before = (
            sim.system.rod.kinetic_energy(),
            sim.system.potential_energy(),
        );
        let report = sim
            .system
            .change_knots(|rod, heard| adapter.adapt(rod, &[], None, heard))
            .expect("adapt");
        inserted += report.inserted;
        let after = (
            sim.system.rod.kinetic_energy(),
            sim.system.potential_energy(),
        );
        assert!((before.0 - after.0).abs() <= 1e-12 * before.0.abs().max(1e-12));
        assert!((before.1 - after.1).abs() <= 1e-12 * before.1.abs());
    }
    println!(
        "{inserted} insertions, {} control points",
        sim.system.rod.len()
    );
    assert!(inserted > 0, "the falling cable should have been refined");
}

const GRAB: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 2.0
control_points = {N}
{KNOTS}
[[pins]]
at = 0.0
[[pins]]
at = 1.0
[[grabs]]
at = 0.3
to = [0.3, -0.2, 0.0]
end_time = 0.2
stiffness = 1000.0
[solver]
method = "implicit-euler"
dt = 0.001
duration = 0.5
[output]
samples = 101
probes = [0.3]
{ADAPT}
"#;

const ADAPT: &str = "[adaptivity]\ninsert_threshold = 0.02\nremove_threshold = 0.002\n\
    max_control_points = 64\nmin_span = 0.005\ninteraction_multiplicity = 3";

fn grab_run(n: usize, knots: &str, adapt: &str) -> RunResult {
    let text = GRAB
        .replace("{N}", &n.to_string())
        .replace("{KNOTS}", knots)
        .replace("{ADAPT}", adapt);
    run(&Scene::from_toml(&text).expect("grab scene")).expect("run")
}

/// Largest distance between the two runs' material points at the end.
fn deviation(a: &RunResult, b: &RunResult) -> Real {
    let pairs = a.samples.positions.iter().zip(&b.samples.positions);
    pairs
        .map(|(p, q)| (0..3).map(|k| (p[k] - q[k]).powi(2)).sum::<Real>().sqrt())
        .fold(0.0, Real::max)
}

#[test]
fn adaptive_grab_matches_a_fine_reference_with_far_fewer_control_points() {
    // Reference: 255 control points, uniform knots with the grab point tripled, so that the
    // reference itself resolves the corner the grab makes.
    let mut knots = vec![0.0; 4];
    knots.extend((1..250).map(|i| i as Real / 250.0));
    knots.extend([0.3, 0.3, 1.0, 1.0, 1.0, 1.0]);
    knots.sort_by(Real::total_cmp);
    let list: Vec<String> = knots.iter().map(|k| format!("{k:?}")).collect();
    let reference = grab_run(
        knots.len() - 4,
        &format!("knots = [{}]", list.join(", ")),
        "",
    );
    let tolerance = 0.01 * 0.2; // 1 % of the pull
    let adaptive = grab_run(8, "", ADAPT);
    let most = adaptive
        .control_points_history
        .iter()
        .map(|h| h[1] as usize)
        .max();
    let most = most.expect("history");
    let error = deviation(&adaptive, &reference);
    println!(
        "adaptive: {error:.2e} m with at most {most} control points, {:.3} s",
        adaptive.wall_seconds
    );
    assert!(error <= tolerance, "adaptive deviation {error:e}");
    let mut coarsest_uniform = None;
    for n in [16, 32, 64, 128] {
        let uniform = grab_run(n, "", "");
        let e = deviation(&uniform, &reference);
        println!("uniform {n}: {e:.2e} m, {:.3} s", uniform.wall_seconds);
        if e <= tolerance && coarsest_uniform.is_none() {
            coarsest_uniform = Some(n);
        }
    }
    // If no uniform rod up to 128 reaches it, the coarsest that does has more than 128.
    let coarsest = coarsest_uniform.unwrap_or(129);
    assert!(
        3 * most <= coarsest,
        "adaptive {most} vs uniform {coarsest}"
    );
}

/// The mixed stretching energy depends on the basis: its tension space refines with the
/// knots. Both before and after an insertion it lies in
/// \[E_pointwise − G, E_pointwise\], where the pointwise energy is invariant and the gap
/// G ≥ 0 is the strain energy the tension space does not resolve, so
/// |ΔE| ≤ max(G_before, G_after). Checked on 2 000 random insertions into a stretched,
/// wiggly rod, with the gap shrinking as the rod is refined (it vanishes as the rod
/// converges: the ARCHITECTURE.md exception).
#[test]
fn mixed_energy_changes_by_at_most_the_unresolved_strain_energy() {
    let (mixed, exact) = (Stretching::new(100.0).expect("EA"), pointwise(100.0));
    let mut rod = rod(10);
    let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
    let mut gap0 = None;
    let mut worst: Real = 0.0;
    for op in 0..2000 {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        let s = 0.001 + 0.998 * ((state >> 11) as Real / (1u64 << 53) as Real);
        if rod.knot_multiplicity(s) != 0 {
            continue;
        }
        let (before, reference) = (mixed.energy(&rod), exact.energy(&rod));
        let gap_before = reference - before;
        rod.insert_knot(s).expect("insertion");
        let after = mixed.energy(&rod);
        let gap_after = exact.energy(&rod) - after;
        let round_off = 1e-12 * reference;
        assert!(
            gap_before >= -round_off && gap_after >= -round_off,
            "gap below zero"
        );
        let bound = gap_before.max(gap_after) + round_off;
        assert!(
            (after - before).abs() <= bound,
            "op {op}: |ΔE| {} > {bound}",
            (after - before).abs()
        );
        worst = worst.max((after - before).abs() / reference);
        gap0.get_or_insert(gap_before / reference);
        if rod.len() > 200 {
            break;
        }
    }
    let gap_end = (exact.energy(&rod) - mixed.energy(&rod)) / exact.energy(&rod);
    let gap0 = gap0.expect("insertions");
    println!(
        "unresolved share of the strain energy: {gap0:.2e} at 10 points, {gap_end:.2e} at {}; \
         largest relative change per insertion {worst:.2e}",
        rod.len()
    );
    // Measured: 4.6e-1 → 1.7e-2 (random knots, 10 → 201 points).
    assert!(gap_end < 0.1 * gap0, "the gap must shrink under refinement");
}
