//! Scene errors in the user's words. When a scene's TOML does not deserialize, the
//! document is read again ([`super::probe`]), each reading past the problems found
//! before, until every problem is found; they are reported together
//! ([`Error::Format`]):
//!
//! * a value of the wrong type: "`rod.rest_length`: expected a number, found the
//!   string "1.0"" (never serde's `f64` or `usize`);
//! * an unknown key or table, with the closest known name if one is close
//!   (Damerau–Levenshtein distance at most a third of the name's length):
//!   "unknown table [wrold]: did you mean [world]?";
//! * a name that is none of those allowed: "`solver.method`: "implicit_euler" is not
//!   one of …; did you mean "implicit-euler"?";
//! * a value out of range that a deserializer refuses (its error `"= inf: …"`), as
//!   [`Error::InvalidField`] words it: "scene field `rod.stretch_stiffness` = inf: …";
//! * every missing required field and table, in one sentence.

use crate::error::Error;
use crate::scene::found::{join, Found, Seen, What};
use crate::scene::probe::{self, Fix, Reading};
use serde::de::DeserializeOwned;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt;
use toml::de::DeTable;

/// Most problems one error reports (each costs a reading of the document).
const MAX_PROBLEMS: usize = 40;

/// One thing wrong with a scene's keys or values ([`Error::Format`]).
#[derive(Debug, Clone, PartialEq)]
pub enum Problem {
    /// A value of the wrong type, an unknown key or table, a name not allowed.
    Wrong {
        /// Dotted path of the value or key (`rod.rest_length`, `pins[1].at`, `wrold`).
        field: String,
        /// Line and column (1-based) of the text to blame, if known.
        position: Option<(usize, usize)>,
        /// What is wrong, naming the field.
        message: String,
    },
    /// A required field or table that is absent.
    Missing {
        /// Dotted path.
        field: String,
        /// Whether it is a table (`[solver]`).
        table: bool,
        /// When it is required, if not always.
        note: Option<String>,
    },
}

impl Problem {
    /// Dotted path of the field, key or table the problem is about.
    pub fn field(&self) -> &str {
        match self {
            Self::Wrong { field, .. } | Self::Missing { field, .. } => field,
        }
    }
}

