//! One path for knot changes, energies' lifecycle hooks, static solves through the
//! same stages as time steps.

use crate::common;

use common::sample_gap;
use nalgebra::Vector3;
use splinerod::adaptivity::{AdaptParams, Adapter, InteractionCriterion};
use splinerod::energies::{Capabilities, Interaction, Lifecycle};
use splinerod::prelude::*;
use splinerod::{run, Scene};
use splinerod_core::CoreError;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// A cable hanging from both ends, cut at 0.4 at t = 0, rest shape its initial one.
const CUT_CABLE: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = 4.0
control_points = 12
start = [0.0, 0.0, 0.0]
end = [0.9, 0.0, 0.0]
rest_shape = "initial"

[[pins]]
at = 0.0

[[pins]]
at = 1.0

[[cuts]]
at = 0.4
time = 0.0

[solver]
method = "static"

[output]
samples = 21
"#;

fn with_method(text: &str, method: &str) -> String {
    text.replace(
        "method = \"static\"",
        &format!("method = \"{method}\"\ndt = 0.02\nduration = 30.0"),
    )
}

#[test]
fn static_cut_with_initial_rest_shape_matches_the_dynamic_equilibrium() {
    let statics = run(&Scene::from_toml(CUT_CABLE).unwrap()).unwrap();
    assert_eq!(statics.pieces, 2);
    let dynamic =
        run(&Scene::from_toml(&with_method(CUT_CABLE, "implicit-euler")).unwrap()).unwrap();
    assert_eq!(dynamic.pieces, 2);
    let gap = sample_gap(&statics, &dynamic);
    // The damped motion settles to well within this after 30 s (damping 4/s).
    assert!(
        gap < 1e-6,
        "static and dynamic equilibria differ by {gap:e} m"
    );
    // The pieces hang: the free ends fell below the pins.
    assert!(statics.samples.positions[8][1] < -0.3);
}

#[test]
fn static_cut_matches_with_every_integrator_and_formulation() {
    for rest in ["rest_shape = \"initial\"", ""] {
        let text = CUT_CABLE.replace("rest_shape = \"initial\"", rest);
        let statics = run(&Scene::from_toml(&text).unwrap()).unwrap();
        for method in ["bdf2", "implicit-midpoint"] {
            let text = with_method(&text, method);
            let text = text.replace("damping = 4.0", "damping = 6.0");
            let dynamic = run(&Scene::from_toml(&text).unwrap()).unwrap();
            let gap = sample_gap(&statics, &dynamic);
            // The midpoint rule does not damp the stiffest modes (its amplification
            // factor tends to -1): a little axial ringing is left after 30 s.
            let allowed = if method == "bdf2" { 1e-6 } else { 2e-4 };
            assert!(gap < allowed, "{method}, '{rest}': {gap:e} m");
        }
    }
}

#[test]
fn knot_changes_behind_the_energies_are_refused_and_leave_the_state() {
    let scene = Scene::from_toml(&with_method(CUT_CABLE, "implicit-euler")).unwrap();
    let mut sim = scene.build().unwrap();
    sim.step(0.01).unwrap();
    sim.system.rod.insert_knot(0.3).unwrap();
    let before = sim.system.rod.positions.clone();
    let err = sim.step(0.01).unwrap_err();
    assert!(matches!(err, Error::KnotsChangedUnheard), "{err}");
    assert!(err.to_string().contains("change_knots"), "{err}");
    assert_eq!(sim.system.rod.positions, before);
    assert_eq!(sim.steps, 1);
    assert!(sim.cut(0.5).is_err());
    assert!(sim.estimate_now().is_err());
    // The same change through the system is heard and the run goes on.
    let mut sim = scene.build().unwrap();
    sim.system.insert_knot(0.3).unwrap();
    sim.system.cut(0.7).unwrap();
    sim.step(0.01).unwrap();
    assert_eq!(sim.system.rod.pieces(), 2);
}

