//! Every shipped scene loads, and bad input is reported with file, line
//! and field.

use std::path::Path;

use drape_io::scene::Scene;

fn scenes_dir() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes")
}

#[test]
fn every_shipped_scene_loads() {
    let mut count = 0;
    for entry in std::fs::read_dir(scenes_dir()).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "toml") {
            let scene = Scene::from_file(&path, &[]).unwrap_or_else(|e| panic!("{e}"));
            scene.model.check().unwrap();
            count += 1;
        }
    }
    assert!(count >= 6, "{count} scenes");
}

fn error_of(text: &str) -> drape_io::scene::SceneError {
    Scene::parse(text, Path::new("bad.toml"), &[]).unwrap_err()
}

const GOOD: &str = r#"
[simulation]
end_time = 0.01

[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
blank = { width = 100, height = 100, cells = [4, 4] }

[[tools]]
name = "floor"
friction = 0.1
geometry = { kind = "plane", point = [0, 0, -1], normal = [0, 0, 1] }
"#;

#[test]
fn the_good_scene_loads_and_overrides_apply() {
    let scene = Scene::parse(GOOD, Path::new("good.toml"), &[]).unwrap();
    assert_eq!(scene.model.tools[0].friction, 0.1);
    let set = [("tools.0.friction".to_owned(), "0.3".to_owned())];
    let scene = Scene::parse(GOOD, Path::new("good.toml"), &set).unwrap();
    assert_eq!(scene.model.tools[0].friction, 0.3);
    let set = [("fabric.orientation_deg".to_owned(), "45".to_owned())];
    let scene = Scene::parse(GOOD, Path::new("good.toml"), &set).unwrap();
    assert_eq!(scene.spec.fabric.orientation_deg, 45.0);
    // A table the file does not have is created; a typo is still an error.
    let set = [("output.vtu".to_owned(), "false".to_owned())];
    let scene = Scene::parse(GOOD, Path::new("good.toml"), &set).unwrap();
    assert!(!scene.spec.output.vtu);
    let set = [("output.vtuu".to_owned(), "false".to_owned())];
    let e = Scene::parse(GOOD, Path::new("good.toml"), &set).unwrap_err();
    assert!(e.to_string().contains("vtuu"), "{e}");
}

#[test]
fn broken_toml_names_its_line() {
    let e = error_of("[simulation]\nend_time = \n");
    assert_eq!(e.line, Some(2), "{e}");
    assert!(e.to_string().starts_with("bad.toml:2:"), "{e}");
}

#[test]
fn an_unknown_key_is_an_error_naming_it() {
    let e = error_of(&GOOD.replace("friction = 0.1", "fricton = 0.1"));
    assert!(e.to_string().contains("fricton"), "{e}");
    assert_eq!(e.line, Some(12), "{e}");
}

#[test]
fn a_negative_friction_names_field_and_line() {
    let e = error_of(&GOOD.replace("friction = 0.1", "friction = -0.1"));
    assert_eq!(e.field, "tools[0].friction");
    assert_eq!(e.line, Some(12), "{e}");
    assert!(e.message.contains("≥ 0"), "{e}");
}

#[test]
fn a_negative_modulus_names_field_and_line() {
    let text = GOOD.replace(
        "material = \"glass-serge-4x3\"",
        "material = { name = \"m\", thickness = 0.5, fibre_volume_fraction = 0.5, density = 1e-9, fibre = { modulus = -70000, crimp_strain = 0.01 }, resin = { young = 30, poisson = 0.4 } }",
    );
    let e = error_of(&text);
    assert_eq!(e.field, "fabric.material.fibre.modulus", "{e}");
    assert_eq!(e.line, Some(6), "{e}");
}

#[test]
fn an_unknown_node_set_lists_the_known_ones() {
    let text =
        format!("{GOOD}\n[[boundary]]\nnodes = \"leftt\"\nmotion = {{ kind = \"fixed\" }}\n");
    let e = error_of(&text);
    assert_eq!(e.field, "boundary[0].nodes");
    assert!(e.message.contains("left"), "{e}");
}

#[test]
fn a_missing_file_is_reported() {
    let e = Scene::from_file(Path::new("/nonexistent/scene.toml"), &[]).unwrap_err();
    assert!(e.to_string().contains("/nonexistent/scene.toml"), "{e}");
}

#[test]
fn a_tool_file_that_does_not_exist_names_the_field() {
    let text = GOOD.replace(
        "geometry = { kind = \"plane\", point = [0, 0, -1], normal = [0, 0, 1] }",
        "geometry = { kind = \"mesh\", file = \"missing-punch.stl\" }",
    );
    let e = error_of(&text);
    assert_eq!(e.field, "tools[0].geometry.file", "{e}");
    assert_eq!(e.line, Some(13), "{e}");
    assert!(e.message.contains("missing-punch.stl"), "{e}");
}

#[test]
fn a_holder_ring_is_a_closed_tool_and_bad_radii_name_their_field() {
    let ring = |extra: &str| {
        format!(
            "{GOOD}\n[[tools]]\nname = \"holder\"\ngeometry = {{ kind = \"ring\", center = [0, 0, 0.3], inner_radius = 95, outer_radius = 250{extra} }}\n"
        )
    };
    // Defaults: a sharp edge, 10 mm tall; with an edge radius, twice it.
    for extra in ["", ", edge_radius = 8", ", edge_radius = 5, thickness = 5"] {
        let scene = Scene::parse(&ring(extra), Path::new("good.toml"), &[]).unwrap();
        assert!(scene.model.tools[1].surface.is_closed(), "{extra}");
    }
    let scene = Scene::parse(&ring(", edge_radius = 8"), Path::new("good.toml"), &[]).unwrap();
    let top = scene.model.tools[1].surface.aabb().max.z;
    assert!((top - 16.3).abs() < 1e-12, "{top}");
    for (extra, field) in [
        (", edge_radius = -1", "tools[1].geometry.edge_radius"),
        (
            ", edge_radius = 5, thickness = 4",
            "tools[1].geometry.thickness",
        ),
        (", edge_radius = 200", "tools[1].geometry.outer_radius"),
    ] {
        let e = error_of(&ring(extra));
        assert_eq!(e.field, field, "{e}");
        assert_eq!(e.line, Some(17), "{e}");
    }
}
