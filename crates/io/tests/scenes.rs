//! Every shipped scene loads, and bad input is reported with file, line
//! and field.

use std::path::Path;

use drape_io::scene::{MaterialSpec, Scene};

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

fn with_sets(text: &str, sets: &[(&str, &str)]) -> Result<Scene, drape_io::scene::SceneError> {
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect();
    Scene::parse(text, Path::new("good.toml"), &sets)
}

/// Words that would leak Rust's types into a user's message.
const RUST_WORDS: [&str; 12] = [
    "f64",
    "usize",
    "u32",
    "u64",
    "i64",
    "struct",
    "enum",
    "Spec",
    "sequence",
    "map,",
    "variant of",
    "Material ",
];

fn assert_plain(message: &str) {
    for w in RUST_WORDS {
        assert!(!message.contains(w), "`{w}` in: {message}");
    }
}

#[test]
fn set_errors_name_the_key_and_say_it_came_from_set() {
    // A type error in an override: the key, the value, and no file line.
    let e = with_sets(GOOD, &[("simulation.end_time", "abc")]).unwrap_err();
    assert_eq!(e.field, "simulation.end_time", "{e}");
    assert_eq!(e.line, None, "{e}");
    assert!(e.message.contains("\"abc\""), "{e}");
    assert!(e.message.contains("expected a number"), "{e}");
    assert!(e.message.contains("--set simulation.end_time=abc"), "{e}");
    assert_plain(&e.to_string());

    // A list entry's value check: the override, not the file's line 12.
    let e = with_sets(GOOD, &[("tools.0.friction", "-1")]).unwrap_err();
    assert_eq!(e.field, "tools[0].friction", "{e}");
    assert_eq!(e.line, None, "{e}");
    assert!(e.message.contains("--set tools.0.friction=-1"), "{e}");
    assert!(e.message.contains("≥ 0"), "{e}");
    // Written the way errors show it, the key works too.
    let scene = with_sets(GOOD, &[("tools[0].friction", "0.25")]).unwrap();
    assert_eq!(scene.model.tools[0].friction, 0.25);

    // A value from the file is still located in the file, even when other
    // values were overridden.
    let bad_file = GOOD.replace("friction = 0.1", "friction = -0.1");
    let e = with_sets(&bad_file, &[("simulation.end_time", "0.02")]).unwrap_err();
    assert_eq!(
        (e.field.as_str(), e.line),
        ("tools[0].friction", Some(12)),
        "{e}"
    );
    assert!(!e.message.contains("--set"), "{e}");

    // Entries that do not exist.
    let e = with_sets(GOOD, &[("tools.3.friction", "0.1")]).unwrap_err();
    assert!(e.message.contains("there is no entry 3"), "{e}");
    assert!(e.message.contains("--set tools.3.friction=0.1"), "{e}");
    let e = with_sets(GOOD, &[("springs.0.stiffness", "1")]).unwrap_err();
    assert!(e.message.contains("no `springs` list"), "{e}");
    let e = with_sets(GOOD, &[("simulation.frames", "18446744073709551615")]).unwrap_err();
    assert!(e.message.contains("too large"), "{e}");

    // A wrong type deeper down, and a table replaced by a number.
    let e = with_sets(GOOD, &[("fabric.blank.cells", "[1.5, 2]")]).unwrap_err();
    assert_eq!(e.field, "fabric.blank.cells[0]", "{e}");
    assert!(e.message.contains("whole number"), "{e}");
    assert_plain(&e.to_string());
    let e = with_sets(GOOD, &[("fabric", "5")]).unwrap_err();
    assert_eq!(e.field, "fabric", "{e}");
    assert!(
        e.message.contains("`material`, `fibres` and `blank`"),
        "{e}"
    );
    assert_plain(&e.to_string());
}

