//! The hard-case suite: scenes chosen to break a time stepper or a static solver — stiff
//! and feather-light rods, extreme scales, every degree, violent starts, long steps on
//! large rods, contact — each of which must run with every step converged.
//!
//! `tests/hard_cases.rs` runs them with their reference checks (small-dt references,
//! exact scaling, static equilibria); `splinerod bench` reports how many converge
//! (`hard_cases_converged`). A case is a scene; most are variations of one cable:
//! L = 1 m, μ = 0.1 kg/m, EA = 100 N, 16 cubic control points, released straight between
//! pins 0.8 m apart under gravity.

use crate::{Error, RunResult, Scene};

/// One case of the suite.
#[derive(Debug, Clone)]
pub struct HardCase {
    /// Short unique name.
    pub name: String,
    /// The scene to run.
    pub scene: Scene,
}

/// Parameters of the cable the cases vary.
#[derive(Debug, Clone, PartialEq)]
pub struct Cable {
    /// Rest length, m.
    pub length: f64,
    /// Distance between the end pins, m (the rod starts straight between them).
    pub span: f64,
    /// Linear density, kg/m.
    pub density: f64,
    /// Axial stiffness, N.
    pub ea: f64,
    /// Bending stiffness, N·m² (`None`: none).
    pub ei: Option<f64>,
    /// Control points.
    pub control_points: usize,
    /// Degree.
    pub degree: usize,
    /// Mass-proportional damping, 1/s.
    pub damping: f64,
    /// `"implicit-euler"`, `"implicit-midpoint"`, `"bdf2"` or `"static"`.
    pub method: &'static str,
    /// Time step, s.
    pub dt: f64,
    /// Duration, s.
    pub duration: f64,
    /// Pin the far end too.
    pub pin_both: bool,
    /// Clamp the first pin (needs bending).
    pub clamp: bool,
    /// Rod radius, m (needed by contact).
    pub radius: Option<f64>,
    /// Gravity along −y, m/s².
    pub gravity: f64,
    /// `rod.stretch_formulation` (`None`: the default, `"auto"`).
    pub stretch_formulation: Option<&'static str>,
    /// Extra TOML appended to the scene (grabs, contact, ...).
    pub extra: String,
}

impl Default for Cable {
    fn default() -> Self {
        Self {
            length: 1.0,
            span: 0.8,
            density: 0.1,
            ea: 100.0,
            ei: None,
            control_points: 16,
            degree: 3,
            damping: 0.0,
            method: "implicit-euler",
            dt: 0.01,
            duration: 0.5,
            pin_both: true,
            clamp: false,
            radius: None,
            gravity: 9.81,
            stretch_formulation: None,
            extra: String::new(),
        }
    }
}

impl Cable {
    /// The scene of this cable (gravity 9.81 m/s² along −y, 41 samples).
    pub fn scene(&self) -> Result<Scene, Error> {
        Scene::from_toml(&self.toml())
    }

    /// The scene file of this cable.
    pub fn toml(&self) -> String {
        let bending = self
            .ei
            .map_or(String::new(), |ei| format!("bending_stiffness = {ei:e}\n"));
        let radius = self
            .radius
            .map_or(String::new(), |r| format!("radius = {r:e}\n"));
        let clamp = if self.clamp { "clamp = true\n" } else { "" };
        let form = self.stretch_formulation.map_or(String::new(), |f| {
            format!("stretch_formulation = \"{f}\"\n")
        });
        let far_pin = if self.pin_both {
            "[[pins]]\nat = 1.0\n"
        } else {
            ""
        };
        let timing = if self.method == "static" {
            String::new()
        } else {
            format!("dt = {:e}\nduration = {:e}\n", self.dt, self.duration)
        };
        format!(
            "[rod]\nrest_length = {l:e}\nlinear_density = {mu:e}\nstretch_stiffness = {ea:e}\n\
             {form}{bending}{radius}damping = {damping:e}\ncontrol_points = {n}\ndegree = {degree}\n\
             start = [0.0, 0.0, 0.0]\nend = [{span:e}, 0.0, 0.0]\n\n[[pins]]\nat = 0.0\n{clamp}{far_pin}\n\
             [world]\ngravity = [0.0, {g:e}, 0.0]\n\n[solver]\nmethod = \"{method}\"\n{timing}\n\
             [output]\nsamples = 41\n{extra}",
            l = self.length,
            mu = self.density,
            ea = self.ea,
            damping = self.damping,
            n = self.control_points,
            degree = self.degree,
            span = self.span,
            method = self.method,
            g = -self.gravity,
            extra = self.extra,
        )
    }

    /// This cable as a named case.
    pub fn case(&self, name: impl Into<String>) -> Result<HardCase, Error> {
        Ok(HardCase {
            name: name.into(),
            scene: self.scene()?,
        })
    }
}

