//! Observations of a real rod for parameter identification (`splinerod fit
//! --observations FILE`, issue #48): CSV files with a header, one kind per file, told
//! apart by their columns:
//!
//! | columns | kind | residual |
//! |---|---|---|
//! | `t,s,x,y,z` | [`ObservationKind::Marker`]: a marker at material coordinate `s` (m of rest length, as Python's `positions(s)`) | the marker's position minus the rod's point `C(s)` |
//! | `t,x,y,z` | [`ObservationKind::Point`]: an unlabelled point (a point cloud) | the distance to the nearest point of the curve |
//! | `t,pin,fx,fy,fz` | [`ObservationKind::PinForce`]: the force measured at `[[pins]]` entry `pin` | the measured force minus the pin's |
//!
//! Any file may add a `sigma` column (> 0, in the rows' units: m or N) weighting its
//! rows by `1/σ` (default 1). `t` (s) is empty for a static scene's equilibrium.
//! Columns may come in any order; unknown columns, a missing one, a value that is not a
//! finite number, a negative time, a negative or unknown pin index and a `σ ≤ 0` are
//! errors naming the file, the line and the column.

use crate::Error;
use splinerod_core::Real;
use std::path::Path;

/// What one file observes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ObservationKind {
    /// Markers at known material coordinates.
    Marker,
    /// Unlabelled points near the curve.
    Point,
    /// Forces measured at pins.
    PinForce,
}

/// One row of an observation file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Time, s (`None`: the static equilibrium).
    pub t: Option<Real>,
    /// The marker's material coordinate, m of rest length ([`ObservationKind::Marker`]).
    pub s: Option<Real>,
    /// The pin's index in `[[pins]]` ([`ObservationKind::PinForce`]).
    pub pin: Option<usize>,
    /// The observed position (m) or force (N).
    pub value: [Real; 3],
    /// Its standard deviation, in the same unit (> 0; 1 without a `sigma` column).
    pub sigma: Real,
    /// Line of the file it was read from (1-based, the header is line 1).
    pub line: usize,
}

/// The rows of one observation file.
#[derive(Debug, Clone, PartialEq)]
pub struct ObservationFile {
    /// Where it was read from.
    pub path: String,
    /// What its rows observe.
    pub kind: ObservationKind,
    /// The rows, in file order.
    pub rows: Vec<Observation>,
}

impl ObservationFile {
    /// Scalar residuals the file gives a fit: 3 per row, 1 per unlabelled point.
    pub fn residual_count(&self) -> usize {
        match self.kind {
            ObservationKind::Point => self.rows.len(),
            _ => 3 * self.rows.len(),
        }
    }

    /// Checks the rows against the scene they observe: a scene with `pins` pins, a rod
    /// (the first of `[[rods]]`) of rest length `rest_length` (m), and a run to `end`
    /// seconds (`None`: a static scene, whose rows have no time). Errors name the file,
    /// the line and what is wrong.
    pub fn check(&self, pins: usize, rest_length: Real, end: Option<Real>) -> Result<(), Error> {
        let bad = |row: &Observation, message: String| Error::Parse {
            file: Some(self.path.clone()),
            position: Some((row.line, 1)),
            field: None,
            message,
        };
        for row in &self.rows {
            match (row.t, end) {
                (Some(t), None) => {
                    return Err(bad(
                        row,
                        format!("`t` = {t}: a static scene's rows have no time (leave it empty)"),
                    ));
                }
                (None, Some(_)) => {
                    return Err(bad(
                        row,
                        "`t` is empty: a run's rows need their time".into(),
                    ))
                }
                (Some(t), Some(end)) if t > end => {
                    return Err(bad(
                        row,
                        format!("`t` = {t}: after the run's end ({end} s)"),
                    ));
                }
                _ => {}
            }
            if let Some(s) = row.s.filter(|s| !(0.0..=rest_length).contains(s)) {
                return Err(bad(
                    row,
                    format!("`s` = {s}: outside the rod's rest length [0, {rest_length}] m"),
                ));
            }
            if let Some(pin) = row.pin.filter(|&p| p >= pins) {
                return Err(bad(
                    row,
                    format!("`pin` = {pin}: the scene has {pins} [[pins]] entries"),
                ));
            }
        }
        Ok(())
    }

    /// Reads and checks the file at `path`.
    pub fn read(path: &Path) -> Result<Self, Error> {
        let text = std::fs::read_to_string(path).map_err(|source| Error::Io {
            path: path.display().to_string(),
            source,
        })?;
        Self::parse(&path.display().to_string(), &text)
    }

