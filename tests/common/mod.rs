//! Shared helpers of the integration tests: reference data and scene builders.
#![allow(dead_code)]

use serde_json::Value;
use splinerod::{Real, Scene};

/// Parsed JSON of a file in `tests/data/`.
pub fn reference(name: &str) -> Value {
    let path = format!("{}/tests/data/{name}", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// A JSON array of numbers.
pub fn numbers(v: &Value) -> Vec<Real> {
    v.as_array()
        .expect("array")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

/// The reference catenary: material fractions and equilibrium (x, y).
pub fn catenary_reference() -> (Vec<Real>, Vec<[Real; 2]>) {
    let r = reference("catenary_L1_D0.8_mu0.1_EA100.json");
    let s = numbers(&r["s"]);
    let xy = r["xy"]
        .as_array()
        .expect("xy")
        .iter()
        .map(|p| {
            let p = numbers(p);
            [p[0], p[1]]
        })
        .collect();
    (s, xy)
}

/// The catenary scene (L = 1, D = 0.8, μ = 0.1, EA = 100) with `n` control points,
/// ending with the given `[solver]` table.
pub fn catenary_scene(n: usize, damping: Real, solver: &str) -> Scene {
    let text = format!(
        r#"
[rod]
rest_length = 1.0
linear_density = 0.1
stretch_stiffness = 100.0
damping = {damping}
control_points = {n}
start = [0.0, 0.0, 0.0]
end = [0.8, 0.0, 0.0]

[[pins]]
at = 0.0

[[pins]]
at = 1.0

[solver]
{solver}
"#
    );
    Scene::from_toml(&text).expect("valid catenary scene")
}

/// Largest distance between the run's samples and the reference material points.
pub fn max_error(positions: &[[Real; 3]], reference: &[[Real; 2]]) -> Real {
    assert_eq!(positions.len(), reference.len());
    positions
        .iter()
        .zip(reference)
        .map(|(p, r)| ((p[0] - r[0]).powi(2) + (p[1] - r[1]).powi(2) + p[2].powi(2)).sqrt())
        .fold(0.0, Real::max)
}