#[test]
fn settle_needs_an_equilibrium_solver_and_step_works_quasi_statically() {
    let scene = Scene::from_toml(&with_method(CUT_CABLE, "bdf2")).unwrap();
    let err = scene.build().unwrap().settle().unwrap_err();
    assert!(matches!(err, Error::NotAnEquilibriumSolver(_)), "{err}");
    // A static scene stepped in time: each step is the equilibrium at its end.
    let scene = Scene::from_toml(CUT_CABLE).unwrap();
    let mut sim = scene.build().unwrap();
    sim.cut(0.4).unwrap();
    let first = sim.step(1.0).unwrap();
    assert!(first.solver.converged && first.solver.newton_iterations > 0);
    let second = sim.step(1.0).unwrap();
    let (n1, n2) = (
        first.solver.newton_iterations,
        second.solver.newton_iterations,
    );
    assert!(
        n2 < n1,
        "from equilibrium: {n2} iterations, from the start {n1}"
    );
    assert_eq!(sim.steps, 2);
    assert_eq!(sim.system.rod.kinetic_energy(), 0.0);
}

/// A per-step energy: a spring tying every control point to where the step started
/// (a viscous drag of stiffness `k`), counting its hooks and naming an interaction
/// point.
struct Tether {
    k: f64,
    start: Vec<Vector3<f64>>,
    steps: Arc<AtomicUsize>,
    at: f64,
}

impl Energy for Tether {
    fn name(&self) -> &str {
        "tether"
    }
    fn energy(&self, rod: &Rod) -> f64 {
        let d = rod.positions.iter().zip(&self.start);
        0.5 * self.k * d.map(|(q, s)| (q - s).norm_squared()).sum::<f64>()
    }
    fn add_gradient(&self, rod: &Rod, g: &mut [Vector3<f64>]) {
        for ((g, q), s) in g.iter_mut().zip(&rod.positions).zip(&self.start) {
            *g += (q - s) * self.k;
        }
    }
    fn bandwidth(&self, _rod: &Rod) -> usize {
        0
    }
    fn capabilities(&self) -> Capabilities<'_> {
        Capabilities {
            lifecycle: Some(self),
            interaction: Some(self),
            ..Capabilities::default()
        }
    }
    fn lifecycle_mut(&mut self) -> Option<&mut dyn Lifecycle> {
        Some(self)
    }
}

impl Lifecycle for Tether {
    fn begin_step(&mut self, rod: &Rod, dt: f64) -> Result<(), CoreError> {
        assert!(dt > 0.0);
        self.start.clone_from(&rod.positions);
        self.steps.fetch_add(1, Ordering::Relaxed);
        Ok(())
    }
}

impl Interaction for Tether {
    fn interaction_points(&self, _rod: &Rod, out: &mut Vec<f64>) -> Result<(), CoreError> {
        out.push(self.at);
        Ok(())
    }
}

#[test]
fn an_energy_with_per_step_state_runs_through_the_hooks() {
    let scene = Scene::from_toml(&with_method(CUT_CABLE, "implicit-euler")).unwrap();
    let drop_height = |tether: Option<f64>| {
        let mut sim = scene.build().unwrap();
        let steps = Arc::new(AtomicUsize::new(0));
        if let Some(k) = tether {
            sim.system.energies.push(Box::new(Tether {
                k,
                start: sim.system.rod.positions.clone(),
                steps: steps.clone(),
                at: 0.61,
            }));
            let adapter = Adapter::new(AdaptParams {
                max_control_points: 40,
                ..AdaptParams::default()
            })
            .unwrap()
            .with(InteractionCriterion::new(0.05).unwrap());
            sim = sim.with_adapter(adapter);
        }
        let mut substeps = 0;
        for _ in 0..10 {
            substeps += sim.step(0.02).unwrap().substeps.substeps;
        }
        let sag = -sim.system.rod.point(0.5).unwrap().y;
        (sag, steps.load(Ordering::Relaxed), substeps, sim)
    };
    let (free, _, _, _) = drop_height(None);
    let (tethered, hooks, substeps, sim) = drop_height(Some(50.0));
    assert_eq!(hooks, substeps, "begin_step once per sub-step");
    assert!(
        tethered < 0.8 * free,
        "drag slows the fall: {tethered} vs {free}"
    );
    // The interaction point at 0.61 (0.055 from the nearest initial knot) was refined around.
    let knots = sim.system.rod.basis().knots();
    let near = knots.iter().filter(|&&u| (u - 0.61).abs() < 0.03).count();
    assert!(near >= 1, "no knot near the interaction point: {knots:?}");
}

