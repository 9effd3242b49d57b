//! The `.usda` text pieces the writer needs: numbers written so that they read back
//! exactly (doubles with the shortest round-trip digits, floats rounded once from the
//! double and then written with theirs), tuples, time-sample blocks and prim names.

use nalgebra::Vector3;
use splinerod_core::Real;
use std::fmt::{self, Write};

/// A double written exactly: the shortest digits that read back to the same value, in
/// plain notation for moderate magnitudes and in scientific notation otherwise (both
/// are USD float literals).
#[derive(Debug, Clone, Copy)]
pub(super) struct Num(pub Real);

impl fmt::Display for Num {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let a = self.0.abs();
        if a == 0.0 || (1e-3..1e7).contains(&a) {
            write!(f, "{}", self.0)
        } else {
            write!(f, "{:e}", self.0)
        }
    }
}

/// A double rounded to the nearest float (what a `float` or `point3f` attribute holds),
/// written with the float's shortest round-trip digits.
#[derive(Debug, Clone, Copy)]
pub(super) struct Float(pub Real);

impl fmt::Display for Float {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let x = self.0 as f32;
        let a = x.abs();
        if a == 0.0 || (1e-3..1e7).contains(&a) {
            write!(f, "{x}")
        } else {
            write!(f, "{x:e}")
        }
    }
}

/// `(x, y, z)` with each coordinate written by `N`.
pub(super) fn tuple<N: fmt::Display>(
    out: &mut String,
    v: &Vector3<Real>,
    num: impl Fn(Real) -> N,
) -> fmt::Result {
    write!(out, "({}, {}, {})", num(v.x), num(v.y), num(v.z))
}

/// Indentation of an attribute in a prim's body.
pub(super) const ATTRIBUTE: &str = "            ";

/// Indentation of a time sample inside an attribute's block.
pub(super) const SAMPLE: &str = "                ";

/// Opens one time sample of an array attribute: `CODE: [` indented by [`SAMPLE`].
pub(super) fn open_sample(out: &mut String, code: i64) -> fmt::Result {
    write!(out, "{SAMPLE}{code}: [")
}

/// Closes what [`open_sample`] opened: `],` and a line break.
pub(super) fn close_sample(out: &mut String) {
    out.push_str("],\n");
}

/// The separator before item `i` of an array (none before the first).
pub(super) fn separator(out: &mut String, i: usize) {
    if i > 0 {
        out.push_str(", ");
    }
}

/// `samples` (lines written by [`open_sample`] … [`close_sample`]) as the time samples
/// of the attribute declared by `declaration` (e.g. `point3f[] points`), indented by
/// [`ATTRIBUTE`].
pub(super) fn time_samples(out: &mut String, declaration: &str, samples: &str) -> fmt::Result {
    writeln!(out, "{ATTRIBUTE}{declaration}.timeSamples = {{")?;
    out.push_str(samples);
    writeln!(out, "{ATTRIBUTE}}}")
}

/// A valid USD prim name from `name`: letters, digits and `_` kept, anything else `_`,
/// and `_` in front of a leading digit; `fallback` for an empty name.
pub(super) fn prim_name(name: &str, fallback: &str) -> String {
    let mut out = String::with_capacity(name.len() + 1);
    for (i, c) in name.chars().enumerate() {
        if i == 0 && c.is_ascii_digit() {
            out.push('_');
        }
        out.push(if c.is_ascii_alphanumeric() { c } else { '_' });
    }
    if out.is_empty() {
        fallback.to_string()
    } else {
        out
    }
}

/// `text` as a USD string literal (quotes and backslashes escaped, control characters
/// dropped).
pub(super) fn quoted(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + 2);
    out.push('"');
    for c in text.chars().filter(|c| !c.is_control()) {
        if c == '"' || c == '\\' {
            out.push('\\');
        }
        out.push(c);
    }
    out.push('"');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip() {
        for x in [0.1, -1e-20, 3.0000000000000004, 1e300, 123456.789, 0.0] {
            let back: Real = Num(x).to_string().parse().unwrap();
            assert_eq!(back, x);
            let float: f32 = Float(x).to_string().parse().unwrap();
            assert_eq!(float, x as f32);
        }
    }

    #[test]
    fn names_are_identifiers() {
        assert_eq!(prim_name("upper rope", "rod"), "upper_rope");
        assert_eq!(prim_name("2nd", "rod"), "_2nd");
        assert_eq!(prim_name("", "rod_1"), "rod_1");
        assert_eq!(quoted("a \"b\"\\"), r#""a \"b\"\\""#);
    }
}
