//! `splinerod bench --quick` finishes in CI-friendly time and reports every figure as a
//! finite positive number under the documented JSON keys.

#[test]
fn quick_bench_reports_every_key() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_splinerod"))
        .args(["bench", "--quick", "--json"])
        .arg(std::env::temp_dir().join(format!("splinerod-bench-{}.json", std::process::id())))
        .output()
        .expect("run bench");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let path = std::env::temp_dir().join(format!("splinerod-bench-{}.json", std::process::id()));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("json")).expect("parse");
    for key in [
        "step_us_16",
        "step_us_16_consistent",
        "static_newton_us_16",
        "per_cp_flatness",
        "ensemble_rod_steps_per_s_1",
        "ensemble_rod_steps_per_s_all",
        "ensemble_rod_steps_per_s_alone_1",
        "batched_speedup",
        "parallel_efficiency",
        "threads",
        "bytes_per_cp",
        "stiff_catenary_settle_s",
        "knot_step_us",
        "checkpoint_us_16",
        "checkpoint_bytes_16",
    ] {
        let v = json[key].as_f64().unwrap_or(f64::NAN);
        assert!(v.is_finite() && v > 0.0, "{key} = {v}");
    }
    for n in ["1000", "10000", "100000"] {
        let v = json["per_cp_ns"][n].as_f64().unwrap_or(f64::NAN);
        assert!(v.is_finite() && v > 0.0, "per_cp_ns[{n}] = {v}");
    }
    let _ = std::fs::remove_file(path);
}
