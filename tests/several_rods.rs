//! Several rods in one system (`[[rods]]`): rods that do not touch move exactly as they
//! would alone; two ropes crossing rest on each other with the forces statics demands;
//! bad tables are named.

use crate::common;

use common::*;
use nalgebra::Vector3;
use splinerod::{run, Real, Scene};

/// Rod `a`: a cable hanging between pins, with bending. Rod `b`: a stiffer, heavier,
/// more damped rope pinned at one end and grabbed at 70 %, with the mixed stretching
/// alone (so a rod alone would use fewer quadrature points).
const ROD_A: &str = r#"
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 300.0
bending_stiffness = 1e-4
damping = 0.5
control_points = 12
start = [0.0, 0.0, 0.0]
end = [0.95, 0.0, 0.0]
"#;

const ROD_B: &str = r#"
rest_length = 0.7
linear_density = 0.3
stretch_stiffness = 2000.0
damping = 3.0
control_points = 9
start = [0.0, 1.0, 0.2]
end = [0.7, 1.0, 0.2]
"#;

const PINS_A: &str = "[[pins]]\nROD\nat = 0.0\n\n[[pins]]\nROD\nat = 1.0\n";
const PINS_B: &str = "[[pins]]\nROD\nat = 0.0\n\n[[grabs]]\nROD\nat = 0.7\nto = [0.5, 0.6, 0.4]\nend_time = 0.3\nstiffness = 50.0\n";
const SOLVER: &str =
    "[solver]\nmethod = \"implicit-euler\"\ndt = 0.002\nduration = 0.5\n\n[output]\nsamples = 9\n";

fn alone(rod: &str, entries: &str) -> String {
    format!("[rod]{rod}\n{}\n{SOLVER}", entries.replace("ROD\n", ""))
}

fn together() -> String {
    format!(
        "[[rods]]\nname = \"b\"{ROD_B}\n[[rods]]\nname = \"a\"{ROD_A}\n{}\n{}\n{SOLVER}",
        PINS_A.replace("ROD", "rod = \"a\""),
        PINS_B.replace("ROD", "rod = \"b\""),
    )
}

fn positions(samples: &[[Real; 3]]) -> Vec<Vector3<Real>> {
    samples.iter().map(|p| Vector3::from(*p)).collect()
}

#[test]
fn rods_that_do_not_touch_move_as_they_would_alone() {
    let joined = run(&accepted(&together())).expect("joined run");
    let a = run(&accepted(&alone(ROD_A, PINS_A))).expect("a alone");
    let b = run(&accepted(&alone(ROD_B, PINS_B))).expect("b alone");
    assert_eq!(joined.rods.len(), 2);
    assert_eq!(joined.rods[0].name, "b");
    for (rod, single) in [(&joined.rods[0], &b), (&joined.rods[1], &a)] {
        let (p, q) = (
            positions(&rod.samples.positions),
            positions(&single.samples.positions),
        );
        let gap = p
            .iter()
            .zip(&q)
            .map(|(x, y)| (x - y).norm())
            .fold(0.0, Real::max);
        // Newton stops each step within its tolerance: the joined solve may take one
        // iteration more or less than a rod alone. (The rods share their time steps: a
        // sub-step one of them needed would be taken by both.)
        assert!(gap < 1e-9, "{}: {gap:e} m from the rod alone", rod.name);
        for (name, e) in &rod.energy {
            let alone = single.energy[name];
            assert!(
                (e - alone).abs() <= 1e-6 * alone.abs().max(1e-6),
                "{name}: {e} vs {alone}"
            );
        }
    }
    // Each rod's knots and pin forces, as alone.
    for (rod, single) in [(&joined.rods[0], &b), (&joined.rods[1], &a)] {
        assert_eq!(rod.knots.len(), single.knots.len());
        for (s, t) in rod.knots.iter().zip(&single.knots) {
            assert!((s - t).abs() < 1e-12, "{}: knot {s} vs {t}", rod.name);
        }
        assert_eq!(rod.pin_forces.len(), single.pin_forces.len());
        for (f, g) in rod.pin_forces.iter().zip(&single.pin_forces) {
            assert!(
                (Vector3::from(*f) - Vector3::from(*g)).norm() < 1e-5,
                "{f:?} {g:?}"
            );
        }
    }
    // One force per [[pins]] entry in file order: a's two pins, then b's.
    assert_eq!(joined.pin_forces.len(), 3);
    for (f, g) in joined.pin_forces[..2].iter().zip(&a.pin_forces) {
        assert!(
            (Vector3::from(*f) - Vector3::from(*g)).norm() < 1e-5,
            "{f:?} {g:?}"
        );
    }
}

