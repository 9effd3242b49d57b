//! The scenes of `scenes/`, compiled into the library so that a program (and the Python
//! package, `splinerod.bundled_scene`) finds them wherever it runs, without the
//! repository at hand: [`SCENES`] holds each file's text under its stem, [`scene_text`]
//! looks one up, [`scene`] parses it.

use crate::{Error, Scene};

/// Every bundled scene, `(name, TOML text)`, sorted by name; the name is the file stem
/// in `scenes/` (`"hanging_cable"` for `scenes/hanging_cable.toml`).
pub const SCENES: &[(&str, &str)] = &[
    (
        "body_pendulum",
        include_str!("../scenes/body_pendulum.toml"),
    ),
    ("body_tow", include_str!("../scenes/body_tow.toml")),
    ("cantilever", include_str!("../scenes/cantilever.toml")),
    (
        "catenary_static",
        include_str!("../scenes/catenary_static.toml"),
    ),
    ("cut_contact", include_str!("../scenes/cut_contact.toml")),
    ("cut_three", include_str!("../scenes/cut_three.toml")),
    ("cut_two", include_str!("../scenes/cut_two.toml")),
    ("drape_sphere", include_str!("../scenes/drape_sphere.toml")),
    (
        "ensemble_cables",
        include_str!("../scenes/ensemble_cables.toml"),
    ),
    (
        "grab_adaptive",
        include_str!("../scenes/grab_adaptive.toml"),
    ),
    ("grab_uniform", include_str!("../scenes/grab_uniform.toml")),
    ("gripper_turn", include_str!("../scenes/gripper_turn.toml")),
    (
        "hanging_cable",
        include_str!("../scenes/hanging_cable.toml"),
    ),
    ("knot_pulled", include_str!("../scenes/knot_pulled.toml")),
    (
        "knot_pulled_fixed",
        include_str!("../scenes/knot_pulled_fixed.toml"),
    ),
    ("knot_tying", include_str!("../scenes/knot_tying.toml")),
    (
        "knot_tying_adaptive",
        include_str!("../scenes/knot_tying_adaptive.toml"),
    ),
    (
        "knot_tying_tolerance",
        include_str!("../scenes/knot_tying_tolerance.toml"),
    ),
    ("loop_pulled", include_str!("../scenes/loop_pulled.toml")),
    ("michell_ring", include_str!("../scenes/michell_ring.toml")),
    ("plectoneme", include_str!("../scenes/plectoneme.toml")),
    ("ring_drop", include_str!("../scenes/ring_drop.toml")),
    ("rope_pileup", include_str!("../scenes/rope_pileup.toml")),
    (
        "ropes_crossing",
        include_str!("../scenes/ropes_crossing.toml"),
    ),
    (
        "ropes_crossing_pinned",
        include_str!("../scenes/ropes_crossing_pinned.toml"),
    ),
    ("rubber_band", include_str!("../scenes/rubber_band.toml")),
    (
        "string_midpoint",
        include_str!("../scenes/string_midpoint.toml"),
    ),
    ("string_modes", include_str!("../scenes/string_modes.toml")),
    ("suture_ring", include_str!("../scenes/suture_ring.toml")),
    (
        "twist_buckling",
        include_str!("../scenes/twist_buckling.toml"),
    ),
];

/// The names of the bundled scenes, sorted.
pub fn names() -> impl Iterator<Item = &'static str> {
    SCENES.iter().map(|(name, _)| *name)
}

/// The TOML text of the bundled scene `name` (a file stem of `scenes/`). An unknown name
/// is an error listing the bundled ones.
pub fn scene_text(name: &str) -> Result<&'static str, Error> {
    match SCENES.binary_search_by(|(n, _)| n.cmp(&name)) {
        Ok(i) => Ok(SCENES[i].1),
        Err(_) => {
            let known: Vec<_> = names().collect();
            let reason = format!("is not a bundled scene; they are: {}", known.join(", "));
            Err(Error::field("scene", format!("{name:?}"), reason))
        }
    }
}

/// The bundled scene `name`, parsed and checked as [`Scene::from_toml`] does.
pub fn scene(name: &str) -> Result<Scene, Error> {
    Scene::from_toml(scene_text(name)?)
}
