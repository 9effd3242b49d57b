//! Contact without a stiffness to guess (#46): with `[contact]` and no `stiffness`, a
//! rope resting on a plane, on a sphere and on another rope sits at `r` (`r₁ + r₂`)
//! within the gap tolerance (default and given, several radii, densities and
//! stiffnesses), and every bundled contact scene with its `stiffness` removed keeps its
//! clearance (≥ 0.95 of the contact distance) and ends with no contact deeper than the
//! tolerance. Figures: `cargo test --release --test integration contact_tolerance:: -- --nocapture`.

use nalgebra::Vector3;
use splinerod::{Real, Scene, Simulation};

/// A rope: radius, linear density, EA, EI.
#[derive(Clone, Copy, Debug)]
struct Rope {
    r: Real,
    rho: Real,
    ea: Real,
    ei: Real,
}

const ROPES: [Rope; 3] = [
    Rope {
        r: 0.005,
        rho: 0.1,
        ea: 500.0,
        ei: 1e-5,
    },
    Rope {
        r: 0.01,
        rho: 0.5,
        ea: 2000.0,
        ei: 1e-4,
    },
    Rope {
        r: 0.002,
        rho: 0.02,
        ea: 100.0,
        ei: 1e-7,
    },
];

fn rod_table(rope: &Rope, length: Real, start: [Real; 3], end: [Real; 3]) -> String {
    format!(
        "rest_length = {length}\nlinear_density = {}\nstretch_stiffness = {}\n\
         bending_stiffness = {}\ndamping = 5.0\ncontrol_points = 16\nradius = {}\n\
         start = {start:?}\nend = {end:?}\n",
        rope.rho, rope.ea, rope.ei, rope.r
    )
}

/// `[contact]` with an optional `tolerance` line, and friction `mu`.
fn contact_table(tolerance: Option<Real>, mu: Real) -> String {
    let t = tolerance.map_or(String::new(), |t| format!("tolerance = {t}\n"));
    format!("[contact]\nfriction = {mu}\n{t}")
}

fn settle(text: &str, duration: Real) -> Simulation {
    let scene = Scene::from_toml(text).expect("scene");
    let mut sim = scene.build().expect("simulation");
    let dt = 0.005;
    while sim.time < duration - 1e-9 {
        sim.step(dt).expect("step");
    }
    assert!(
        sim.system.rod.kinetic_energy() < 1e-6,
        "not at rest: {} J",
        sim.system.rod.kinetic_energy()
    );
    sim
}

/// The tolerance the run used (the default or the given one).
fn tolerance_of(sim: &Simulation) -> Real {
    let c = sim
        .system
        .summary()
        .expect("summary")
        .contact
        .expect("contact");
    c.tolerance.expect("a tolerance")
}

/// Points of the rod every 1 % of its parameter range.
fn points(sim: &Simulation) -> Vec<Vector3<Real>> {
    let rod = &sim.system.rod;
    let l = rod.material().rest_length;
    (0..=100)
        .map(|k| rod.point(l * k as Real / 100.0).expect("point"))
        .collect()
}

#[test]
fn a_rope_on_a_plane_rests_at_its_radius_within_the_tolerance() {
    for (k, rope) in ROPES.iter().enumerate() {
        for given in [None, Some(0.02 * rope.r)] {
            let y = 1.3 * rope.r;
            let text = format!(
                "[rod]\n{}\n{}\n[[obstacles]]\nkind = \"plane\"\npoint = [0.0, 0.0, 0.0]\nnormal = [0.0, 1.0, 0.0]\n\
                 [solver]\nmethod = \"implicit-euler\"\ndt = 0.005\nduration = 1.5\n",
                rod_table(rope, 0.5, [0.0, y, 0.0], [0.5, y, 0.0]),
                contact_table(given, 0.0)
            );
            let sim = settle(&text, 1.5);
            let tau = tolerance_of(&sim);
            let heights = points(&sim)
                .iter()
                .map(|p| p.y - rope.r)
                .collect::<Vec<_>>();
            let (lo, hi) = heights
                .iter()
                .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), &h| {
                    (a.min(h), b.max(h))
                });
            eprintln!(
                "plane, rope {k} {rope:?}, tolerance {tau:.2e} m: gap {lo:.3e} .. {hi:.3e} m ({:.3} .. {:.3} of it)",
                lo / tau,
                hi / tau
            );
            assert!(
                lo >= -tau && hi <= tau,
                "rope {k}: gap {lo:e} .. {hi:e}, tolerance {tau:e}"
            );
        }
    }
}