/// The issue #44 rod: 1 m, μ = 0.1 kg/m, EA = 100 N, bending `ei`, 16 points, no
/// gravity, released straight between pins `1 − compression` metres apart (compressed
/// by that fraction), stepped by `method` at `dt` for 0.5 s.
pub fn compressed_rod(ei: f64, compression: f64, method: &'static str, dt: f64) -> Cable {
    Cable {
        span: 1.0 - compression,
        ei: Some(ei),
        gravity: 0.0,
        method,
        dt,
        ..Cable::default()
    }
}

/// The cable `c` scaled to length `λ·L` so that its motion is the same up to units:
/// lengths ×λ, times ×√λ (gravity fixed), so EA ×λ (tension ∝ μ g L) and dt ×√λ.
pub fn scaled(c: &Cable, lambda: f64) -> Cable {
    Cable {
        length: c.length * lambda,
        span: c.span * lambda,
        ea: c.ea * lambda,
        ei: c.ei.map(|ei| ei * lambda * lambda),
        dt: c.dt * lambda.sqrt(),
        duration: c.duration * lambda.sqrt(),
        damping: c.damping / lambda.sqrt(),
        ..c.clone()
    }
}

/// Every case of the suite (at least 25), in a fixed order.
pub fn hard_cases() -> Result<Vec<HardCase>, Error> {
    let base = Cable::default();
    let whip = Cable {
        pin_both: false,
        span: 1.0,
        damping: 0.5,
        dt: 0.01,
        duration: 0.6,
        extra: WHIP.into(),
        ..base.clone()
    };
    let mut cases = vec![
        Cable {
            ea: 1e7,
            duration: 2.0,
            ..base.clone()
        }
        .case("stiff EA 1e7, dt 10 ms")?,
        Cable {
            density: 1e-6,
            duration: 2.0,
            ..base.clone()
        }
        .case("feather-light mu 1e-6")?,
        scaled(
            &Cable {
                dt: 0.01,
                ..base.clone()
            },
            1e-3,
        )
        .case("1 mm rod")?,
        scaled(&base, 1e3).case("1 km rod")?,
        Cable {
            control_points: 1000,
            duration: 0.2,
            ..base.clone()
        }
        .case("1000 control points")?,
        Cable {
            method: "implicit-midpoint",
            dt: 0.02,
            duration: 1.0,
            ..base.clone()
        }
        .case("midpoint dt 20 ms")?,
        Cable {
            ea: 1e9,
            dt: 0.05,
            duration: 1.0,
            ..base.clone()
        }
        .case("EA 1e9, dt 50 ms")?,
        // A nylon suture: E = 750 MPa, r = 0.2 mm, 1140 kg/m³ (EA = Eπr², μ = ρπr²).
        Cable {
            length: 0.3,
            span: 0.24,
            density: 1140.0 * std::f64::consts::PI * 4e-8,
            ea: 750e6 * std::f64::consts::PI * 4e-8,
            damping: 30.0,
            dt: 1e-3,
            duration: 0.5,
            ..base.clone()
        }
        .case("hanging nylon suture, dt 1 ms")?,
        Cable {
            ea: 1e9,
            dt: 0.05,
            duration: 1.0,
            method: "bdf2",
            ..base.clone()
        }
        .case("EA 1e9, BDF2 dt 50 ms")?,
        Cable {
            density: 1e-8,
            ea: 0.1,
            dt: 0.05,
            ..base.clone()
        }
        .case("silk-like mu 1e-8, EA 0.1 N")?,
        Cable {
            degree: 1,
            ..base.clone()
        }
        .case("degree 1")?,
        Cable {
            degree: 2,
            ..base.clone()
        }
        .case("degree 2")?,
        Cable {
            degree: 4,
            ei: Some(1e-3),
            ..base.clone()
        }
        .case("degree 4 with bending")?,
        Cable {
            degree: 5,
            ei: Some(1e-3),
            ..base.clone()
        }
        .case("degree 5 with bending")?,
        Cable {
            degree: 1,
            control_points: 2,
            pin_both: false,
            span: 1.0,
            ..base.clone()
        }
        .case("2 control points, pendulum")?,
        Cable {
            span: 0.1,
            ..base.clone()
        }
        .case("compressed to 10 %")?,
        Cable {
            span: 3.0,
            ..base.clone()
        }
        .case("stretched to 3x")?,
        compressed_rod(10.0, 0.2, "implicit-euler", 0.01).case("bending, compressed 20 %")?,
        compressed_rod(0.1, 0.9, "bdf2", 0.05).case("bending, compressed 90 %, BDF2 dt 50 ms")?,
        compressed_rod(50.0, 0.5, "implicit-midpoint", 0.001)
            .case("stiff bending, compressed 50 %, midpoint")?,
        Cable {
            span: 0.25,
            ea: 4e7,
            control_points: 32,
            method: "static",
            ..base.clone()
        }
        .case("static EA 4e7 from 75 % compressed")?,
        Cable {
            control_points: 10_000,
            duration: 0.02,
            ..base.clone()
        }
        .case("10000 control points")?,
        Cable {
            dt: 0.05,
            duration: 1.0,
            ..base.clone()
        }
        .case("implicit Euler dt 50 ms")?,
        Cable {
            method: "implicit-midpoint",
            dt: 0.05,
            duration: 1.0,
            ..base.clone()
        }
        .case("midpoint dt 50 ms")?,
        Cable {
            method: "bdf2",
            dt: 0.05,
            duration: 1.0,
            ..base.clone()
        }
        .case("BDF2 dt 50 ms")?,
        Cable {
            method: "static",
            ea: 1e7,
            ..base.clone()
        }
        .case("static EA 1e7 from straight")?,
        Cable {
            method: "static",
            span: 0.1,
            ..base.clone()
        }
        .case("static from 10 % compressed")?,
        Cable {
            method: "static",
            ea: 1e5,
            span: 0.2,
            control_points: 24,
            ..base.clone()
        }
        .case("static stiff from 20 % compressed")?,
        Cable {
            ea: 1e4,
            ei: Some(1.0),
            pin_both: false,
            span: 1.0,
            dt: 0.05,
            clamp: true,
            ..base.clone()
        }
        .case("cantilever, bending-dominated, dt 50 ms")?,
        Cable {
            method: "static",
            ea: 1e6,
            ei: Some(0.1),
            pin_both: false,
            span: 1.0,
            clamp: true,
            ..base.clone()
        }
        .case("static cantilever EA 1e6")?,
        whip.case("40 m/s whip")?,
        Cable {
            method: "implicit-midpoint",
            ..whip.clone()
        }
        .case("40 m/s whip, midpoint")?,
        Cable {
            control_points: 12,
            pin_both: false,
            span: 1.0,
            damping: 0.5,
            dt: 0.02,
            duration: 1.0,
            radius: Some(0.01),
            extra: FLOOR.into(),
            ..base.clone()
        }
        .case("contact with a floor, dt 20 ms")?,
    ];
    cases.push(folded_static()?);
    Ok(cases)
}

