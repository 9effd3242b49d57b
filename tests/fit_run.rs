//! Identification from a trajectory (#48): a damped cable swinging from a pin for 2 s,
//! observed by 10 markers every 0.1 s with 0.1 mm of noise; its damping and bending
//! stiffness are fitted through the run's forward sensitivities, with implicit Euler and
//! with BDF2. The same from unlabelled points, and with the pin's measured force the
//! density too.

use crate::common;
use nalgebra::Vector3;
use splinerod::fit::run_fit::RunFit;
use splinerod::fit::Model;
use splinerod::sensitivity::observed_sensitivities;
use splinerod::{Real, Scene};

/// The swinging cable with damping `alpha` (1/s) and EI `ei`, stepped by `method`.
fn swinging(method: &str, alpha: Real, ei: Real) -> Scene {
    Scene::from_toml(&format!(
        "[rod]\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 200.0\n\
         bending_stiffness = {ei}\ndamping = {alpha}\ncontrol_points = 12\n\
         start = [0.0, 0.0, 0.0]\nend = [1.0, 0.0, 0.0]\n\n[[pins]]\nat = 0.0\n\n\
         [world]\ngravity = [0.0, -9.81, 0.0]\n\n[solver]\nmethod = \"{method}\"\n\
         dt = 0.01\nduration = 2.0\ntolerance = 1e-13\n"
    ))
    .expect("scene")
}

/// Markers at s = 0.1 … 1.0 m every 0.1 s of the true run, σ = 0.1 mm.
fn markers(truth: &Scene) -> Vec<(Real, Real, Vector3<Real>, Real)> {
    let mut found = Vec::new();
    let mut step = 0;
    let mut observe = |view: &splinerod::sensitivity::StepView<'_>| {
        let (t, rod) = (view.t, view.rod);
        step += 1;
        if step % 10 == 0 {
            for k in 1..=10 {
                let s = k as Real / 10.0;
                let p = rod.point(s)?;
                let i = found.len();
                let noise = Vector3::from_fn(|c, _| 1e-4 * common::noise(7 * i + c));
                found.push((t, s, p + noise, 1e-4));
            }
        }
        Ok(())
    };
    observed_sensitivities(truth, &[], &mut observe).expect("the true run");
    found
}

#[test]
fn damping_and_bending_stiffness_are_recovered_from_a_trajectory() {
    for method in ["implicit-euler", "bdf2"] {
        let data = markers(&swinging(method, 0.3, 5e-3));
        let params = ["rod.damping", "rod.bending_stiffness"];
        let start = swinging(method, 0.6, 1e-2);
        let mut fit = RunFit::new(&start, &params, &data).expect("fit");
        let report = fit.fit().expect("fitted");
        println!(
            "{method}: damping {:.6} ± {:.1e}, EI {:.6e} ± {:.1e}, rms {:.3}, {} simulations",
            report.parameters[0],
            report.std[0],
            report.parameters[1],
            report.std[1],
            report.residual_rms,
            report.simulations
        );
        assert!(report.converged);
        // Asked: within 5 %; held to the static fits' 2 % and 3 reported σ.
        common::recovered(&report, &params, &[0.3, 5e-3]);
    }
}

#[test]
fn a_runs_jacobian_matches_differences_of_runs() {
    let truth = swinging("implicit-euler", 0.3, 5e-3);
    let data = markers(&truth);
    let params = ["rod.damping", "rod.bending_stiffness"];
    let p = [0.3, 5e-3];
    let mut fit = RunFit::new(&truth, &params, &data).expect("fit");
    let m = fit.residual_count();
    for k in 0..2 {
        let (worst, largest) = jacobian_error(&mut fit, &p, k, 1e-4, 0..m);
        println!("{}: worst {worst:.3e} of {largest:.3e}", params[k]);
        assert!(
            worst < 1e-4 * largest,
            "{}: {worst} of {largest}",
            params[k]
        );
    }
}

#[test]
fn a_runs_rest_length_column_matches_differences_of_runs() {
    // Markers in metres slide along the rescaled rod: the column has −(s/L) C'(s)
    // besides the forward sensitivities'. Evaluated at L = 0.995 m (the cable starts a
    // little stretched between its pin and its given end), markers up to 0.9 m.
    let truth = swinging("implicit-euler", 0.3, 5e-3);
    let data: Vec<_> = markers(&truth).into_iter().filter(|m| m.1 <= 0.9).collect();
    let params = ["rod.rest_length"];
    let mut fit = RunFit::new(&truth, &params, &data).expect("fit");
    let m = fit.residual_count();
    let (worst, largest) = jacobian_error(&mut fit, &[0.995], 0, 1e-5, 0..m);
    println!("rod.rest_length: worst {worst:.3e} of {largest:.3e}");
    assert!(worst < 1e-5 * largest, "{worst} of {largest}");
}

