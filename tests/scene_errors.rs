//! Scene errors in the user's words: a value of the wrong type says what was expected
//! and what was found ("a number", "a whole number", "true or false", "a table", "a
//! list of 3 numbers", never serde's `f64` or `usize`); an unknown key that is a table
//! is called a table; a close name is suggested; every missing required field is named
//! at once; command-line options that do not go together say why in a sentence.

use crate::common;

use common::cli::{fresh_dir, ok, refused};
use common::*;
use splinerod::Scene;

/// A valid scene that every test alters.
const BASE: &str = r#"[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 6
start = [0.0, 0.0, 0.0]
end = [0.8, 0.0, 0.0]

[[pins]]
at = 0.0

[world]
gravity = [0.0, -9.81, 0.0]

[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.05
line_search = true
"#;

/// The error of `text`, which must be refused; checked to be free of Rust's words.
fn refused_scene(text: &str) -> String {
    let message = rejected(text);
    for rust in [
        "f64",
        "usize",
        "u64",
        "i64",
        "struct ",
        "sequence",
        "invalid type",
    ] {
        assert!(!message.contains(rust), "`{rust}` in: {message}");
    }
    message
}

/// `message` contains `part`.
fn says(message: &str, part: &str) {
    assert!(message.contains(part), "no `{part}` in: {message}");
}

#[test]
fn base_scene_is_valid() {
    accepted(BASE);
}

#[test]
fn wrong_types_say_what_was_expected_and_found() {
    for (key, value, words) in [
        (
            "rest_length",
            "\"1.0\"",
            "`rod.rest_length`: expected a number, found the string \"1.0\"",
        ),
        (
            "control_points",
            "16.0",
            "`rod.control_points`: expected a whole number, found 16.0",
        ),
        (
            "control_points",
            "-6",
            "`rod.control_points`: expected a whole number ≥ 0, found -6",
        ),
        (
            "line_search",
            "1",
            "`solver.line_search`: expected true or false, found 1",
        ),
        (
            "start",
            "[0.0, 0.0]",
            "`rod.start`: expected a list of 3 numbers, found a list of 2",
        ),
        (
            "start",
            "[0.0, \"a\", 0.0]",
            "`rod.start[1]`: expected a number, found the string \"a\"",
        ),
        (
            "stretch_stiffness",
            "true",
            "`rod.stretch_stiffness`: expected a number (N) or \"inextensible\", found true",
        ),
    ] {
        let message = refused_scene(&set_in(BASE, key, value));
        says(&message, words);
    }
    let no_world = BASE.replace("[world]\ngravity = [0.0, -9.81, 0.0]\n", "");
    let message = refused_scene(&format!("world = 5\n{no_world}"));
    says(&message, "`world`: expected a table, found 5");
    let no_pins = BASE.replace("[[pins]]\nat = 0.0\n", "");
    let message = refused_scene(&format!("pins = 3\n{no_pins}"));
    says(&message, "`pins`: expected a list, found 3");
}

#[test]
fn wrong_types_keep_their_line_and_column() {
    let message = refused_scene(&set_in(BASE, "rest_length", "\"1.0\""));
    says(&message, "line 2, column 15: `rod.rest_length`");
}

#[test]
fn an_unknown_table_is_called_a_table_with_the_closest_name() {
    let message = refused_scene(&BASE.replace("[world]", "[wrold]"));
    says(&message, "unknown table [wrold]: did you mean [world]?");
    assert!(!message.contains("field"), "{message}");
    let message = refused_scene(&BASE.replace("[[pins]]", "[[pinns]]"));
    says(&message, "unknown table [[pinns]]: did you mean [[pins]]?");
    assert!(!message.contains("field"), "{message}");
    let message = refused_scene(&with_line_in(BASE, "[rod]", "colour = { red = 1 }"));
    says(&message, "unknown table [rod.colour] ([rod] takes `name`,");
}

#[test]
fn an_unknown_field_gets_the_closest_name_or_the_list() {
    let typo = BASE.replace("linear_density", "linear_densty");
    let message = refused_scene(&typo);
    says(
        &message,
        "unknown field `rod.linear_densty`: did you mean `linear_density`?",
    );
    let message = refused_scene(&with_line_in(BASE, "[world]", "colour = 1"));
    says(
        &message,
        "unknown field `world.colour` ([world] takes `gravity`)",
    );
    let message = refused_scene(&BASE.replace("implicit-euler", "implicit_euler"));
    says(
        &message,
        "`solver.method`: \"implicit_euler\" is not one of",
    );
    says(&message, "did you mean \"implicit-euler\"?");
}

#[test]
fn every_missing_required_field_is_named_at_once() {
    let three = ["linear_density", "control_points", "method"]
        .iter()
        .fold(BASE.to_string(), |text, key| without_in(&text, key));
    let message = refused_scene(&three);
    says(
        &message,
        "missing fields `rod.linear_density`, `rod.control_points` and `solver.method`",
    );
    // With the rest length (one of rest_length and overhand) and a missing table too.
    let no_solver = without_in(BASE.split("[solver]").next().unwrap(), "rest_length");
    let message = refused_scene(&without_in(&no_solver, "linear_density"));
    says(&message, "`rod.linear_density`");
    says(
        &message,
        "`rod.rest_length` (required unless rod.overhand gives the shape)",
    );
    says(&message, "missing table [solver]");
    assert!(!message.contains("field `solver`"), "{message}");
}

#[test]
fn a_missing_rod_table_is_a_table() {
    let solver_only = format!("[solver]{}", BASE.split("[solver]").nth(1).unwrap());
    let message = refused_scene(&solver_only);
    assert_eq!(message, "missing table [rod] (or [[rods]])");
    let rod = BASE
        .split("\n\n")
        .next()
        .unwrap()
        .replace("[rod]", "[[rods]]");
    let both = format!("{BASE}\n{rod}\n");
    let message = refused_scene(&both);
    says(&message, "table [[rods]] is given with [rod]");
    assert!(!message.contains("field"), "{message}");
}

#[test]
fn problems_of_every_kind_are_reported_together() {
    let text = without_in(&BASE.replace("[world]", "[wrold]"), "control_points");
    let text = set_in(&text, "dt", "\"fast\"");
    let message = refused_scene(&text);
    says(&message, "line 11, column 2: unknown table [wrold]");
    says(
        &message,
        "line 16, column 6: `solver.dt`: expected a number",
    );
    says(&message, "missing field `rod.control_points`");
    let error = Scene::from_toml(&text).unwrap_err();
    assert_eq!(error.field_name(), Some("wrold"));
}

#[test]
fn the_command_line_says_it_on_one_line() {
    let dir = fresh_dir("scene-errors");
    let path = dir.join("scene.toml");
    let text = without_in(&BASE.replace("[world]", "[wrold]"), "linear_density");
    std::fs::write(&path, text).unwrap();
    let path = path.to_str().unwrap();
    let line = refused(&["run", path]);
    says(
        &line,
        "scene.toml: line 11, column 2: unknown table [wrold]",
    );
    says(&line, "; missing field `rod.linear_density`");
    std::fs::write(dir.join("scene.toml"), BASE).unwrap();
    let gif = dir.join("run.gif");
    let gif = gif.to_str().unwrap();
    let line = refused(&["run", path, "--gif", gif]);
    assert_eq!(
        line,
        "error: --gif needs --frames DIR: the GIF is assembled from the PNG pictures written there"
    );
    let frames = dir.join("frames");
    let checkpoint = dir.join("checkpoint");
    let (frames, checkpoint) = (frames.to_str().unwrap(), checkpoint.to_str().unwrap());
    let line = refused(&[
        "run",
        path,
        "--gif",
        gif,
        "--frames",
        frames,
        "--checkpoint",
        checkpoint,
    ]);
    says(
        &line,
        "--gif cannot go with --checkpoint: a GIF cannot be continued",
    );
    ok(&["run", path, "--gif", gif, "--frames", frames]);
    assert!(std::path::Path::new(gif).exists(), "no GIF written");
    std::fs::remove_dir_all(&dir).unwrap();
}
