//! Identification of a real cable's parameters (#48) on synthetic data with known
//! answers: 40 markers with 0.1 mm of noise on a static cable clamped at one end and
//! hanging under its weight; EA and EI recovered with the density known, and with the
//! density free the fit says what the shape alone cannot separate.

use crate::common;
use splinerod::fit::{ObservationFile, SceneFit};
use splinerod::{Real, Scene};

/// The clamped cable with EA `ea` and EI `ei`, as scene text.
fn cable_text(ea: Real, ei: Real) -> String {
    format!(
        "[rod]\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = {ea}\n\
         bending_stiffness = {ei}\ncontrol_points = 16\nstart = [0.0, 0.0, 0.0]\n\
         end = [1.0, 0.0, 0.0]\n\n[[pins]]\nat = 0.0\nclamp = true\n\n\
         [world]\ngravity = [0.0, -9.81, 0.0]\n\n[solver]\nmethod = \"static\"\ntolerance = 1e-12\n"
    )
}

/// The clamped cable with EA `ea` and EI `ei`.
fn cable(ea: Real, ei: Real) -> Scene {
    Scene::from_toml(&cable_text(ea, ei)).expect("scene")
}

/// 40 markers of the true cable (EA 50 N, EI 1e-3 N·m²), σ = 0.1 mm.
fn markers() -> ObservationFile {
    let truth = splinerod::sensitivity::static_sensitivities(
        &cable(50.0, 1e-3),
        &["rod.stretch_stiffness"],
    )
    .expect("the true equilibrium");
    let mut csv = String::from("t,s,x,y,z,sigma\n");
    for k in 0..40 {
        let s = (k + 1) as Real / 40.0;
        let p = truth.rod.point(s).expect("point");
        let n = |c: usize| 1e-4 * common::noise(3 * k + c);
        csv += &format!(",{s},{},{},{},1e-4\n", p.x + n(0), p.y + n(1), p.z + n(2));
    }
    ObservationFile::parse("markers.csv", &csv).expect("markers")
}

#[test]
fn ea_and_ei_are_recovered_from_noisy_markers() {
    let files = [markers()];
    let start = cable(80.0, 2e-3);
    let params = ["rod.stretch_stiffness", "rod.bending_stiffness"];
    let report = SceneFit::new(&start, &params, &files)
        .expect("fit")
        .fit()
        .expect("fitted");
    println!("{report:?}");
    assert!(report.converged);
    common::recovered(&report, &params, &[50.0, 1e-3]);
    assert!(
        (report.residual_rms - 1.0).abs() < 0.3,
        "residuals in units of σ: {}",
        report.residual_rms
    );
    assert!(
        report.simulations <= 40,
        "{} simulations",
        report.simulations
    );
}

#[test]
fn with_the_density_free_the_shape_fixes_only_ratios() {
    let files = [markers()];
    let params = [
        "rod.stretch_stiffness",
        "rod.bending_stiffness",
        "rod.linear_density",
    ];
    let report = SceneFit::new(&cable(80.0, 2e-3), &params, &files)
        .expect("fit")
        .fit()
        .expect("fitted");
    println!("{report:?}");
    assert_eq!(
        report.unidentifiable.len(),
        1,
        "{:?}",
        report.unidentifiable
    );
    let (group, direction) = &report.unidentifiable[0];
    assert_eq!(group, &vec![0, 1, 2]);
    // The direction (1, 1, 1)/√3 in (ln EA, ln EI, ln μ): only EA/μ and EI/μ are seen.
    let third = (1.0 / 3.0 as Real).sqrt();
    for d in direction {
        assert!((d.abs() - third).abs() < 1e-3, "{direction:?}");
    }
    let ratio = report.parameters[0] / report.parameters[2];
    assert!((ratio / 500.0 - 1.0).abs() < 0.02, "EA/μ {ratio}");
}

