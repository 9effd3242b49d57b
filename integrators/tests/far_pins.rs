//! Pins eliminated at a control point that a far block couples to a distant one.
//!
//! The system is the suite's quadratic string plus a zero-rest-length spring
//! \\(\tfrac{k}{2}|q_a - q_b|^2\\) between control points `a` and `b` beyond the band,
//! whose Hessian is assembled with `add_coupling` in two halves (so its far block is
//! duplicated). The whole potential is quadratic, \\(E = \tfrac12 q^T K q - f^T q\\), so
//! the static equilibrium and one implicit Euler step are each one dense KKT solve,
//! computed here with nalgebra's LU as the independent reference:
//!
//! \\[ \begin{pmatrix} A & -G^T \\ G & 0 \end{pmatrix}
//!     \begin{pmatrix} y \\ \mu \end{pmatrix} = \begin{pmatrix} r \\ c \end{pmatrix}, \\]
//!
//! with `A = K`, `y = q`, `r = f`, `c = p` for statics and `A = M + h²K`, `y = v`,
//! `r = M v₀ − h (K q₀ − f)`, `c = (p − G q₀)/h`, `μ = h λ` for implicit Euler.
//! A counting global allocator (per thread) checks that steps with far blocks allocate
//! nothing once the workspaces are sized.

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use splinerod_core::{BlockBanded, HessianKind, Pin, Real, Rod};
use splinerod_integrators::conformance::TestString;
use splinerod_integrators::{
    ImplicitEuler, Integrator, LinearSolverKind, NewtonParams, StaticParams, StaticSolver, System,
};

/// Control points.
const N: usize = 10;

#[path = "common/counting.rs"]
mod counting;
use counting::allocations_during;

/// The test string plus a zero-rest-length spring between control points `ends`.
struct Tethered {
    string: TestString,
    stiffness: Real,
    ends: (usize, usize),
}

impl Tethered {
    /// A string (k = 3, gravity −y) pinned at `pins` (curve parameters, m), with a spring
    /// of stiffness 20 N/m between control points `ends`; the rod starts slightly bent.
    fn new(pins: &[Real], ends: (usize, usize)) -> Self {
        let mut string = TestString::new(N, 3.0, Vector3::new(0.0, -9.81, 0.0)).unwrap();
        string.pins = pins
            .iter()
            .map(|&s| Pin::here(&string.rod, s).unwrap())
            .collect();
        for (i, q) in string.rod.positions.iter_mut().enumerate() {
            q.z += 0.01 * (i as Real).sin();
        }
        Self {
            string,
            stiffness: 20.0,
            ends,
        }
    }

    fn stretch(&self) -> Vector3<Real> {
        let q = &self.string.rod.positions;
        q[self.ends.0] - q[self.ends.1]
    }
}

impl System for Tethered {
    fn rod(&self) -> &Rod {
        &self.string.rod
    }
    fn rod_mut(&mut self) -> &mut Rod {
        &mut self.string.rod
    }
    fn pins(&self) -> &[Pin] {
        &self.string.pins
    }
    fn potential_energy(&self) -> Real {
        self.string.potential_energy() + 0.5 * self.stiffness * self.stretch().norm_squared()
    }
    fn add_potential_gradient(&self, g: &mut [Vector3<Real>]) {
        self.string.add_potential_gradient(g);
        let force = self.stretch() * self.stiffness;
        g[self.ends.0] += force;
        g[self.ends.1] -= force;
    }
    fn add_potential_hessian(&self, kind: HessianKind, h: &mut BlockBanded) {
        self.string.add_potential_hessian(kind, h);
        let (a, b) = self.ends;
        let half = Matrix3::from_diagonal_element(0.5 * self.stiffness);
        for _ in 0..2 {
            h.add_coupling(a, a, &half);
            h.add_coupling(b, b, &half);
        }
        // The coupling in both orientations: two far blocks at one position.
        h.add_coupling(a, b, &-half);
        h.add_coupling(b, a, &-half);
    }
}

/// The pins' constraint matrix `G` (3 rows per pin).
fn constraint_matrix(sys: &Tethered) -> DMatrix<Real> {
    let rod = sys.rod();
    let mut g = DMatrix::zeros(3 * sys.pins().len(), 3 * rod.len());
    for (p, pin) in sys.pins().iter().enumerate() {
        let row = pin.row(rod).unwrap();
        for k in 0..row.order {
            for a in 0..3 {
                g[(3 * p + a, 3 * (row.first + k) + a)] = row.value[k];
            }
        }
    }
    g
}

fn flatten(v: &[Vector3<Real>]) -> DVector<Real> {
    DVector::from_iterator(3 * v.len(), v.iter().flat_map(|x| x.iter().copied()))
}

