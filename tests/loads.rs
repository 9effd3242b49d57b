//! Point loads: a static rod carries its end load to its pin exactly, bad `[[loads]]`
//! are refused naming the field, and the capstan law: a rope over a capsule, loaded at
//! both ends, slips when the load ratio passes e^{μθ} (θ = π here).

use crate::common;

use common::{assert_field, rejected};
use nalgebra::Vector3;
use splinerod::{run, run_observed, Error, Frame, Observer, Scene, StepReport};

const HANGING: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 10
end = [0.0, -1.0, 0.0]

[[pins]]
at = 0.0

[[loads]]
at = 1.0
force = [0.3, -2.0, 0.1]

[solver]
method = "static"
"#;

#[test]
fn a_static_rod_carries_its_end_load_to_the_pin() {
    let result = run(&Scene::from_toml(HANGING).expect("scene")).expect("runs");
    // The rod pulls its pin with its weight (0.981 N down) plus the load.
    let expected = Vector3::new(0.3, -2.0 - 0.981, 0.1);
    let pin = Vector3::from(result.pin_forces[0]);
    assert!((pin - expected).norm() < 1e-9 * expected.norm(), "{pin:?}");
    assert!(result.energy.contains_key("load"));
}

#[test]
fn bad_loads_name_the_field() {
    let cases = [
        (
            "force = [0.3, -2.0, 0.1]",
            "force = [0.3, nan, 0.1]",
            "loads[0].force",
        ),
        ("at = 1.0\nforce", "at = 1.5\nforce", "loads[0].at"),
        ("force = [0.3, -2.0, 0.1]", "", "loads[0].force"),
        (
            "force = [0.3, -2.0, 0.1]",
            "force = [0.3, -2.0, 0.1]\npath = [[0.0, 0.0, -1.0, 0.0]]",
            "loads[0].force",
        ),
        (
            "force = [0.3, -2.0, 0.1]",
            "path = [[1.0, 0.0, -1.0, 0.0], [0.5, 0.0, -2.0, 0.0]]",
            "loads[0].path[1]",
        ),
    ];
    for (from, to, field) in cases {
        assert!(HANGING.contains(from), "{from}");
        assert_field(&rejected(&HANGING.replace(from, to)), field);
    }
}

/// The load ratio ramps from 1 at `T0` to 1.5 e^{μπ} at `T1`.
const T0: f64 = 1.5;
const T1: f64 = 7.5;

/// A light rope (no gravity) over a horizontal capsule of radius 5 cm, 1 N at one end,
/// a load ramping up at the other; friction `mu`.
fn capstan(mu: f64) -> Scene {
    let top = 1.5 * (mu * std::f64::consts::PI).exp();
    let text = format!(
        "[rod]\nrest_length = 1.0\nlinear_density = 0.01\nstretch_stiffness = 1000.0\n\
         bending_stiffness = 1e-6\ndamping = 5.0\ncontrol_points = 40\nradius = 0.005\n\
         start = [-0.5, 0.055, 0.0]\nend = [0.5, 0.055, 0.0]\n\
         [world]\ngravity = [0.0, 0.0, 0.0]\n\
         [contact]\nstiffness = 1e5\nfriction = {mu}\n\
         [[obstacles]]\nkind = \"capsule\"\na = [0.0, 0.0, -0.1]\nb = [0.0, 0.0, 0.1]\nradius = 0.05\n\
         [[loads]]\nat = 0.0\nforce = [0.0, -1.0, 0.0]\n\
         [[loads]]\nat = 1.0\npath = [[0.0, 0.0, -1.0, 0.0], [{T0}, 0.0, -1.0, 0.0], [{T1}, 0.0, -{top}, 0.0]]\n\
         [solver]\nmethod = \"implicit-euler\"\ndt = 0.002\nduration = {T1}\n"
    );
    Scene::from_toml(&text).expect("capstan scene")
}

/// Stops the run when the loaded end slides faster than 1 cm/s after the ramp began.
#[derive(Default)]
struct SlipWatch {
    last: Option<(f64, Vector3<f64>)>,
    slipped_at: Option<f64>,
}

impl Observer for SlipWatch {
    fn step(&mut self, frame: &Frame<'_>, _: &StepReport, _: f64) -> Result<(), Error> {
        let end = frame.system.rod.point(1.0)?;
        if let Some((t, before)) = self.last {
            let speed = (end - before).norm() / (frame.time - t);
            if frame.time > T0 + 0.2 && speed > 0.01 {
                self.slipped_at = Some(frame.time);
                return Err(Error::Stopped("the rope slipped".into()));
            }
        }
        self.last = Some((frame.time, end));
        Ok(())
    }
}

#[test]
fn a_rope_over_a_capsule_slips_at_the_capstan_ratio() {
    for mu in [0.1, 0.3, 0.5] {
        let threshold = (mu * std::f64::consts::PI).exp();
        let mut watch = SlipWatch::default();
        let outcome = run_observed(&capstan(mu), &mut [&mut watch]);
        assert!(
            matches!(outcome, Err(Error::Stopped(_))),
            "mu {mu}: no slip"
        );
        let t = watch.slipped_at.expect("slip time");
        let ratio = 1.0 + (1.5 * threshold - 1.0) * (t - T0) / (T1 - T0);
        let error = ratio / threshold - 1.0;
        eprintln!("mu {mu}: slips at ratio {ratio:.4}, capstan {threshold:.4} ({error:+.4})");
        assert!(error.abs() < 0.03, "mu {mu}: {ratio} against {threshold}");
    }
}
