//! Cost of a 16-point implicit Euler step (one Newton iteration, as `splinerod bench`)
//! and of the stretching energy's value, gradient and Hessian, for both formulations
//! (`cargo run --release --example stretch_cost`). Best of 10 batches, interleaved, so
//! the two formulations see the same machine load.
use splinerod::core::{BlockBanded, HessianKind};
use splinerod::prelude::*;
use splinerod::problems::pinned_cable_with;
use std::time::Instant;

fn step_us(formulation: StretchFormulation) -> Result<Real, Error> {
    let params = NewtonParams {
        max_iterations: 1,
        accept_unconverged: true,
        ..NewtonParams::default()
    };
    let system = pinned_cable_with(16, 1.05, 100.0, formulation)?;
    let mut sim = Simulation::new(system, Box::new(ImplicitEuler::new(params)?));
    for _ in 0..5 {
        sim.step(1e-3)?;
    }
    let t = Instant::now();
    for _ in 0..2000 {
        sim.step(1e-3)?;
    }
    Ok(t.elapsed().as_secs_f64() / 2000.0 * 1e6)
}

/// Energy, gradient and Hessian of the stretching alone, µs.
fn parts_us(formulation: StretchFormulation) -> Result<[Real; 3], Error> {
    let mut e = Stretching::new(1e4)?;
    e.formulation = formulation;
    let mut rod = pinned_cable_with(16, 1.05, 100.0, formulation)?.rod;
    for (i, q) in rod.positions.iter_mut().enumerate() {
        q.y += 0.01 * (i as Real).sin();
    }
    let bw = e.bandwidth(&rod);
    let mut h = BlockBanded::zeros(rod.len(), bw);
    let mut g = vec![Vector3::zeros(); rod.len()];
    let reps = 5000;
    let time = |f: &mut dyn FnMut()| {
        let t = Instant::now();
        for _ in 0..reps {
            f();
        }
        t.elapsed().as_secs_f64() / reps as Real * 1e6
    };
    let mut sink = 0.0;
    let te = time(&mut || sink += e.energy(&rod));
    let tg = time(&mut || e.add_gradient(&rod, &mut g));
    let th = time(&mut || {
        h.reset(rod.len(), bw);
        e.add_hessian(&rod, HessianKind::Exact, &mut h)
    });
    std::hint::black_box(sink);
    Ok([te, tg, th])
}

fn main() -> Result<(), Error> {
    if std::env::var("PROFILE_MIXED").is_ok() {
        for _ in 0..20 {
            step_us(StretchFormulation::Mixed)?;
        }
        return Ok(());
    }
    let forms = [StretchFormulation::Pointwise, StretchFormulation::Mixed];
    let mut step = [Real::MAX; 2];
    let mut parts = [[Real::MAX; 3]; 2];
    for _ in 0..10 {
        for (k, &f) in forms.iter().enumerate() {
            step[k] = step[k].min(step_us(f)?);
            let p = parts_us(f)?;
            for j in 0..3 {
                parts[k][j] = parts[k][j].min(p[j]);
            }
        }
    }
    for (k, f) in forms.iter().enumerate() {
        let [e, g, h] = parts[k];
        println!(
            "{f:?}: step {:.2} µs; stretching energy {e:.2}, gradient {g:.2}, Hessian {h:.2} µs",
            step[k]
        );
    }
    println!("mixed / pointwise step: {:.2}", step[1] / step[0]);
    Ok(())
}
