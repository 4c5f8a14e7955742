//! A list of fixed length given with more values than it holds is refused,
//! naming the list and its line (or the `--set` that gave it), wherever
//! the list is: in the scene's own tables, in internally tagged tables
//! (geometry, motion, amplitude), in a material table, in a profile.

use std::path::Path;

use drape_io::scene::{Scene, SceneError};

fn scenes_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

/// A scene that uses every list of fixed length drape reads (but a mesh
/// blank's, checked below).
const ALL: &str = r#"gravity = [0, 0, -9810]

[simulation]
end_time = 0.01

[fabric]
orientation_deg = 0
fibres = "trusses"
blank = { width = 100, height = 100, cells = [4, 4], center = [0, 0, 0] }

[fabric.material]
name = "m"
thickness = 0.5
fibre_volume_fraction = 0.5
density = 1.5e-9
bending_rigidity = [1.0, 1.0]
fibre = { modulus = 70000, crimp_strain = 0.0, compression_factor = 0.01 }
resin = { young = 10, poisson = 0.3 }

[[tools]]
name = "floor"
friction = 0.1
geometry = { kind = "plane", point = [0, 0, -1], normal = [0, 0, 1] }
motion = { kind = "displacement", direction = [0, 0, 1], distance = 1, amplitude = { kind = "table", points = [[0, 0], [1, 1]] } }

[[tools]]
name = "bump"
friction = 0.1
geometry = { kind = "revolution", origin = [0, 0, -50], profile = [{ kind = "line", from = [0, 10], to = [10, 0] }] }

[[springs]]
nodes = "corners"
table = [[0, 0], [1, 1]]
anchor_offset = [0, 0, 1]

[[boundary]]
nodes = "left"
motion = { kind = "velocity", value = [0, 0, 1], amplitude = { kind = "ramp", duration = 0.01 } }

[[boundary]]
nodes = "right"
motion = { kind = "picture_frame", shear_deg = 10, pin = [0, 0, 0], amplitude = { kind = "ramp", duration = 0.01 } }

[[boundary]]
nodes = "bottom"
motion = { kind = "displacement", value = [0, 0, 1], amplitude = { kind = "ramp", duration = 0.01 } }

[[loads]]
nodes = "top"
force = [0, 0, 1]

[output]
shear_range_deg = [0, 50]

[kinematic]
mould = "floor"
seed = [0, 0]
direction = [0, 0, -1]
warp_generator = [[-10, 0, -1], [10, 0, -1]]
"#;

fn parse(text: &str, sets: &[(&str, &str)]) -> Result<Scene, SceneError> {
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect();
    Scene::parse(text, Path::new("all.toml"), &sets)
}

/// Every list of fixed length, by its `--set` key, its field in errors,
/// and a value one longer than it holds.
const LISTS: [(&str, &str, &str); 19] = [
    ("gravity", "gravity", "[0, 0, -9, 810]"),
    ("fabric.blank.center", "fabric.blank.center", "[0, 0, 0, 1]"),
    ("fabric.blank.cells", "fabric.blank.cells", "[4, 4, 4]"),
    (
        "fabric.material.bending_rigidity",
        "fabric.material.bending_rigidity",
        "[1, 1, 1]",
    ),
    (
        "tools.0.geometry.point",
        "tools[0].geometry.point",
        "[0, 0, -1, 2]",
    ),
    (
        "tools.0.geometry.normal",
        "tools[0].geometry.normal",
        "[0, 0, 1, 0]",
    ),
    (
        "tools.0.motion.direction",
        "tools[0].motion.direction",
        "[0, 0, 1, 5]",
    ),
    (
        "tools.0.motion.amplitude.points",
        "tools[0].motion.amplitude.points[1]",
        "[[0, 0], [1, 1, 2]]",
    ),
    (
        "tools.1.geometry.origin",
        "tools[1].geometry.origin",
        "[0, 0, -50, 1]",
    ),
    (
        "tools.1.geometry.profile.0.from",
        "tools[1].geometry.profile[0].from",
        "[0, 10, 1]",
    ),
    (
        "springs.0.table",
        "springs[0].table[1]",
        "[[0, 0], [1, 1, 1]]",
    ),
    (
        "springs.0.anchor_offset",
        "springs[0].anchor_offset",
        "[0, 0, 1, 1]",
    ),
    (
        "boundary.0.motion.value",
        "boundary[0].motion.value",
        "[0, 0, 1, 1]",
    ),
    (
        "boundary.1.motion.pin",
        "boundary[1].motion.pin",
        "[0, 0, 0, 1]",
    ),
    ("loads.0.force", "loads[0].force", "[0, 0, 1, 1]"),
    (
        "output.shear_range_deg",
        "output.shear_range_deg",
        "[0, 50, 60]",
    ),
    ("kinematic.seed", "kinematic.seed", "[0, 0, 1]"),
    (
        "kinematic.direction",
        "kinematic.direction",
        "[0, 0, -1, 0]",
    ),
    (
        "kinematic.warp_generator",
        "kinematic.warp_generator[1]",
        "[[-10, 0, -1], [10, 0, -1, 7]]",
    ),
];

