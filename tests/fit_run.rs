//! Identification from a trajectory (#48): a damped cable swinging from a pin for 2 s,
//! observed by 10 markers every 0.1 s with 0.1 mm of noise; its damping and bending
//! stiffness are fitted through the run's forward sensitivities, with implicit Euler and
//! with BDF2.

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
    let mut observe = |t: Real, rod: &splinerod::Rod, _: &[_]| {
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
    let (mut r, mut j) = (vec![0.0; m], vec![0.0; 2 * m]);
    fit.evaluate(&p, &mut r, Some(&mut j)).expect("evaluated");
    for k in 0..2 {
        let h = 1e-4 * p[k];
        let mut residuals = |v: Real| {
            let mut q = p;
            q[k] = v;
            let mut out = vec![0.0; m];
            fit.evaluate(&q, &mut out, None).expect("run");
            out
        };
        let (up, down) = (residuals(p[k] + h), residuals(p[k] - h));
        let (mut worst, mut largest) = (0.0 as Real, 0.0 as Real);
        for i in 0..m {
            let fd = (up[i] - down[i]) / (2.0 * h);
            worst = worst.max((j[i * 2 + k] - fd).abs());
            largest = largest.max(fd.abs());
        }
        println!("{}: worst {worst:.3e} of {largest:.3e}", params[k]);
        assert!(
            worst < 1e-4 * largest,
            "{}: {worst} of {largest}",
            params[k]
        );
    }
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
    // Unlabelled points and static rows are not observations of a run (yet): named.
    let points = ObservationFile::parse("cloud.csv", "t,x,y,z\n0.5,0.1,0.2,0.0\n").unwrap();
    let e = splinerod::fit::command::fit_scene(&start, &[points], &params).err();
    assert!(e.expect("refused").to_string().contains("cloud.csv"));
    let static_row = ObservationFile::parse("still.csv", "t,s,x,y,z\n,0.5,0.1,0.2,0.0\n").unwrap();
    let e = splinerod::fit::command::fit_scene(&start, &[static_row], &params).err();
    assert!(e.expect("refused").to_string().contains("still.csv"));
}
