//! The facade's error: every lower crate's error, plus scene and I/O errors.

use crate::scene::problems::Listed;
use crate::scene::Problem;
use splinerod_adaptivity::AdaptError;
use splinerod_core::{CoreError, Requirement};
use splinerod_integrators::IntegratorError;

/// Anything that can go wrong in splinerod.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// A scene file is not valid TOML for a scene (syntax, an unknown or missing key, a
    /// value of the wrong type); where it is known, the file and position.
    #[error("{}{}{message}", file.as_ref().map(|f| format!("{f}: ")).unwrap_or_default(), position.map(|(l, c)| format!("line {l}, column {c}: ")).unwrap_or_default())]
    Parse {
        /// The file, if read from one.
        file: Option<String>,
        /// Line and column (1-based) of the offending text, if known.
        position: Option<(usize, usize)>,
        /// Dotted path of the offending field (`rod.rest_length`), if known.
        field: Option<String>,
        /// What the parser said.
        message: String,
    },
    /// A scene's keys or values do not fit the scene format: every value of the wrong
    /// type, unknown key or table and missing required field found, each naming its
    /// dotted path, in the user's words ([`Problem`]).
    #[error("{}{}", file.as_ref().map(|f| format!("{f}: ")).unwrap_or_default(), Listed(problems))]
    Format {
        /// The file, if read from one.
        file: Option<String>,
        /// What is wrong, values and keys first, then the missing fields (at least one).
        problems: Vec<Problem>,
    },
    /// A required scene field is missing; names it.
    #[error("missing field `{field}` ({reason})")]
    MissingField {
        /// Dotted path of the field.
        field: String,
        /// When it is required.
        reason: String,
    },
    /// A known-answer problem or study could not be evaluated (its embedded reference
    /// data are malformed, or the run did not show what is measured).
    #[error("{problem}: {reason}")]
    Study {
        /// The problem.
        problem: String,
        /// What went wrong.
        reason: String,
    },
    /// Writing JSON failed.
    #[error("JSON: {0}")]
    Json(#[from] serde_json::Error),
    /// The thread pool could not be built.
    #[error("thread pool: {0}")]
    ThreadPool(String),
    /// The command needs a cargo feature this build does not have.
    #[error("this needs the `{0}` feature")]
    FeatureMissing(&'static str),
    /// An observer stopped the run.
    #[error("stopped by an observer: {0}")]
    Stopped(String),
    /// A scene field is out of range; names the field and the value.
    #[error("{}: {reason}", named(.field, .value))]
    InvalidField {
        /// Dotted path of the field, e.g. `rod.linear_density` or `pins[1].at`.
        field: String,
        /// The value given, as written.
        value: String,
        /// What it must satisfy.
        reason: String,
    },
    /// Command-line options that do not go together; names one and says why.
    #[error("{message}")]
    Options {
        /// The option at fault (`--gif`).
        option: &'static str,
        /// What is wrong, naming the options.
        message: String,
    },
    /// A scene's estimated needs exceed a resource limit (`splinerod run
    /// --allow-large` runs it anyway); names the fields behind the estimate.
    #[error("`{field}`: the run would need {estimate:.3e} {what}, over the limit of {limit:.1e} (see scenes/README.md, resource limits); pass --allow-large to run it anyway")]
    TooLarge {
        /// The scene fields behind the estimate.
        field: String,
        /// What is counted.
        what: &'static str,
        /// The estimate.
        estimate: f64,
        /// The limit.
        limit: f64,
    },
    /// A scene's estimated memory exceeds the machine's physical memory; names the
    /// fields behind the estimate.
    #[error("`{field}`: the run would need {estimate:.3e} bytes of memory, more than this machine has ({available:.3e})")]
    OutOfMemory {
        /// The scene fields behind the estimate.
        field: String,
        /// The estimate, bytes.
        estimate: f64,
        /// Physical memory, bytes.
        available: f64,
    },
    /// Reading or writing a file failed.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// What the OS said.
        source: std::io::Error,
    },
    /// The rod's knots changed (or the rod was replaced) without the energies hearing of
    /// it; change knots through `RodSystem::change_knots` (or `insert_knot`,
    /// `remove_knot`, `cut`).
    #[error(
        "the rod's knots changed without its energies hearing of it: change knots through \
         RodSystem::change_knots (or insert_knot, remove_knot, cut)"
    )]
    KnotsChangedUnheard,
    /// `Simulation::settle` needs an equilibrium solver; names the integrator given.
    #[error("settling needs an equilibrium solver (method = \"static\"), not `{0}`")]
    NotAnEquilibriumSolver(String),
    /// A member of an ensemble failed; names it.
    #[error("ensemble member {index}: {source}")]
    Member {
        /// Index of the member.
        index: usize,
        /// What went wrong.
        source: Box<Error>,
    },
    /// A stop asked from outside (SIGINT, SIGTERM, a stop request, Python's
    /// `KeyboardInterrupt`) ended the work before it had a state to report; says where.
    /// (A solve abandoned inside a step is [`IntegratorError::Interrupted`]; see
    /// [`Error::is_interrupted`].)
    #[error("interrupted {0}")]
    Interrupted(&'static str),
    /// A step failed at the shortest sub-step allowed (`solver.min_dt`,
    /// [`crate::substep::StepControl::min_dt`]): the sub-stepper never goes below it.
    #[error("the step from t = {time} s cannot be completed with sub-steps of at least `solver.min_dt` = {min_dt:e} s: {reason}")]
    MinDtReached {
        /// Start of the step, s.
        time: f64,
        /// The shortest sub-step allowed, s.
        min_dt: f64,
        /// Why the shortest sub-step failed, and what to change.
        reason: String,
    },
    /// From the core (basis, knots, rod).
    #[error(transparent)]
    Core(#[from] CoreError),
    /// From an integrator or solver.
    #[error(transparent)]
    Integrator(#[from] IntegratorError),
    /// A step failed on a non-finite value that an energy returned; names the energy.
    #[error("energy `{energy}` returned a non-finite {what}: {source}")]
    EnergyNotFinite {
        /// The energy's name.
        energy: String,
        /// `"energy"` or `"gradient"`.
        what: &'static str,
        /// The solver's failure.
        source: IntegratorError,
    },
    /// From the adaptivity crate.
    #[error(transparent)]
    Adapt(#[from] AdaptError),
}

impl Error {
    /// An [`Error::Study`].
    pub fn study(problem: impl Into<String>, reason: impl Into<String>) -> Self {
        Self::Study {
            problem: problem.into(),
            reason: reason.into(),
        }
    }

    /// The dotted path of the scene field (or command-line option) this error is about,
    /// if it names one: the field out of range, missing, unknown or of the wrong type;
    /// for an ensemble member's error, the field its error names.
    pub fn field_name(&self) -> Option<&str> {
        match self {
            Self::InvalidField { field, .. }
            | Self::MissingField { field, .. }
            | Self::TooLarge { field, .. }
            | Self::OutOfMemory { field, .. } => Some(field),
            Self::Parse { field, .. } => field.as_deref(),
            Self::Options { option, .. } => Some(option),
            Self::Format { problems, .. } => problems.first().map(Problem::field),
            Self::Member { source, .. } => source.field_name(),
            Self::MinDtReached { .. } => Some("solver.min_dt"),
            _ => None,
        }
    }

    /// Whether this error is a stop asked from outside: [`Error::Interrupted`], or a
    /// solve abandoned on request ([`IntegratorError::Interrupted`]), also an ensemble
    /// member's.
    pub fn is_interrupted(&self) -> bool {
        match self {
            Self::Interrupted(_) | Self::Integrator(IntegratorError::Interrupted) => true,
            Self::Member { source, .. } => source.is_interrupted(),
            _ => false,
        }
    }

    /// An [`Error::InvalidField`].
    pub fn field(
        field: impl Into<String>,
        value: impl std::fmt::Display,
        reason: impl Into<String>,
    ) -> Self {
        Self::InvalidField {
            field: field.into(),
            value: readable(value.to_string()),
            reason: reason.into(),
        }
    }
}

/// A number written out in more than 24 characters (`1e300` prints 301 digits) in
/// exponent form; anything else as it is.
fn readable(value: String) -> String {
    match value.parse::<f64>() {
        Ok(v) if value.len() > 24 => format!("{v:e}"),
        _ => value,
    }
}

// Range checks of scene values: an error naming the field and the value.

/// Error naming `field` and `v` unless `v` satisfies `requirement`.
pub(crate) fn require(field: &str, v: f64, requirement: Requirement) -> Result<(), Error> {
    requirement
        .check(v)
        .map_err(|reason| Error::field(field, v, reason))
}

pub(crate) fn positive(field: &str, v: f64) -> Result<(), Error> {
    require(field, v, Requirement::Positive)
}

pub(crate) fn non_negative(field: &str, v: f64) -> Result<(), Error> {
    require(field, v, Requirement::NonNegative)
}

pub(crate) fn fraction(field: &str, v: f64) -> Result<(), Error> {
    require(field, v, Requirement::Fraction)
}

pub(crate) fn finite_vec(field: &str, v: [f64; 3]) -> Result<(), Error> {
    let finite = Requirement::Finite;
    match v.iter().try_for_each(|&x| finite.check(x)) {
        Ok(()) => Ok(()),
        Err(reason) => Err(Error::field(field, format!("{v:?}"), reason)),
    }
}

/// The scene's tables and arrays of tables: an [`Error::InvalidField`] about one calls
/// it a table, not a field.
const TABLES: [&str; 15] = [
    "rod",
    "rods",
    "pins",
    "world",
    "solver",
    "output",
    "adaptivity",
    "grabs",
    "cuts",
    "ensemble",
    "contact",
    "obstacles",
    "loads",
    "rod.ring",
    "rod.overhand",
];

/// What an [`Error::InvalidField`] names, and its value: a command-line option
/// (`option `--every` = 0`), an input of `splinerod merge`, a scene table
/// (`table [rod.overhand] is given`) or a scene field (`scene field `rod.degree` = 12`).
fn named(field: &str, value: &str) -> String {
    let what = if field.starts_with("--") {
        format!("option `{field}`")
    } else if field.starts_with("merge") {
        format!("input `{field}`")
    } else if let Some(table) = table_name(field) {
        table
    } else {
        format!("scene field `{field}`")
    };
    match value.strip_prefix("given") {
        Some(rest) => format!("{what} is given{rest}"),
        None => format!("{what} = {value}"),
    }
}

/// `field` as a table's name (`[ensemble]`, `[[rods]]`, `table `pins[1]``), if it is
/// one of the scene's [`TABLES`] (a rod of `[[rods]]` as `rod`).
fn table_name(field: &str) -> Option<String> {
    let mut plain = String::new();
    let mut indexed = false;
    for part in field.split('.') {
        let name = part.split('[').next().unwrap_or(part);
        indexed |= name.len() < part.len();
        if !plain.is_empty() {
            plain.push('.');
        }
        plain.push_str(name);
    }
    let plain = match plain.strip_prefix("rods.") {
        Some(rest) => format!("rod.{rest}"),
        None => plain,
    };
    if !TABLES.contains(&plain.as_str()) {
        return None;
    }
    let array = ["rods", "pins", "grabs", "cuts", "obstacles", "loads"].contains(&field);
    Some(match (indexed, array) {
        (true, _) => format!("table `{field}`"),
        (false, true) => format!("table [[{field}]]"),
        (false, false) => format!("table [{field}]"),
    })
}