#[test]
fn the_command_line_fits_and_names_what_it_cannot_use() {
    use crate::common::cli::{fresh_dir, ok, refused};
    let dir = fresh_dir("fit");
    let scene = dir.join("cable.toml");
    let text = format!("# the bench cable\n{}", cable_text(80.0, 2e-3));
    std::fs::write(&scene, text).expect("scene");
    let obs = dir.join("markers.csv");
    let m = markers();
    let mut csv = String::from("t,s,x,y,z,sigma\n");
    for r in &m.rows {
        csv += &format!(
            ",{},{},{},{},{}\n",
            r.s.unwrap(),
            r.value[0],
            r.value[1],
            r.value[2],
            r.sigma
        );
    }
    std::fs::write(&obs, &csv).expect("markers");
    let json = dir.join("fit.json");
    let (scene, obs, json) = (
        scene.to_str().unwrap(),
        obs.to_str().unwrap(),
        json.to_str().unwrap(),
    );
    let params = "--params=rod.stretch_stiffness,rod.bending_stiffness";
    let fitted = dir.join("fitted.toml");
    let out = fitted.to_str().unwrap();
    ok(&[
        "fit",
        scene,
        "--observations",
        obs,
        params,
        "--json",
        json,
        "--scene-out",
        out,
    ]);
    let value: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(json).unwrap()).unwrap();
    let ea = value["parameters"][0]["value"].as_f64().expect("EA");
    assert!((ea / 50.0 - 1.0).abs() < 0.02, "EA {ea}");
    // The fitted scene: the user's file, comment kept, the fitted values exactly.
    let written = std::fs::read_to_string(&fitted).expect("fitted scene");
    assert!(written.starts_with("# the bench cable\n"), "{written}");
    let fitted = Scene::from_toml(&written).expect("a scene");
    assert_eq!(fitted.rod.stretch_stiffness.to_bits(), ea.to_bits());
    let ei = value["parameters"][1]["value"].as_f64().expect("EI");
    assert_eq!(
        fitted.rod.bending_stiffness.map(Real::to_bits),
        Some(ei.to_bits())
    );
    assert_eq!(value["parameters"][1]["name"], "rod.bending_stiffness");
    assert!(value["converged"].as_bool().expect("converged"));
    assert!(value["simulations"].as_u64().expect("simulations") <= 40);

    // Bad input: a NaN in a file, too few observations, an unknown parameter.
    let bad = dir.join("bad.csv");
    std::fs::write(&bad, "t,s,x,y,z\n,0.5,nan,0,0\n").unwrap();
    let line = refused(&[
        "fit",
        scene,
        "--observations",
        bad.to_str().unwrap(),
        params,
    ]);
    assert!(
        line.contains("bad.csv") && line.contains("line 2"),
        "{line}"
    );
    let one = dir.join("one.csv");
    std::fs::write(&one, "t,s,x,y,z\n,0.5,0.1,-0.4,0\n").unwrap();
    let three =
        "--params=rod.stretch_stiffness,rod.bending_stiffness,rod.linear_density,world.gravity[1]";
    let line = refused(&["fit", scene, "--observations", one.to_str().unwrap(), three]);
    assert!(
        line.contains("observations") && line.contains("3 residuals for 4 parameters"),
        "{line}"
    );
    let line = refused(&["fit", scene, "--observations", obs, "--params=rod.radius"]);
    assert!(line.contains("rod.radius"), "{line}");
}

#[test]
fn the_measured_clamp_force_separates_the_density() {
    // The clamp's force (the cable's weight, and the sag's pull) measured to 0.1 mN fixes
    // μ; with the 40 markers the fit then recovers all three.
    let truth = splinerod::run(&cable(50.0, 1e-3))
        .expect("truth")
        .pin_forces[0];
    let mut csv = String::from("t,pin,fx,fy,fz,sigma\n");
    let n = |c: usize| 1e-4 * common::noise(500 + c);
    csv += &format!(
        ",0,{},{},{},1e-4\n",
        truth[0] + n(0),
        truth[1] + n(1),
        truth[2] + n(2)
    );
    let forces = ObservationFile::parse("forces.csv", &csv).expect("forces");
    let files = [markers(), forces];
    let mut start = cable(80.0, 2e-3);
    start.rod.linear_density = 0.15;
    let params = [
        "rod.stretch_stiffness",
        "rod.bending_stiffness",
        "rod.linear_density",
    ];
    let report = SceneFit::new(&start, &params, &files)
        .expect("fit")
        .fit()
        .expect("fitted");
    println!("{report:?}");
    assert!(
        report.unidentifiable.is_empty(),
        "{:?}",
        report.unidentifiable
    );
    common::recovered(&report, &params, &[50.0, 1e-3, 0.1]);
}

