//! Bad input in the adaptivity, grab and cut tables and the bending fields: one clear
//! error naming the field.

use splinerod::Scene;

const BASE: &str = r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
control_points = 8

[[pins]]
at = 0.0

[solver]
method = "implicit-euler"
dt = 0.01
duration = 0.1
"#;

fn rejects(extra: &str, field: &str) {
    let text = format!("{BASE}\n{extra}\n");
    let result = std::panic::catch_unwind(|| Scene::from_toml(&text));
    let Ok(result) = result else {
        panic!("panicked on {extra}");
    };
    match result {
        Ok(_) => panic!("accepted: {extra}"),
        Err(e) => {
            let message = e.to_string();
            assert!(
                message.contains(field),
                "{extra}: `{message}` does not name {field}"
            );
        }
    }
}

#[test]
fn base_with_every_table_is_valid() {
    let text = format!(
        "{BASE}\n[adaptivity]\nmax_control_points = 30\n[[grabs]]\nat = 0.5\nto = [0.5, 0.1, 0.0]\n\
         end_time = 0.1\nstiffness = 10.0\n[[cuts]]\nat = 0.4\ntime = 0.05\n"
    );
    Scene::from_toml(&text).expect("valid");
}

#[test]
fn cut_or_grab_outside_the_rod() {
    for at in ["-0.1", "1.5", "0.0", "1.0", "nan"] {
        rejects(&format!("[[cuts]]\nat = {at}\ntime = 0.0"), "cuts[0].at");
    }
    for at in ["-0.1", "1.5", "nan"] {
        let grab =
            format!("[[grabs]]\nat = {at}\nto = [0.0, 0.0, 0.0]\nend_time = 1.0\nstiffness = 1.0");
        rejects(&grab, "grabs[0].at");
    }
    rejects("[[cuts]]\nat = 0.5\ntime = -1.0", "cuts[0].time");
}

#[test]
fn bad_grab_values() {
    let grab = |to: &str, times: &str, k: &str| {
        format!("[[grabs]]\nat = 0.5\nto = {to}\n{times}\nstiffness = {k}")
    };
    rejects(
        &grab("[0.0, nan, 0.0]", "end_time = 1.0", "1.0"),
        "grabs[0].to",
    );
    rejects(
        &grab("[0.0, 0.0, 0.0]", "end_time = 1.0", "-5.0"),
        "grabs[0].stiffness",
    );
    rejects(
        &grab("[0.0, 0.0, 0.0]", "end_time = 1.0", "0.0"),
        "grabs[0].stiffness",
    );
    let backwards = "start_time = 2.0\nend_time = 1.0";
    rejects(
        &grab("[0.0, 0.0, 0.0]", backwards, "1.0"),
        "grabs[0].end_time",
    );
    rejects(
        "[[grabs]]\nat = 0.5\nto = [0.0, 0.0, 0.0]\nstiffness = 1.0",
        "end_time",
    );
}

#[test]
fn bad_adaptivity_values() {
    let cases = [
        ("insert_threshold = -0.1", "adaptivity.insert_threshold"),
        ("remove_threshold = -0.01", "adaptivity.remove_threshold"),
        (
            "insert_threshold = 0.01\nremove_threshold = 0.02",
            "adaptivity.remove_threshold",
        ),
        ("shape_tolerance = 0.0", "adaptivity.shape_tolerance"),
        ("shape_tolerance = nan", "adaptivity.shape_tolerance"),
        ("max_control_points = 5", "adaptivity.max_control_points"),
        ("min_span = 0.0", "adaptivity.min_span"),
        ("min_span = 2.0", "adaptivity.min_span"),
        ("interaction_radius = -1.0", "adaptivity.interaction_radius"),
        (
            "interaction_multiplicity = 0",
            "adaptivity.interaction_multiplicity",
        ),
        (
            "min_control_points = 50\nmax_control_points = 40",
            "adaptivity.min_control_points",
        ),
        ("min_control_points = 1", "adaptivity.min_control_points"),
        ("colour = 1", "adaptivity.colour"),
        ("tolerance = 0.0", "adaptivity.tolerance"),
        ("tolerance = -1e-4", "adaptivity.tolerance"),
        ("tolerance = nan", "adaptivity.tolerance"),
        ("tolerance = inf", "adaptivity.tolerance"),
        ("tolerance = \"small\"", "adaptivity.tolerance"),
        (
            "tolerance = 1e-4\ninsert_threshold = 0.05",
            "adaptivity.insert_threshold",
        ),
        (
            "tolerance = 1e-4\nremove_threshold = 0.001",
            "adaptivity.remove_threshold",
        ),
    ];
    for (line, field) in cases {
        rejects(&format!("[adaptivity]\n{line}"), field);
    }
}

/// `[output] error_estimate` must be a boolean.
#[test]
fn bad_error_estimate_flag() {
    rejects("[output]\nerror_estimate = 1", "output.error_estimate");
}

#[test]
fn bad_bending_values() {
    let with_rod_line =
        |line: &str| BASE.replace("control_points = 8", &format!("control_points = 8\n{line}"));
    for (line, field) in [
        ("bending_stiffness = -1.0", "rod.bending_stiffness"),
        ("bending_stiffness = nan", "rod.bending_stiffness"),
        (
            "bending_stiffness = 1.0\ndegree = 1",
            "rod.bending_stiffness",
        ),
    ] {
        let text = with_rod_line(line);
        let e = Scene::from_toml(&text).expect_err(line).to_string();
        assert!(e.contains(field), "{line}: {e}");
    }
    let clamp_without_bending = BASE.replace("at = 0.0", "at = 0.0\nclamp = true");
    let e = Scene::from_toml(&clamp_without_bending)
        .expect_err("clamp")
        .to_string();
    assert!(e.contains("pins[0].clamp"), "{e}");
    let unknown_method = BASE.replace("implicit-euler", "explicit-euler");
    let e = Scene::from_toml(&unknown_method)
        .expect_err("method")
        .to_string();
    assert!(e.contains("solver.method") || e.contains("method"), "{e}");
}
