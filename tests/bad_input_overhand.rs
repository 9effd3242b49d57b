//! Bad input in `[rod.overhand]` (a preformed overhand knot): one clear error naming the
//! field and the value, never a panic.

use crate::common;

use common::*;
use splinerod::knot::OverhandSpec;

#[test]
fn overhand_conflicts_name_the_field() {
    for (line, field) in [
        ("rest_length = 1.0", "rod.rest_length"),
        ("start = [0.0, 0.0, 0.0]", "rod.start"),
        ("end = [0.5, 0.0, 0.0]", "rod.end"),
        ("knots = \"uniform\"", "rod.knots"),
        (
            "knots = [0, 0, 0, 0, 1, 2, 3, 4, 5, 6, 7, 8, 8, 8, 8]",
            "rod.knots",
        ),
        (
            "initial_control_points = [[0.0, 0.0, 0.0], [0.1, 0.0, 0.0], [0.2, 0.0, 0.0], \
             [0.3, 0.0, 0.0], [0.4, 0.0, 0.0], [0.5, 0.0, 0.0], [0.6, 0.0, 0.0], \
             [0.7, 0.0, 0.0], [0.8, 0.0, 0.0], [0.9, 0.0, 0.0], [1.0, 0.0, 0.0]]",
            "rod.initial_control_points",
        ),
    ] {
        let message = rejected(&with_line_in(KNOT, "[rod]", line));
        assert_field(&message, field);
        assert!(message.contains("overhand"), "{line}: {message}");
    }
    // The default knots, spelled out, are not a conflict.
    accepted(&with_line_in(KNOT, "[rod]", "knots = \"clamped\""));
}

#[test]
fn bad_overhand_size() {
    for value in ["0.0", "-0.15", "-1.0", "nan", "inf"] {
        let message = rejected(&set_in(KNOT, "size", value));
        assert_field_value(&message, "rod.overhand.size", &shown(value));
    }
}

#[test]
fn bad_overhand_span() {
    for value in ["0.0", "-0.5", "nan", "inf"] {
        let message = rejected(&set_in(KNOT, "span", value));
        assert_field_value(&message, "rod.overhand.span", &shown(value));
    }
    let spec = OverhandSpec {
        size: 0.15,
        span: 0.5,
        control_points: 11,
        degree: 3,
    };
    let min = spec.min_span();
    assert!(min > 0.0 && min < 0.5, "min_span {min}");
    for span in [0.5 * min, 0.99 * min, min] {
        let message = rejected(&set_in(KNOT, "span", &span.to_string()));
        assert_field_value(&message, "rod.overhand.span", &span.to_string());
        assert!(message.contains("width"), "{message}");
    }
    accepted(&set_in(KNOT, "span", &(1.2 * min).to_string()));
}

#[test]
fn overhand_missing_or_unknown_fields() {
    let message = rejected(&without_in(KNOT, "span"));
    assert!(message.contains("missing field"), "{message}");
    assert_field(&message, "rod.overhand.span");
    let message = rejected(&without_in(KNOT, "size"));
    assert_field(&message, "rod.overhand.size");
    let message = rejected(&with_line_in(KNOT, "[rod.overhand]", "turns = 2"));
    assert_field(&message, "rod.overhand.turns");
}

#[test]
fn overhand_too_few_control_points() {
    for n in ["5", "6", "3", "2", "0"] {
        let message = rejected(&set_in(KNOT, "control_points", n));
        assert_field_value(&message, "rod.control_points", n);
    }
    let message = rejected(&set_in(KNOT, "control_points", "500"));
    assert_field_value(&message, "rod.control_points", "500");
}

#[test]
fn overhand_bad_degree() {
    for degree in ["0", "10"] {
        let message = rejected(&with_line_in(KNOT, "[rod]", &format!("degree = {degree}")));
        assert!(
            message.contains("rod.overhand.degree") || message.contains("rod.degree"),
            "degree = {degree}: {message}"
        );
    }
}

// ---------------------------------------------------------------- command line
