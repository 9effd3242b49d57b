//! A progress bar for long runs (indicatif), drawn on standard error only when it is a
//! terminal: piped or captured output stays clean.

use crate::run::observe::{Frame, Observer};
use crate::{Error, RunResult, StepReport};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use splinerod_core::Real;

/// Shows steps done, elapsed time and an estimate of the time left.
#[derive(Debug, Default)]
pub struct Progress {
    bar: Option<ProgressBar>,
}

impl Progress {
    /// A progress bar (hidden when standard error is not a terminal).
    pub fn new() -> Self {
        Self::default()
    }
}

impl Observer for Progress {
    fn start(&mut self, frame: &Frame<'_>) -> Result<(), Error> {
        if frame.total_steps == 0 {
            return Ok(());
        }
        let bar = ProgressBar::with_draw_target(
            Some(frame.total_steps as u64),
            ProgressDrawTarget::stderr(),
        );
        let template = "{bar:40} {pos}/{len} steps, t = {msg} s [{elapsed} < {eta}]";
        if let Ok(style) = ProgressStyle::with_template(template) {
            bar.set_style(style);
        }
        self.bar = Some(bar);
        Ok(())
    }

    fn resume(&mut self, frame: &Frame<'_>, _state: Option<&str>) -> Result<(), Error> {
        self.start(frame)?;
        if let Some(bar) = &self.bar {
            bar.set_position(frame.step as u64);
        }
        Ok(())
    }

    fn step(&mut self, frame: &Frame<'_>, _report: &StepReport, _wall: Real) -> Result<(), Error> {
        if let Some(bar) = &self.bar {
            bar.set_position(frame.step as u64);
            bar.set_message(format!("{:.3}", frame.time));
        }
        Ok(())
    }

    fn finish(&mut self, _frame: &Frame<'_>, _result: &RunResult) -> Result<(), Error> {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
        Ok(())
    }
}
