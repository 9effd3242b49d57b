//! Random sequences of knot insertions, removals and cuts, made between the stages of
//! every run mode (static, the three integrators, an ensemble; with and without an
//! initial rest shape, contact and bending), must reach every energy: after each
//! change and each stage, every energy whose data follow the basis equals a rebuild of
//! it on the current basis ([`Lifecycle::for_finer_rod`] on the rod itself).

use nalgebra::Vector3;
use proptest::prelude::*;
use splinerod::prelude::*;
use splinerod::{Ensemble, Scene};

#[derive(Debug, Clone)]
enum Change {
    Insert(f64),
    Remove(usize),
    Cut(f64),
}

fn change() -> impl Strategy<Value = Change> {
    prop_oneof![
        (0.02..0.98f64).prop_map(Change::Insert),
        (0usize..64).prop_map(Change::Remove),
        (0.1..0.9f64).prop_map(Change::Cut),
    ]
}

const METHODS: [&str; 4] = ["static", "implicit-euler", "implicit-midpoint", "bdf2"];

/// A cable pinned at both ends, run by one of the [`METHODS`] (modes 0-3) or as an
/// ensemble of two members (4: implicit Euler, 5: static), optionally with the initial shape as rest shape, bending and contact.
fn scene(mode: usize, rest: bool, bending: bool, contact: bool) -> Scene {
    // Ensembles (modes 4 and 5): of implicit-Euler members, and of static solves.
    let method = [METHODS[..].to_vec(), vec!["implicit-euler", "static"]].concat()[mode];
    let solver = if method == "static" {
        "method = \"static\"".to_string()
    } else {
        format!("method = \"{method}\"\ndt = 0.01\nduration = 1.0")
    };
    let mut text = format!(
        "[rod]\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 100.0\n\
         damping = 2.0\ncontrol_points = 10\nstart = [0.0, 0.0, 0.0]\nend = [0.8, 0.0, 0.0]\n\
         radius = 0.01\n{}{}\n[[pins]]\nat = 0.0\n\n[[pins]]\nat = 1.0\n\n[solver]\n{solver}\n",
        if rest {
            "rest_shape = \"initial\"\n"
        } else {
            ""
        },
        if bending {
            "bending_stiffness = 1e-4\n"
        } else {
            ""
        },
    );
    if contact {
        text.push_str("\n[contact]\nstiffness = 1e4\nfloor = -0.5\n");
    }
    if mode >= 4 {
        text.push_str("\n[ensemble]\ncount = 2\nperturbation = 0.001\n");
    }
    Scene::from_toml(&text).expect("scene")
}

/// Every energy equals its rebuild on the rod's current basis.
fn caches_match(sim: &Simulation) -> Result<(), TestCaseError> {
    let system = &sim.system;
    prop_assert!(system.check_knots_heard().is_ok());
    let rod = &system.rod;
    for e in &system.energies {
        let lifecycle = e.capabilities().lifecycle;
        let Some(rebuilt) = lifecycle.and_then(|l| l.for_finer_rod(rod)) else {
            continue;
        };
        let (a, b) = (e.energy(rod), rebuilt.energy(rod));
        prop_assert!(
            (a - b).abs() <= 1e-9 * a.abs().max(1e-6),
            "{}: energy {a} against rebuilt {b}",
            e.name()
        );
        let mut ga = vec![Vector3::zeros(); rod.len()];
        let mut gb = ga.clone();
        e.add_gradient(rod, &mut ga);
        rebuilt.add_gradient(rod, &mut gb);
        let scale = ga.iter().map(|g| g.norm()).fold(1e-6, f64::max);
        let worst = ga
            .iter()
            .zip(&gb)
            .map(|(x, y)| (x - y).norm())
            .fold(0.0, f64::max);
        prop_assert!(
            worst <= 1e-9 * scale,
            "{}: gradient off by {worst:e}",
            e.name()
        );
    }
    Ok(())
}