#[test]
fn the_fit_needs_ten_times_fewer_simulations_than_nelder_mead() {
    // The same objective from the same start: simulations until the residuals' root mean
    // square first comes within 1e-6 of the least-squares optimum's, for the fit (from
    // its history) and for Nelder–Mead (argmin's, stopped there).
    let files = [markers()];
    let params = ["rod.stretch_stiffness", "rod.bending_stiffness"];
    let mut fit = SceneFit::new(&cable(80.0, 2e-3), &params, &files).expect("fit");
    let report = fit.fit().expect("fitted");
    let target = report.residual_rms * (1.0 + 1e-6);
    let fitted = report
        .simulations_to(target)
        .expect("the fit reaches its optimum");
    let simplex = fit.nelder_mead(target, 2_000).expect("simplex");
    println!(
        "to rms {target:.9}: least squares {fitted} simulations ({} in all), Nelder–Mead {} \
         (EA {:.4}, EI {:.6e})",
        report.simulations, simplex.simulations, simplex.parameters[0], simplex.parameters[1]
    );
    assert!(simplex.reached, "{simplex:?}");
    assert!(
        simplex.simulations >= 10 * fitted,
        "{} against {fitted}",
        simplex.simulations
    );
}

#[test]
fn synthetic_observations_are_reproducible_and_check_their_noise() {
    use splinerod::fit::synthetic::{noisy_markers, noisy_pin_force};
    let truth = cable(50.0, 1e-3);
    let a = noisy_markers(&truth, 10, 1e-4, 3).expect("markers");
    let b = noisy_markers(&truth, 10, 1e-4, 3).expect("markers");
    assert_eq!(a, b, "one seed, one data set");
    let c = noisy_markers(&truth, 10, 1e-4, 4).expect("markers");
    assert_ne!(a, c);
    // The noise is what was asked for: the markers' distance to the clean curve.
    let clean = splinerod::sensitivity::static_sensitivities(&truth, &[]).expect("truth");
    let many = noisy_markers(&truth, 400, 1e-3, 5).expect("markers");
    let deviations: Vec<Real> = many
        .rows
        .iter()
        .flat_map(|r| {
            let p = clean.rod.point(r.s.unwrap()).unwrap();
            (0..3).map(move |c| r.value[c] - p[c])
        })
        .collect();
    let rms = (deviations.iter().map(|d| d * d).sum::<Real>() / deviations.len() as Real).sqrt();
    assert!((rms / 1e-3 - 1.0).abs() < 0.1, "noise rms {rms}");
    for sigma in [0.0, -1.0, Real::NAN] {
        let e = noisy_markers(&truth, 10, sigma, 1).expect_err("refused");
        assert!(e.to_string().contains("sigma"), "{e}");
    }
    let e = noisy_pin_force(&truth, 3, 1e-4, 1).expect_err("no pin 3");
    assert!(e.to_string().contains("pin"), "{e}");
}

#[test]
fn fitted_values_are_written_into_the_scene_file_in_place() {
    use splinerod::fit::scene_out::with_fitted_values;
    let text = "[[rods]] # upper\nname = \"a\"\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 10.0 # guessed\n\
                control_points = 8\nstart = [0.0, 0.0, 0.0]\nend = [1.0, 0.0, 0.0]\n\n\
                [[rods]]\nname = \"b\"\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 20.0\n\
                control_points = 8\nstart = [0.0, 1.0, 0.0]\nend = [1.0, 1.0, 0.0]\n\n\
                [[pins]]\nrod = \"a\"\nat = 0.0\n\n[[pins]]\nrod = \"b\"\nat = 0.0\n\n\
                [[loads]]\nrod = \"b\"\nat = 1.0\nforce = [0.0, -1.0, 0.0]\n\n\
                [solver]\nmethod = \"static\"\n";
    Scene::from_toml(text).expect("the starting scene");
    let names = [
        "rods[1].stretch_stiffness",
        "world.gravity[0]",
        "loads[0].force[1]",
    ]
    .map(String::from);
    let values = [33.25, 0.125, -2.5];
    let out = with_fitted_values("s.toml", text, &names, &values).expect("written");
    let scene = Scene::from_toml(&out).expect("a scene");
    assert_eq!(scene.rods[0].stretch_stiffness, 10.0);
    assert_eq!(scene.rods[1].stretch_stiffness, 33.25);
    assert_eq!(
        scene.world.gravity,
        [0.125, -9.81, 0.0],
        "the default written whole"
    );
    assert_eq!(scene.loads[0].force, Some([0.0, -2.5, 0.0]));
    assert!(out.contains("stretch_stiffness = 10.0 # guessed"), "{out}");
    assert!(out.contains("[[rods]] # upper"), "{out}");
    let e = with_fitted_values("s.toml", text, &["rod.stretch_stiffness".into()], &[1.0])
        .expect_err("the scene has [[rods]]");
    assert!(e.to_string().contains("rod.stretch_stiffness"), "{e}");
}

