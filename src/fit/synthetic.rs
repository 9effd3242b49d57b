//! Synthetic observations of a scene with known parameters, for studies of the fit
//! (the report's calibration section) and for users checking a calibration set-up
//! before they measure: the static equilibrium of the true scene observed by markers,
//! unlabelled points and pin forces, or a run (implicit Euler, BDF2) observed by
//! points and pin forces at step ends, with Gaussian noise of a given σ, from a seeded
//! ChaCha8 generator (the same seed, the same data).

use crate::fit::observations::{Observation, ObservationFile, ObservationKind};
use crate::sensitivity::{observed_sensitivities, static_sensitivities};
use crate::sensitivity::{StaticSensitivities, StepView};
use crate::{Error, Scene};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal, Uniform};
use splinerod_core::Real;

/// `count` markers spread evenly over the static `truth`'s first rod (at `s = k L /
/// count`, `k = 1 ..= count`), each coordinate with Gaussian noise of standard deviation
/// `sigma` (m, > 0), from the generator seeded with `seed`.
pub fn noisy_markers(
    truth: &Scene,
    count: usize,
    sigma: Real,
    seed: u64,
) -> Result<ObservationFile, Error> {
    let length = truth.rod_spec(0).rest_length;
    let at = |k: usize, _: &mut ChaCha8Rng| k as Real * length / count as Real;
    let rows = noisy_rows(truth, count, (sigma, seed), at, true)?;
    let path = format!("synthetic markers (σ = {sigma} m, seed {seed})");
    let kind = ObservationKind::Marker;
    Ok(ObservationFile { path, kind, rows })
}

/// `count` unlabelled points near the static `truth`'s first rod: at material
/// coordinates drawn uniformly over it (not reported: a point cloud's points carry no
/// label), each coordinate with Gaussian noise of standard deviation `sigma` (m, > 0),
/// seeded with `seed`.
pub fn noisy_points(
    truth: &Scene,
    count: usize,
    sigma: Real,
    seed: u64,
) -> Result<ObservationFile, Error> {
    let along = along_first_rod(truth)?;
    let at = |_: usize, rng: &mut ChaCha8Rng| along.sample(rng);
    let rows = noisy_rows(truth, count, (sigma, seed), at, false)?;
    let path = format!("synthetic points (σ = {sigma} m, seed {seed})");
    let kind = ObservationKind::Point;
    Ok(ObservationFile { path, kind, rows })
}

/// Rows `1 ..= count` observing the static `truth`'s first rod at `at(k)` (m of rest
/// length), with noise `(sigma, seed)`; `labelled`: the rows say where.
fn noisy_rows(
    truth: &Scene,
    count: usize,
    (sigma, seed): (Real, u64),
    mut at: impl FnMut(usize, &mut ChaCha8Rng) -> Real,
    labelled: bool,
) -> Result<Vec<Observation>, Error> {
    let (found, noise, mut rng) = equilibrium_and_noise(truth, sigma, seed)?;
    let length = truth.rod_spec(0).rest_length;
    (1..=count)
        .map(|k| {
            let s = at(k, &mut rng);
            let p = found.rod.point(truth.material_coordinate(s / length))?;
            Ok(Observation {
                t: None,
                s: labelled.then_some(s),
                pin: None,
                value: std::array::from_fn(|c| p[c] + noise.sample(&mut rng)),
                sigma,
                line: k + 1,
            })
        })
        .collect()
}

/// The force of `[[pins]]` entry `pin` of the static `truth` on its rod, each component
/// with Gaussian noise of standard deviation `sigma` (N, > 0), seeded with `seed`.
pub fn noisy_pin_force(
    truth: &Scene,
    pin: usize,
    sigma: Real,
    seed: u64,
) -> Result<ObservationFile, Error> {
    let (found, noise, mut rng) = equilibrium_and_noise(truth, sigma, seed)?;
    let Some(force) = found.forces.get(pin) else {
        let reason = format!("the scene has {} pins", found.forces.len());
        return Err(Error::field("pin", pin, reason));
    };
    Ok(ObservationFile {
        path: format!("synthetic force of pin {pin} (σ = {sigma} N, seed {seed})"),
        kind: ObservationKind::PinForce,
        rows: vec![Observation {
            t: None,
            s: None,
            pin: Some(pin),
            value: std::array::from_fn(|c| force[c] + noise.sample(&mut rng)),
            sigma,
            line: 2,
        }],
    })
}