#[test]
fn the_scene_with_every_list_loads() {
    let scene = parse(ALL, &[]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(scene.model.gravity.z, -9810.0);
}

#[test]
fn a_list_one_value_too_long_from_set_is_refused_naming_it() {
    for (key, field, value) in LISTS {
        let e = match parse(ALL, &[(key, value)]) {
            Ok(_) => panic!("--set {key}={value} was accepted"),
            Err(e) => e,
        };
        // The list itself (or the entry of a list of lists that is too long).
        assert_eq!(e.field, field, "--set {key}={value}: {e}");
        assert!(e.message.contains("values is not allowed"), "{e}");
        assert!(e.message.contains(&format!("--set {key}={value}")), "{e}");
        assert!(!e.message.contains("sequence"), "{e}");
    }
}

#[test]
fn a_stray_comma_in_the_file_is_refused_at_its_line() {
    for (from, to, field, line) in [
        (
            "gravity = [0, 0, -9810]",
            "gravity = [0, 0, -9,810]",
            "gravity",
            1,
        ),
        (
            "cells = [4, 4]",
            "cells = [4, 4, 4]",
            "fabric.blank.cells",
            9,
        ),
        (
            "center = [0, 0, 0]",
            "center = [0, 0, 0, 0]",
            "fabric.blank.center",
            9,
        ),
        (
            "anchor_offset = [0, 0, 1]",
            "anchor_offset = [0, 0, 1,5]",
            "springs[0].anchor_offset",
            34,
        ),
        ("seed = [0, 0]", "seed = [0, 0, 0]", "kinematic.seed", 57),
        (
            "direction = [0, 0, 1]",
            "direction = [0, 0, 1, 0]",
            "tools[0].motion.direction",
            24,
        ),
        (
            "normal = [0, 0, 1]",
            "normal = [0, 0, 1, 0]",
            "tools[0].geometry.normal",
            23,
        ),
    ] {
        let text = ALL.replacen(from, to, 1);
        assert_ne!(text, ALL, "{from}");
        let e = parse(&text, &[])
            .err()
            .unwrap_or_else(|| panic!("`{to}` was accepted"));
        assert_eq!((e.field.as_str(), e.line), (field, Some(line)), "{to}: {e}");
        assert!(
            e.to_string()
                .starts_with(&format!("all.toml:{line}: {field}: ")),
            "{e}"
        );
    }
}

#[test]
fn a_mesh_blanks_placement_lists_are_checked_too() {
    let path = scenes_dir().join("imported-plate.toml");
    for (key, value) in [
        ("fabric.blank.offset", "[0, 0, 0, 5]"),
        ("fabric.blank.rotate", "[0, 0, 90, 5]"),
    ] {
        let sets = [(key.to_owned(), value.to_owned())];
        let e = Scene::from_file(&path, &sets)
            .err()
            .unwrap_or_else(|| panic!("{key}"));
        assert_eq!(e.field, key, "{e}");
        assert!(
            e.message
                .contains("a list of 4 values is not allowed: expected 3"),
            "{e}"
        );
    }
    let sets = [("fabric.blank.offset".to_owned(), "[0, 0, 5]".to_owned())];
    Scene::from_file(&path, &sets).unwrap();
}

#[test]
fn a_list_one_value_short_is_named_too() {
    for (key, field, value) in [
        ("gravity", "gravity", "[0, -9810]"),
        (
            "tools.0.motion.direction",
            "tools[0].motion.direction",
            "[0, 1]",
        ),
        (
            "tools.0.geometry.point",
            "tools[0].geometry.point",
            "[0, 0]",
        ),
        (
            "tools.1.geometry.profile.0.from",
            "tools[1].geometry.profile[0].from",
            "[0]",
        ),
        ("kinematic.seed", "kinematic.seed", "[0]"),
    ] {
        let e = match parse(ALL, &[(key, value)]) {
            Ok(_) => panic!("--set {key}={value} was accepted"),
            Err(e) => e,
        };
        assert_eq!(e.field, field, "--set {key}={value}: {e}");
        assert!(e.message.contains("values is not allowed"), "{e}");
    }
}
