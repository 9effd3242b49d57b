//! The derivative by the rest length (`Parameters`, `"rest_length"`): for fixed control
//! points, against central differences of the gradients of rods whose domain is
//! `[0, L ± h]` (every material coordinate at its fraction), each energy built for its
//! rod as a scene builds it — every stretching form, bending, twist, gravity, a penalty
//! clamp, a point force and spring, contact with itself (a crossing) and with a sphere.

use nalgebra::Vector3;
use splinerod_core::{BSplineSpace, Material, Real, Rod};
use splinerod_energies::contact::Obstacle;
use splinerod_energies::{
    Bending, Clamp, Contact, ContactParams, Energy, Frame, Gravity, PointForce, PointSpring,
    StretchFormulation, Stretching, Twisting,
};

/// A rod of rest length `l` with the control points `q` (clamped cubic knots on
/// `[0, l]`), optionally cut at the middle.
fn rod(l: Real, q: &[Vector3<Real>], cut: bool) -> Rod {
    let material = Material {
        rest_length: l,
        linear_density: 0.1,
    };
    // A cut repeats the knot at it to multiplicity d + 1: four more points.
    let n = if cut { q.len() - 4 } else { q.len() };
    let basis = BSplineSpace::clamped_uniform(3, n, l).expect("basis");
    let mut rod = Rod::straight(
        material,
        Box::new(basis),
        Vector3::zeros(),
        Vector3::x() * l,
    )
    .expect("rod");
    if cut {
        rod.cut(0.5 * l).expect("cut");
    }
    assert_eq!(rod.len(), q.len());
    rod.positions.copy_from_slice(q);
    rod
}

/// A wavy curve of `n` points about 0.9 long.
fn wavy(n: usize) -> Vec<Vector3<Real>> {
    (0..n)
        .map(|i| {
            let x = i as Real / (n - 1) as Real;
            Vector3::new(0.9 * x, 0.05 * (6.0 * x).sin(), 0.03 * (4.0 * x).cos())
        })
        .collect()
}

/// An energy built for a rod.
type Make<'a> = &'a dyn Fn(&Rod) -> Box<dyn Energy>;

/// The largest error of `make`'s rest-length derivative at `q` (rest length 1) against
/// central differences of its gradient at `1 ± h`, relative to the largest entry.
fn error(make: Make<'_>, q: &[Vector3<Real>], cut: bool) -> Real {
    let here = rod(1.0, q, cut);
    let energy = make(&here);
    let mut exact = vec![Vector3::zeros(); q.len()];
    let parameters = energy.capabilities().parameters.expect("parameters");
    assert!(parameters.parameter_names().contains(&"rest_length"));
    let given = parameters
        .add_gradient_derivative(&here, "rest_length", &mut exact)
        .expect("derivative");
    assert!(given, "{} gives the rest length", energy.name());
    let gradient = |l: Real| {
        let r = rod(l, q, cut);
        let mut g = vec![Vector3::zeros(); q.len()];
        make(&r).add_gradient(&r, &mut g);
        g
    };
    let central = |h: Real| -> Vec<Vector3<Real>> {
        let (a, b) = (gradient(1.0 + h), gradient(1.0 - h));
        a.iter().zip(&b).map(|(a, b)| (a - b) / (2.0 * h)).collect()
    };
    let (coarse, fine) = (central(1e-4), central(5e-5));
    let largest = exact.iter().fold(0.0, |m: Real, v| m.max(v.amax()));
    // Only the point force and spring have none (their points stay at their fractions).
    let pointwise = energy.bandwidth(&here) == 0
        || energy
            .capabilities()
            .parameters
            .is_some_and(|p| p.parameter_names() == ["rest_length"])
            && largest == 0.0;
    assert!(
        largest > 0.0 || pointwise,
        "{}: no derivative",
        energy.name()
    );
    // Against the derivative, or where it vanishes the gradient's scale per unit length.
    let g = gradient(1.0).iter().fold(0.0, |m: Real, v| m.max(v.amax()));
    let scale = largest.max(g);
    let worst = exact
        .iter()
        .zip(coarse.iter().zip(&fine))
        .map(|(d, (c, f))| (d - (f * 4.0 - c) / 3.0).amax())
        .fold(0.0, Real::max);
    let error = worst / scale;
    println!(
        "{}: |∂∇E/∂L| up to {largest:.3e}, relative error {error:.2e}",
        energy.name()
    );
    error
}

