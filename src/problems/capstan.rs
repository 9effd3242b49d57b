//! The capstan law at a full turn: a rope (radius 5 mm, 0.01 kg/m, EA = 1000 N, light
//! bending) wound once around a horizontal capsule (radius 5 cm) as a helix of wrap
//! θ = 2π, the outgoing strand beside the incoming one so the rope touches itself. One
//! end pulls 1 N, the other `ratio` N; with friction μ the rope holds while the ratio
//! stays below e^{μθ} = e^{2πμ} and slides above it. No gravity.
//!
//! The wrap is given as the least-squares fit of a clamped uniform cubic with the
//! requested number of control points to 400 points of the helix
//! (`initial_control_points`), which is also the rope's rest shape (`rest_shape =
//! "initial"`); a coarse fit overlapping the capsule is refined and pushed out when the
//! scene is built (#46). What is measured of a run ([`run`]): when the heavy end first
//! moves faster than 1 cm/s averaged over 0.1 s (it slips), the smallest clearance
//! ratio, the most rope–rope contact pairs and the control points at the start and at
//! the end. The tests (`tests/capstan_turn.rs`) and the report
//! (`crate::report::capstan`) run it.

use crate::{Error, Real, Scene};
use nalgebra::{DMatrix, Vector3};
use splinerod_core::{BSplineSpace, Material, Rod};
use std::collections::VecDeque;
use std::f64::consts::PI;
use std::time::Instant;

/// Capsule radius, m.
pub const CAPSULE_RADIUS: Real = 0.05;
/// Rope radius, m.
pub const ROPE_RADIUS: Real = 0.005;
/// Length of each straight lead, m.
pub const LEAD: Real = 0.3;
/// Time step of every run, s.
pub const DT: Real = 0.002;
/// End speed above which the rope slips, m/s.
pub const SLIP_SPEED: Real = 0.01;
/// The time over which the end's speed is averaged, s: long enough that a knot removal
/// (which may move the curve by the adapter's shape tolerance at once) and the creep of
/// the regularised friction stay below [`SLIP_SPEED`], short enough not to lag a slip.
pub const SPEED_WINDOW: Real = 0.1;

/// The capstan ratio e^{μθ} of a full turn (θ = 2π).
pub fn capstan_ratio(mu: Real) -> Real {
    (2.0 * PI * mu).exp()
}

/// The wrap: a straight lead along +x above the capsule, one helical turn around it
/// (radius ρ, rising 2δ along the axis), a straight lead on. Returns the point at
/// arclength `s` and the total length.
pub fn wrap(s: Real) -> (Vector3<Real>, Real) {
    let rho = CAPSULE_RADIUS + 1.3 * ROPE_RADIUS;
    let delta = 1.15 * ROPE_RADIUS;
    let rise = 2.0 * delta / (2.0 * PI);
    let c = (rho * rho + rise * rise).sqrt();
    let turn = 2.0 * PI * c;
    let total = 2.0 * LEAD + turn;
    let point = if s <= LEAD {
        Vector3::new(s - LEAD, rho, -delta)
    } else if s <= LEAD + turn {
        let phi = (s - LEAD) / c;
        Vector3::new(rho * phi.sin(), rho * phi.cos(), -delta + rise * phi)
    } else {
        Vector3::new(s - LEAD - turn, rho, delta)
    };
    (point, total)
}

/// One capstan run: the rope, the contact, the load on the heavy end, the duration.
#[derive(Debug, Clone, PartialEq)]
pub struct Turn {
    /// Friction coefficient.
    pub mu: Real,
    /// Control points of the fitted wrap.
    pub control_points: usize,
    /// `[contact] stiffness`, N/m; `None`: the barrier, no stiffness to guess.
    pub contact_stiffness: Option<Real>,
    /// The body of an `[adaptivity]` table (`Some("")`: the defaults); `None`: uniform.
    pub adaptivity: Option<String>,
    /// The heavy end's load ratio over time, keyframes `[t, ratio]` (s, –), linear
    /// between them and held after the last; one keyframe: held from the start.
    pub ratio: Vec<[Real; 2]>,
    /// Simulated time, s.
    pub duration: Real,
}

impl Turn {
    /// The load ratio at time `t`.
    pub fn ratio_at(&self, t: Real) -> Real {
        let k = &self.ratio;
        match k.iter().position(|p| p[0] > t) {
            Some(0) => k[0][1],
            Some(i) => {
                let (a, b) = (k[i - 1], k[i]);
                a[1] + (b[1] - a[1]) * (t - a[0]) / (b[0] - a[0])
            }
            None => k.last().map_or(Real::NAN, |p| p[1]),
        }
    }