/// The acceptance scene: a rope with free ends across a taut rope, at right angles.
#[test]
fn two_ropes_crossing_rest_on_each_other() {
    let text = std::fs::read_to_string("scenes/ropes_crossing.toml").expect("scene");
    let scene = Scene::from_toml(&text).expect("valid");
    let mut sim = scene.build().expect("build");
    let steps = scene.step_count();
    let mut least: Real = Real::INFINITY;
    for _ in 0..steps {
        sim.step(scene.solver.dt.expect("dt")).expect("step");
        let summary = sim.system.energies.iter().find(|e| e.name() == "contact");
        let contact = summary
            .and_then(|e| e.capabilities().summary)
            .expect("contact")
            .summary(&sim.system.rod)
            .expect("summary");
        if let Some(c) = contact.contact {
            least = least.min(c.min_clearance_ratio.unwrap_or(Real::INFINITY));
        }
    }
    assert!(least >= 0.95, "clearance {least} of r₁ + r₂");
    // The thin rope rests on the thick one: centre lines r₁ + r₂ = 16 mm apart.
    let (a, b) = (
        sim.system
            .rod
            .point(scene.coordinate(0, 0.5))
            .expect("lower"),
        sim.system
            .rod
            .point(scene.coordinate(1, 0.5))
            .expect("upper"),
    );
    let gap = (b - a).norm();
    assert!(
        (gap - 0.016).abs() < 0.05 * 0.016,
        "centre lines {gap} m apart"
    );
    let rod = &sim.system.rod;
    let g = 9.81;
    let (lower, upper) = (0.1 * 1.0 * g, 0.05 * 0.6 * g);
    // The contact's force on the upper rope: minus its gradient there.
    let contact = sim
        .system
        .energies
        .iter()
        .find(|e| e.name() == "contact")
        .expect("contact");
    let mut gradient = vec![Vector3::zeros(); rod.len()];
    contact.add_gradient(rod, &mut gradient);
    let on_upper: Vector3<Real> = -gradient[rod.segment_points(1)]
        .iter()
        .sum::<Vector3<Real>>();
    assert!(
        (on_upper.y - upper).abs() < 0.01 * upper,
        "contact {on_upper} vs weight {upper}"
    );
    let held: Real = sim.integrator.pin_forces().iter().map(|f| f.y).sum();
    let both = lower + upper;
    println!(
        "contact on upper {:.6} N (weight {upper:.6}), pins {held:.6} N (weights {both:.6}), \
         clearance {least:.4}",
        on_upper.y
    );
    assert!(
        (held - both).abs() < 0.01 * both,
        "pins hold {held} N of {both} N"
    );
    // The upper rope hangs over the lower one on both sides.
    let middle = rod.point(scene.coordinate(1, 0.5)).expect("middle");
    for end in [0.0, 1.0] {
        let tip = rod.point(scene.coordinate(1, end)).expect("end");
        assert!(tip.y < middle.y - 0.1, "end {end} at {tip} above {middle}");
    }
}

/// `output.probes` on any rod (#49 item 5): a plain fraction is on the first rod, a
/// `{ rod, at }` table on the rod it names; each records that material point, the same
/// as the rod's own samples there and, rods that do not touch, as the rod alone.
#[test]
fn probes_follow_the_rod_they_name() {
    let probes =
        "samples = 9\nprobes = [0.5, { rod = \"a\", at = 0.5 }, { at = 1.0, rod = \"b\" }]\n";
    let joined = run(&accepted(&together().replace("samples = 9\n", probes))).expect("run");
    let a = alone(ROD_A, PINS_A).replace("samples = 9\n", "samples = 9\nprobes = [0.5]\n");
    let a = run(&accepted(&a)).expect("a alone");
    let p = &joined.probes;
    assert_eq!(p.len(), 3);
    assert_eq!(
        (p[0].rod.as_deref(), p[1].rod.as_deref()),
        (None, Some("a"))
    );
    let last = |k: usize| Vector3::from(*p[k].positions.last().expect("positions"));
    // The last record is the final state: the rods' own samples (9 per rod).
    let sample = |rod: usize, i: usize| Vector3::from(joined.rods[rod].samples.positions[i]);
    for (k, rod, i) in [(0, 0, 4), (1, 1, 4), (2, 0, 8)] {
        let gap = (last(k) - sample(rod, i)).norm();
        assert!(
            gap < 1e-12,
            "probe {k}: {gap:e} m from rods[{rod}] sample {i}"
        );
    }
    assert_eq!(p[1].t.len(), a.probes[0].t.len());
    for (x, y) in p[1].positions.iter().zip(&a.probes[0].positions) {
        let gap = (Vector3::from(*x) - Vector3::from(*y)).norm();
        assert!(gap < 1e-9, "{gap:e} m from rod a alone");
    }
    // Bad entries are named.
    let bad = |entry: &str| {
        let probes = format!("samples = 9\nprobes = [0.5, {entry}]\n");
        rejected(&together().replace("samples = 9\n", &probes))
    };
    assert_field_value(
        &bad("{ rod = \"c\", at = 0.5 }"),
        "output.probes[1].rod",
        "\"c\"",
    );
    assert_field_value(
        &bad("{ rod = \"a\", at = 1.5 }"),
        "output.probes[1].at",
        "1.5",
    );
    assert_field_value(
        &bad("{ rod = \"a\", at = nan }"),
        "output.probes[1].at",
        "NaN",
    );
    assert_field(&bad("{ rod = \"a\" }"), "output.probes[1]");
    assert_field(
        &bad("{ rod = \"a\", at = 0.5, side = 1 }"),
        "output.probes[1]",
    );
    assert_field(&bad("\"middle\""), "output.probes[1]");
}

