//! Bad scenes through the `splinerod` command line: exit code 2 and one `error:` line
//! naming the file, the field and the value (the scenes of `bad_input.rs`); a valid
//! scene writes its JSON.

use crate::bad_input::{set, with_line, BASE};
use crate::common;

use common::cli::{fresh_dir, refused, refused_scene, splinerod};
use common::{assert_field, assert_field_value};
use std::path::Path;

#[test]
fn cli_nan_density() {
    let stderr = refused_scene("nan", &set("linear_density", "nan"));
    assert_field_value(&stderr, "rod.linear_density", "NaN");
}

#[test]
fn cli_unknown_field() {
    let stderr = refused_scene("unknown", &with_line("[rod]", "colour = \"red\""));
    assert_field(&stderr, "rod.colour");
    assert!(stderr.contains("scene.toml"), "file not named: {stderr}");
}

#[test]
fn cli_missing_file() {
    let dir = fresh_dir("missing");
    let path = dir.join("no_such_scene.toml");
    let stderr = refused(&["run", path.to_str().expect("UTF-8")]);
    assert!(stderr.contains(&path.display().to_string()), "{stderr}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn cli_malformed_toml() {
    let text = BASE.replacen("linear_density = 0.1", "linear_density = = 0.1", 1);
    let stderr = refused_scene("syntax", &text);
    assert!(stderr.contains("scene.toml"), "file not named: {stderr}");
    assert!(stderr.contains("line 3"), "line not named: {stderr}");
    let unclosed = BASE.replacen("[world]", "[world", 1);
    let stderr = refused_scene("unclosed", &unclosed);
    assert!(stderr.contains("line 18"), "line not named: {stderr}");
}

/// `value[path]` for a dotted `path`, which must exist.
fn get<'a>(value: &'a serde_json::Value, path: &str) -> &'a serde_json::Value {
    path.split('.').fold(value, |v, key| {
        v.get(key).unwrap_or_else(|| panic!("JSON has no `{path}`"))
    })
}

#[test]
fn cli_valid_scene_writes_json() {
    let dir = fresh_dir("valid");
    let json = dir.join("out.json");
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/catenary_static.toml");
    let (scene, out_json) = (
        scene.to_str().expect("UTF-8"),
        json.to_str().expect("UTF-8"),
    );
    let out = splinerod(&["run", scene, "--json", out_json]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "stderr: {stderr}");
    let text = std::fs::read_to_string(&json).expect("JSON written");
    let result: serde_json::Value = serde_json::from_str(&text).expect("valid JSON");
    for key in ["time", "steps", "control_points", "wall_seconds"] {
        assert!(get(&result, key).is_number(), "`{key}` is not a number");
    }
    for key in ["energy.kinetic", "energy.stretch", "energy.gravity"] {
        assert!(get(&result, key).as_f64().unwrap().is_finite(), "`{key}`");
    }
    let s = get(&result, "samples.s").as_array().unwrap();
    let positions = get(&result, "samples.positions").as_array().unwrap();
    assert!(s.len() >= 2);
    assert_eq!(s.len(), positions.len());
    assert!(positions.iter().all(|p| p.as_array().unwrap().len() == 3));
    for key in ["probes", "knots", "pin_forces"] {
        assert!(get(&result, key).is_array(), "`{key}` is not an array");
    }
    assert!(get(&result, "solver.newton_iterations").is_number());
    for key in ["substeps", "rejected_steps", "continuation_steps"] {
        assert!(get(&result, &format!("solver.{key}")).is_number(), "{key}");
    }
    assert!(
        get(&result, "solver.smallest_dt").is_null(),
        "static: no dt"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