#[test]
fn type_errors_say_what_the_field_accepts() {
    // (replace, by, field, line, words the message must hold)
    let cases: [(&str, &str, &str, usize, &str); 9] = [
        (
            "end_time = 0.01",
            "end_time = \"soon\"",
            "simulation.end_time",
            3,
            "a number",
        ),
        (
            "material = \"glass-serge-4x3\"",
            "material = 5",
            "fabric.material",
            6,
            "preset name",
        ),
        (
            "material = \"glass-serge-4x3\"",
            "material = { name = \"m\", thickness = 0.5 }",
            "fabric.material",
            6,
            "`fibre` is missing",
        ),
        (
            "cells = [4, 4]",
            "cells = [4, -4]",
            "fabric.blank.cells[1]",
            8,
            "whole number ≥ 0",
        ),
        (
            "cells = [4, 4]",
            "cells = [4]",
            "fabric.blank.cells",
            8,
            "a list of 2 values",
        ),
        (
            "fibres = \"trusses\"",
            "fibres = \"truss\"",
            "fabric.fibres",
            7,
            "`trusses`",
        ),
        (
            "name = \"floor\"",
            "name = 3",
            "tools[0].name",
            11,
            "text in quotes",
        ),
        // Inside a table chosen by its `kind`, serde reads the values
        // without their places: the table is named.
        (
            "point = [0, 0, -1]",
            "point = [0, 0]",
            "tools[0].geometry.point",
            13,
            "3 values",
        ),
        (
            "geometry = { kind",
            "motion = { kind = \"displacement\", direction = [0, 0, 1], distance = 1, amplitude = 3 }\ngeometry = { kind",
            "tools[0].motion",
            13,
            "smooth_step",
        ),
    ];
    for (from, to, field, line, words) in cases {
        let text = GOOD.replace(from, to);
        assert_ne!(text, GOOD, "{from}");
        let e = error_of(&text);
        let shown = e.to_string();
        assert_eq!(e.field, field, "{shown}");
        assert_eq!(e.line, Some(line), "{shown}");
        assert!(shown.contains(words), "`{words}` not in: {shown}");
        assert_plain(&shown);
    }
    for (nodes, words) in [
        ("-1", "node set name"),
        ("[1, \"left\"]", "mixes node numbers and set names"),
        ("[-3]", "-3 is not allowed"),
    ] {
        let text = format!("{GOOD}\n[[springs]]\nnodes = {nodes}\nstiffness = 1\n");
        let e = error_of(&text);
        let shown = e.to_string();
        assert!(e.field.starts_with("springs[0].nodes"), "{shown}");
        assert_eq!(e.line, Some(16), "{shown}");
        assert!(shown.contains(words), "`{words}` not in: {shown}");
        assert_plain(&shown);
    }
}

#[test]
fn a_preloaded_spring_anchored_at_its_node_is_refused() {
    let spring =
        |keys: &str| format!("{GOOD}\n[[springs]]\nnodes = \"corners\"\nstiffness = 2\n{keys}\n");
    let e = error_of(&spring("preload = 3"));
    let text = e.to_string();
    assert!(
        text.contains("springs[0]")
            && text.contains("force of 3 N")
            && text.contains("no direction"),
        "{text}"
    );
    // A rest length at the node: F(−L₀) = −2·1.5 N at the start.
    assert!(
        error_of(&spring("rest_length = 1.5"))
            .to_string()
            .contains("force of -3 N")
    );
    // An anchor offset gives the force a direction; no preload, no force.
    for keys in ["preload = 3\nanchor_offset = [0, 0, -5]", ""] {
        Scene::parse(&spring(keys), Path::new("good.toml"), &[]).unwrap();
    }
}

#[test]
fn absurd_frame_counts_are_refused() {
    let e = error_of(&GOOD.replace(
        "end_time = 0.01",
        "end_time = 0.01\nframes = 9223372036854775807",
    ));
    assert_eq!(
        (e.field.as_str(), e.line),
        ("simulation.frames", Some(4)),
        "{e}"
    );
    assert!(e.message.contains("100000"), "{e}");
    let e = with_sets(GOOD, &[("simulation.frames", "100001")]).unwrap_err();
    assert!(e.message.contains("--set simulation.frames=100001"), "{e}");
    with_sets(GOOD, &[("simulation.frames", "100000")]).unwrap();
}

#[test]
fn node_set_names_match_regardless_of_case() {
    let text = format!("{GOOD}\n[[boundary]]\nnodes = \"LEFT\"\nmotion = {{ kind = \"fixed\" }}\n");
    let scene = Scene::parse(&text, Path::new("good.toml"), &[]).unwrap();
    assert_eq!(scene.model.boundary[0].nodes, scene.model.node_sets["left"]);
}

