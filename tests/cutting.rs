//! Cutting (paper §5.1): after a cut the pieces are mechanically independent — no
//! Hessian or mass coupling across the cut, and pulling one piece leaves the other's
//! trajectory unchanged.

use splinerod::core::{BlockBanded, HessianKind};
use splinerod::prelude::*;
use splinerod::Grab;

/// The paper's 12-control-point rod hanging from both ends, after 0.1 s of falling,
/// cut at mid-length.
fn cut_rod(params: NewtonParams, formulation: StretchFormulation) -> Simulation {
    let system =
        splinerod::problems::pinned_cable_with(12, 0.8, 100.0, formulation).expect("cable");
    let mut sim = Simulation::new(
        system,
        Box::new(ImplicitEuler::new(params).expect("params")),
    );
    for _ in 0..20 {
        sim.step(0.005).expect("step");
    }
    sim.cut(0.5).expect("cut");
    sim
}

/// Index of the first control point of the right piece: with the cut knots at indices
/// `c ..= c + d`, basis function `c` is the first whose support starts at the cut.
fn right_piece_start(rod: &Rod) -> usize {
    let knots = rod.basis().knots();
    knots.iter().position(|&t| t == 0.5).expect("cut knot")
}

/// Right-piece control points after each of 60 steps, and the left piece at the end.
type Trajectory = (Vec<Vec<Vector3<Real>>>, Vec<Vector3<Real>>);

fn run_after_cut(
    params: NewtonParams,
    formulation: StretchFormulation,
    pull_left: bool,
) -> Trajectory {
    let mut sim = cut_rod(params, formulation);
    if pull_left {
        let t0 = sim.time;
        let grab =
            Grab::new(0.2, Vector3::new(0.1, 0.1, 0.3), (t0, t0 + 0.1), 500.0).expect("grab");
        sim.system.grabs.push(grab);
    }
    let first = right_piece_start(&sim.system.rod);
    let right = (0..60)
        .map(|_| {
            sim.step(0.005).expect("step");
            sim.system.rod.positions[first..].to_vec()
        })
        .collect();
    (right, sim.system.rod.positions[..first].to_vec())
}

#[test]
fn no_coupling_across_the_cut() {
    let sim = cut_rod(NewtonParams::default(), StretchFormulation::default());
    let rod = &sim.system.rod;
    assert_eq!(rod.pieces(), 2);
    let first = right_piece_start(rod);
    let mut h = BlockBanded::zeros(rod.len(), rod.basis().degree());
    for e in &sim.system.energies {
        e.add_hessian(rod, HessianKind::Exact, &mut h);
    }
    for i in 0..first {
        for j in first..rod.len() {
            assert_eq!(h.block(i, j), nalgebra::Matrix3::zeros(), "K[{i},{j}]");
            assert_eq!(rod.mass_matrix().get(i, j), 0.0, "M[{i},{j}]");
        }
    }
}

/// Largest difference between two right-piece trajectories, m.
fn largest_gap(a: &Trajectory, b: &Trajectory) -> Real {
    a.0.iter()
        .zip(&b.0)
        .flat_map(|(a, b)| a.iter().zip(b).map(|(p, q)| (p - q).amax()))
        .fold(0.0, Real::max)
}

#[test]
fn pulling_one_piece_leaves_the_other_unchanged() {
    // A fixed number of Newton iterations and no line search: the solver's control flow
    // no longer depends on the other piece, so the right piece is computed the same way,
    // up to round-off: the factorisation is chosen for the whole matrix (Cholesky, or
    // the indefinite block LDLT while the pulled piece is compressed), and its
    // arithmetic differs in the last bits.
    let fixed = NewtonParams {
        max_iterations: 3,
        tolerance: 1e-300,
        line_search: false,
        accept_unconverged: true,
        ..NewtonParams::default()
    };
    //
    // The consistent form (the default) corrects each Newton step by conjugate
    // gradients, whose scalars are inner products over the whole rod: a piece's step is
    // exact only once they have converged, so it is independent of the other piece to
    // the iteration's relative tolerance (1e-9 of the step) rather than to round-off.
    for (formulation, bound) in [
        (StretchFormulation::Mixed, 1e-13),
        (StretchFormulation::MixedConsistent, 1e-10),
    ] {
        let alone = run_after_cut(fixed, formulation, false);
        let pulled = run_after_cut(fixed, formulation, true);
        let worst = largest_gap(&alone, &pulled);
        println!("{formulation:?}, fixed Newton iterations: right piece differs by {worst:.2e} m");
        assert!(
            worst < bound,
            "{formulation:?}: right piece changed by {worst:e} m"
        );
        let moved = alone.1.iter().zip(&pulled.1).map(|(a, b)| (a - b).norm());
        assert!(
            moved.fold(0.0, Real::max) > 0.05,
            "the grab should move the left piece"
        );
    }
    // With the default convergence test, the iteration count is global: the right piece
    // then agrees to the Newton tolerance.
    let (alone, pulled) = (
        run_after_cut(
            NewtonParams::default(),
            StretchFormulation::default(),
            false,
        ),
        run_after_cut(NewtonParams::default(), StretchFormulation::default(), true),
    );
    let worst = largest_gap(&alone, &pulled);
    println!("default Newton settings: right piece differs by {worst:.2e} m");
    assert!(worst < 1e-9);
}
