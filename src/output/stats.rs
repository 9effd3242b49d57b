//! Per-step statistics as CSV (`--stats OUT.csv`): one row per step with the time,
//! resolution, Newton counters and residual, every energy term, the step's wall time and
//! the wall time of each of its stages (`drivers_seconds` ... `record_seconds`).
//! Written to `OUT.csv.partial` and renamed at the end, so a run that fails leaves no
//! file claiming to be complete.

use crate::run::observe::{Frame, Observer};
use crate::{Error, RunResult, StageTimes, StepReport};
use splinerod_core::Real;
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

/// Writes one CSV row per step.
pub struct StatsWriter {
    path: PathBuf,
    partial: PathBuf,
    writer: Option<csv::Writer<BufWriter<File>>>,
    energies: Vec<String>,
}

impl std::fmt::Debug for StatsWriter {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("StatsWriter")
            .field("path", &self.path)
            .finish()
    }
}

fn io_error(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.display().to_string(),
        source,
    }
}

fn csv_error(path: &Path, e: csv::Error) -> Error {
    io_error(path, std::io::Error::other(e.to_string()))
}

impl StatsWriter {
    /// A writer to `path` (created, with `.partial` appended, at the start of the run).
    pub fn new(path: &Path) -> Result<Self, Error> {
        let mut partial = path.as_os_str().to_owned();
        partial.push(".partial");
        let partial = PathBuf::from(partial);
        // Appending, not truncated yet: a resumed run continues what is there (`start`
        // empties it).
        let file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&partial)
            .map_err(|e| io_error(&partial, e))?;
        Ok(Self {
            path: path.to_path_buf(),
            writer: Some(csv::Writer::from_writer(BufWriter::new(file))),
            partial,
            energies: Vec::new(),
        })
    }

    /// Cuts the partial file to `bytes` (after flushing what is buffered).
    fn truncate(&mut self, bytes: u64) -> Result<(), Error> {
        let path = self.partial.clone();
        let writer = self.writer()?;
        writer.flush().map_err(|e| io_error(&path, e))?;
        let file = writer.get_ref().get_ref();
        file.set_len(bytes).map_err(|e| io_error(&path, e))
    }

    fn writer(&mut self) -> Result<&mut csv::Writer<BufWriter<File>>, Error> {
        let missing = || std::io::Error::other("the statistics file is already closed");
        self.writer
            .as_mut()
            .ok_or_else(|| io_error(&self.partial, missing()))
    }
}

impl Drop for StatsWriter {
    /// A run that did not finish leaves no partial file behind.
    fn drop(&mut self) {
        if self.writer.take().is_some() {
            let _ = std::fs::remove_file(&self.partial);
        }
    }
}

impl Observer for StatsWriter {
    fn start(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        let system = frame.system;
        self.energies = system
            .energies
            .iter()
            .map(|e| e.name().to_string())
            .collect();
        if !system.grabs.is_empty() {
            self.energies.push("grab".into());
        }
        let mut header: Vec<String> = [
            "time",
            "step",
            "control_points",
            "newton_iterations",
            "converged",
            "residual",
            "kinetic",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect();
        header.extend(self.energies.iter().cloned());
        header.push("wall_seconds".into());
        let stages = StageTimes::NAMES.iter().map(|n| format!("{n}_seconds"));
        header.extend(stages);
        self.truncate(0)?;
        let path = self.partial.clone();
        self.writer()?
            .write_record(&header)
            .map_err(|e| csv_error(&path, e))
    }

    fn checkpoint(&mut self) -> Result<Option<String>, Error> {
        let path = self.partial.clone();
        let writer = self.writer()?;
        writer.flush().map_err(|e| io_error(&path, e))?;
        let file = writer.get_ref().get_ref();
        let bytes = file.metadata().map_err(|e| io_error(&path, e))?.len();
        let state = serde_json::json!({ "bytes": bytes, "energies": self.energies });
        Ok(Some(state.to_string()))
    }

    fn resume(&mut self, _frame: &Frame<'_>, state: Option<&str>) -> Result<(), Error> {
        let bad = || Error::field("checkpoint", self.path.display(), "no statistics state");
        let state: serde_json::Value = serde_json::from_str(state.ok_or_else(bad)?)?;
        let bytes = state["bytes"].as_u64().ok_or_else(bad)?;
        self.energies = serde_json::from_value(state["energies"].clone())?;
        let here = std::fs::metadata(&self.partial).map_or(0, |m| m.len());
        if here < bytes {
            // The run that wrote the checkpoint finished its file: continue from it.
            let text = std::fs::read(&self.path).map_err(|e| io_error(&self.path, e))?;
            let kept = text.get(..bytes as usize).ok_or_else(|| {
                let short = std::io::Error::other("shorter than at the checkpoint");
                io_error(&self.path, short)
            })?;
            self.truncate(0)?;
            let path = self.partial.clone();
            let mut file: &File = self.writer()?.get_ref().get_ref();
            file.write_all(kept).map_err(|e| io_error(&path, e))?;
        }
        self.truncate(bytes)
    }

    fn step(&mut self, frame: &Frame<'_>, report: &StepReport, wall: Real) -> Result<(), Error> {
        let breakdown = frame.system.energy_breakdown();
        let energy = |name: &str| {
            let found = breakdown.iter().find(|(n, _)| n == name);
            found.map_or(0.0, |(_, v)| *v)
        };
        let mut row = vec![
            frame.time.to_string(),
            frame.step.to_string(),
            frame.system.rod.distinct_len().to_string(),
            report.solver.newton_iterations.to_string(),
            report.solver.converged.to_string(),
            report.solver.residual.to_string(),
            frame.system.rod.kinetic_energy().to_string(),
        ];
        row.extend(self.energies.iter().map(|n| energy(n).to_string()));
        row.push(wall.to_string());
        row.extend(report.stages.values().iter().map(|t| t.to_string()));
        let path = self.partial.clone();
        self.writer()?
            .write_record(&row)
            .map_err(|e| csv_error(&path, e))
    }

    fn finish(&mut self, _frame: &Frame<'_>, _result: &RunResult) -> Result<(), Error> {
        let Some(mut writer) = self.writer.take() else {
            return Ok(());
        };
        writer.flush().map_err(|e| io_error(&self.partial, e))?;
        drop(writer);
        std::fs::rename(&self.partial, &self.path).map_err(|e| io_error(&self.path, e))
    }
}