#[test]
fn the_resolved_scene_builds_the_same_model_from_its_values_alone() {
    let dir = tempfile::tempdir().unwrap();
    let meshes = dir.path().join("meshes");
    std::fs::create_dir(&meshes).unwrap();
    std::fs::copy(
        scenes_dir().join("meshes/plate.msh"),
        meshes.join("plate.msh"),
    )
    .unwrap();
    let text = GOOD
        .replace("fibres = \"trusses\"", "fibres = \"embedded\"")
        .replace(
            "blank = { width = 100, height = 100, cells = [4, 4] }",
            "blank = { mesh = \"meshes/plate.msh\" }",
        );
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let sets = [("tools.0.friction".to_owned(), "0.3".to_owned())];
    let scene = Scene::from_file(&path, &sets).unwrap();
    let spec = scene.resolved_spec();
    let mesh = spec.fabric.blank.mesh.clone().unwrap();
    assert!(Path::new(&mesh).is_absolute(), "{mesh}");
    assert_eq!(scene.input_files(), vec![std::path::PathBuf::from(&mesh)]);
    assert_eq!(spec.tools[0].friction, 0.3);
    // Through JSON (as in a checkpoint) and back, named by a path that is
    // not where the scene was.
    let json = serde_json::to_string(&spec).unwrap();
    let again = Scene::from_spec(
        serde_json::from_str(&json).unwrap(),
        Path::new("elsewhere.toml"),
    )
    .unwrap();
    assert_eq!(again.spec, spec);
    assert_eq!(again.model.x0, scene.model.x0);
    assert_eq!(again.model.tools[0].friction, 0.3);
    assert_eq!(again.settings, scene.settings);
}

/// A material card named relative to the scene is resolved like a mesh:
/// absolute in the resolved scene (a checkpoint resumes from anywhere) and
/// among the input files a resume checks.
#[test]
fn a_relative_material_card_is_resolved_like_a_mesh() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("cards")).unwrap();
    let mut card = drape_constitutive::Material::preset("glass-serge-4x3").unwrap();
    card.resin.young *= 2.0;
    let card_path = dir.path().join("cards/stiff.toml");
    std::fs::write(&card_path, toml::to_string(&card).unwrap()).unwrap();
    let text = GOOD.replace(
        "material = \"glass-serge-4x3\"",
        "material = \"cards/stiff.toml\"",
    );
    assert_ne!(text, GOOD);
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let scene = Scene::from_file(&path, &[]).unwrap();
    let spec = scene.resolved_spec();
    let MaterialSpec::Preset(name) = &spec.fabric.material else {
        panic!("a card stays a name: {:?}", spec.fabric.material);
    };
    assert!(Path::new(name).is_absolute(), "{name}");
    assert_eq!(
        std::fs::canonicalize(name).unwrap(),
        std::fs::canonicalize(&card_path).unwrap()
    );
    assert!(scene.input_files().iter().any(|f| f == Path::new(name)));
    let json = serde_json::to_string(&spec).unwrap();
    let again = Scene::from_spec(
        serde_json::from_str(&json).unwrap(),
        Path::new("elsewhere.toml"),
    )
    .unwrap();
    // Read from a scene named elsewhere: a relative card would not be found.
    assert_eq!(again.spec, spec);
    assert_eq!(again.model.x0, scene.model.x0);
}

#[test]
fn guard_keys_reach_the_settings() {
    let scene = Scene::parse(GOOD, Path::new("good.toml"), &[]).unwrap();
    let guard = &scene.settings.guard;
    assert!(
        guard.enabled && guard.max_energy_error == Some(0.05) && guard.max_kinetic_ratio.is_none()
    );
    let set = |k: &str, v: &str| [(k.to_owned(), v.to_owned())];
    let scene = Scene::parse(
        GOOD,
        Path::new("good.toml"),
        &set("simulation.quasi_static", "true"),
    )
    .unwrap();
    assert_eq!(scene.settings.guard.max_kinetic_ratio, Some(1.0));
    let scene = Scene::parse(
        GOOD,
        Path::new("good.toml"),
        &set("simulation.instability_guard", "false"),
    )
    .unwrap();
    assert!(!scene.settings.guard.enabled && scene.settings.guard.max_energy_error.is_none());
    let scene = Scene::parse(
        GOOD,
        Path::new("good.toml"),
        &set("simulation.max_energy_error", "0.2"),
    )
    .unwrap();
    assert_eq!(scene.settings.guard.max_energy_error, Some(0.2));
}