#[test]
fn each_energy_s_rest_length_derivative_matches_differences() {
    let q = wavy(12);
    let forms = [
        StretchFormulation::Mixed,
        StretchFormulation::Pointwise,
        StretchFormulation::MixedConsistent,
    ];
    for form in forms {
        for guard in [false, true] {
            let make = move |_: &Rod| -> Box<dyn Energy> {
                let mut s = Stretching::new(50.0).expect("stretching");
                s.formulation = form;
                s.guard = guard;
                Box::new(s)
            };
            assert!(error(&make, &q, false) < 1e-7, "{form:?}, guard {guard}");
        }
    }
    let makers: Vec<(&str, Box<Make<'_>>)> = vec![
        (
            "bending",
            Box::new(&|r: &Rod| -> Box<dyn Energy> {
                Box::new(Bending::for_rod(0.3, r).expect("bending"))
            }),
        ),
        (
            "gravity",
            Box::new(&|_: &Rod| -> Box<dyn Energy> {
                Box::new(Gravity::new(Vector3::new(0.5, -9.81, 0.2)).expect("gravity"))
            }),
        ),
        (
            "clamp",
            Box::new(&|r: &Rod| -> Box<dyn Energy> {
                let at = 0.3 * r.material().rest_length;
                Box::new(Clamp::new(at, Vector3::new(1.0, 0.2, 0.0), 40.0).expect("clamp"))
            }),
        ),
        (
            "point force",
            Box::new(&|r: &Rod| -> Box<dyn Energy> {
                let at = 0.7 * r.material().rest_length;
                Box::new(PointForce::new(at, Vector3::new(0.0, 1.0, 2.0)).expect("force"))
            }),
        ),
        (
            "point spring",
            Box::new(&|r: &Rod| -> Box<dyn Energy> {
                let at = 0.4 * r.material().rest_length;
                Box::new(PointSpring::new(at, Vector3::new(0.3, 0.2, 0.1), 30.0).expect("spring"))
            }),
        ),
        (
            "sphere",
            Box::new(&|_: &Rod| -> Box<dyn Energy> {
                let params = ContactParams::new(0.01, 1e4).expect("params");
                let sphere = Obstacle::Sphere {
                    centre: Vector3::new(0.45, -0.15, 0.0),
                    radius: 0.16,
                };
                let contact = Contact::new(params).expect("contact");
                Box::new(contact.with_obstacles([sphere]).expect("sphere"))
            }),
        ),
    ];
    for (name, make) in &makers {
        let e = error(make.as_ref(), &q, false);
        assert!(e < 1e-7, "{name}: relative error {e:e}");
    }
}

#[test]
fn twist_and_self_contact_rest_length_derivatives_match_differences() {
    // Twist: built on the straight rod (its rest holonomy), evaluated on the wavy one.
    let q = wavy(12);
    let straight: Vec<Vector3<Real>> = (0..12)
        .map(|i| Vector3::new(0.9 * i as Real / 11.0, 0.0, 0.0))
        .collect();
    let make = |r: &Rod| -> Box<dyn Energy> {
        let start = rod(r.material().rest_length, &straight, false);
        let frame = Frame::along(Vector3::x()).expect("frame");
        let twisting =
            Twisting::between_axes(0.2, &start, frame, Vector3::new(0.0, 0.3, 1.0)).expect("twist");
        Box::new(twisting)
    };
    assert!(error(&make, &q, false) < 1e-7, "twist");
    // Self-contact: a rod cut in two, its second piece crossing the first closer than
    // the reach.
    let n = 16;
    let half = n / 2;
    let crossing: Vec<Vector3<Real>> = (0..n)
        .map(|k| match k < half {
            true => Vector3::new(0.9 * k as Real / (half - 1) as Real, 0.0, 0.0),
            false => {
                let t = (k - half) as Real / (n - 1 - half) as Real;
                Vector3::new(0.45, 0.0195, 0.3 - 0.6 * t)
            }
        })
        .collect();
    let make = |_: &Rod| -> Box<dyn Energy> {
        Box::new(Contact::new(ContactParams::new(0.01, 1e4).expect("params")).expect("contact"))
    };
    assert!(error(&make, &crossing, true) < 1e-7, "self-contact");
}
