//! Sensitivities of static equilibria (#48) against central finite differences of static
//! solves (two step sizes, extrapolated): the catenary (EA, density, gravity, a point load), the cantilever
//! (EI, EA, density) and a twisted clamped rod (GJ), pins' positions (held, driven,
//! clamped), the rest length of each and of a rope on obstacles; bad parameter paths
//! named.

use splinerod::sensitivity::{set_parameter, static_sensitivities};
use splinerod::{Real, Scene};

/// A bundled scene with a tight static tolerance (the finite differences need the
/// equilibria to ~1e-13 m).
fn tight(name: &str) -> Scene {
    let mut scene =
        Scene::load(format!("{}/scenes/{name}.toml", env!("CARGO_MANIFEST_DIR"))).expect("scene");
    scene.solver.tolerance = Some(1e-13);
    scene
}

/// The equilibrium's samples of `scene`, then its pin forces.
fn samples(scene: &Scene) -> Vec<[Real; 3]> {
    let result = splinerod::run(scene).expect("static solve");
    let mut out = result.samples.positions;
    out.extend(result.pin_forces);
    out
}

/// Sets a parameter of a scene to a value.
type Setter<'a> = &'a dyn Fn(&mut Scene, Real);

/// Sets `rod.rest_length` (the domain scales, every material coordinate at its fraction).
fn rest_length(scene: &mut Scene, v: Real) {
    set_parameter(scene, "rod.rest_length", v).expect("rest length");
}

