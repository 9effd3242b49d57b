//! Ensembles: bit-identical results whatever the thread count, members identical to the
//! same rods run one by one, and clear errors for bad `[ensemble]` values.

use splinerod::{run, Ensemble, Scene, Simulation};

const SCENE: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 2.0
control_points = 12
end = [0.8, 0.0, 0.0]
[[pins]]
at = 0.0
[[pins]]
at = 1.0
[ensemble]
count = 24
seed = 3
stretch_stiffness = [50.0, 200.0]
damping = [0.5, 3.0]
perturbation = 0.02
[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.2
"#;

fn members(scene: &Scene) -> Vec<Simulation> {
    let spec = scene.ensemble.as_ref().expect("ensemble");
    (0..spec.count)
        .map(|i| spec.member(scene, i).expect("member").1)
        .collect()
}

fn positions(sims: &[Simulation]) -> Vec<Vec<[f64; 3]>> {
    sims.iter()
        .map(|s| {
            s.system
                .rod
                .positions
                .iter()
                .map(|p| [p.x, p.y, p.z])
                .collect()
        })
        .collect()
}

fn run_on(threads: usize, scene: &Scene) -> Vec<Vec<[f64; 3]>> {
    run_with(threads, scene, true)
}

fn run_with(threads: usize, scene: &Scene, batched: bool) -> Vec<Vec<[f64; 3]>> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .expect("pool");
    pool.install(|| {
        let mut ensemble = Ensemble::new(members(scene));
        ensemble.batched = batched;
        for _ in 0..20 {
            ensemble.step(0.01).expect("step");
        }
        positions(&ensemble.members)
    })
}

#[test]
fn results_are_bit_identical_with_one_or_several_threads() {
    let scene = Scene::from_toml(SCENE).expect("scene");
    let (one, four) = (run_on(1, &scene), run_on(4, &scene));
    assert_eq!(one, four);
    // The members really differ (the variations were applied).
    assert_ne!(one[0], one[1]);
}

#[test]
fn members_match_the_same_rods_run_one_by_one() {
    let scene = Scene::from_toml(SCENE).expect("scene");
    let together = run_with(2, &scene, false);
    let mut alone = members(&scene);
    for sim in &mut alone {
        for _ in 0..20 {
            sim.step(0.01).expect("step");
        }
    }
    assert_eq!(together, positions(&alone));
    // Batched, the same up to round-off.
    let batched = run_on(2, &scene);
    let worst = batched
        .iter()
        .flatten()
        .flatten()
        .zip(together.iter().flatten().flatten())
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    println!("batched against alone: {worst:e} m");
    assert!(worst < 1e-12, "{worst:e}");
    let result = run(&scene).expect("ensemble run");
    assert_eq!(result.ensemble.len(), 24);
    for (summary, sim) in result.ensemble.iter().zip(&alone) {
        assert_eq!(summary.control_points, sim.system.rod.len());
        // The run batches its members: the same up to round-off.
        let (a, b) = (summary.energy["kinetic"], sim.system.rod.kinetic_energy());
        assert!((a - b).abs() <= 1e-12 * b.abs(), "{a} against {b}");
    }
}

#[test]
fn bad_ensemble_values_name_the_field() {
    let cases = [
        ("count = 24", "count = 0", "ensemble.count"),
        (
            "stretch_stiffness = [50.0, 200.0]",
            "stretch_stiffness = [300.0, 200.0]",
            "ensemble.stretch_stiffness",
        ),
        (
            "stretch_stiffness = [50.0, 200.0]",
            "stretch_stiffness = [nan, 200.0]",
            "ensemble.stretch_stiffness[0]",
        ),
        (
            "damping = [0.5, 3.0]",
            "damping = [-1.0, 3.0]",
            "ensemble.damping[0]",
        ),
        (
            "perturbation = 0.02",
            "perturbation = inf",
            "ensemble.perturbation",
        ),
        ("seed = 3", "seed = 3\ncolour = 1", "colour"),
    ];
    for (from, to, field) in cases {
        let text = SCENE.replace(from, to);
        let e = Scene::from_toml(&text).expect_err(to).to_string();
        assert!(e.contains(field), "{to}: {e}");
    }
}

#[test]
fn a_static_ensemble_solves_every_member_alone() {
    let statics = SCENE.replace("method = \"implicit-euler\"", "method = \"static\"");
    let scene = Scene::from_toml(&statics).expect("static ensemble");
    let result = run(&scene).expect("static ensemble runs");
    assert_eq!(result.ensemble.len(), 24);
    assert_eq!(result.steps, 0);
    // Each member is its own rod's equilibrium: stiffer members sag less.
    let spec = scene.ensemble.as_ref().expect("ensemble");
    for i in [0, 7, 23] {
        let (member_scene, _) = spec.member(&scene, i).expect("member");
        let mut alone = member_scene.clone();
        alone.ensemble = None;
        let single = run(&alone).expect("member alone");
        let m = &result.ensemble[i];
        assert!(m.energy["kinetic"] == 0.0);
        assert!(
            // The member starts perturbed, the rod alone straight: the same equilibrium.
            (m.sag - sag_of(&single)).abs() < 1e-9,
            "member {i}: {} against {}",
            m.sag,
            sag_of(&single)
        );
    }
}

/// Chord height minus material midpoint height of a run's samples (odd count).
fn sag_of(r: &splinerod::RunResult) -> f64 {
    let p = &r.samples.positions;
    let mid = p[p.len() / 2][1];
    0.5 * (p[0][1] + p[p.len() - 1][1]) - mid
}