/// `K` and `f` of the quadratic potential, `K` from the Hessian and `f = K q − ∇E(q)`.
fn quadratic(sys: &Tethered) -> (DMatrix<Real>, DVector<Real>) {
    let rod = sys.rod();
    let mut k = BlockBanded::zeros(rod.len(), rod.basis().degree());
    sys.add_potential_hessian(HessianKind::Exact, &mut k);
    assert!(k.has_far_blocks(), "the spring must couple beyond the band");
    let k = k.to_dense();
    let mut grad = vec![Vector3::zeros(); rod.len()];
    sys.add_potential_gradient(&mut grad);
    let f = &k * flatten(&rod.positions) - flatten(&grad);
    (k, f)
}

/// Solves the KKT system of the module docs; returns `(y, μ)`.
fn kkt(
    a: &DMatrix<Real>,
    g: &DMatrix<Real>,
    r: &DVector<Real>,
    c: &DVector<Real>,
) -> (DVector<Real>, DVector<Real>) {
    let (n, m) = (a.nrows(), g.nrows());
    let mut big = DMatrix::zeros(n + m, n + m);
    big.view_mut((0, 0), (n, n)).copy_from(a);
    big.view_mut((0, n), (n, m)).copy_from(&-g.transpose());
    big.view_mut((n, 0), (m, n)).copy_from(g);
    let mut rhs = DVector::zeros(n + m);
    rhs.rows_mut(0, n).copy_from(r);
    rhs.rows_mut(n, m).copy_from(c);
    let sol = big.lu().solve(&rhs).expect("KKT system is regular");
    (sol.rows(0, n).into_owned(), sol.rows(n, m).into_owned())
}

/// Pin targets `c`, stacked.
fn targets(sys: &Tethered) -> DVector<Real> {
    DVector::from_iterator(
        3 * sys.pins().len(),
        sys.pins().iter().flat_map(|p| p.position.iter().copied()),
    )
}

/// Largest entry of `a − b` relative to the largest of `b`.
fn relative(a: &DVector<Real>, b: &DVector<Real>) -> Real {
    (a - b).amax() / b.amax()
}

/// Pin configurations: an end pin coupled to a free point (plus an interior pin by Schur
/// complement), both ends pinned and coupled to each other, and a far coupling between
/// free points next to an end pin.
fn cases() -> Vec<(Vec<Real>, (usize, usize))> {
    vec![
        (vec![0.0, 0.7], (0, N - 1)),
        (vec![0.0, 2.0], (N - 1, 0)),
        (vec![2.0, 1.1], (N - 1, 2)),
        (vec![0.0], (1, N - 2)),
    ]
}

#[test]
fn static_equilibrium_with_far_couplings_at_eliminated_pins_matches_dense_kkt() {
    for (pins, ends) in cases() {
        for kind in [LinearSolverKind::Banded, LinearSolverKind::Sparse] {
            let mut sys = Tethered::new(&pins, ends);
            let (k, f) = quadratic(&sys);
            let (q, mu) = kkt(&k, &constraint_matrix(&sys), &f, &targets(&sys));
            let params = StaticParams {
                linear_solver: kind,
                ..StaticParams::default()
            };
            let mut solver = StaticSolver::new(params).unwrap();
            let stats = solver.solve(&mut sys).unwrap();
            let label = format!("pins {pins:?}, spring {ends:?}, {kind:?}");
            assert!(stats.converged, "{label}");
            // Tolerances: the KKT matrices have condition numbers ~1e4, so 1e-9 leaves
            // a margin of ~1e3 over round-off in both solves.
            let dq = relative(&flatten(&sys.rod().positions), &q);
            assert!(dq < 1e-9, "{label}: positions differ by {dq:e}");
            let dmu = relative(&flatten(solver.pin_forces()), &mu);
            assert!(dmu < 1e-9, "{label}: pin forces differ by {dmu:e}");
            for pin in sys.pins() {
                assert!(pin.violation(sys.rod()).unwrap().norm() < 1e-12, "{label}");
            }
        }
    }
}

/// One implicit Euler step of `sys` (first pin moved during the step) with at most
/// `iterations` Newton iterations, checked against the dense KKT solution; returns the
/// Newton iterations used.
fn check_euler_step(
    mut sys: Tethered,
    kind: LinearSolverKind,
    iterations: usize,
    label: &str,
) -> usize {
    let h = 0.01;
    for (i, v) in sys.rod_mut().velocities.iter_mut().enumerate() {
        *v = Vector3::new(0.1 * i as Real, 0.2, -0.05 * (i as Real).cos());
    }
    sys.string.pins[0].position += Vector3::new(0.0, 0.003, -0.002);
    let rod = sys.rod();
    let mut m = BlockBanded::zeros(rod.len(), rod.basis().degree());
    m.add_scaled_scalar(1.0, rod.mass_matrix());
    let m = m.to_dense();
    let (k, f) = quadratic(&sys);
    let (q0, v0) = (flatten(&rod.positions), flatten(&rod.velocities));
    let g = constraint_matrix(&sys);
    let a = &m + &k * (h * h);
    let r = &m * &v0 - (&k * &q0 - &f) * h;
    let c = (targets(&sys) - &g * &q0) / h;
    let (v, mu) = kkt(&a, &g, &r, &c);

    let params = NewtonParams {
        linear_solver: kind,
        max_iterations: iterations,
        ..NewtonParams::default()
    };
    let mut euler = ImplicitEuler::new(params).unwrap();
    let stats = euler.step(&mut sys, h).unwrap();
    assert_eq!(stats.symbolic_analyses, 1, "{label}: one far pattern");
    let dv = relative(&flatten(&sys.rod().velocities), &v);
    assert!(dv < 1e-10, "{label}: velocities differ by {dv:e}");
    // Pin forces are μ / h.
    let dmu = relative(&(flatten(&euler.pin_forces()) * h), &mu);
    assert!(dmu < 1e-9, "{label}: pin impulses differ by {dmu:e}");
    // Same far pattern on the next step: no new analysis.
    let next = euler.step(&mut sys, h).unwrap();
    assert_eq!(next.symbolic_analyses, 0, "{label}");
    stats.newton_iterations
}