#[test]
fn yarn_bending_is_an_option_of_the_fabric() {
    let off = [("fabric.bending".to_owned(), "false".to_owned())];
    let plain = Scene::parse(GOOD, Path::new("good.toml"), &off).unwrap();
    assert!(plain.model.bending.is_empty() && !plain.model.features().bending);
    assert!(plain.warnings.is_empty(), "{:?}", plain.warnings);
    let on = [("fabric.bending".to_owned(), "true".to_owned())];
    let scene = Scene::parse(GOOD, Path::new("good.toml"), &on).unwrap();
    // 4 × 4 cells: 5 lines of 3 interior nodes per family.
    assert_eq!(scene.model.bending[0].len(), 30);
    assert!(scene.model.features().bending);
    // Embedded fibres at 30° have no mesh line along the yarns.
    let mut set = on.to_vec();
    set.push(("fabric.fibres".to_owned(), "embedded".to_owned()));
    set.push(("fabric.orientation_deg".to_owned(), "30".to_owned()));
    let e = Scene::parse(GOOD, Path::new("good.toml"), &set).unwrap_err();
    let text = e.to_string();
    assert!(
        text.contains("fabric.bending") && text.contains("mesh lines along the yarns"),
        "{text}"
    );
    // A material table without a rigidity.
    let inline = GOOD.replace(
        r#"material = "glass-serge-4x3""#,
        r#"bending = true
material = { name = "m", thickness = 0.5, fibre_volume_fraction = 0.5, density = 1e-9, fibre = { modulus = 1000.0, crimp_strain = 0.0 }, resin = { young = 10.0, poisson = 0.3 } }"#,
    );
    let text = error_of(&inline).to_string();
    assert!(
        text.contains("fabric.bending") && text.contains("bending_rigidity"),
        "{text}"
    );
    // A negative rigidity names its field.
    let bad = inline.replace(
        "density = 1e-9,",
        "density = 1e-9, bending_rigidity = [0.5, -1.0],",
    );
    let text = error_of(&bad).to_string();
    assert!(text.contains("bending_rigidity[1]"), "{text}");
}

#[test]
fn yarn_buckling_is_the_presets_law_and_false_runs_the_papers_yarn() {
    let preset = drape_constitutive::Material::preset("glass-serge-4x3").unwrap();
    let paper = drape_constitutive::Material::paper_preset("glass-serge-4x3").unwrap();
    let scene = Scene::parse(GOOD, Path::new("good.toml"), &[]).unwrap();
    assert_eq!(scene.model.trusses[0].law, preset.fibre);
    assert!(scene.model.trusses[0].law.buckling_stress > 0.0);
    let off = [("fabric.yarn_buckling".to_owned(), "false".to_owned())];
    let scene = Scene::parse(GOOD, Path::new("good.toml"), &off).unwrap();
    assert_eq!(scene.model.trusses[0].law, paper.fibre);
    // Embedded fibres get it from the same material.
    let mut set = off.to_vec();
    set.push(("fabric.fibres".to_owned(), "embedded".to_owned()));
    let scene = Scene::parse(GOOD, Path::new("good.toml"), &set).unwrap();
    assert!(scene.model.trusses.is_empty());
    let on = [("fabric.yarn_buckling".to_owned(), "true".to_owned())];
    Scene::parse(GOOD, Path::new("good.toml"), &on).unwrap();
    // `true` on a material without a buckling stress names the key.
    let inline = GOOD.replace(
        r#"material = "glass-serge-4x3""#,
        r#"yarn_buckling = true
material = { name = "m", thickness = 0.5, fibre_volume_fraction = 0.5, density = 1e-9, fibre = { modulus = 1000.0, crimp_strain = 0.01 }, resin = { young = 10.0, poisson = 0.3 } }"#,
    );
    let text = error_of(&inline).to_string();
    assert!(
        text.contains("fabric.yarn_buckling") && text.contains("buckling_stress"),
        "{text}"
    );
    // A table's buckling stress is checked against its crimp, by name.
    let bad = inline.replace(
        "crimp_strain = 0.01 }",
        "crimp_strain = 0.0, buckling_stress = 1.0 }",
    );
    let text = error_of(&bad).to_string();
    assert!(
        text.contains("fabric.material.fibre.crimp_strain"),
        "{text}"
    );
}