    /// Parses `text`, the contents of the file called `path` (for errors).
    pub fn parse(path: &str, text: &str) -> Result<Self, Error> {
        let mut reader = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .from_reader(text.as_bytes());
        let bad = |line: usize, column: Option<usize>, message: String| Error::Parse {
            file: Some(path.to_string()),
            position: Some((line, column.map_or(1, |c| c + 1))),
            field: None,
            message,
        };
        let header: Vec<String> = reader
            .headers()
            .map_err(|e| bad(1, None, e.to_string()))?
            .iter()
            .map(str::to_string)
            .collect();
        let columns = Columns::of(&header).map_err(|m| bad(1, None, m))?;
        let mut rows = Vec::new();
        for (k, record) in reader.records().enumerate() {
            let line = k + 2;
            let record = record.map_err(|e| bad(line, None, e.to_string()))?;
            let row = columns
                .row(&record, line)
                .map_err(|(c, m)| bad(line, Some(c), m))?;
            rows.push(row);
        }
        if rows.is_empty() {
            return Err(bad(1, None, "no observations after the header".into()));
        }
        Ok(Self {
            path: path.to_string(),
            kind: columns.kind,
            rows,
        })
    }
}

/// Where each column of a file is.
struct Columns {
    kind: ObservationKind,
    t: usize,
    s: Option<usize>,
    pin: Option<usize>,
    value: [usize; 3],
    sigma: Option<usize>,
}

impl Columns {
    /// The columns of `header`, or what is wrong with it.
    fn of(header: &[String]) -> Result<Self, String> {
        let find = |name: &str| header.iter().position(|h| h == name);
        let kind = if find("pin").is_some() {
            ObservationKind::PinForce
        } else if find("s").is_some() {
            ObservationKind::Marker
        } else {
            ObservationKind::Point
        };
        let names: &[&str] = match kind {
            ObservationKind::Marker => &["t", "s", "x", "y", "z"],
            ObservationKind::Point => &["t", "x", "y", "z"],
            ObservationKind::PinForce => &["t", "pin", "fx", "fy", "fz"],
        };
        let known = |h: &String| names.contains(&h.as_str()) || h == "sigma";
        if let Some(unknown) = header.iter().find(|h| !known(h)) {
            return Err(format!(
                "unknown column `{unknown}`: a file has the columns {} (and optionally sigma)",
                names.join(",")
            ));
        }
        let need = |name: &str| {
            find(name)
                .ok_or_else(|| format!("missing column `{name}` (columns: {})", names.join(",")))
        };
        let value = match kind {
            ObservationKind::PinForce => [need("fx")?, need("fy")?, need("fz")?],
            _ => [need("x")?, need("y")?, need("z")?],
        };
        Ok(Self {
            kind,
            t: need("t")?,
            s: find("s"),
            pin: find("pin"),
            value,
            sigma: find("sigma"),
        })
    }

    /// The observation of `record` (on `line`), or the column and what is wrong there.
    fn row(&self, record: &csv::StringRecord, line: usize) -> Result<Observation, (usize, String)> {
        let number = |c: usize, name: &str| -> Result<Real, (usize, String)> {
            let text = record.get(c).unwrap_or("");
            match text.parse::<Real>() {
                Ok(v) if v.is_finite() => Ok(v),
                _ => Err((c, format!("`{name}` = \"{text}\": must be a finite number"))),
            }
        };
        let t = match record.get(self.t).unwrap_or("") {
            "" => None,
            _ => match number(self.t, "t")? {
                t if t >= 0.0 => Some(t),
                t => return Err((self.t, format!("`t` = {t}: must not be negative"))),
            },
        };
        let s = self.s.map(|c| number(c, "s")).transpose()?;
        let pin = match self.pin {
            None => None,
            Some(c) => {
                let text = record.get(c).unwrap_or("");
                let index = text.parse::<usize>().map_err(|_| {
                    (
                        c,
                        format!(
                            "`pin` = \"{text}\": must be the index of a [[pins]] entry (0, 1, …)"
                        ),
                    )
                })?;
                Some(index)
            }
        };
        let names = match self.kind {
            ObservationKind::PinForce => ["fx", "fy", "fz"],
            _ => ["x", "y", "z"],
        };
        let value = [
            number(self.value[0], names[0])?,
            number(self.value[1], names[1])?,
            number(self.value[2], names[2])?,
        ];
        let sigma = match self.sigma {
            None => 1.0,
            Some(c) => match number(c, "sigma")? {
                v if v > 0.0 => v,
                v => return Err((c, format!("`sigma` = {v}: must be positive"))),
            },
        };
        Ok(Observation {
            t,
            s,
            pin,
            value,
            sigma,
            line,
        })
    }
}