#[test]
fn a_rope_draped_on_a_sphere_rests_at_its_radius_within_the_tolerance() {
    let big = 0.1;
    for (k, rope) in ROPES.iter().enumerate() {
        let y = big + 1.3 * rope.r;
        let text = format!(
            "[rod]\n{}\n{}\n[[obstacles]]\nkind = \"sphere\"\ncentre = [0.0, 0.0, 0.0]\nradius = {big}\n\
             [solver]\nmethod = \"implicit-euler\"\ndt = 0.005\nduration = 2.0\n",
            rod_table(rope, 0.5, [-0.25, y, 0.0], [0.25, y, 0.0]),
            contact_table(None, 0.5)
        );
        let sim = settle(&text, 2.0);
        let tau = tolerance_of(&sim);
        let gaps: Vec<Real> = points(&sim)
            .iter()
            .map(|p| p.norm() - big - rope.r)
            .collect();
        let least = gaps.iter().copied().fold(Real::INFINITY, Real::min);
        // The top of the drape (the middle fifth of the rope) rests on the sphere.
        let top = &gaps[40..=60];
        let highest = top.iter().copied().fold(Real::NEG_INFINITY, Real::max);
        eprintln!(
            "sphere, rope {k} {rope:?}, tolerance {tau:.2e} m: least gap {least:.3e} m, top gaps up to {highest:.3e} m"
        );
        assert!(least >= -tau, "rope {k}: {least:e} deeper than {tau:e}");
        assert!(
            highest <= tau,
            "rope {k}: the top sits {highest:e} m off, tolerance {tau:e}"
        );
    }
}

#[test]
fn a_rope_resting_on_another_sits_at_the_sum_of_radii_within_the_tolerance() {
    // A rope five times thinner than the one it rests on costs minutes: the detection
    // reach follows the thickest rod, so the thin one's samples pair with many.
    let thinner = Rope {
        r: 0.004,
        rho: 0.05,
        ea: 200.0,
        ei: 1e-6,
    };
    for (k, upper) in [ROPES[0], ROPES[1], thinner].iter().enumerate() {
        let lower = Rope {
            r: 0.01,
            rho: 0.1,
            ea: 2000.0,
            ei: 1e-4,
        };
        let y0 = lower.r + 1.3 * upper.r;
        let text = format!(
            "[[rods]]\nname = \"lower\"\n{}\n[[rods]]\nname = \"upper\"\n{}\n\
             [[pins]]\nrod = \"lower\"\nat = 0.0\n[[pins]]\nrod = \"lower\"\nat = 1.0\n{}\n\
             [solver]\nmethod = \"implicit-euler\"\ndt = 0.005\nduration = 3.0\n",
            rod_table(&lower, 1.0, [-0.5, 0.0, 0.0], [0.5, 0.0, 0.0]),
            rod_table(upper, 0.4, [0.0, y0, -0.2], [0.0, y0, 0.2]),
            contact_table(None, 0.5)
        );
        let sim = settle(&text, 3.0);
        let tau = tolerance_of(&sim);
        let summary = sim
            .system
            .summary()
            .expect("summary")
            .contact
            .expect("contact");
        let d = summary.min_distance.expect("the ropes touch");
        let gap = d - lower.r - upper.r;
        eprintln!("rope {k} {upper:?} on a rope: gap {gap:.3e} m, tolerance {tau:.2e} m");
        assert!(gap.abs() <= tau, "rope {k}: gap {gap:e}, tolerance {tau:e}");
    }
}

/// The bundled scenes with `[contact]`, their `stiffness` line removed, run for at
/// most `cap` seconds: (name, smallest clearance seen, end gap, tolerance).
fn bundled_without_stiffness(cap: Real) -> Vec<(String, Real, Option<Real>, Real)> {
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes");
    let mut names: Vec<_> = std::fs::read_dir(dir)
        .expect("scenes")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .collect();
    names.sort();
    let mut out = Vec::new();
    for path in names {
        let text = std::fs::read_to_string(&path).expect("scene text");
        if !text.contains("\n[contact]") {
            continue;
        }
        let stripped: String = text
            .lines()
            .filter(|l| !l.trim_start().starts_with("stiffness =") || !in_contact(&text, l))
            .map(|l| format!("{l}\n"))
            .collect();
        let mut scene = Scene::from_toml(&stripped).expect("scene without stiffness");
        scene.solver.duration = scene.solver.duration.map(|d| d.min(cap));
        let result = splinerod::run(&scene).expect("runs");
        let c = result.contact.expect("contact statistics");
        let name = path.file_stem().unwrap().to_string_lossy().to_string();
        let clearance = c.min_clearance_ratio.unwrap_or(Real::INFINITY);
        out.push((name, clearance, c.end_gap, c.tolerance.expect("tolerance")));
    }
    out
}

/// Whether `line` of `text` lies in its `[contact]` table.
fn in_contact(text: &str, line: &str) -> bool {
    let mut table = "";
    for l in text.lines() {
        if l.starts_with('[') {
            table = l.trim();
        }
        if std::ptr::eq(l, line) {
            return table == "[contact]";
        }
    }
    false
}

#[test]
fn bundled_contact_scenes_run_without_a_stiffness() {
    let runs = bundled_without_stiffness(0.6);
    assert!(runs.len() >= 10, "{} contact scenes", runs.len());
    for (name, clearance, gap, tau) in runs {
        eprintln!("{name}: clearance {clearance:.4}, end gap {gap:?} m, tolerance {tau:.2e} m");
        assert!(clearance >= 0.95, "{name}: clearance {clearance}");
        if let Some(g) = gap {
            assert!(g >= -tau, "{name}: ends {g:e} m deep, tolerance {tau:e}");
        }
    }
}