/// Unset, `fabric.bending` is on wherever the material has a rigidity and
/// the mesh lines follow the yarns; where either is missing the scene
/// loads without it and one warning says why, naming the field.
#[test]
fn yarn_bending_is_on_by_default_where_it_can_hold_the_blank() {
    let default = Scene::parse(GOOD, Path::new("good.toml"), &[]).unwrap();
    let explicit = Scene::parse(
        GOOD,
        Path::new("good.toml"),
        &[("fabric.bending".to_owned(), "true".to_owned())],
    )
    .unwrap();
    assert!(default.model.features().bending);
    assert_eq!(default.model.bending[0].len(), 30);
    assert_eq!(
        default.model.bending[0].nodes,
        explicit.model.bending[0].nodes
    );
    let glass = drape_constitutive::Material::preset("glass-serge-4x3").unwrap();
    assert_eq!(
        Some(default.model.bending[0].rigidity),
        glass.bending_rigidity
    );
    assert!(default.warnings.is_empty(), "{:?}", default.warnings);
    // The ±45 diamond mesh and embedded fibres at 0° on the grid follow
    // the yarns too.
    for set in [
        vec![("fabric.orientation_deg", "45")],
        vec![("fabric.fibres", "embedded")],
        vec![
            ("fabric.fibres", "embedded"),
            ("fabric.orientation_deg", "90"),
        ],
    ] {
        let set: Vec<(String, String)> = set
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect();
        let scene = Scene::parse(GOOD, Path::new("good.toml"), &set).unwrap();
        assert!(scene.model.features().bending, "{set:?}");
        assert!(scene.warnings.is_empty(), "{set:?}: {:?}", scene.warnings);
    }
    // Embedded fibres at 30°: no line along the yarns; no error, no
    // bending, one warning that says so.
    let set = [
        ("fabric.fibres".to_owned(), "embedded".to_owned()),
        ("fabric.orientation_deg".to_owned(), "30".to_owned()),
    ];
    let angled = Scene::parse(GOOD, Path::new("good.toml"), &set).unwrap();
    assert!(!angled.model.features().bending);
    assert_eq!(angled.warnings.len(), 1, "{:?}", angled.warnings);
    let text = &angled.warnings[0];
    assert!(
        text.contains("fabric.bending")
            && text.contains("yarn bending is off")
            && text.contains("0 of the blank's 9 interior nodes"),
        "{text}"
    );
    // A material without a rigidity: off, with a warning naming the key
    // it lacks.
    let inline = GOOD.replace(
        r#"material = "glass-serge-4x3""#,
        r#"material = { name = "m", thickness = 0.5, fibre_volume_fraction = 0.5, density = 1e-9, fibre = { modulus = 1000.0, crimp_strain = 0.0 }, resin = { young = 10.0, poisson = 0.3 } }"#,
    );
    let bare = Scene::parse(&inline, Path::new("bare.toml"), &[]).unwrap();
    assert!(!bare.model.features().bending && bare.model.bending.is_empty());
    assert_eq!(bare.warnings.len(), 1, "{:?}", bare.warnings);
    assert!(
        bare.warnings[0].contains("fabric.bending")
            && bare.warnings[0].contains("bending_rigidity"),
        "{}",
        bare.warnings[0]
    );
    // `false` says it is meant: no warning.
    let quiet = Scene::parse(
        &inline,
        Path::new("bare.toml"),
        &[("fabric.bending".to_owned(), "false".to_owned())],
    )
    .unwrap();
    assert!(quiet.warnings.is_empty(), "{:?}", quiet.warnings);
}

