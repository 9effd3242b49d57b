//! Rigid obstacles of the contact energy: a plane obstacle equals the floor, gradients
//! and the exact Hessian against finite differences, a definite Hessian, the distance functions, validation.

use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, BlockBanded, HessianKind, Material, Real, Rod};
use splinerod_energies::{Contact, ContactParams, Energy, Obstacle};

const R: Real = 0.01;
const K: Real = 1e4;

fn rod_between(a: Vector3<Real>, b: Vector3<Real>, n: usize) -> Rod {
    let material = Material {
        rest_length: 1.0,
        linear_density: 0.1,
    };
    let basis = BSplineSpace::clamped_uniform(3, n, 1.0).unwrap();
    Rod::straight(material, Box::new(basis), a, b).unwrap()
}

fn with(obstacles: Vec<Obstacle>) -> Contact {
    let c = Contact::new(ContactParams::new(R, K).unwrap()).unwrap();
    c.with_obstacles(obstacles).unwrap()
}

fn gradient(e: &dyn Energy, rod: &Rod) -> Vec<Vector3<Real>> {
    let mut g = vec![Vector3::zeros(); rod.len()];
    e.add_gradient(rod, &mut g);
    g
}

#[test]
fn a_plane_obstacle_presses_like_the_floor() {
    let depth = 0.3 * R;
    let y = -1.0 + R - depth;
    let rod = rod_between(Vector3::new(0.0, y, 0.0), Vector3::new(1.0, y, 0.0), 8);
    let floor = Contact::new(ContactParams::new(R, K).unwrap().with_floor(-1.0).unwrap()).unwrap();
    let plane = with(vec![Obstacle::Plane {
        point: Vector3::new(0.3, -1.0, 7.0),
        normal: Vector3::y(),
    }]);
    let (a, b) = (floor.energy(&rod), plane.energy(&rod));
    assert!(a > 0.0 && (a - b).abs() <= 1e-9 * a, "floor {a}, plane {b}");
    let (ga, gb) = (gradient(&floor, &rod), gradient(&plane, &rod));
    let (fa, fb): (Vector3<Real>, Vector3<Real>) = (ga.iter().sum(), gb.iter().sum());
    assert!((fa - fb).norm() <= 1e-9 * fa.norm(), "{fa:?} {fb:?}");
    let s = plane.summary(&rod).unwrap();
    assert!(s.obstacle_contacts > 0);
    let ratio = s.min_clearance_ratio.unwrap();
    assert!((ratio - (1.0 - 0.3)).abs() < 1e-9, "{ratio}");
}

/// A bent rod over the top of `obstacle`, its lowest points `depth` into the penalty.
fn draped(depth: Real) -> Rod {
    let mut rod = rod_between(
        Vector3::new(-0.5, 0.0, 0.0),
        Vector3::new(0.5, 0.0, 0.0),
        12,
    );
    for q in rod.positions.iter_mut() {
        let x = q.x;
        *q = Vector3::new(x, 0.1 + R - depth - 0.3 * x * x, 0.02 * x);
    }
    rod
}

fn check_gradient(c: &Contact, rod: &Rod) {
    let g = gradient(c, rod);
    let scale = g.iter().map(|v| v.norm()).fold(0.0, Real::max);
    assert!(scale > 0.0, "no contact");
    let h = 1e-7;
    for i in 0..rod.len() {
        for axis in 0..3 {
            let mut plus = rod.clone();
            plus.positions[i][axis] += h;
            let mut minus = rod.clone();
            minus.positions[i][axis] -= h;
            let fd = (c.energy(&plus) - c.energy(&minus)) / (2.0 * h);
            let err = (fd - g[i][axis]).abs();
            assert!(err <= 1e-5 * scale, "q{i}[{axis}]: {fd} vs {}", g[i][axis]);
        }
    }
}

