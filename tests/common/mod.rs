//! Editing and checking scene texts for the bad-input tests: replace, drop or add one
//! line, and assert that a scene is rejected with an error naming the field and value.
#![allow(dead_code)] // each test binary uses a different subset

pub mod cli;

use splinerod::prelude::Vector3;
use splinerod::Scene;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// The line of `text` that sets `key`; there must be exactly one.
pub fn line_of<'a>(text: &'a str, key: &str) -> &'a str {
    let prefix = format!("{key} = ");
    let lines: Vec<&str> = text.lines().filter(|l| l.starts_with(&prefix)).collect();
    assert_eq!(
        lines.len(),
        1,
        "`{key}` must be set exactly once in the base"
    );
    lines[0]
}

/// `text` with the value of `key` replaced by `value` (TOML syntax).
pub fn set_in(text: &str, key: &str, value: &str) -> String {
    text.replacen(line_of(text, key), &format!("{key} = {value}"), 1)
}

/// `text` without the line that sets `key`.
pub fn without_in(text: &str, key: &str) -> String {
    text.replacen(&format!("{}\n", line_of(text, key)), "", 1)
}

/// `text` with `line` added after the header `table`.
pub fn with_line_in(text: &str, table: &str, line: &str) -> String {
    assert!(text.contains(table), "no {table} in the base");
    text.replacen(table, &format!("{table}\n{line}"), 1)
}

/// Parses, validates and builds `text`, which must fail without panicking; the error.
pub fn rejected(text: &str) -> String {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        Scene::from_toml(text).and_then(|scene| scene.build_system().map(|_| ()))
    }));
    match outcome {
        Ok(Err(e)) => e.to_string(),
        Ok(Ok(())) => panic!("scene accepted:\n{text}"),
        Err(_) => panic!("scene panicked instead of failing:\n{text}"),
    }
}

/// Parses, validates and builds `text`, which must pass.
pub fn accepted(text: &str) -> Scene {
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        let scene = Scene::from_toml(text)?;
        scene.build_system()?;
        Ok::<_, splinerod::Error>(scene)
    }));
    match outcome {
        Ok(Ok(scene)) => scene,
        Ok(Err(e)) => panic!("scene rejected: {e}\n{text}"),
        Err(_) => panic!("scene panicked:\n{text}"),
    }
}

/// `message` names `field`.
pub fn assert_field(message: &str, field: &str) {
    assert!(message.contains(field), "`{field}` not named in: {message}");
}

/// `message` names `field` followed by `value` (as Rust displays it).
pub fn assert_field_value(message: &str, field: &str, value: &str) {
    assert_field(message, field);
    let after = message.split_once(field).unwrap().1;
    let after = after.trim_start_matches(['`', ' ', '=']);
    assert!(
        after.starts_with(value),
        "`{field}` not followed by {value} in: {message}"
    );
}

/// `value` as the error displays it: `-1.0` as `-1`, `nan` as `NaN`, a number of more
/// than 24 characters in exponent form (`1e300`).
pub fn shown(value: &str) -> String {
    let v = value.parse::<f64>().unwrap();
    match v.to_string() {
        long if long.len() > 24 => format!("{v:e}"),
        short => short,
    }
}

/// Negative, zero and non-finite values of `key` in `text` are rejected naming `field`
/// and the value.
pub fn assert_needs_positive_in(text: &str, key: &str, field: &str) {
    for value in ["-2.5", "-1.0", "0.0", "0", "nan", "inf", "-inf"] {
        let toml_value = if value == "0" { "0.0" } else { value };
        assert_field_value(
            &rejected(&set_in(text, key, toml_value)),
            field,
            &shown(value),
        );
    }
}

/// Largest distance between the sampled end positions of two runs, m.
pub fn sample_gap(a: &splinerod::RunResult, b: &splinerod::RunResult) -> f64 {
    let pairs = a.samples.positions.iter().zip(&b.samples.positions);
    pairs
        .map(|(p, q)| (Vector3::from(*p) - Vector3::from(*q)).norm())
        .fold(0.0, f64::max)
}

/// A valid rod with a preformed overhand knot (as `scenes/knot_tying.toml`).
pub const KNOT: &str = r#"[rod]
linear_density = 0.01
stretch_stiffness = 100.0
control_points = 11
radius = 0.003
rest_shape = "initial"

[rod.overhand]
size = 0.15
span = 0.5

[[pins]]
at = 0.0

[contact]
stiffness = 1e4

[solver]
method = "implicit-euler"
dt = 0.001
duration = 0.01
"#;

/// A deterministic stand-in for Gaussian noise of unit variance: sample `i` (a sum of 12
/// uniforms from a xorshift seeded by `i`).
pub fn noise(i: usize) -> splinerod::Real {
    let mut x = (i as u64 + 7).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut sum = 0.0;
    for _ in 0..12 {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        sum += (x >> 11) as splinerod::Real / (1u64 << 53) as splinerod::Real;
    }
    sum - 6.0
}

/// Every fitted parameter within 2 % of its true value and within 3 reported σ.
pub fn recovered(report: &splinerod::fit::FitReport, params: &[&str], truths: &[splinerod::Real]) {
    for (k, &truth) in truths.iter().enumerate() {
        let (p, s) = (report.parameters[k], report.std[k]);
        assert!(
            (p / truth - 1.0).abs() < 0.02,
            "{}: {p} vs {truth}",
            params[k]
        );
        assert!(
            (p - truth).abs() < 3.0 * s,
            "{}: {p} vs {truth} ± {s}",
            params[k]
        );
    }
}
