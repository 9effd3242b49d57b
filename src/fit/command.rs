//! `splinerod fit SCENE --observations OBS.csv --params P1,P2,… [--json FIT.json]
//! [--scene-out FITTED.toml]`: reads
//! the scene and the observation files, fits, and reports — the summary lines the
//! command prints and the JSON it writes (`parameters` with `name`, `value` and `std`,
//! `correlation`, `residual_rms`, `iterations`, `simulations`, `converged`, and
//! `unidentifiable`: the groups of parameters the observations cannot separate, by
//! name, with the direction in the fitted variables that they do not see).

use crate::fit::run_fit::RunFit;
use crate::fit::scene_out::with_fitted_values;
use crate::fit::{FitReport, ObservationFile, SceneFit};
use crate::scene::Method;
use crate::{Error, Scene};
use std::path::{Path, PathBuf};

/// A fit's report with the parameters' names.
pub struct NamedFit {
    /// The parameters' scene paths, in order.
    pub names: Vec<String>,
    /// The fit.
    pub report: FitReport,
}

/// Fits the parameters `params` (comma-separated scene paths) of the scene at `scene`
/// to the observation files `observations`.
pub fn fit_files(scene: &Path, observations: &[PathBuf], params: &str) -> Result<NamedFit, Error> {
    let scene = Scene::load(scene)?;
    let files = observations
        .iter()
        .map(|p| ObservationFile::read(p))
        .collect::<Result<Vec<_>, _>>()?;
    let names: Vec<&str> = params.split(',').map(str::trim).collect();
    fit_scene(&scene, &files, &names)
}

/// Fits the parameters `names` (scene paths) of `scene` to the observations `files`
/// (read with [`ObservationFile::read`] or [`ObservationFile::parse`]): what
/// [`fit_files`] does after reading, and Python's `splinerod.fit`.
pub fn fit_scene(
    scene: &Scene,
    files: &[ObservationFile],
    names: &[&str],
) -> Result<NamedFit, Error> {
    let report = match scene.solver.method {
        Method::Static => SceneFit::new(scene, names, files)?.fit()?,
        _ => RunFit::from_files(scene, names, files)?.fit()?,
    };
    Ok(NamedFit {
        names: names.iter().map(|s| s.to_string()).collect(),
        report,
    })
}

impl NamedFit {
    /// Writes the scene file at `scene` with the fitted values in place of its own to
    /// `out` (`--scene-out`, [`crate::fit::scene_out`]).
    pub fn write_scene(&self, scene: &Path, out: &Path) -> Result<(), Error> {
        let io = |path: &Path| {
            let path = path.display().to_string();
            move |source| Error::Io { path, source }
        };
        let text = std::fs::read_to_string(scene).map_err(io(scene))?;
        let file = scene.display().to_string();
        let fitted = with_fitted_values(&file, &text, &self.names, &self.report.parameters)?;
        std::fs::write(out, fitted).map_err(io(out))
    }

    /// What `splinerod fit` prints: each parameter with its deviation, the residual,
    /// the cost, and a warning per group the observations cannot separate.
    pub fn summary(&self) -> Vec<String> {
        let r = &self.report;
        let mut lines: Vec<String> = self
            .names
            .iter()
            .zip(&r.parameters)
            .zip(&r.std)
            .map(|((n, p), s)| format!("{n} = {p:.6e} ± {s:.2e}"))
            .collect();
        lines.push(format!(
            "residual rms {:.3} (in units of σ), {} iterations, {} simulations{}",
            r.residual_rms,
            r.iterations,
            r.simulations,
            if r.converged { "" } else { ", NOT converged" }
        ));
        lines.extend(self.warnings().into_iter().map(|w| format!("warning: {w}")));
        lines
    }

    /// One warning per group of parameters the observations cannot separate (without
    /// the `warning: ` that [`summary`](Self::summary) puts before each).
    pub fn warnings(&self) -> Vec<String> {
        let groups = self.report.unidentifiable.iter();
        groups
            .map(|(group, direction)| {
                let names: Vec<&str> = group.iter().map(|&k| self.names[k].as_str()).collect();
                format!(
                    "the observations cannot separate {}: moving them along {direction:.3?} \
                     (log of positive parameters) changes nothing they see; their values are \
                     where the fit started along that direction, their deviations infinite",
                    names.join(", ")
                )
            })
            .collect()
    }

    /// The JSON of `splinerod fit` (module docs).
    pub fn json(&self) -> serde_json::Value {
        let r = &self.report;
        let parameters: Vec<serde_json::Value> = self
            .names
            .iter()
            .zip(&r.parameters)
            .zip(&r.std)
            .map(|((n, p), s)| serde_json::json!({ "name": n, "value": p, "std": s }))
            .collect();
        let groups: Vec<serde_json::Value> = r
            .unidentifiable
            .iter()
            .map(|(group, direction)| {
                let names: Vec<&str> = group.iter().map(|&k| self.names[k].as_str()).collect();
                serde_json::json!({ "parameters": names, "direction": direction })
            })
            .collect();
        serde_json::json!({
            "parameters": parameters,
            "correlation": r.correlation,
            "residual_rms": r.residual_rms,
            "iterations": r.iterations,
            "simulations": r.simulations,
            "converged": r.converged,
            "unidentifiable": groups,
        })
    }
}