/// The static equilibrium of `truth`, the centred normal distribution of standard
/// deviation `sigma` (checked finite and positive) and the generator seeded with `seed`.
fn equilibrium_and_noise(
    truth: &Scene,
    sigma: Real,
    seed: u64,
) -> Result<(StaticSensitivities, Normal<Real>, ChaCha8Rng), Error> {
    let (noise, rng) = noise_and_generator(sigma, seed)?;
    let found = static_sensitivities(truth, &[])?;
    Ok((found, noise, rng))
}

/// The centred normal distribution of standard deviation `sigma` (checked finite and
/// positive) and the generator seeded with `seed`.
fn noise_and_generator(sigma: Real, seed: u64) -> Result<(Normal<Real>, ChaCha8Rng), Error> {
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(Error::field("sigma", sigma, "must be finite and positive"));
    }
    let noise = Normal::new(0.0, sigma).map_err(|e| Error::field("sigma", sigma, e.to_string()))?;
    Ok((noise, ChaCha8Rng::seed_from_u64(seed)))
}

/// `count` unlabelled points near the run of `truth` after every `every`-th step (at
/// material coordinates drawn uniformly over its first rod), each coordinate with
/// Gaussian noise of standard deviation `sigma` (m, > 0), seeded with `seed`; rows with
/// their times.
pub fn noisy_run_points(
    truth: &Scene,
    (every, count): (usize, usize),
    sigma: Real,
    seed: u64,
) -> Result<ObservationFile, Error> {
    let length = truth.rod_spec(0).rest_length;
    let along = along_first_rod(truth)?;
    let rows = observe_run(truth, every, (sigma, seed), |view, noise, rng, out| {
        for _ in 0..count {
            let s = along.sample(rng);
            let p = view.rod.point(truth.material_coordinate(s / length))?;
            let value = std::array::from_fn(|c| p[c] + noise.sample(rng));
            out.push((None, value));
        }
        Ok(())
    })?;
    let path = format!("synthetic points of a run (σ = {sigma} m, seed {seed})");
    let kind = ObservationKind::Point;
    Ok(ObservationFile { path, kind, rows })
}

/// The force the rod puts on `[[pins]]` entry `pin`'s support during the run of
/// `truth`, after every `every`-th step, each component with Gaussian noise of standard
/// deviation `sigma` (N, > 0), seeded with `seed`.
pub fn noisy_run_pin_forces(
    truth: &Scene,
    pin: usize,
    every: usize,
    sigma: Real,
    seed: u64,
) -> Result<ObservationFile, Error> {
    let rows = observe_run(truth, every, (sigma, seed), |view, noise, rng, out| {
        let f = view.pin_force(pin)?;
        out.push((Some(pin), std::array::from_fn(|c| f[c] + noise.sample(rng))));
        Ok(())
    })?;
    let path = format!("synthetic force of pin {pin} during a run (σ = {sigma} N, seed {seed})");
    let kind = ObservationKind::PinForce;
    Ok(ObservationFile { path, kind, rows })
}

/// What an observer of a synthetic run adds after a step: `(pin, value)` rows.
type RunRows = Vec<(Option<usize>, [Real; 3])>;

/// The rows `observe` makes after every `every`-th step (> 0) of the run of `truth`,
/// with the noise `(sigma, seed)`, timed.
fn observe_run(
    truth: &Scene,
    every: usize,
    (sigma, seed): (Real, u64),
    mut observe: impl FnMut(
        &StepView<'_>,
        &Normal<Real>,
        &mut ChaCha8Rng,
        &mut RunRows,
    ) -> Result<(), Error>,
) -> Result<Vec<Observation>, Error> {
    if every == 0 {
        return Err(Error::field(
            "every",
            every,
            "observe after every n-th step, n > 0",
        ));
    }
    let (noise, mut rng) = noise_and_generator(sigma, seed)?;
    let (mut rows, mut step, mut made) = (Vec::new(), 0, RunRows::new());
    observed_sensitivities(truth, &[], &mut |view| {
        step += 1;
        if step % every != 0 {
            return Ok(());
        }
        made.clear();
        observe(view, &noise, &mut rng, &mut made)?;
        for &(pin, value) in &made {
            let line = rows.len() + 2;
            let (t, s) = (Some(view.t), None);
            rows.push(Observation {
                t,
                s,
                pin,
                value,
                sigma,
                line,
            });
        }
        Ok(())
    })?;
    Ok(rows)
}

/// The uniform distribution of material coordinates over `truth`'s first rod, m.
fn along_first_rod(truth: &Scene) -> Result<Uniform<Real>, Error> {
    let length = truth.rod_spec(0).rest_length;
    Uniform::new_inclusive(0.0, length)
        .map_err(|e| Error::field("rod.rest_length", length, e.to_string()))
}
