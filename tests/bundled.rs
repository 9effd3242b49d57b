//! The scenes compiled into the library (`splinerod::bundled`) are exactly the files of
//! `scenes/`, and each one loads.

use std::path::Path;

#[test]
fn bundled_scenes_are_the_scene_files() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut files: Vec<(String, String)> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "toml"))
        .map(|p| {
            let stem = p.file_stem().unwrap().to_string_lossy().into_owned();
            (stem, std::fs::read_to_string(&p).unwrap())
        })
        .collect();
    files.sort();
    let bundled: Vec<(String, String)> = splinerod::bundled::SCENES
        .iter()
        .map(|(n, t)| (n.to_string(), t.to_string()))
        .collect();
    let names = |v: &[(String, String)]| v.iter().map(|f| f.0.clone()).collect::<Vec<_>>();
    assert_eq!(
        names(&bundled),
        names(&files),
        "scenes/ and bundled::SCENES differ"
    );
    assert_eq!(
        bundled, files,
        "a bundled scene's text differs from its file"
    );
}

#[test]
fn every_bundled_scene_loads() {
    for name in splinerod::bundled::names() {
        if let Err(e) = splinerod::bundled::scene(name) {
            panic!("bundled scene {name}: {e}");
        }
    }
}

#[test]
fn an_unknown_bundled_scene_names_the_known_ones() {
    let message = splinerod::bundled::scene_text("hanging_cabel")
        .unwrap_err()
        .to_string();
    assert!(message.contains("\"hanging_cabel\""), "{message}");
    assert!(message.contains("hanging_cable"), "{message}");
    assert!(message.contains("ring_drop"), "{message}");
}