#[test]
fn ea_and_ei_are_recovered_from_unlabelled_points() {
    // 60 points of a point cloud (no material coordinates) with 0.1 mm of noise: the
    // residual is each point's distance to the curve.
    use splinerod::fit::synthetic::noisy_points;
    let files = [noisy_points(&cable(50.0, 1e-3), 60, 1e-4, 11).expect("points")];
    let params = ["rod.stretch_stiffness", "rod.bending_stiffness"];
    let report = SceneFit::new(&cable(80.0, 2e-3), &params, &files)
        .expect("fit")
        .fit()
        .expect("fitted");
    println!("{report:?}");
    assert!(report.converged);
    // The cable hangs almost vertically from its clamp: stretching moves its points
    // along the curve, which unlabelled points do not see (only the end's reach does),
    // so EA is poorly determined and the fit says so; EI shapes the bend and is fixed.
    let (ei, ei_std) = (report.parameters[1], report.std[1]);
    assert!(
        (ei / 1e-3 - 1.0).abs() < 0.02 && (ei - 1e-3).abs() < 3.0 * ei_std,
        "EI {ei} ± {ei_std}"
    );
    let (ea, std) = (report.parameters[0], report.std[0]);
    assert!((ea - 50.0).abs() < 3.0 * std, "EA {ea} ± {std}");
    assert!(
        std > 0.1 * ea,
        "EA's deviation {std} says the points barely see it"
    );
}

#[test]
fn a_points_residual_derivative_matches_differences() {
    // The distance's derivative through the nearest point (no derivative of s* needed)
    // against central differences of the distance itself, one point off the curve.
    use splinerod::fit::closest::closest_point;
    use splinerod::fit::Model;
    let csv = "t,x,y,z,sigma\n,0.6,-0.05,0.002,1e-3\n";
    let files = [ObservationFile::parse("p.csv", csv).expect("a point")];
    let params = ["rod.stretch_stiffness", "rod.bending_stiffness"];
    let p = [50.0, 1e-3];
    let mut fit = SceneFit::new(&cable(p[0], p[1]), &params, &files).expect("fit");
    let (mut r, mut j) = ([0.0], [0.0; 2]);
    fit.evaluate(&p, &mut r, Some(&mut j)).expect("evaluated");
    for k in 0..2 {
        let h = 1e-4 * p[k];
        let at = |v: Real| {
            let mut q = p;
            q[k] = v;
            let found = splinerod::sensitivity::static_sensitivities(&cable(q[0], q[1]), &[])
                .expect("solved");
            let x = nalgebra::Vector3::new(0.6, -0.05, 0.002);
            (x - closest_point(&found.rod, &x).expect("nearest").1).norm() / 1e-3
        };
        let fd = (at(p[k] + h) - at(p[k] - h)) / (2.0 * h);
        println!("{}: {} against {fd}", params[k], j[k]);
        assert!(
            (j[k] - fd).abs() < 1e-5 * fd.abs(),
            "{}: {} vs {fd}",
            params[k],
            j[k]
        );
    }
}

/// The catenary pinned 0.8 m apart with rest length `l` and EA `ea`.
fn catenary(l: Real, ea: Real) -> String {
    format!(
        "[rod]\nrest_length = {l}\nlinear_density = 0.1\nstretch_stiffness = {ea}\n\
         control_points = 16\nstart = [0.0, 0.0, 0.0]\nend = [0.8, 0.0, 0.0]\n\n\
         [[pins]]\nat = 0.0\n\n[[pins]]\nat = 1.0\n\n\
         [world]\ngravity = [0.0, -9.81, 0.0]\n\n[solver]\nmethod = \"static\"\ntolerance = 1e-12\n"
    )
}