/// The largest difference between column `k` of `fit`'s Jacobian at `p` and central
/// differences of its residuals at the relative step `step`, over the residuals `rows`,
/// and the largest difference quotient there.
fn jacobian_error(
    fit: &mut RunFit<'_>,
    p: &[Real],
    k: usize,
    step: Real,
    rows: std::ops::Range<usize>,
) -> (Real, Real) {
    let (m, n) = (fit.residual_count(), p.len());
    let (mut r, mut j) = (vec![0.0; m], vec![0.0; n * m]);
    fit.evaluate(p, &mut r, Some(&mut j)).expect("evaluated");
    let h = step * p[k];
    let mut residuals = |v: Real| {
        let mut q = p.to_vec();
        q[k] = v;
        let mut out = vec![0.0; m];
        fit.evaluate(&q, &mut out, None).expect("run");
        out
    };
    let (up, down) = (residuals(p[k] + h), residuals(p[k] - h));
    let (mut worst, mut largest) = (0.0 as Real, 0.0 as Real);
    for i in rows {
        let fd = (up[i] - down[i]) / (2.0 * h);
        worst = worst.max((j[i * n + k] - fd).abs());
        largest = largest.max(fd.abs());
    }
    (worst, largest)
}

#[test]
fn a_runs_markers_must_fall_on_step_ends() {
    let scene = swinging("implicit-euler", 0.3, 5e-3);
    let params = ["rod.damping"];
    for t in [0.015, 0.0, 2.5] {
        let marker = [(t, 0.5, Vector3::zeros(), 1e-4)];
        let e = RunFit::new(&scene, &params, &marker)
            .err()
            .expect("refused");
        assert!(e.to_string().contains("observations.t"), "{e}");
    }
    // A scheme without forward sensitivities: the run is refused, naming the field.
    let midpoint = swinging("implicit-midpoint", 0.3, 5e-3);
    let marker = [(0.5, 0.5, Vector3::zeros(), 1e-4)];
    let mut fit = RunFit::new(&midpoint, &params, &marker).expect("markers fit the run");
    let (mut r, mut j) = ([0.0; 3], [0.0; 3]);
    let e = fit
        .evaluate(&[0.3], &mut r, Some(&mut j))
        .expect_err("refused");
    assert!(e.to_string().contains("solver.method"), "{e}");
}

#[test]
fn a_run_is_fitted_from_a_marker_file_and_refuses_other_observations() {
    use splinerod::fit::ObservationFile;
    let data = markers(&swinging("bdf2", 0.3, 5e-3));
    let mut csv = String::from("t,s,x,y,z,sigma\n");
    for (t, s, p, sigma) in &data {
        csv += &format!("{t},{s},{},{},{},{sigma}\n", p.x, p.y, p.z);
    }
    let file = ObservationFile::parse("trajectory.csv", &csv).expect("markers");
    let start = swinging("bdf2", 0.6, 1e-2);
    let params = ["rod.damping", "rod.bending_stiffness"];
    let fitted = splinerod::fit::command::fit_scene(&start, &[file], &params).expect("fitted");
    assert!((fitted.report.parameters[0] / 0.3 - 1.0).abs() < 0.05);
    assert!((fitted.report.parameters[1] / 5e-3 - 1.0).abs() < 0.05);
    // A static row (no time) is no observation of a run: named with its file.
    let static_row = ObservationFile::parse("still.csv", "t,s,x,y,z\n,0.5,0.1,0.2,0.0\n").unwrap();
    let e = splinerod::fit::command::fit_scene(&start, &[static_row], &params).err();
    assert!(e.expect("refused").to_string().contains("still.csv"));
}

#[test]
fn damping_and_bending_stiffness_are_recovered_from_unlabelled_points_of_a_run() {
    use splinerod::fit::synthetic::noisy_run_points;
    for method in ["implicit-euler", "bdf2"] {
        // 10 points every 0.1 s at unknown material coordinates, σ = 0.1 mm.
        let truth = swinging(method, 0.3, 5e-3);
        let cloud = noisy_run_points(&truth, (10, 10), 1e-4, 11).expect("points");
        let params = ["rod.damping", "rod.bending_stiffness"];
        let start = swinging(method, 0.6, 1e-2);
        let fitted = splinerod::fit::command::fit_scene(&start, &[cloud], &params).expect("fit");
        let report = &fitted.report;
        println!("{method}, points: {}", described(report, &params));
        assert!(report.converged);
        common::recovered(report, &params, &[0.3, 5e-3]);
    }
}

