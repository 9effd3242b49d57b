//! Failure handling at the facade: a step that produces non-finite values fails with an
//! error and leaves the simulation exactly as it was; the public types can cross threads
//! (ensembles run rods on rayon's pool).

use splinerod::prelude::*;

/// An energy whose gradient turns NaN once the rod's midpoint sags below `depth`:
/// stands for any user energy that breaks down in some configuration.
struct BreaksBelow {
    depth: Real,
}

impl Energy for BreaksBelow {
    fn energy(&self, _rod: &Rod) -> Real {
        0.0
    }
    fn add_gradient(&self, rod: &Rod, gradient: &mut [Vector3<Real>]) {
        let mid = rod.len() / 2;
        if rod.positions[mid].y < -self.depth {
            gradient[mid].y += Real::NAN;
        }
    }
}

fn hanging_cable(poison_depth: Real) -> Simulation {
    let system = splinerod::problems::pinned_cable(12, 0.8, 100.0)
        .expect("cable")
        .with_energy(BreaksBelow {
            depth: poison_depth,
        });
    let euler = ImplicitEuler::new(NewtonParams::default()).expect("params");
    Simulation::new(system, Box::new(euler))
}

#[test]
fn non_finite_step_fails_and_leaves_the_state_unchanged() {
    let mut sim = hanging_cable(0.01);
    let mut failure = None;
    for _ in 0..200 {
        let (positions, velocities) = (
            sim.system.rod.positions.clone(),
            sim.system.rod.velocities.clone(),
        );
        let (time, steps) = (sim.time, sim.steps);
        match sim.step(1e-3) {
            Ok(_) => continue,
            Err(e) => {
                assert_eq!(sim.system.rod.positions, positions, "positions changed");
                assert_eq!(sim.system.rod.velocities, velocities, "velocities changed");
                assert_eq!((sim.time, sim.steps), (time, steps), "clock advanced");
                failure = Some(e);
                break;
            }
        }
    }
    let error = failure.expect("the midpoint sags past 1 cm within 0.2 s");
    println!("{error}");
    assert!(error.to_string().contains("non-finite"), "{error}");
    // Retrying from the restored state fails the same way, and the rod stays finite.
    assert!(sim.step(1e-3).is_err());
    assert!(sim.system.rod.check_finite().is_ok());
}

#[test]
fn public_types_are_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<Rod>();
    check::<RodSystem>();
    check::<Simulation>();
    check::<Scene>();
    check::<splinerod::RunResult>();
    check::<splinerod::Error>();
    check::<Box<dyn Energy>>();
    check::<Box<dyn Integrator>>();
    check::<Box<dyn BasisSpace>>();
}

/// `solver.max_step` shortens Newton steps (more iterations) but solves the same
/// equations: a step of the plucked string (a convex incremental potential) ends where
/// the unlimited one does.
#[test]
fn a_newton_step_limit_takes_more_iterations_to_the_same_solution() {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/scenes/string_modes.toml"
    ))
    .unwrap()
    .replace("dt = 0.001", "dt = 0.005\nnewton_iterations = 400");
    let free = Scene::from_toml(&text).unwrap();
    let limited = Scene::from_toml(&text.replace("duration", "max_step = 1e-4\nduration")).unwrap();
    assert_eq!(limited.solver.max_step, Some(1e-4));
    let (mut a, mut b) = (free.build().unwrap(), limited.build().unwrap());
    let (ra, rb) = (a.step(0.005).unwrap(), b.step(0.005).unwrap());
    assert!(ra.solver.converged && rb.solver.converged, "{ra:?} {rb:?}");
    assert!(rb.solver.newton_iterations >= 5, "{rb:?}");
    assert!(ra.solver.newton_iterations < rb.solver.newton_iterations);
    let gap = (a.system.rod.positions.iter())
        .zip(&b.system.rod.positions)
        .map(|(p, q)| (p - q).norm())
        .fold(0.0, Real::max);
    assert!(gap < 1e-9, "{gap}");
    let bad = Scene::from_toml(&text.replace("duration", "max_step = -1.0\nduration"));
    assert!(bad.unwrap_err().to_string().contains("solver.max_step"));
}

/// Newton stops only at a converged iterate. The shaken hanging cables' merit is a sum
/// of gravity and inertia terms far larger than itself, so it rounds above the decrease
/// of Newton's last steps: a line search on them halves on noise, and a halved step
/// that then passed the step test used to stop Newton up to the tolerance short of the
/// solution (2e-10 m on member 6 of seed 11). Past the shaken start (three steps), every
/// member's steps solved to 1e-10·L must equal those solved to 1e-12·L to round-off.
/// On the lumped mixed form, whose Newton matrix is the exact Hessian (the consistent
/// form's conjugate gradients stop at a tenth of the tolerance: agreement to 1.5e-12 m).
#[test]
fn newton_stops_at_a_converged_iterate_whatever_the_merits_rounding() {
    let base = include_str!("../scenes/hanging_cable.toml").replacen(
        "stretch_stiffness = 100.0\n",
        "stretch_stiffness = 100.0\nstretch_formulation = \"mixed\"\n",
        1,
    );
    for seed in [2, 4, 11, 15] {
        let text = format!(
            "{base}\n[ensemble]\ncount = 10\nseed = {seed}\nstretch_stiffness = [50.0, 400.0]\n\
             linear_density = [0.05, 0.2]\ndamping = [0.5, 4.0]\nperturbation = 0.01\n"
        );
        let scene = Scene::from_toml(&text).unwrap();
        let tight = NewtonParams {
            tolerance: 1e-12,
            max_iterations: 100,
            ..scene.newton_params()
        };
        for member in 0..10 {
            let build = || scene.ensemble.as_ref().unwrap().member(&scene, member);
            let (mut a, mut b) = (build().unwrap().1, build().unwrap().1);
            for step in 0..12 {
                if step == 3 {
                    b.integrator = Box::new(ImplicitEuler::new(tight).unwrap());
                }
                let (ra, rb) = (a.step(0.005).unwrap(), b.step(0.005).unwrap());
                let gap = (a.system.rod.positions.iter())
                    .zip(&b.system.rod.positions)
                    .map(|(p, q)| (p - q).amax())
                    .fold(0.0, Real::max);
                let at = format!("seed {seed} member {member} step {step}: {gap:e} m");
                assert!(
                    gap <= 1e-12,
                    "{at} ({:?} against {:?})",
                    ra.solver,
                    rb.solver
                );
            }
        }
    }
}