#[test]
fn the_rest_length_is_fitted_from_markers_in_metres() {
    // Markers painted every 2.5 cm along a rope of 1 m (σ = 0.1 mm); the fit starts
    // from 1.03 m and EA 150 N, and writes the fitted length back to the file.
    let truth = Scene::from_toml(&catenary(1.0, 100.0)).expect("scene");
    let rod = splinerod::sensitivity::static_sensitivities(&truth, &["rod.rest_length"])
        .expect("the true equilibrium")
        .rod;
    let mut csv = String::from("t,s,x,y,z,sigma\n");
    for k in 0..39 {
        let s = (k + 1) as Real / 40.0;
        let p = rod.point(s).expect("point");
        let n = |c: usize| 1e-4 * common::noise(3 * k + c);
        csv += &format!(",{s},{},{},{},1e-4\n", p.x + n(0), p.y + n(1), p.z + n(2));
    }
    let files = [ObservationFile::parse("markers.csv", &csv).expect("markers")];
    let text = catenary(1.03, 150.0);
    let start = Scene::from_toml(&text).expect("scene");
    let params = ["rod.rest_length", "rod.stretch_stiffness"];
    let report = SceneFit::new(&start, &params, &files)
        .expect("fit")
        .fit()
        .expect("fitted");
    println!("{report:?}");
    assert!(report.converged);
    common::recovered(&report, &params, &[1.0, 100.0]);
    assert!(
        (report.parameters[0] - 1.0).abs() < 1e-4,
        "{}",
        report.parameters[0]
    );
    let names: Vec<String> = params.iter().map(|p| p.to_string()).collect();
    let written = splinerod::fit::scene_out::with_fitted_values(
        "start.toml",
        &text,
        &names,
        &report.parameters,
    )
    .expect("written back");
    let back = Scene::from_toml(&written).expect("scene");
    assert_eq!(back.rod.rest_length, report.parameters[0]);
    // Shorter than its farthest marker (0.975 m), the rod no longer carries it: named.
    let mut fit = SceneFit::new(&start, &params, &files).expect("fit");
    let mut r = vec![0.0; splinerod::fit::Model::residual_count(&fit)];
    let e = splinerod::fit::Model::evaluate(&mut fit, &[0.95, 100.0], &mut r, None)
        .expect_err("too short");
    assert!(e.to_string().contains("rod.rest_length"), "{e}");
}

#[test]
fn points_in_metres_move_along_the_rod_with_its_rest_length() {
    // Python's `sensitivities(params, s)` takes s in metres: a point keeps its distance
    // from the start as L changes, so its derivative has −(s/L) C'(s) besides the
    // control points'.
    let scene = Scene::from_toml(&catenary(1.0, 100.0)).expect("scene");
    let s = [0.0, 0.25, 0.6, 0.95];
    let path = ["rod.rest_length"];
    let exact = splinerod::sensitivity_at::static_sensitivities_at(&scene, &path, &s)
        .expect("sensitivities");
    let at = |l: Real| {
        let mut moved = scene.clone();
        splinerod::sensitivity::set_parameter(&mut moved, path[0], l).expect("set");
        splinerod::sensitivity_at::static_sensitivities_at(&moved, &path, &s)
            .expect("moved")
            .at
    };
    let central = |h: Real| {
        let (a, b) = (at(1.0 + h), at(1.0 - h));
        let d: Vec<[Real; 3]> = a
            .iter()
            .zip(&b)
            .map(|(a, b)| std::array::from_fn(|c| (a[c] - b[c]) / (2.0 * h)))
            .collect();
        d
    };
    let (coarse, fine) = (central(1e-4), central(5e-5));
    let largest = exact.positions[0]
        .iter()
        .flatten()
        .fold(0.0, |m: Real, x| m.max(x.abs()));
    for ((d, c), f) in exact.positions[0].iter().zip(&coarse).zip(&fine) {
        for i in 0..3 {
            let reference = (4.0 * f[i] - c[i]) / 3.0;
            let error = (d[i] - reference).abs() / largest;
            assert!(error < 1e-6, "{d:?} vs {reference}: {error:e}");
        }
    }
}