#[test]
fn ensemble_with_contact_reports_contact_per_member() {
    let text = std::fs::read_to_string("scenes/cut_contact.toml").unwrap();
    let text = format!("{text}\n[ensemble]\ncount = 3\nseed = 7\nperturbation = 0.002\n");
    let result = run(&Scene::from_toml(&text).unwrap()).unwrap();
    assert_eq!(result.ensemble.len(), 3);
    for m in &result.ensemble {
        let c = m.contact.expect("member contact statistics");
        assert!(c.max_pairs > 0, "member {}: {c:?}", m.index);
        assert!(c.min_clearance_ratio.unwrap() > 0.5);
    }
    assert!(result.contact.is_some());
}

#[test]
fn stage_timings_reach_the_json_and_the_csv() {
    let scene = Scene::from_toml(&with_method(CUT_CABLE, "implicit-euler")).unwrap();
    let mut scene = scene;
    scene.solver.duration = Some(0.1);
    let dir = std::env::temp_dir().join(format!("splinerod-stages-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let csv = dir.join("stats.csv");
    let mut stats = splinerod::output::stats::StatsWriter::new(&csv).unwrap();
    let result = splinerod::run_observed(&scene, &mut [&mut stats]).unwrap();
    let s = result.stage_seconds;
    assert!(
        s.integrate > 0.0 && s.record > 0.0 && s.drivers >= 0.0,
        "{s:?}"
    );
    let json = serde_json::to_value(&result).unwrap();
    assert!(json["stage_seconds"]["integrate"].as_f64().unwrap() > 0.0);
    let text = std::fs::read_to_string(&csv).unwrap();
    let header = text.lines().next().unwrap();
    for name in splinerod::StageTimes::NAMES {
        assert!(header.contains(&format!("{name}_seconds")), "{header}");
    }
    assert_eq!(text.lines().count(), 1 + 5);
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_static_solve_adapts_to_its_tolerance() {
    use splinerod::elastic_catenary::ElasticCatenary;
    use splinerod::locking::{distance, WEIGHT};
    for (ea, tolerance) in [(1e2, 1e-5), (1e4, 1e-4)] {
        let text = format!(
            "[rod]\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = {ea}\n\
             control_points = 6\nend = [0.8, 0.0, 0.0]\n[[pins]]\nat = 0.0\n[[pins]]\nat = 1.0\n\
             [solver]\nmethod = \"static\"\n[adaptivity]\ntolerance = {tolerance}\n"
        );
        let mut sim = Scene::from_toml(&text).unwrap().build().unwrap();
        let report = sim.settle().unwrap();
        assert!(report.adapt.inserted > 0 && report.solver.converged);
        let exact = ElasticCatenary::new(1.0, 0.8, WEIGHT, ea).unwrap();
        let error = distance(&sim.system, &exact).unwrap();
        let estimate = sim.error_estimate().unwrap().max();
        let n = sim.system.rod.len();
        assert!(
            error < 2.0 * tolerance,
            "EA {ea}: error {error:e} at {n} points"
        );
        assert!(n <= 40, "EA {ea}: {n} control points");
        assert!(
            estimate > error / 3.0 && estimate < 3.0 * error,
            "EA {ea}: estimate {estimate:e}, error {error:e}"
        );
        assert_eq!(sim.steps, 0);
    }
}

#[test]
fn a_single_run_reports_its_own_errors() {
    // A step far too long for Newton with one iteration and no sub-stepping room.
    let text = with_method(CUT_CABLE, "implicit-midpoint")
        .replace("dt = 0.02", "dt = 2.0")
        .replace(
            "[output]",
            "newton_iterations = 1\nmin_dt = 2.0\n\n[output]",
        )
        .replace(
            "[solver]\nmethod",
            "[solver]\naccept_unconverged = false\nmethod",
        );
    let err = run(&Scene::from_toml(&text).unwrap()).unwrap_err();
    // The midpoint rule gains energy at the shortest sub-step allowed (it used to go
    // below min_dt and fail there in Newton).
    assert!(matches!(err, Error::MinDtReached { .. }), "{err}");
    assert_eq!(err.field_name(), Some("solver.min_dt"));
    assert!(!err.to_string().contains("ensemble"), "{err}");
}
