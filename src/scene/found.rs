//! The error of a reading of [`super::probe`]: what serde reported, kept in pieces (the
//! type expected and the value found, the unknown key and the keys known, the missing
//! field) for [`super::problems`] to word, with the dotted path it happened at.

use serde::de::{self, Unexpected};
use std::ops::Range;

/// What went wrong, in serde's pieces.
#[derive(Debug, Clone)]
pub(crate) enum What {
    /// A required field is absent.
    Missing(&'static str),
    /// A key the table does not take; `table` is set when its value is a table (`"[]"`)
    /// or an array of tables (`"[[]]"`).
    Unknown {
        /// The key.
        key: String,
        /// The keys the table takes.
        known: &'static [&'static str],
        /// The brackets of its value, if a table.
        table: Option<&'static str>,
    },
    /// A string that is none of the names allowed.
    NotOneOf {
        /// The string given.
        given: String,
        /// The names allowed.
        known: &'static [&'static str],
    },
    /// A value of the wrong type (or out of the type's range).
    Mismatch {
        /// What serde expected (`f64`, `struct SolverSpec`, …).
        expected: String,
        /// What it found.
        found: Seen,
    },
    /// A list of the wrong length.
    Length {
        /// What serde expected (`an array of length 3`).
        expected: String,
        /// The length found.
        found: usize,
    },
    /// Anything else, as said.
    Custom(String),
}

/// A value as serde saw it ([`Unexpected`] owned).
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Seen {
    /// `true` or `false`.
    Bool(bool),
    /// A whole number.
    Integer(i128),
    /// A number with a fraction or exponent.
    Float(f64),
    /// A string.
    Str(String),
    /// Anything else, described.
    Other(String),
}

impl From<Unexpected<'_>> for Seen {
    fn from(u: Unexpected<'_>) -> Self {
        match u {
            Unexpected::Bool(b) => Self::Bool(b),
            Unexpected::Unsigned(n) => Self::Integer(n.into()),
            Unexpected::Signed(n) => Self::Integer(n.into()),
            Unexpected::Float(x) => Self::Float(x),
            Unexpected::Char(c) => Self::Str(c.to_string()),
            Unexpected::Str(s) => Self::Str(s.to_string()),
            Unexpected::Seq => Self::Other("a list".into()),
            Unexpected::Map => Self::Other("a table".into()),
            Unexpected::Unit => Self::Other("nothing".into()),
            Unexpected::Other(s) => Self::Other(s.into()),
            other => Self::Other(other.to_string()),
        }
    }
}

/// The error of a reading: [`What`] went wrong, where (once known) and the span of the
/// text to blame.
#[derive(Debug, Clone)]
pub(crate) struct Found {
    /// Dotted path, `None` until an enclosing value places it.
    pub path: Option<String>,
    /// Byte range of the text to blame.
    pub span: Option<Range<usize>>,
    /// What went wrong.
    pub what: What,
}

impl Found {
    /// An error not yet placed.
    pub fn new(what: What) -> Self {
        Self {
            path: None,
            span: None,
            what,
        }
    }

    /// Places the error at the value at `path` (spanning `span`) unless already placed:
    /// a missing field or an unknown key at the key inside it.
    pub fn at(mut self, path: &str, span: Option<Range<usize>>) -> Self {
        if self.path.is_none() {
            self.path = Some(match &self.what {
                What::Missing(field) => join(path, field),
                What::Unknown { key, .. } => join(path, key),
                _ => path.to_string(),
            });
            self.span = span;
        }
        self
    }
}

impl std::fmt::Display for Found {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?} at {:?}", self.what, self.path)
    }
}

impl std::error::Error for Found {}

impl de::Error for Found {
    fn custom<T: std::fmt::Display>(msg: T) -> Self {
        Self::new(What::Custom(msg.to_string()))
    }

    fn invalid_type(unexp: Unexpected<'_>, exp: &dyn de::Expected) -> Self {
        Self::new(What::Mismatch {
            expected: exp.to_string(),
            found: unexp.into(),
        })
    }

    fn invalid_value(unexp: Unexpected<'_>, exp: &dyn de::Expected) -> Self {
        Self::invalid_type(unexp, exp)
    }

    fn invalid_length(len: usize, exp: &dyn de::Expected) -> Self {
        Self::new(What::Length {
            expected: exp.to_string(),
            found: len,
        })
    }

    fn unknown_variant(variant: &str, expected: &'static [&'static str]) -> Self {
        Self::new(What::NotOneOf {
            given: variant.to_string(),
            known: expected,
        })
    }

    fn unknown_field(field: &str, expected: &'static [&'static str]) -> Self {
        Self::new(What::Unknown {
            key: field.to_string(),
            known: expected,
            table: None,
        })
    }

    fn missing_field(field: &'static str) -> Self {
        Self::new(What::Missing(field))
    }
}

/// `path.key` (or `key` at the top).
pub(crate) fn join(path: &str, key: &str) -> String {
    if path.is_empty() {
        key.to_string()
    } else {
        format!("{path}.{key}")
    }
}