/// Deserializes `text` as a `T`. When it does not fit, an [`Error::Format`] naming every
/// problem found, with those `also` finds in the document (requirements serde cannot
/// state, such as one of two keys); toml's own error for text that is not TOML.
pub(crate) fn read<T: DeserializeOwned>(
    text: &str,
    also: fn(&DeTable<'_>) -> Vec<Problem>,
) -> Result<T, Error> {
    toml::from_str(text).map_err(|e| match find::<T>(text, also) {
        Some(problems) if !problems.is_empty() => Error::Format {
            file: None,
            problems,
        },
        _ => super::parse_error(text, &e),
    })
}

/// Every problem of `text` as a `T` (`None` if it is not TOML).
fn find<T: DeserializeOwned>(
    text: &str,
    also: fn(&DeTable<'_>) -> Vec<Problem>,
) -> Option<Vec<Problem>> {
    let root = probe::root_value(DeTable::parse(text).ok()?);
    let mut fixes = BTreeMap::new();
    let (mut found, mut tables) = (Vec::new(), BTreeSet::new());
    for _ in 0..MAX_PROBLEMS {
        let reading = Reading::new(&fixes);
        let result = T::deserialize(reading.root(&root));
        tables.append(&mut reading.tables.take());
        let Err(e) = result else { break };
        let e = e.at("", None);
        let path = e.path.clone().unwrap_or_default();
        let fix = match e.what {
            What::Unknown { .. } => Fix::Drop,
            _ => Fix::StandIn,
        };
        // A stand-in that did not fit, or one whose type was guessed, ends the search.
        let named = matches!(e.what, What::Missing(_) | What::Unknown { .. });
        if fixes.contains_key(&path) || (reading.guessed.get() && !named) {
            break;
        }
        fixes.insert(path, fix);
        found.push(e);
    }
    let mut problems: Vec<_> = found
        .into_iter()
        .map(|e| problem(text, e, &tables))
        .collect();
    if let Some(table) = root.get_ref().as_table() {
        for extra in also(table) {
            if problems.iter().all(|p| p.field() != extra.field()) {
                problems.push(extra);
            }
        }
    }
    // In the order of the file, then the missing ones.
    problems.sort_by_key(|p| match p {
        Problem::Wrong { position, .. } => (false, *position),
        Problem::Missing { .. } => (true, None),
    });
    Some(problems)
}

/// The problem `e` describes, in the user's words; `tables` are the missing fields read
/// as tables.
fn problem(text: &str, e: Found, tables: &BTreeSet<String>) -> Problem {
    let field = e.path.unwrap_or_default();
    let at = if field.is_empty() {
        String::new()
    } else {
        format!("`{field}`: ")
    };
    let message = match e.what {
        What::Missing(_) => {
            return Problem::Missing {
                table: tables.contains(&field),
                field,
                note: None,
            }
        }
        What::Unknown { key, known, table } => unknown(&field, &key, known, table),
        What::NotOneOf { given, known } => {
            let hint = closest(&given, known)
                .map(|s| format!("; did you mean \"{s}\"?"))
                .unwrap_or_default();
            format!("{at}\"{given}\" is not one of {}{hint}", one_of(known))
        }
        What::Mismatch { expected, found } => format!(
            "{at}expected {}, found {}",
            expected_words(&expected, &found),
            found_words(&found)
        ),
        What::Length { expected, found } => {
            let expected = expected_words(&expected, &Seen::Other(String::new()));
            format!("{at}expected {expected}, found a list of {found}")
        }
        // A value out of range, as `Error::InvalidField` words it.
        What::Custom(message) if message.starts_with("= ") => {
            format!("scene field `{field}` {message}")
        }
        What::Custom(message) => format!("{at}{message}"),
    };
    Problem::Wrong {
        field,
        position: e.span.map(|s| line_column(text, s.start)),
        message,
    }
}

/// "unknown field `rod.colour`" or "unknown table [wrold]", with the closest known name
/// or, without one close, the names known.
fn unknown(field: &str, key: &str, known: &'static [&'static str], table: Option<&str>) -> String {
    let parent = field
        .strip_suffix(key)
        .map(|p| p.trim_end_matches('.'))
        .unwrap_or("");
    let name = |path: &str| match table {
        Some("[[]]") => format!("[[{path}]]"),
        Some(_) => format!("[{path}]"),
        None => format!("`{path}`"),
    };
    let what = if table.is_some() { "table" } else { "field" };
    let head = format!("unknown {what} {}", name(field));
    if let Some(close) = closest(key, known) {
        let close = match table {
            Some(_) => name(&join(parent, close)),
            None => format!("`{close}`"),
        };
        return format!("{head}: did you mean {close}?");
    }
    let owner = match parent {
        "" => "a scene".to_string(),
        p if p.contains('[') => format!("`{p}`"),
        p => format!("[{p}]"),
    };
    let list: Vec<_> = known.iter().map(|k| format!("`{k}`")).collect();
    format!("{head} ({owner} takes {})", list.join(", "))
}

/// The name in `known` closest to `given`, if close: Damerau–Levenshtein distance at
/// most a third of its length (at least 1), or the same but for case.
fn closest<'k>(given: &str, known: &[&'k str]) -> Option<&'k str> {
    let allowed = (given.chars().count() / 3).max(1);
    known
        .iter()
        .map(|k| {
            let d = strsim::damerau_levenshtein(&given.to_lowercase(), &k.to_lowercase());
            (d, *k)
        })
        .filter(|(d, _)| *d <= allowed)
        .min_by_key(|(d, _)| *d)
        .map(|(_, k)| k)
}

/// `"a", "b" or "c"`.
pub(crate) fn one_of(names: &[&str]) -> String {
    let quoted: Vec<_> = names.iter().map(|n| format!("\"{n}\"")).collect();
    match quoted.split_last() {
        None => "nothing".into(),
        Some((last, [])) => last.clone(),
        Some((last, rest)) => format!("{} or {last}", rest.join(", ")),
    }
}