    /// The scene's TOML.
    pub fn scene_text(&self) -> Result<String, Error> {
        let total = wrap(0.0).1;
        let points = fitted_wrap(self.control_points)?;
        let points: Vec<String> = points
            .iter()
            .map(|q| format!("[{}, {}, {}]", q.x, q.y, q.z))
            .collect();
        let stiffness = self
            .contact_stiffness
            .map_or(String::new(), |k| format!("stiffness = {k}\n"));
        let heavy = match self.ratio.as_slice() {
            [] => return Err(Error::study("capstan", "no load ratio")),
            [[_, r]] => format!("force = [{r}, 0.0, 0.0]"),
            keys => {
                let path: Vec<String> = keys
                    .iter()
                    .map(|[t, r]| format!("[{t}, {r}, 0.0, 0.0]"))
                    .collect();
                format!("path = [{}]", path.join(", "))
            }
        };
        let adaptivity = self
            .adaptivity
            .as_ref()
            .map_or(String::new(), |a| format!("[adaptivity]\n{a}\n"));
        Ok(format!(
            "[rod]\nrest_length = {total}\nlinear_density = 0.01\nstretch_stiffness = 1000.0\n\
             bending_stiffness = 1e-6\ndamping = 5.0\ncontrol_points = {n}\n\
             radius = {ROPE_RADIUS}\nrest_shape = \"initial\"\ninitial_control_points = [{p}]\n\
             [world]\ngravity = [0.0, 0.0, 0.0]\n\
             [contact]\n{stiffness}friction = {mu}\n\
             [[obstacles]]\nkind = \"capsule\"\na = [0.0, 0.0, -0.1]\nb = [0.0, 0.0, 0.1]\n\
             radius = {CAPSULE_RADIUS}\n\
             [[loads]]\nat = 0.0\nforce = [-1.0, 0.0, 0.0]\n\
             [[loads]]\nat = 1.0\n{heavy}\n\
             [solver]\nmethod = \"implicit-euler\"\ndt = {DT}\nduration = {d}\n{adaptivity}",
            n = self.control_points,
            p = points.join(", "),
            mu = self.mu,
            d = self.duration,
        ))
    }

    /// The scene.
    pub fn scene(&self) -> Result<Scene, Error> {
        Scene::from_toml(&self.scene_text()?)
    }
}

/// Control points of the clamped uniform cubic with `n` control points closest (least
/// squares over 400 points) to the wrap.
pub fn fitted_wrap(n: usize) -> Result<Vec<Vector3<Real>>, Error> {
    let total = wrap(0.0).1;
    let basis = BSplineSpace::clamped_uniform(3, n, total)?;
    let material = Material {
        rest_length: total,
        linear_density: 0.01,
    };
    let x = Vector3::x() * total;
    let rod = Rod::straight(material, Box::new(basis), Vector3::zeros(), x)?;
    let (mut a, mut rhs) = (DMatrix::<Real>::zeros(n, n), DMatrix::<Real>::zeros(n, 3));
    for j in 0..400 {
        let s = total * (j as Real + 0.5) / 400.0;
        let b = rod.basis_at(s)?;
        let p = wrap(s).0;
        for i in 0..b.order {
            for k in 0..b.order {
                a[(b.first + i, b.first + k)] += b.value[i] * b.value[k];
            }
            for c in 0..3 {
                rhs[(b.first + i, c)] += b.value[i] * p[c];
            }
        }
    }
    let q = a
        .lu()
        .solve(&rhs)
        .ok_or_else(|| Error::study("capstan", "singular least-squares fit"))?;
    Ok((0..n)
        .map(|i| Vector3::new(q[(i, 0)], q[(i, 1)], q[(i, 2)]))
        .collect())
}

/// What one run of a [`Turn`] showed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TurnRun {
    /// The first time after the watch began at which the heavy end's speed, averaged
    /// over the last [`SPEED_WINDOW`], passed [`SLIP_SPEED`] (the run stops there);
    /// `None`: it held to the end.
    pub slip_time: Option<Real>,
    /// Control points after the scene was built (a coarse start refined).
    pub start_points: usize,
    /// Control points at the end.
    pub end_points: usize,
    /// Smallest clearance ratio seen (contact distance over its reach; below 1:
    /// overlap).
    pub clearance: Real,
    /// Most rope–rope contact pairs at once.
    pub pairs: usize,
    /// Wall time of the stepping, s.
    pub wall_seconds: Real,
}

/// Runs `turn`, watching the heavy end's speed from time `watch_from` on; stops at the
/// first slip.
pub fn run(turn: &Turn, watch_from: Real) -> Result<TurnRun, Error> {
    let mut sim = turn.scene()?.build()?;
    let start_points = sim.system.rod.len();
    let l = sim.system.rod.material().rest_length;
    let (mut clearance, mut pairs) = (Real::INFINITY, 0);
    let mut slip_time = None;
    // The end's positions over the last `SPEED_WINDOW`, oldest first.
    let window = (SPEED_WINDOW / DT).round() as usize;
    let mut ends = VecDeque::from([sim.system.rod.point(l)?]);
    let clock = Instant::now();
    while sim.time < turn.duration - 1e-9 {
        let report = sim.step(DT)?;
        if let Some(c) = report.energies.contact {
            clearance = clearance.min(c.min_clearance_ratio.unwrap_or(Real::INFINITY));
            pairs = pairs.max(c.pairs);
        }
        ends.push_back(sim.system.rod.point(l)?);
        if ends.len() > window + 1 {
            ends.pop_front();
        }
        let span = (ends.len() - 1) as Real * DT;
        let speed = (ends[ends.len() - 1] - ends[0]).norm() / span;
        if sim.time > watch_from && speed > SLIP_SPEED {
            slip_time = Some(sim.time);
            break;
        }
    }
    Ok(TurnRun {
        slip_time,
        start_points,
        end_points: sim.system.rod.len(),
        clearance,
        pairs,
        wall_seconds: clock.elapsed().as_secs_f64(),
    })
}