#[test]
fn sphere_and_capsule_gradients_match_finite_differences() {
    let sphere = Obstacle::Sphere {
        centre: Vector3::zeros(),
        radius: 0.1,
    };
    let capsule = Obstacle::Capsule {
        a: Vector3::new(0.0, 0.0, -0.3),
        b: Vector3::new(0.0, 0.0, 0.3),
        radius: 0.1,
    };
    for o in [sphere, capsule] {
        let c = with(vec![o]);
        let rod = draped(0.4 * R);
        check_gradient(&c, &rod);
        let mut h = BlockBanded::zeros(rod.len(), rod.basis().degree());
        c.add_hessian(&rod, HessianKind::Definite, &mut h);
        let dense = h.to_dense();
        let min = dense.clone().symmetric_eigenvalues().min();
        assert!(min >= -1e-9 * dense.amax(), "{o:?}: eigenvalue {min}");
        assert!(c.admissible(&rod));
    }
}

#[test]
fn the_exact_hessian_of_curved_obstacles_matches_differences_of_the_gradient() {
    // With the surface-curvature term: the sphere's and the capsule's (side and cap).
    let obstacles = [
        Obstacle::Sphere {
            centre: Vector3::zeros(),
            radius: 0.1,
        },
        Obstacle::Capsule {
            a: Vector3::new(0.0, 0.0, -0.3),
            b: Vector3::new(0.0, 0.0, 0.3),
            radius: 0.1,
        },
        Obstacle::Capsule {
            a: Vector3::new(0.0, 0.0, 0.0),
            b: Vector3::new(0.0, 0.0, 0.3),
            radius: 0.1,
        },
    ];
    for o in obstacles {
        let c = with(vec![o]);
        let rod = draped(0.4 * R);
        let mut h = BlockBanded::zeros(rod.len(), rod.basis().degree());
        c.add_hessian(&rod, HessianKind::Exact, &mut h);
        let dense = h.to_dense();
        let step = 1e-7;
        let mut worst: Real = 0.0;
        for j in 0..3 * rod.len() {
            let (mut plus, mut minus) = (rod.clone(), rod.clone());
            plus.positions[j / 3][j % 3] += step;
            minus.positions[j / 3][j % 3] -= step;
            let (gp, gm) = (gradient(&c, &plus), gradient(&c, &minus));
            for i in 0..3 * rod.len() {
                let fd = (gp[i / 3][i % 3] - gm[i / 3][i % 3]) / (2.0 * step);
                worst = worst.max((fd - dense[(i, j)]).abs());
            }
        }
        assert!(
            worst <= 1e-5 * dense.amax(),
            "{o:?}: {worst} of {}",
            dense.amax()
        );
    }
}

#[test]
fn distances_to_the_surfaces() {
    let capsule = Obstacle::Capsule {
        a: Vector3::zeros(),
        b: Vector3::new(1.0, 0.0, 0.0),
        radius: 0.2,
    };
    // Beside the axis, beyond an end, on the axis.
    let (d, n) = capsule.distance(&Vector3::new(0.5, 0.5, 0.0));
    assert!((d - 0.3).abs() < 1e-15 && (n - Vector3::y()).norm() < 1e-15);
    let (d, n) = capsule.distance(&Vector3::new(1.6, 0.0, 0.0));
    assert!((d - 0.4).abs() < 1e-15 && (n - Vector3::x()).norm() < 1e-15);
    assert!((capsule.distance(&Vector3::new(0.5, 0.0, 0.0)).0 + 0.2).abs() < 1e-15);
    let sphere = Obstacle::Sphere {
        centre: Vector3::new(1.0, 2.0, 3.0),
        radius: 0.5,
    };
    assert!((sphere.distance(&Vector3::new(1.0, 2.0, 4.0)).0 - 0.5).abs() < 1e-15);
}

#[test]
fn bad_obstacles_are_refused() {
    let bad = [
        Obstacle::Plane {
            point: Vector3::zeros(),
            normal: Vector3::new(0.0, 2.0, 0.0),
        },
        Obstacle::Sphere {
            centre: Vector3::zeros(),
            radius: -1.0,
        },
        Obstacle::Capsule {
            a: Vector3::zeros(),
            b: Vector3::zeros(),
            radius: 0.1,
        },
        Obstacle::Sphere {
            centre: Vector3::new(Real::NAN, 0.0, 0.0),
            radius: 1.0,
        },
    ];
    for o in bad {
        let c = Contact::new(ContactParams::new(R, K).unwrap()).unwrap();
        assert!(c.with_obstacles([o]).is_err(), "{o:?}");
    }
}