/// What serde expected, in the user's words: "a number" for `f64`, "a whole number"
/// for `usize` ("≥ 0" when a negative one was `found`), "a table" for a struct.
fn expected_words(expected: &str, found: &Seen) -> String {
    let negative = matches!(found, Seen::Integer(n) if *n < 0);
    let words = match expected {
        "f32" | "f64" => "a number",
        "u8" | "u16" | "u32" | "u64" | "u128" | "usize" if negative => "a whole number ≥ 0",
        "u8" | "u16" | "u32" | "u64" | "u128" | "usize" => "a whole number",
        "i8" | "i16" | "i32" | "i64" | "i128" | "isize" => "a whole number",
        "a boolean" => "true or false",
        "a string" | "a borrowed string" | "a character" => "a string",
        "a sequence" => "a list",
        "a map" => "a table",
        other if other.starts_with("struct ") || other.contains("tagged enum ") => "a table",
        other => {
            if let Some(n) = other.strip_prefix("an array of length ") {
                return format!("a list of {n} numbers");
            }
            if let Some(n) = other.strip_prefix("a tuple of size ") {
                return format!("a list of {n} values");
            }
            other
        }
    };
    words.to_string()
}

/// A value as the user wrote it: `16.0`, `true`, `the string "1.0"`, `a table`.
fn found_words(found: &Seen) -> String {
    match found {
        Seen::Bool(b) => b.to_string(),
        Seen::Integer(n) => n.to_string(),
        Seen::Float(x) => format!("{x:?}"),
        Seen::Str(s) => format!("the string \"{s}\""),
        Seen::Other(s) => s.clone(),
    }
}

/// Line and column (1-based) of byte `offset` of `text`.
pub(crate) fn line_column(text: &str, offset: usize) -> (usize, usize) {
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let column = before.chars().rev().take_while(|&c| c != '\n').count() + 1;
    (line, column)
}

/// Problems listed on one line: each wrong value or key (with its position), then the
/// missing fields and tables in one sentence each.
pub(crate) struct Listed<'a>(pub &'a [Problem]);

impl fmt::Display for Listed<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let mut parts = Vec::new();
        let mut fields = Vec::new();
        let mut tables = Vec::new();
        for p in self.0 {
            match p {
                Problem::Wrong {
                    position, message, ..
                } => parts.push(match position {
                    Some((l, c)) => format!("line {l}, column {c}: {message}"),
                    None => message.clone(),
                }),
                Problem::Missing { field, table, note } => {
                    let note = note.as_ref().map(|n| format!(" ({n})")).unwrap_or_default();
                    match table {
                        true => tables.push(format!("[{field}]{note}")),
                        false => fields.push(format!("`{field}`{note}")),
                    }
                }
            }
        }
        for (names, one, many) in [(fields, "field", "fields"), (tables, "table", "tables")] {
            match names.split_last() {
                None => {}
                Some((last, [])) => parts.push(format!("missing {one} {last}")),
                Some((last, rest)) => {
                    parts.push(format!("missing {many} {} and {last}", rest.join(", ")))
                }
            }
        }
        write!(f, "{}", parts.join("; "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_close_names_are_suggested() {
        let known = ["linear_density", "damping", "degree"];
        assert_eq!(closest("linear_densty", &known), Some("linear_density"));
        assert_eq!(closest("Degree", &known), Some("degree"));
        assert_eq!(closest("colour", &known), None);
        assert_eq!(one_of(&["a", "b", "c"]), "\"a\", \"b\" or \"c\"");
    }

    #[test]
    fn serde_types_are_worded() {
        let float = Seen::Float(16.0);
        assert_eq!(expected_words("usize", &float), "a whole number");
        assert_eq!(
            expected_words("u64", &Seen::Integer(-6)),
            "a whole number ≥ 0"
        );
        assert_eq!(expected_words("f64", &float), "a number");
        assert_eq!(expected_words("struct RodSpec", &float), "a table");
        assert_eq!(
            expected_words("an array of length 3", &float),
            "a list of 3 numbers"
        );
        assert_eq!(found_words(&float), "16.0");
        assert_eq!(found_words(&Seen::Str("1.0".into())), "the string \"1.0\"");
    }
}