/// A grab dragging the free end sideways by 2 m in 50 ms (40 m/s), then holding it.
const WHIP: &str = "\n[[grabs]]\nat = 1.0\nto = [1.0, 2.0, 0.0]\nstart_time = 0.0\n\
                    end_time = 0.05\nstiffness = 1e4\n";

/// A floor 0.3 m below the pin, rod radius 1 cm.
const FLOOR: &str = "\n[contact]\nstiffness = 1e5\nfloor = -0.3\n";

/// A static solve from a rod folded back on itself: the control points run out to
/// 1.1 m and back to the far pin at 0.8 m (the base cable's pins).
fn folded_static() -> Result<HardCase, Error> {
    let n = 16;
    let points: Vec<String> = (0..n)
        .map(|i| {
            let f = i as f64 / (n - 1) as f64;
            let x = if f < 0.5 {
                2.2 * f
            } else {
                1.1 - 0.6 * (f - 0.5)
            };
            format!(
                "[{x:e}, {:e}, 0.0]",
                0.05 * (f * std::f64::consts::TAU).sin()
            )
        })
        .collect();
    let text = format!(
        "[rod]\nrest_length = 1.0\nlinear_density = 0.1\nstretch_stiffness = 100.0\n\
         control_points = {n}\ninitial_control_points = [{}]\n\n[[pins]]\nat = 0.0\n\n\
         [[pins]]\nat = 1.0\n\n[world]\ngravity = [0.0, -9.81, 0.0]\n\n[solver]\n\
         method = \"static\"\n\n[output]\nsamples = 41\n",
        points.join(", ")
    );
    Ok(HardCase {
        name: "static from a fold".into(),
        scene: Scene::from_toml(&text)?,
    })
}

/// Whether a run converged everywhere: no unconverged step and finite end samples.
pub fn converged(result: &RunResult) -> bool {
    result.solver.unconverged_steps == 0
        && result
            .samples
            .positions
            .iter()
            .all(|p| p.iter().all(|c| c.is_finite()))
}

/// Runs every case and counts those that finish with [`converged`] results.
pub fn count_converged() -> Result<usize, Error> {
    let cases = hard_cases()?;
    Ok(cases
        .iter()
        .filter(|c| crate::run(&c.scene).is_ok_and(|r| converged(&r)))
        .count())
}