/// `per_length`: springs and loads given per mm of the blank's edge reach
/// each edge node times its share of the outline (half of each outline
/// edge it ends), so the totals are the per-mm values times the perimeter
/// whatever the mesh; a node off the edge is refused.
#[test]
fn springs_and_loads_per_length_follow_the_edge() {
    // 100 × 100 mm in 4 × 2 cells: 25 mm along x, 50 mm along y, so the
    // corners, the x-edge nodes and the y-edge midpoints have three shares.
    let text = format!(
        "{}\n[[springs]]\nnodes = \"boundary\"\nstiffness = 0.01\npreload = 0.002\n\
         anchor_offset = [0, 0, -5]\nper_length = true\n\
         [[loads]]\nnodes = \"boundary\"\nforce = [0, 0, -0.003]\nper_length = true\n",
        GOOD.replace("cells = [4, 4]", "cells = [4, 2]")
    );
    let scene = Scene::parse(&text, Path::new("good.toml"), &[]).unwrap();
    let model = &scene.model;
    let perimeter = 400.0;
    let mut shares: Vec<(u32, f64)> = Vec::new();
    let (mut stiffness, mut preload) = (0.0, 0.0);
    for batch in &model.springs {
        let (f0, _) = batch.table.force_and_stiffness(0.0);
        let (f1, k) = batch.table.force_and_stiffness(1.0);
        assert!((f1 - f0 - k).abs() < 1e-15);
        for &n in &batch.nodes {
            shares.push((n, k / 0.01));
            stiffness += k;
            preload += f0;
        }
    }
    assert!((stiffness - 0.01 * perimeter).abs() < 1e-12, "{stiffness}");
    assert!((preload - 0.002 * perimeter).abs() < 1e-12, "{preload}");
    let boundary = model.node_set("boundary").unwrap();
    assert_eq!(shares.len(), boundary.len());
    let mut seen: Vec<f64> = shares.iter().map(|s| s.1).collect();
    seen.sort_by(f64::total_cmp);
    seen.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    assert_eq!(seen.len(), 3, "{seen:?}");
    for (want, got) in [25.0, 37.5, 50.0].iter().zip(&seen) {
        assert!((want - got).abs() < 1e-9, "{seen:?}");
    }
    let load: f64 = model
        .loads
        .iter()
        .map(|l| l.force.z * l.nodes.len() as f64)
        .sum();
    assert!((load + 0.003 * perimeter).abs() < 1e-12, "{load}");

    // An interior node has no share of the edge.
    let e = error_of(&format!(
        "{GOOD}\n[[loads]]\nnodes = [12]\nforce = [0, 0, -1]\nper_length = true\n"
    ));
    assert!(
        e.field.starts_with("loads[0].nodes") && e.message.contains("not on the blank's edge"),
        "{e}"
    );
}

#[test]
fn the_membrane_tangent_reaches_the_implicit_settings_and_a_bad_one_is_named() {
    use drape_time::tangent::MembraneTangentChoice;
    let scene = with_sets(GOOD, &[]).unwrap();
    assert_eq!(
        scene.implicit.membrane_tangent,
        MembraneTangentChoice::Exact
    );
    for (value, choice) in [
        ("exact", MembraneTangentChoice::Exact),
        ("tension_field", MembraneTangentChoice::TensionField),
        (
            "tension_field_when_indefinite",
            MembraneTangentChoice::TensionFieldWhenIndefinite,
        ),
    ] {
        let scene = with_sets(GOOD, &[("simulation.membrane_tangent", value)]).unwrap();
        assert_eq!(scene.implicit.membrane_tangent, choice, "{value}");
    }
    let e = with_sets(GOOD, &[("simulation.membrane_tangent", "tension")]).unwrap_err();
    let message = e.to_string();
    assert!(message.contains("membrane_tangent"), "{message}");
    assert!(
        message.contains("tension_field_when_indefinite"),
        "{message}"
    );
}

#[test]
fn the_contact_solver_reaches_the_implicit_settings_and_a_bad_one_is_named() {
    use drape_time::ContactSolver;
    let scene = with_sets(GOOD, &[]).unwrap();
    assert_eq!(scene.implicit.contact_solver, ContactSolver::ActiveSet);
    for (value, choice) in [
        ("condensed", ContactSolver::Condensed),
        ("active_set", ContactSolver::ActiveSet),
    ] {
        let scene = with_sets(GOOD, &[("simulation.contact_solver", value)]).unwrap();
        assert_eq!(scene.implicit.contact_solver, choice, "{value}");
    }
    let e = with_sets(GOOD, &[("simulation.contact_solver", "active-set")]).unwrap_err();
    let message = e.to_string();
    assert!(message.contains("contact_solver"), "{message}");
    assert!(message.contains("active_set"), "{message}");
}