#[test]
fn implicit_euler_steps_with_far_couplings_at_eliminated_pins_match_dense_kkt() {
    // The potential is quadratic, so the first Newton step is already exact: the
    // linearised step (one iteration) must match the dense solution, multipliers
    // included, and full Newton must stop after a second, negligible step. (Later
    // iterations would hide an inexact first step, since Newton corrects itself.)
    for (pins, ends) in cases() {
        for kind in [LinearSolverKind::Banded, LinearSolverKind::Sparse] {
            let label = format!("pins {pins:?}, spring {ends:?}, {kind:?}");
            check_euler_step(Tethered::new(&pins, ends), kind, 1, &label);
            let iterations = check_euler_step(Tethered::new(&pins, ends), kind, 10, &label);
            assert_eq!(iterations, 2, "{label}");
        }
    }
}

#[test]
fn moving_the_far_coupling_triggers_one_new_analysis() {
    let mut sys = Tethered::new(&[0.0, 2.0], (0, N - 1));
    let mut euler = ImplicitEuler::new(NewtonParams::default()).unwrap();
    assert_eq!(euler.step(&mut sys, 0.01).unwrap().symbolic_analyses, 1);
    assert_eq!(euler.step(&mut sys, 0.01).unwrap().symbolic_analyses, 0);
    sys.ends = (1, N - 2);
    assert_eq!(euler.step(&mut sys, 0.01).unwrap().symbolic_analyses, 1);
    assert_eq!(euler.step(&mut sys, 0.01).unwrap().symbolic_analyses, 0);
    // A spring within the band: no far blocks, back to the banded path (no analysis).
    sys.ends = (2, 4);
    assert_eq!(euler.step(&mut sys, 0.01).unwrap().symbolic_analyses, 0);
}

#[test]
fn the_spring_gradient_matches_its_energy() {
    // The reference above trusts the test system's gradient and Hessian; check them
    // against central differences of the energy (step 1e-6: error ~1e-12 · stiffness
    // for this quadratic energy, round-off ~1e-10 · energy scale).
    let mut sys = Tethered::new(&[], (0, N - 1));
    let mut grad = vec![Vector3::zeros(); N];
    sys.add_potential_gradient(&mut grad);
    let (k, _) = quadratic(&sys);
    let e = 1e-6;
    for i in 0..N {
        for a in 0..3 {
            sys.rod_mut().positions[i][a] += e;
            let plus = sys.potential_energy();
            let mut gp = vec![Vector3::zeros(); N];
            sys.add_potential_gradient(&mut gp);
            sys.rod_mut().positions[i][a] -= 2.0 * e;
            let minus = sys.potential_energy();
            sys.rod_mut().positions[i][a] += e;
            let fd = (plus - minus) / (2.0 * e);
            assert!((fd - grad[i][a]).abs() < 1e-6, "gradient ({i}, {a})");
            let column = (flatten(&gp) - flatten(&grad)) / e;
            let exact = k.column(3 * i + a);
            assert!((column - exact).amax() < 1e-6, "Hessian column ({i}, {a})");
        }
    }
}

#[test]
fn steps_with_far_couplings_do_not_allocate_after_warm_up() {
    for kind in [LinearSolverKind::Banded, LinearSolverKind::Sparse] {
        let mut sys = Tethered::new(&[0.0, 0.7], (0, N - 1));
        let params = NewtonParams {
            linear_solver: kind,
            ..NewtonParams::default()
        };
        let mut euler = ImplicitEuler::new(params).unwrap();
        let warm_up = allocations_during(|| {
            for _ in 0..5 {
                euler.step(&mut sys, 0.01).unwrap();
            }
        });
        assert!(warm_up > 0, "the counter counts");
        let count = allocations_during(|| {
            for _ in 0..20 {
                euler.step(&mut sys, 0.01).unwrap();
            }
        });
        assert_eq!(count, 0, "{kind:?}: {count} allocations in 20 steps");
    }
}