/// #49 item 5: each rod's surface may have its own friction coefficient, and a contact
/// between two rods takes the smaller: the crossing ropes with coefficients 0.9 (lower)
/// and 0.5 (upper, whose free ends also touch each other) of their own move bit for bit
/// (the runs compared under one kernel set, either)
/// as with `[contact] friction = 0.5` for all; with 0.2 on one rope they move otherwise.
#[test]
fn a_contact_between_rods_takes_the_smaller_friction() {
    let base = || {
        let mut scene = Scene::load(format!(
            "{}/scenes/ropes_crossing.toml",
            env!("CARGO_MANIFEST_DIR")
        ))
        .expect("scene");
        scene.solver.duration = Some(0.4);
        scene.adaptivity = None;
        scene
    };
    let run_with = |mu: Real, own: [Option<Real>; 2]| {
        let mut scene = base();
        scene.contact.as_mut().expect("[contact]").friction = mu;
        for (rod, mu) in scene.rods.iter_mut().zip(own) {
            rod.friction = mu;
        }
        run(&scene).expect("run").samples.positions
    };
    let reference = run_with(0.5, [None, None]);
    // The lower rope 0.9, the upper 0.5 (its ends touch each other too): every contact 0.5.
    assert_eq!(run_with(0.0, [Some(0.9), Some(0.5)]), reference);
    assert_eq!(run_with(0.9, [None, Some(0.5)]), reference);
    assert_ne!(run_with(0.5, [Some(0.2), None]), reference);
}

#[test]
fn bad_rods_tables_are_named() {
    let good = together();
    let msg = rejected(&good.replace("rod = \"b\"\nat = 0.0", "rod = \"c\"\nat = 0.0"));
    assert_field_value(&msg, "pins[2].rod", "\"c\"");
    let msg = rejected(&good.replacen("rod = \"a\"\n", "", 1));
    assert_field(&msg, "pins[0].rod");
    let msg = rejected(&good.replace("name = \"a\"", "name = \"b\""));
    assert_field(&msg, "rods[1].name");
    let msg = rejected(&good.replace("name = \"a\"\n", ""));
    assert_field(&msg, "rods[1].name");
    // A rod's own fields and entries are named as in the file.
    let msg = rejected(&good.replace("damping = 0.5", "damping = -0.5"));
    assert_field_value(&msg, "rods[1].damping", "-0.5");
    let msg = rejected(&good.replace("damping = 0.5", "friction = -0.5"));
    assert_field_value(&msg, "rods[1].friction", "-0.5");
    let msg = rejected(&good.replace("at = 0.7", "at = 1.7"));
    assert_field_value(&msg, "grabs[0].at", "1.7");
    let msg = rejected(&good.replace("rod = \"b\"\nat = 0.0", "rod = \"b\"\nat = nan"));
    assert_field(&msg, "pins[2].at");
    let msg = rejected(&format!("[rod]{ROD_A}\n{good}"));
    assert_field(&msg, "rods");
    let msg = rejected(&good.replacen("control_points = 12", "control_points = 12\ndegree = 2", 1));
    assert_field(&msg, "rods[1].degree");
    let msg = rejected(SOLVER);
    assert_field(&msg, "rod");
}