/// Checks the sensitivities of `scene` to each `(path, set)` (`set` changes the
/// parameter by a relative `h` on a copy) against central differences; returns the
/// largest relative error.
fn check(scene: &Scene, cases: &[(&str, Setter<'_>)]) -> Real {
    check_with_step(scene, cases, 1e-3)
}

/// [`check`] with the differences' relative step `step` (1e-3 in [`check`]).
fn check_with_step(scene: &Scene, cases: &[(&str, Setter<'_>)], step: Real) -> Real {
    let paths: Vec<&str> = cases.iter().map(|c| c.0).collect();
    let exact = static_sensitivities(scene, &paths).expect("sensitivities");
    let base = samples(scene);
    for (p, q) in exact.at.iter().zip(&base[..exact.at.len()]) {
        let gap = (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0, Real::max);
        assert!(
            gap < 1e-10,
            "the sensitivities' equilibrium is the run's: {gap:e}"
        );
    }
    let mut worst: Real = 0.0;
    for (k, (path, set)) in cases.iter().enumerate() {
        let value = exact.parameters[k].1;
        // Central differences at h and h/2 (relative 1e-3), extrapolated (Richardson):
        // the truncation is O(h⁴) ~ 1e-12 and the round-off of the equilibria (~1e-16 m)
        // stays near 1e-7 of the difference even for the stiff cantilever's EA, whose
        // derivative is a 1e-6 m stretch per unit of relative EA.
        let central = |h: Real| {
            let (mut up, mut down) = (scene.clone(), scene.clone());
            set(&mut up, value + h);
            set(&mut down, value - h);
            let (a, b) = (samples(&up), samples(&down));
            let d: Vec<[Real; 3]> = a
                .iter()
                .zip(&b)
                .map(|(a, b)| std::array::from_fn(|c| (a[c] - b[c]) / (2.0 * h)))
                .collect();
            d
        };
        let h = step * value.abs().max(1e-3);
        let (coarse, fine) = (central(h), central(h / 2.0));
        // Samples, then pin forces: each judged against its own largest derivative —
        // or, where the pin forces' vanishes (a cantilever's reaction is its weight
        // whatever EI or EA), against 1e-3 of the forces per unit of the parameter
        // (|F|/|p|: the derivative of a force proportional to the parameter).
        let samples = exact.positions[k].len();
        let forces = base[samples..].iter().flatten();
        let per_unit = forces.fold(0.0, |m: Real, x| m.max(x.abs())) / value.abs().max(1e-3);
        let derivatives = [&exact.positions[k][..], &exact.pin_forces[k][..]];
        let mut error: Real = 0.0;
        let mut scale = 0.0;
        for (part, exact) in derivatives.into_iter().enumerate() {
            let range = if part == 0 {
                0..samples
            } else {
                samples..coarse.len()
            };
            let largest = exact
                .iter()
                .flatten()
                .fold(0.0, |m: Real, x| m.max(x.abs()));
            scale = if part == 0 { largest } else { scale };
            let largest = if part == 0 {
                largest
            } else {
                largest.max(1e-3 * per_unit)
            };
            for ((d, c), f) in exact.iter().zip(&coarse[range.clone()]).zip(&fine[range]) {
                for i in 0..3 {
                    let extrapolated = (4.0 * f[i] - c[i]) / 3.0;
                    error = error.max((d[i] - extrapolated).abs() / largest.max(1e-300));
                }
            }
        }
        println!(
            "{path} = {value}: |dx/dp| up to {scale:.3e}, relative error {error:.2e} \
             (samples and pin forces)"
        );
        worst = worst.max(error);
    }
    worst
}

#[test]
fn the_catenary_s_sensitivities_match_finite_differences() {
    let load = "[[loads]]\nat = 0.3\nforce = [0.2, -0.5, 0.1]\n";
    let text = std::fs::read_to_string(format!(
        "{}/scenes/catenary_static.toml",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let mut scene = Scene::from_toml(&format!("{text}\n{load}")).expect("with a load");
    scene.solver.tolerance = Some(1e-13);
    let error = check(
        &scene,
        &[
            ("rod.stretch_stiffness", &|s, v| s.rod.stretch_stiffness = v),
            ("rod.linear_density", &|s, v| s.rod.linear_density = v),
            ("world.gravity[1]", &|s, v| s.world.gravity[1] = v),
            ("world.gravity[0]", &|s, v| s.world.gravity[0] = v),
            ("loads[0].force[1]", &|s, v| {
                s.loads[0].force.as_mut().unwrap()[1] = v
            }),
            ("loads[0].force[2]", &|s, v| {
                s.loads[0].force.as_mut().unwrap()[2] = v
            }),
            ("rod.rest_length", &rest_length),
        ],
    );
    assert!(error < 1e-6, "relative error {error:e}");
}

#[test]
fn the_cantilever_s_sensitivities_match_finite_differences() {
    let scene = tight("cantilever");
    let error = check(
        &scene,
        &[
            ("rod.bending_stiffness", &|s, v| {
                s.rod.bending_stiffness = Some(v)
            }),
            ("rod.stretch_stiffness", &|s, v| s.rod.stretch_stiffness = v),
            ("rod.linear_density", &|s, v| s.rod.linear_density = v),
            ("rod.rest_length", &rest_length),
        ],
    );
    assert!(error < 1e-6, "relative error {error:e}");
    // With uniform knots the clamp is a penalty of stiffness 1e6 EI/L, which follows
    // the rest length too.
    let mut penalty = tight("cantilever");
    penalty.rod.knots = Some(splinerod::scene::KnotsSpec::Named("uniform".into()));
    let error = check(&penalty, &[("rod.rest_length", &rest_length)]);
    assert!(error < 1e-6, "penalty clamp: relative error {error:e}");
}

#[test]
fn bad_parameter_paths_are_named() {
    let scene = tight("catenary_static");
    for (path, words) in [
        ("rod.radius", "not a rod parameter"),
        ("rod.bending_stiffness", "no energy"),
        ("world.gravity", "not a scalar parameter"),
        ("world.gravity[3]", "components"),
        ("loads[0].force[1]", "0 [[loads]]"),
        ("rods[0].stretch_stiffness", "0 [[rods]]"),
        ("stiffness", "not a scalar parameter"),
    ] {
        let e = static_sensitivities(&scene, &[path])
            .expect_err(path)
            .to_string();
        assert!(e.contains(path) && e.contains(words), "{path}: {e}");
    }
    let mut dynamic = tight("hanging_cable");
    dynamic.solver.duration = Some(0.01);
    let e = static_sensitivities(&dynamic, &["rod.stretch_stiffness"])
        .expect_err("dynamic")
        .to_string();
    assert!(
        e.contains("solver.method") && e.contains("dynamic_sensitivities"),
        "{e}"
    );
}

/// Clamped at both ends, the end turned by 3 rad, sagging sideways under gravity: the
/// twist moment bends the sag out of its plane, so the shape depends on GJ.
fn twisted() -> Scene {
    let text = "[rod]\nrest_length = 1.5\nlinear_density = 0.1\nstretch_stiffness = 1e4\n\
         bending_stiffness = 0.3\ntwist_stiffness = 0.2\ncontrol_points = 12\n\
         start = [0.0, 0.0, 0.0]\nend = [0.0, 0.0, 1.5]\n\n\
         [[pins]]\nat = 0.0\nclamp = true\n\n\
         [[pins]]\nat = 1.0\nclamp = true\nturn = [[0.0, 0.0], [0.5, 3.0]]\n\n\
         [world]\ngravity = [-9.81, 0.0, 0.0]\n\n[solver]\nmethod = \"static\"\n";
    let mut scene = Scene::from_toml(text).expect("scene");
    scene.solver.tolerance = Some(1e-13);
    scene
}

#[test]
fn a_twisted_rod_s_sensitivities_match_finite_differences() {
    let scene = twisted();
    let error = check(
        &scene,
        &[
            ("rod.twist_stiffness", &|s, v| {
                s.rod.twist_stiffness = Some(v)
            }),
            ("rod.bending_stiffness", &|s, v| {
                s.rod.bending_stiffness = Some(v)
            }),
            ("world.gravity[0]", &|s, v| s.world.gravity[0] = v),
        ],
    );
    assert!(error < 1e-6, "relative error {error:e}");
    // The rest length: at 1.5 m between clamps 1.5 m apart the rod is at the edge of
    // buckling (its bending energy changes by 30 % per mm of length), so the clamps are
    // 5 mm further apart: taut, twisted, sagging. Its tension follows the 5 mm stretch,
    // which a step of 1e-3 (1.5 mm) changes by 30 %: the differences' truncation is then
    // 6.5e-4 (1e-4: 6.3e-8; 1e-5: 7e-11), so they step at 1e-5.
    let mut taut = twisted();
    taut.rod.end = Some([0.0, 0.0, 1.505]);
    let error = check_with_step(&taut, &[("rod.rest_length", &rest_length)], 1e-5);
    assert!(error < 1e-6, "rest length: relative error {error:e}");
}

/// The catenary resting on an obstacle (the default barrier contact, whose stiffness
/// follows the loads: its derivative enters too).
fn on_obstacle(obstacle: &str) -> Scene {
    let path = format!("{}/scenes/catenary_static.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(path).expect("scene");
    let text = text.replace("control_points = 16", "control_points = 24\nradius = 0.01")
        + "\n[contact]\n\n[[obstacles]]\n"
        + obstacle;
    let mut scene = Scene::from_toml(&text).expect("scene");
    scene.solver.tolerance = Some(1e-13);
    let pressed = splinerod::run(&scene).expect("run").obstacle_forces[0][1];
    assert!(
        pressed < -0.1,
        "the rope rests on the obstacle: {pressed} N"
    );
    scene
}

#[test]
fn a_rope_on_an_obstacle_s_sensitivities_match_finite_differences() {
    let cases: [(&str, Setter<'_>); 2] = [
        ("rod.stretch_stiffness", &|s, v| s.rod.stretch_stiffness = v),
        ("rod.linear_density", &|s, v| s.rod.linear_density = v),
    ];
    // The rest length moves the rope by half as much (0.5 m/m): differences at 1e-3
    // (0.5 mm) cross the barrier's layer of samples entering and leaving it, so they
    // step at 1e-5 (at 1e-3, 1e-4, 1e-5 on the plane: 1.8e-3, 9.2e-7, 2.2e-10).
    let length: [(&str, Setter<'_>); 1] = [("rod.rest_length", &rest_length)];
    // On a plane the contact's Hessian is exact: so are the sensitivities.
    let plane =
        on_obstacle("kind = \"plane\"\npoint = [0.0, -0.22, 0.0]\nnormal = [0.0, 1.0, 0.0]\n");
    let error = check(&plane, &cases).max(check_with_step(&plane, &length, 1e-5));
    assert!(error < 1e-6, "plane: relative error {error:e}");
    // On a sphere and a capsule the exact Hessian has the surface-curvature term
    // φ′ ∇n: it makes the banded matrix indefinite, and the tangent solve carries it with
    // the stretching's remainder (`newton/carried.rs`). So do the static solve's Newton
    // steps (`carries_indefinite`): without it they left the remainder out there,
    // converged linearly and stopped ~1e-12 m short — the differences' noise, 4.8e-6
    // on the sphere.
    let sphere = on_obstacle("kind = \"sphere\"\ncentre = [0.4, -0.35, 0.0]\nradius = 0.15\n");
    let error = check(&sphere, &cases).max(check_with_step(&sphere, &length, 1e-5));
    assert!(error < 1e-6, "sphere: relative error {error:e}");
    let capsule = on_obstacle(
        "kind = \"capsule\"\na = [0.4, -0.35, -0.2]\nb = [0.4, -0.35, 0.2]\nradius = 0.15\n",
    );
    let error = check(&capsule, &cases).max(check_with_step(&capsule, &length, 1e-5));
    assert!(error < 1e-6, "capsule: relative error {error:e}");
}

#[test]
fn each_rod_of_rods_has_its_own_parameters() {
    // Two catenaries side by side (no contact): the samples are the first rod's, which
    // depends on its own EA and not at all on the second rod's.
    let rod = |name: &str, z: Real, ea: Real| {
        format!(
            "[[rods]]\nname = \"{name}\"\nrest_length = 1.0\nlinear_density = 0.1\n\
             stretch_stiffness = {ea}\nbending_stiffness = 1e-3\ncontrol_points = 12\n\
             start = [0.0, 0.0, {z}]\nend = [0.8, 0.0, {z}]\n\n\
             [[pins]]\nrod = \"{name}\"\nat = 0.0\n[[pins]]\nrod = \"{name}\"\nat = 1.0\n\n"
        )
    };
    let text = rod("a", 0.0, 100.0)
        + &rod("b", 0.5, 300.0)
        + "[world]\ngravity = [0.0, -9.81, 0.0]\n[solver]\nmethod = \"static\"\n";
    let mut scene = Scene::from_toml(&text).expect("scene");
    scene.solver.tolerance = Some(1e-13);
    let error = check(
        &scene,
        &[
            ("rods[0].stretch_stiffness", &|s, v| {
                s.rods[0].stretch_stiffness = v
            }),
            ("rods[0].bending_stiffness", &|s, v| {
                s.rods[0].bending_stiffness = Some(v)
            }),
        ],
    );
    assert!(error < 1e-6, "relative error {error:e}");
    let other = static_sensitivities(&scene, &["rods[1].stretch_stiffness"]).expect("rods[1]");
    assert!(other.positions[0].iter().flatten().all(|d| *d == 0.0));
    assert_eq!(other.parameters[0].1, 300.0);
    let e = static_sensitivities(&scene, &["rod.stretch_stiffness"]).expect_err("rod.");
    assert!(e.to_string().contains("rods[k]"), "{e}");
}

#[test]
fn the_command_line_writes_the_sensitivities_and_names_bad_parameters() {
    use crate::common::cli::{fresh_dir, ok, refused};
    let dir = fresh_dir("sensitivities");
    let json = dir.join("s.json");
    let json = json.to_str().expect("UTF-8");
    let params = "--params=rod.bending_stiffness,world.gravity[1]";
    ok(&[
        "sensitivities",
        "scenes/cantilever.toml",
        params,
        "--json",
        json,
    ]);
    let value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).expect("written")).expect("JSON");
    assert_eq!(value["parameters"][0]["name"], "rod.bending_stiffness");
    assert_eq!(value["parameters"][0]["value"], 10.0);
    let samples = value["s"].as_array().expect("s").len();
    let d = value["positions"]["rod.bending_stiffness"]
        .as_array()
        .expect("positions");
    assert_eq!(d.len(), samples);
    // The tip of the cantilever: δ = w L⁴ / (8 EI) under its weight, so dy/dEI = δ / EI.
    let tip = d[samples - 1][1].as_f64().expect("dy");
    let delta = 0.1 * 9.81 / (8.0 * 10.0);
    assert!(
        (tip - delta / 10.0).abs() < 1e-3 * delta / 10.0,
        "dy/dEI {tip} vs {}",
        delta / 10.0
    );
    let line = refused(&[
        "sensitivities",
        "scenes/cantilever.toml",
        "--params=rod.colour",
    ]);
    assert!(line.contains("rod.colour"), "{line}");
    // A pin the scene lacks, a component a position lacks: exit 2, named.
    for bad in [
        "pins[7].position[0]",
        "pins[0].position[3]",
        "rods[0].rest_length",
    ] {
        let params = format!("--params={bad}");
        let line = refused(&["sensitivities", "scenes/catenary_static.toml", &params]);
        assert!(line.contains(bad), "{line}");
    }
    // A run with a scheme without forward sensitivities (runs of implicit Euler and
    // BDF2 have theirs: sensitivities_dynamic.rs).
    let line = refused(&[
        "sensitivities",
        "scenes/string_midpoint.toml",
        "--params=rod.stretch_stiffness",
    ]);
    assert!(line.contains("solver.method"), "{line}");
}

#[test]
fn the_pins_positions_sensitivities_match_finite_differences() {
    // The catenary's end pin moved along and across the span, and out of its plane (the
    // span shifted to end at x = 0: the differences' step is then 1e-6 m, not 0.8 mm).
    let mut scene = tight("catenary_static");
    scene.rod.start = Some([-0.8, 0.0, 0.0]);
    scene.rod.end = Some([0.0, 0.0, 0.0]);
    let error = check(
        &scene,
        &[
            ("pins[1].position[0]", &|s, v| {
                set_parameter(s, "pins[1].position[0]", v).unwrap()
            }),
            ("pins[1].position[1]", &|s, v| {
                set_parameter(s, "pins[1].position[1]", v).unwrap()
            }),
            ("pins[0].position[2]", &|s, v| {
                set_parameter(s, "pins[0].position[2]", v).unwrap()
            }),
        ],
    );
    assert!(error < 1e-6, "catenary: relative error {error:e}");
    // A driven pin: the static solve holds it at its path's end; the parameter offsets
    // the whole path.
    let mut driven = scene.clone();
    driven.pins[1].path = Some(vec![[0.0, 0.0, 0.0, 0.0], [1.0, -0.2, 0.1, 0.05]]);
    let error = check(
        &driven,
        &[("pins[1].position[0]", &|s, v| {
            set_parameter(s, "pins[1].position[0]", v).unwrap()
        })],
    );
    assert!(error < 1e-6, "driven: relative error {error:e}");
    // Clamps: the tangent pin moves with its clamp (the twisted rod's far clamp moved
    // sideways and along; the cantilever's clamp lifted: a rigid translation).
    // (Moved along the axis, where the end sits at z = 1.5, a relative step 1e-3 is
    // 1.5 mm: the scene shifted to end at z = 0 takes the differences' step 1e-6.)
    let mut twisted = twisted();
    twisted.rod.start = Some([0.0, 0.0, -1.5]);
    twisted.rod.end = Some([0.0, 0.0, 0.0]);
    let error = check(
        &twisted,
        &[
            ("pins[1].position[1]", &|s, v| {
                set_parameter(s, "pins[1].position[1]", v).unwrap()
            }),
            ("pins[1].position[2]", &|s, v| {
                set_parameter(s, "pins[1].position[2]", v).unwrap()
            }),
        ],
    );
    assert!(error < 1e-6, "twisted: relative error {error:e}");
    let lifted = static_sensitivities(&tight("cantilever"), &["pins[0].position[1]"]).unwrap();
    for d in &lifted.positions[0] {
        assert!((d[1] - 1.0).abs() < 1e-9 && d[0].abs() < 1e-9, "{d:?}");
    }
    assert!(lifted.pin_forces[0]
        .iter()
        .flatten()
        .all(|f| f.abs() < 1e-8));
}

#[test]
fn bad_pin_friction_and_rest_length_paths_are_named() {
    let scene = tight("catenary_static");
    for (path, words) in [
        ("pins[7].position[0]", "2 [[pins]]"),
        ("pins[0].position[3]", "3 components"),
        ("pins[0].position", "not a scalar parameter"),
        ("contact.friction", "no [contact]"),
    ] {
        let e = static_sensitivities(&scene, &[path])
            .expect_err(path)
            .to_string();
        assert!(e.contains(path) && e.contains(words), "{path}: {e}");
    }
}

#[test]
fn the_rest_length_moves_a_start_that_follows_it() {
    // Without rod.end the rod starts straight along x for its length: the far pin
    // moves with the rest length (a taut catenary sagging by its stretch).
    let mut scene = tight("catenary_static");
    scene.rod.end = None;
    let error = check(&scene, &[("rod.rest_length", &rest_length)]);
    assert!(error < 1e-6, "relative error {error:e}");
    let found = static_sensitivities(&scene, &["rod.rest_length"]).expect("sensitivities");
    let end = found.positions[0].last().expect("samples");
    assert!(
        (end[0] - 1.0).abs() < 1e-12 && end[1].abs() < 1e-12,
        "{end:?}"
    );
}

#[test]
fn rest_lengths_that_cannot_be_followed_are_named() {
    let path = "rod.rest_length";
    // A rest shape: the initial curve's metric, not the domain's.
    let mut shaped = tight("catenary_static");
    shaped.rod.rest_shape = splinerod::scene::RestShape::Initial;
    let e = static_sensitivities(&shaped, &[path]).expect_err("rest shape");
    assert!(e.to_string().contains("rest_shape"), "{e}");
    // A pin's position given while the far end follows the rest length.
    let mut pinned = tight("catenary_static");
    pinned.rod.end = None;
    pinned.pins[1].position = Some([1.0, 0.0, 0.0]);
    let e = static_sensitivities(&pinned, &[path]).expect_err("pin position");
    assert!(e.to_string().contains("pins[1].position"), "{e}");
    // One of several rods.
    let two = "[[rods]]\nname = \"a\"\nrest_length = 1.0\nlinear_density = 0.1\n\
        stretch_stiffness = 100.0\ncontrol_points = 8\n\n\
        [[rods]]\nname = \"b\"\nrest_length = 1.0\nlinear_density = 0.1\n\
        stretch_stiffness = 100.0\ncontrol_points = 8\nstart = [0.0, 0.0, 1.0]\n\
        end = [1.0, 0.0, 1.0]\n\n[[pins]]\nrod = \"a\"\nat = 0.0\n\n\
        [world]\ngravity = [0.0, -9.81, 0.0]\n[solver]\nmethod = \"static\"\n";
    let two = Scene::from_toml(two).expect("scene");
    let e = static_sensitivities(&two, &["rods[1].rest_length"]).expect_err("rods");
    assert!(e.to_string().contains("rods[1].rest_length"), "{e}");
}