/// Applies `change` through the simulation (errors, such as removing a cut's knot,
/// leave the rod as it was); `cuts` counts the cuts made.
fn apply(sim: &mut Simulation, change: &Change, cuts: &mut usize, max_cuts: usize) {
    let before = sim.system.rod.basis().knots().to_vec();
    let ok = match *change {
        Change::Insert(u) => sim.system.insert_knot(u).is_ok(),
        Change::Remove(i) => {
            let index = i % before.len();
            sim.system.remove_knot(index, 1e-3).is_ok()
        }
        Change::Cut(s) if *cuts < max_cuts && sim.system.rod.knot_multiplicity(s) == 0 => {
            sim.cut(s).is_ok()
        }
        Change::Cut(_) => false,
    };
    *cuts += usize::from(ok && matches!(change, Change::Cut(_)));
    if !ok {
        assert_eq!(
            sim.system.rod.basis().knots(),
            &before[..],
            "failed change kept"
        );
    }
}

fn recoverable(e: &Error) -> bool {
    matches!(e, Error::Integrator(e) if e.is_recoverable())
}

fn stage(sims: &mut Ensemble, statics: bool) -> Result<(), Error> {
    if statics {
        sims.settle()
    } else {
        sims.step(0.01)
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn knot_changes_reach_every_energy_in_every_mode(
        mode in 0usize..6,
        rest in any::<bool>(),
        bending in any::<bool>(),
        contact in any::<bool>(),
        changes in prop::collection::vec(change(), 1..5),
    ) {
        let scene = scene(mode, rest, bending, contact);
        let statics = mode == 0 || mode == 5;
        let sims = match &scene.ensemble {
            Some(spec) => (0..spec.count).map(|i| spec.member(&scene, i).map(|m| m.1)).collect(),
            None => scene.build().map(|s| vec![s]),
        };
        let mut ensemble = Ensemble::new(sims.expect("members"));
        // A static solve needs every piece held: one cut at most.
        let max_cuts = if statics { 1 } else { 3 };
        let mut cuts = vec![0; ensemble.len()];
        for change in &changes {
            for (sim, cuts) in ensemble.members.iter_mut().zip(&mut cuts) {
                apply(sim, change, cuts, max_cuts);
                caches_match(sim)?;
            }
            let before: Vec<_> = ensemble.members.iter().map(|m| m.system.rod.positions.clone()).collect();
            match stage(&mut ensemble, statics) {
                Ok(()) => {}
                // Time steps may fail to converge even at the smallest sub-step on some
                // random bases with bending (BDF2 next to a 0.02 L span; a solver matter,
                // seen without this test and filed separately; the midpoint rule's failures
                // on a cut's sliver span are gone, `midpoint_step_after_cut_then_insertion`):
                // the failed member must then be left as it was.
                Err(Error::Member { index, source }) if !statics && recoverable(&source) => {
                    let failed = &ensemble.members[index];
                    prop_assert_eq!(&failed.system.rod.positions, &before[index]);
                    for m in &ensemble.members {
                        caches_match(m)?;
                    }
                    return Ok(());
                }
                Err(e) => panic!("stage after {change:?}: {e}"),
            }
            for sim in &ensemble.members {
                caches_match(sim)?;
            }
        }
    }
}

/// The proptest case `cc 529a8e8a…` (implicit midpoint, bending, no contact): a cut at
/// 0.429 then a knot inserted at 0.02; the step after the insertion must succeed. The
/// cut lies 4.3e-4 m past the knot 3/7, which left a sliver end span whose stiff mode
/// the midpoint rule could not step even at 1e-8 s (the second step after the cut failed
/// with or without the insertion); the cut now merges the sliver (removes 3/7).
#[test]
fn midpoint_step_after_cut_then_insertion() {
    for rest in [false, true] {
        let scene = scene(2, rest, true, false);
        let mut sim = scene.build().expect("build");
        let mut cuts = 0;
        for change in [Change::Cut(0.4290048675473304), Change::Insert(0.02)] {
            apply(&mut sim, &change, &mut cuts, 3);
            let knots = sim.system.rod.basis().knots();
            assert!(!knots.contains(&(3.0 / 7.0)), "sliver kept: {knots:?}");
            caches_match(&sim).expect("caches");
            sim.step(0.01)
                .unwrap_or_else(|e| panic!("rest {rest}: step after {change:?}: {e}"));
            caches_match(&sim).expect("caches");
        }
        assert_eq!(sim.system.rod.cuts(), vec![0.4290048675473304]);
    }
}