#[test]
fn the_pin_s_measured_force_separates_the_density_in_a_run() {
    use splinerod::fit::synthetic::{noisy_run_pin_forces, noisy_run_points};
    // EA, EI and μ scaled together leave the trajectory as it is (the damping is
    // mass-proportional): the shape sees EA/μ and EI/μ, the pin's force the scale.
    let truth = |mu: Real, ea: Real, ei: Real| {
        let mut s = swinging("bdf2", 0.3, ei);
        s.rod.linear_density = mu;
        s.rod.stretch_stiffness = ea;
        s
    };
    let params = [
        "rod.linear_density",
        "rod.stretch_stiffness",
        "rod.bending_stiffness",
    ];
    let real = truth(0.1, 200.0, 5e-3);
    let cloud = noisy_run_points(&real, (10, 10), 1e-4, 5).expect("points");
    let start = truth(0.15, 250.0, 1e-2);
    let shape = splinerod::fit::command::fit_scene(&start, std::slice::from_ref(&cloud), &params)
        .expect("fit");
    println!(
        "points alone: unidentifiable {:?}",
        shape.report.unidentifiable
    );
    assert_eq!(shape.report.unidentifiable.len(), 1);
    assert_eq!(shape.report.unidentifiable[0].0, vec![0, 1, 2]);
    // The pin's force every 0.1 s (σ = 1 mN) beside the points: all three.
    let force = noisy_run_pin_forces(&real, 0, 10, 1e-3, 6).expect("forces");
    let fitted = splinerod::fit::command::fit_scene(&start, &[cloud, force], &params).expect("fit");
    let report = &fitted.report;
    println!("points and pin force: {}", described(report, &params));
    assert!(report.converged && report.unidentifiable.is_empty());
    common::recovered(report, &params, &[0.1, 200.0, 5e-3]);
}

#[test]
fn a_runs_jacobian_of_points_and_pin_forces_matches_differences_of_runs() {
    use splinerod::fit::run_fit::Observed;
    use splinerod::fit::synthetic::{noisy_run_pin_forces, noisy_run_points};
    let truth = swinging("implicit-euler", 0.3, 5e-3);
    let cloud = noisy_run_points(&truth, (25, 6), 1e-4, 3).expect("points");
    let force = noisy_run_pin_forces(&truth, 0, 25, 1e-3, 4).expect("forces");
    let rows = cloud.rows.iter().chain(&force.rows).map(|o| {
        let what = o.pin.map_or(Observed::Point, Observed::PinForce);
        (o.t.unwrap(), what, Vector3::from(o.value), o.sigma)
    });
    let params = ["rod.linear_density", "rod.damping"];
    let p = [0.1, 0.3];
    let mut fit = RunFit::observed(&truth, &params, rows).expect("fit");
    let m = fit.residual_count();
    assert_eq!(m, cloud.rows.len() + 3 * force.rows.len());
    // A relative step of 1e-6: a point's distance (~σ = 0.1 mm) is not smooth where it
    // vanishes, and larger steps move the curve by a fair part of it. Points' rows,
    // then the forces': each against its own largest derivative.
    for k in 0..2 {
        for (part, rows) in [(0, 0..cloud.rows.len()), (1, cloud.rows.len()..m)] {
            let (worst, largest) = jacobian_error(&mut fit, &p, k, 1e-6, rows);
            let what = ["points", "pin forces"][part];
            println!("{} ({what}): worst {worst:.3e} of {largest:.3e}", params[k]);
            assert!(
                worst < 1e-4 * largest,
                "{}: {worst} of {largest}",
                params[k]
            );
        }
    }
    let bad = [(0.5, Observed::PinForce(3), Vector3::zeros(), 1e-3)];
    let e = RunFit::observed(&truth, &params, bad)
        .err()
        .expect("refused");
    assert!(e.to_string().contains("observations.pin"), "{e}");
}

/// A fit's parameters with their standard deviations, residual and runs, on one line.
fn described(report: &splinerod::fit::FitReport, params: &[&str]) -> String {
    let values = params.iter().enumerate().map(|(k, name)| {
        let (p, s) = (report.parameters[k], report.std[k]);
        format!("{name} {p:.6e} ± {s:.1e}")
    });
    let values: Vec<String> = values.collect();
    format!(
        "{}, rms {:.3}, {} runs",
        values.join(", "),
        report.residual_rms,
        report.simulations
    )
}
