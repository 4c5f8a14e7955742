//! Blanks from mesh files: Gmsh 4.1 and Abaqus .inp read into the same
//! mesh, node sets, scenes that use them, and every error named with its
//! file, line and culprit.

use std::path::{Path, PathBuf};

use drape_constitutive::Material;
use drape_io::mesh_import::{
    ImportErrorKind, ImportedMesh, parse_abaqus, parse_gmsh, read_abaqus, read_gmsh, read_mesh,
};
use drape_io::scene::Scene;
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{Amplitude, BoundaryCondition, Model, Motion};
use drape_time::{Explicit, ExplicitSettings, NoObserver};
use nalgebra::Vector3;

/// The 1-based line of the first line of `text` that equals `content`.
fn line_of(text: &str, content: &str) -> usize {
    text.lines()
        .position(|l| l.trim() == content)
        .unwrap_or_else(|| panic!("no line `{content}`"))
        + 1
}

/// A 30 × 10 mm strip: two quads, then two triangles, with a point, a
/// curve and the surface in physical groups. Node tags are `scale`·k; the
/// file lists node 8 before nodes 2…7, so a dense numbering (scale 1) is
/// out of order.
fn gmsh_strip(scale: u64, last_triangle: &str, triangle_type: u32) -> String {
    let t = |k: u64| k * scale;
    let (min, max) = (t(1), t(8));
    format!(
        "$MeshFormat
4.1 0 8
$EndMeshFormat
$PhysicalNames
3
0 3 \"origin\"
1 2 \"clamp\"
2 1 \"fabric\"
$EndPhysicalNames
$Entities
1 1 1 0
1 0 0 0 1 3
1 0 0 0 0 10 0 1 2 0
1 0 0 0 30 10 0 1 1 0
$EndEntities
$Nodes
3 8 {min} {max}
0 1 0 1
{}
0 0 0
1 1 0 1
{}
0 10 0
2 1 0 6
{}
{}
{}
{}
{}
{}
10 0 0
20 0 0
30 0 0
30 10 0
20 10 0
10 10 0
$EndNodes
$Elements
4 6 1 6
0 1 15 1
1 {}
1 1 1 1
2 {} {}
2 1 3 2
3 {} {} {} {}
4 {} {} {} {}
2 1 {triangle_type} 2
5 {} {} {}
{last_triangle}
$EndElements
",
        t(1),
        t(8),
        t(2),
        t(3),
        t(4),
        t(5),
        t(6),
        t(7),
        t(1),
        t(1),
        t(8),
        t(1),
        t(2),
        t(7),
        t(8),
        t(2),
        t(3),
        t(6),
        t(7),
        t(3),
        t(4),
        t(5),
    )
}

fn good_gmsh() -> String {
    gmsh_strip(1, "6 3 5 6", 2)
}

/// The same strip in Abaqus form, exercising the reader's features:
/// comments, case, continued keyword and element lines, a `D` exponent,
/// GENERATE, sets of sets, T3D2 lines, skipped keywords.
const ABAQUS_STRIP: &str = "\
** A 30 x 10 mm strip: two quads and two triangles.
*Heading
 strip, with commas, ignored
*Node, nset=NODES
1001, 0., 0.
1002, 1.0D1, 0.0
1003, 20, 0, 0
1004, 30, 0
1005, 30, 10
1006, 20, 10
**  a comment between data lines
1007, 10, 10
1008, 0, 10
*ELEMENT, TYPE=s4r,
 ELSET=Quads
1, 1001, 1002,
   1007, 1008
2, 1002, 1003, 1006, 1007
*element, type=M3D3, elset=TRIS
10, 1003, 1004, 1005
11, 1003, 1005, 1006
*Element, type=T3D2, elset=clamp_edge
20, 1001, 1008
*Nset, nset=corners
1001, 1004, 1005, 1008
*NSET, NSET=bottom, GENERATE
1001, 1004, 1
*Elset, elset=all_shells
Quads, TRIS
*Nset, nset=from_elset, elset=TRIS
*Nset, nset=Corners
bottom
*Material, name=resin
*Elastic
3000., 0.3
*Step
*Static
*Boundary
corners, 1, 3
*End Step
";

fn strip_x0() -> Vec<Vector3<f64>> {
    [
        (0.0, 0.0),
        (10.0, 0.0),
        (20.0, 0.0),
        (30.0, 0.0),
        (30.0, 10.0),
        (20.0, 10.0),
        (10.0, 10.0),
        (0.0, 10.0),
    ]
    .iter()
    .map(|&(x, y)| Vector3::new(x, y, 0.0))
    .collect()
}

#[test]
fn gmsh_reads_nodes_elements_and_physical_groups() {
    let mesh = parse_gmsh(good_gmsh().as_bytes(), Path::new("strip.msh")).unwrap();
    // Nodes in file order: tag 1, tag 8, tags 2…7.
    let mut expected = strip_x0();
    let eight = expected.remove(7);
    expected.insert(1, eight);
    assert_eq!(mesh.x0, expected);
    assert_eq!(mesh.quads, [[0, 2, 7, 1], [2, 3, 6, 7]]);
    assert_eq!(mesh.triangles, [[3, 4, 5], [3, 5, 6]]);
    assert_eq!(mesh.quad_labels, [3, 4]);
    assert_eq!(mesh.triangle_labels, [5, 6]);
    assert_eq!(mesh.node_sets["origin"], [0]);
    assert_eq!(mesh.node_sets["clamp"], [0, 1]);
    assert_eq!(mesh.node_sets["fabric"], (0..8).collect::<Vec<_>>());
    assert_eq!(mesh.node_sets["all"], (0..8).collect::<Vec<_>>());
    // One row of elements: every node is on the boundary.
    assert_eq!(mesh.node_sets["boundary"], (0..8).collect::<Vec<_>>());
}

#[test]
fn gmsh_sparse_tags_map_like_dense_ones() {
    let dense = parse_gmsh(good_gmsh().as_bytes(), Path::new("a.msh")).unwrap();
    let sparse_text = gmsh_strip(10, "6 30 50 60", 2);
    let sparse = parse_gmsh(sparse_text.as_bytes(), Path::new("b.msh")).unwrap();
    assert_eq!(dense, sparse);
}

#[test]
fn abaqus_reads_labels_sets_and_continuations() {
    let mesh = parse_abaqus(ABAQUS_STRIP, Path::new("strip.inp")).unwrap();
    assert_eq!(mesh.x0, strip_x0());
    assert_eq!(mesh.quads, [[0, 1, 6, 7], [1, 2, 5, 6]]);
    assert_eq!(mesh.triangles, [[2, 3, 4], [2, 4, 5]]);
    assert_eq!(mesh.quad_labels, [1, 2]);
    assert_eq!(mesh.triangle_labels, [10, 11]);
    let set = |name: &str| mesh.node_sets[name].clone();
    assert_eq!(set("NODES"), (0..8).collect::<Vec<_>>());
    // `corners` and `Corners` are one set; its second part names `bottom`.
    assert_eq!(set("corners"), [0, 1, 2, 3, 4, 7]);
    assert!(!mesh.node_sets.contains_key("Corners"));
    assert_eq!(set("bottom"), [0, 1, 2, 3]);
    assert_eq!(set("from_elset"), [2, 3, 4, 5]);
    assert_eq!(set("elset:Quads"), [0, 1, 2, 5, 6, 7]);
    assert_eq!(set("elset:TRIS"), [2, 3, 4, 5]);
    assert_eq!(set("elset:clamp_edge"), [0, 7]);
    assert_eq!(set("elset:all_shells"), (0..8).collect::<Vec<_>>());
    assert_eq!(set("boundary"), (0..8).collect::<Vec<_>>());
}

#[test]
fn abaqus_follows_includes_and_drops_unused_nodes() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("parts")).unwrap();
    std::fs::write(
        dir.path().join("parts/nodes.inp"),
        "1, 0, 0\n2, 5, 0\n3, 5, 5\n4, 0, 5\n",
    )
    .unwrap();
    // The included file carries the data of the *NODE before it; node 99
    // (a reference point) is in no element and is dropped, with its set.
    let main = "*NODE\n*INCLUDE, INPUT=parts/nodes.inp\n99, 50, 50, 50\n\
                *NSET, NSET=ref\n99\n*ELEMENT, TYPE=M3D4\n7, 1, 2, 3, 4\n";
    let path = dir.path().join("main.inp");
    std::fs::write(&path, main).unwrap();
    let mesh = read_abaqus(&path).unwrap();
    assert_eq!(mesh.x0.len(), 4);
    assert_eq!(mesh.quads, [[0, 1, 2, 3]]);
    assert!(!mesh.node_sets.contains_key("ref"));
    assert_eq!(read_mesh(&path).unwrap(), mesh);
}

#[test]
fn abaqus_instance_translation_is_applied() {
    let text = "*Part, name=P\n*Node\n1, 0, 0\n2, 1, 0\n3, 0, 1\n*Element, type=S3\n1, 1, 2, 3\n\
                *End Part\n*Assembly, name=A\n*Instance, name=P-1, part=P\n5., 0., 2.\n\
                *End Instance\n*End Assembly\n";
    let mesh = parse_abaqus(text, Path::new("inst.inp")).unwrap();
    assert_eq!(mesh.x0[1], Vector3::new(6.0, 0.0, 2.0));
}

#[test]
fn shipped_plate_is_the_same_mesh_in_both_formats() {
    let meshes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/meshes");
    let msh = read_gmsh(meshes.join("plate.msh")).unwrap();
    let inp = read_abaqus(meshes.join("plate.inp")).unwrap();
    assert_eq!(
        (msh.x0.len(), msh.quads.len(), msh.triangles.len()),
        (441, 400, 0)
    );
    assert_eq!(msh.quads, inp.quads);
    for (a, b) in msh.x0.iter().zip(&inp.x0) {
        assert!((a - b).norm() < 1e-8, "{a} vs {b}");
    }
    for name in [
        "left", "right", "bottom", "top", "corners", "boundary", "all",
    ] {
        assert_eq!(msh.node_sets[name], inp.node_sets[name], "{name}");
    }
    assert_eq!(msh.node_sets["left"].len(), 21);
    assert_eq!(msh.node_sets["boundary"].len(), 80);
    let corners: Vec<_> = msh.node_sets["corners"]
        .iter()
        .map(|&n| msh.x0[n as usize])
        .collect();
    assert!(
        corners
            .iter()
            .all(|c| c.x.abs() == 50.0 && c.y.abs() == 50.0)
    );
}

/// The imported plate is the rectangle drape would mesh: the same nodes
/// (as a set), elements and masses.
#[test]
fn imported_plate_model_matches_the_meshed_rectangle() {
    let meshes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/meshes");
    let glass = Material::preset("glass-serge-4x3").unwrap();
    let mesh = read_gmsh(meshes.join("plate.msh")).unwrap();
    let imported = Model::from_mesh(
        &mesh.blank_mesh(30.0),
        &glass,
        FibreRepresentation::Embedded,
    )
    .unwrap();
    let blank = RectangleBlank {
        width: 100.0,
        height: 100.0,
        center: Vector3::zeros(),
        orientation_deg: 30.0,
        element: ElementKind::Quad,
        meshing: Meshing::Cells([20, 20]),
        fibres: FibreRepresentation::Embedded,
    };
    let meshed = Model::from_blank(&blank, &glass).unwrap();
    assert_eq!(imported.node_count(), meshed.node_count());
    assert_eq!(imported.membrane_count(), meshed.membrane_count());
    let total = |m: &Model| m.mass.iter().sum::<f64>();
    assert!((total(&imported) - total(&meshed)).abs() < 1e-9 * total(&meshed));
    let key = |x: &Vector3<f64>| ((x.x * 1e6).round() as i64, (x.y * 1e6).round() as i64);
    let mut a: Vec<_> = imported.x0.iter().map(key).collect();
    let mut b: Vec<_> = meshed.x0.iter().map(key).collect();
    a.sort_unstable();
    b.sort_unstable();
    assert_eq!(a, b);
    assert!(imported.features().embedded_fibres && !imported.features().trusses);
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

const STRIP_SCENE: &str = r#"
[simulation]
end_time = 0.001

[fabric]
material = "glass-serge-4x3"
orientation_deg = 30
fibres = "embedded"
blank = { mesh = "MESH" }

[[springs]]
nodes = "SPRUNG"
stiffness = 1.0

[[boundary]]
nodes = "CLAMPED"
motion = { kind = "fixed" }
"#;

#[test]
fn scenes_use_imported_meshes_and_their_node_sets() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "strip.msh", &good_gmsh());
    write(dir.path(), "strip.inp", ABAQUS_STRIP);
    let glass = Material::preset("glass-serge-4x3").unwrap();
    for (mesh, sprung, clamped) in [
        ("strip.msh", "origin", "clamp"),
        ("strip.inp", "corners", "elset:clamp_edge"),
    ] {
        let text = STRIP_SCENE
            .replace("MESH", mesh)
            .replace("SPRUNG", sprung)
            .replace("CLAMPED", clamped);
        let scene = Scene::from_file(&write(dir.path(), "scene.toml", &text), &[])
            .unwrap_or_else(|e| panic!("{mesh}: {e}"));
        let model = &scene.model;
        assert_eq!(
            (model.node_count(), model.membrane_count()),
            (8, 4),
            "{mesh}"
        );
        assert!(model.features().embedded_fibres, "{mesh}");
        assert_eq!(model.springs[0].nodes, model.node_sets[sprung], "{mesh}");
        assert_eq!(model.boundary[0].nodes, model.node_sets[clamped], "{mesh}");
        let mass: f64 = model.mass.iter().sum();
        assert!(
            (mass - glass.areal_density() * 300.0).abs() < 1e-12 * mass,
            "{mesh}"
        );
    }
}

/// A model from an imported mesh runs: the strip, clamped on the left,
/// pulled on the right.
#[test]
fn an_imported_strip_runs() {
    let mesh = parse_abaqus(ABAQUS_STRIP, Path::new("strip.inp")).unwrap();
    let glass = Material::preset("glass-serge-4x3").unwrap();
    let mut model =
        Model::from_mesh(&mesh.blank_mesh(0.0), &glass, FibreRepresentation::Embedded).unwrap();
    model.boundary.push(BoundaryCondition::fixed(
        model.node_set("elset:clamp_edge").unwrap().to_vec(),
    ));
    let right = vec![3, 4];
    model.boundary.push(BoundaryCondition {
        nodes: right.clone(),
        components: [true, true, true],
        motion: Motion::Displacement {
            value: Vector3::new(0.05, 0.0, 0.0),
            amplitude: Amplitude::SmoothStep { duration: 1e-3 },
        },
    });
    let mut state = model.initial_state();
    let settings = ExplicitSettings {
        end_time: 1e-3,
        ..ExplicitSettings::default()
    };
    let summary = Explicit::new(&model, settings)
        .unwrap()
        .run(&mut state, &mut NoObserver)
        .unwrap();
    assert!(summary.steps > 10);
    assert!((state.x[3].x - 30.05).abs() < 1e-9);
    // The free nodes between moved the right way.
    assert!(state.x[1].x > 10.0 && state.x[2].x > 20.0);
}

#[test]
fn the_shipped_imported_scene_loads_with_either_mesh() {
    let scene_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/imported-plate.toml");
    let msh = Scene::from_file(&scene_path, &[]).unwrap();
    assert_eq!(
        (msh.model.node_count(), msh.model.membrane_count()),
        (441, 400)
    );
    assert_eq!(msh.model.springs[0].nodes.len(), 4);
    assert!(msh.model.features().embedded_fibres && msh.model.features().contact);
    let set = [(
        "fabric.blank.mesh".to_owned(),
        "meshes/plate.inp".to_owned(),
    )];
    let inp = Scene::from_file(&scene_path, &set).unwrap();
    assert_eq!(inp.model.node_count(), 441);
    assert_eq!(inp.model.springs[0].nodes, msh.model.springs[0].nodes);
}

// ---------------------------------------------------------------------------
// Errors.
// ---------------------------------------------------------------------------

#[test]
fn unsupported_element_types_are_named_with_their_line() {
    let text = "*NODE\n1, 0, 0\n2, 1, 0\n3, 1, 1\n4, 0, 1\n*ELEMENT, TYPE=R3D4\n1, 1, 2, 3, 4\n";
    let e = parse_abaqus(text, Path::new("tool.inp")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::UnsupportedElement);
    assert_eq!(e.line, Some(6));
    assert!(e.message.contains("R3D4"), "{e}");
    assert!(
        e.to_string().starts_with("tool.inp:6: element type R3D4"),
        "{e}"
    );

    let e = parse_abaqus(&text.replace("R3D4", "M3D8R"), Path::new("q.inp")).unwrap_err();
    assert!(e.message.contains("second-order"), "{e}");

    // Gmsh: 6-node triangles (type 9), named at their block's header line.
    let text = gmsh_strip(1, "6 3 5 6 7 2 1", 9).replace("5 3 4 5\n", "5 3 4 5 6 7 2\n");
    let e = parse_gmsh(text.as_bytes(), Path::new("tri6.msh")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::UnsupportedElement);
    assert_eq!(e.line, Some(line_of(&text, "2 1 9 2")));
    assert!(e.message.contains("element type 9"), "{e}");
}

#[test]
fn undefined_nodes_are_named() {
    let text = ABAQUS_STRIP.replace("2, 1002, 1003, 1006, 1007", "2, 1002, 1003, 1009, 1007");
    let e = parse_abaqus(&text, Path::new("strip.inp")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::UndefinedNode);
    assert_eq!(e.line, Some(line_of(&text, "2, 1002, 1003, 1009, 1007")));
    assert!(e.message.contains("element 2 uses node 1009"), "{e}");

    let text = ABAQUS_STRIP.replace("1001, 1004, 1005, 1008", "1001, 1004, 1005, 1018");
    let e = parse_abaqus(&text, Path::new("strip.inp")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::UndefinedNode);
    assert!(e.message.contains("node set corners uses node 1018"), "{e}");

    let text = gmsh_strip(1, "6 3 5 66", 2);
    let e = parse_gmsh(text.as_bytes(), Path::new("strip.msh")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::UndefinedNode);
    assert_eq!(e.line, Some(line_of(&text, "6 3 5 66")));
    assert!(e.message.contains("element 6 uses node 66"), "{e}");
}

#[test]
fn inverted_elements_are_reported_not_fixed() {
    let flipped = "2, 1002, 1007, 1006, 1003";
    let text = ABAQUS_STRIP.replace("2, 1002, 1003, 1006, 1007", flipped);
    let e = parse_abaqus(&text, Path::new("strip.inp")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Inverted);
    assert_eq!(e.line, Some(line_of(&text, flipped)));
    assert!(e.message.contains("element 2 is inverted"), "{e}");

    let text = gmsh_strip(1, "6 3 6 5", 2);
    let e = parse_gmsh(text.as_bytes(), Path::new("strip.msh")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Inverted);
    assert_eq!(e.line, Some(line_of(&text, "6 3 6 5")));
    assert!(e.message.contains("element 6 is inverted"), "{e}");

    // An element that shares no node with the rest (duplicated nodes) and
    // faces the other way is inverted too.
    let text = "*NODE\n1,0,0\n2,1,0\n3,1,1\n4,0,1\n5,2,0\n6,3,0\n7,3,1\n\
                *ELEMENT, TYPE=S4\n1, 1, 2, 3, 4\n*ELEMENT, TYPE=S3\n2, 5, 7, 6\n";
    let e = parse_abaqus(text, Path::new("apart.inp")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Inverted);
    assert!(e.message.contains("element 2 is inverted"), "{e}");
    assert_eq!(e.line, Some(12));

    // A whole blank turning the other way is consistent, not inverted.
    let text = "*NODE\n1,0,0\n2,1,0\n3,1,1\n4,0,1\n*ELEMENT, TYPE=S4\n1, 1, 4, 3, 2\n";
    assert!(parse_abaqus(text, Path::new("cw.inp")).is_ok());
}

#[test]
fn degenerate_elements_are_named() {
    let nodes = "*NODE\n1,0,0\n2,1,0\n3,2,0\n4,1,1\n";
    let cases = [
        ("*ELEMENT, TYPE=M3D3\n5, 1, 2, 3\n", "no area"),
        ("*ELEMENT, TYPE=M3D4\n5, 1, 2, 4, 4\n", "repeats node 4"),
        // A bow-tie: nodes not in order round the element.
        ("*ELEMENT, TYPE=M3D4\n5, 1, 3, 2, 4\n", "folded"),
    ];
    for (elements, why) in cases {
        let e = parse_abaqus(&format!("{nodes}{elements}"), Path::new("d.inp")).unwrap_err();
        assert_eq!(e.kind, ImportErrorKind::Degenerate, "{e}");
        assert_eq!(e.line, Some(7), "{e}");
        assert!(
            e.message.contains("element 5 is degenerate") && e.message.contains(why),
            "{e}"
        );
    }
}

#[test]
fn bad_numbers_duplicates_and_broken_data_name_their_line() {
    let cases = [
        (
            "1003, 20, 0, 0",
            "1003, 2O, 0, 0",
            ImportErrorKind::BadNumber,
            "`2O`",
        ),
        (
            "1004, 30, 0",
            "1003, 30, 0",
            ImportErrorKind::Duplicate,
            "node 1003 is defined twice",
        ),
        (
            "10, 1003, 1004, 1005",
            "10, 1003, 1004",
            ImportErrorKind::Syntax,
            "has 2 nodes, expected 3",
        ),
        (
            "\n1001, 1004, 1\n",
            "\n1004, 1001, 1\n",
            ImportErrorKind::Syntax,
            "GENERATE",
        ),
        (
            "\n1001, 1004, 1\n",
            "\n-9223372036854775808, -1, 1\n",
            ImportErrorKind::UndefinedNode,
            "names no nodes",
        ),
        (
            "Quads, TRIS",
            "Quads, TRIANGLES",
            ImportErrorKind::UndefinedSet,
            "TRIANGLES",
        ),
        (
            "1005, 30, 10",
            "1005, 30, inf",
            ImportErrorKind::BadNumber,
            "`inf`",
        ),
    ];
    for (good, bad, kind, says) in cases {
        let text = ABAQUS_STRIP.replace(good, bad);
        let e = parse_abaqus(&text, Path::new("strip.inp")).unwrap_err();
        assert_eq!(e.kind, kind, "{e}");
        assert_eq!(e.line, Some(line_of(&text, bad.trim())), "{e}");
        assert!(e.message.contains(says), "{e}");
    }
    let e = parse_abaqus("*NODE\n1, 0, 0\n", Path::new("empty.inp")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Empty);
}

#[test]
fn broken_and_foreign_gmsh_files_are_refused() {
    // Cut inside the elements: mshio's error, with the line it points at.
    let text = good_gmsh();
    let cut = &text[..text.find("4 2 3 6 7").unwrap() + 3];
    let e = parse_gmsh(cut.as_bytes(), Path::new("cut.msh")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Syntax, "{e}");
    assert!(
        e.line.is_some_and(|l| l >= line_of(&text, "3 1 2 7 8")),
        "{e}"
    );

    let old = text.replace("4.1 0 8", "2.2 0 8");
    let e = parse_gmsh(old.as_bytes(), Path::new("old.msh")).unwrap_err();
    assert_eq!((e.kind, e.line), (ImportErrorKind::Unsupported, Some(2)));
    assert!(e.message.contains("format 2.2"), "{e}");

    let e = parse_gmsh(b"hello\n", Path::new("x.msh")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Syntax);

    // Only the lines of a physical curve saved: no surface.
    let lines_only = text.replace("4 6 1 6\n", "2 2 1 2\n").replace(
        "2 1 3 2\n3 1 2 7 8\n4 2 3 6 7\n2 1 2 2\n5 3 4 5\n6 3 5 6\n",
        "",
    );
    let e = parse_gmsh(lines_only.as_bytes(), Path::new("l.msh")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Empty, "{e}");
    assert!(e.message.contains("Mesh.SaveAll"), "{e}");
}

#[test]
fn missing_files_are_reported() {
    let e = read_gmsh("/nonexistent/plate.msh").unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Read);
    assert!(
        e.to_string()
            .starts_with("/nonexistent/plate.msh: cannot read"),
        "{e}"
    );
    let e = read_mesh("plate.stl").unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Unsupported);

    let dir = tempfile::tempdir().unwrap();
    let text = STRIP_SCENE
        .replace("MESH", "nowhere.msh")
        .replace("SPRUNG", "all")
        .replace("CLAMPED", "all");
    let path = write(dir.path(), "scene.toml", &text);
    let e = Scene::from_file(&path, &[]).unwrap_err();
    assert_eq!(e.field, "fabric.blank.mesh");
    assert_eq!(
        e.line,
        Some(line_of(&text, r#"blank = { mesh = "nowhere.msh" }"#))
    );
    assert!(
        e.message.contains("nowhere.msh: cannot read the mesh"),
        "{e}"
    );
}

#[test]
fn scene_mesh_errors_name_the_field() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "strip.msh", &good_gmsh());
    write(
        dir.path(),
        "flipped.inp",
        &ABAQUS_STRIP.replace("2, 1002, 1003, 1006, 1007", "2, 1002, 1007, 1006, 1003"),
    );
    let scene = |blank: &str, fibres: &str| {
        let text = STRIP_SCENE
            .replace(r#"blank = { mesh = "MESH" }"#, blank)
            .replace(r#"fibres = "embedded""#, fibres)
            .replace("SPRUNG", "all")
            .replace("CLAMPED", "all");
        Scene::from_file(&write(dir.path(), "scene.toml", &text), &[]).unwrap_err()
    };
    let embedded = r#"fibres = "embedded""#;
    let e = scene(r#"blank = { mesh = "strip.msh", width = 10 }"#, embedded);
    assert_eq!(e.field, "fabric.blank.width", "{e}");
    assert!(e.message.contains("cannot be combined with `mesh`"), "{e}");
    let e = scene(r#"blank = { cells = [2, 2] }"#, embedded);
    assert_eq!(e.field, "fabric.blank", "{e}");
    assert!(e.message.contains("`mesh"), "{e}");
    let e = scene(r#"blank = { mesh = "strip.msh" }"#, r#"fibres = "trusses""#);
    assert_eq!(e.field, "fabric.fibres", "{e}");
    assert!(e.message.contains("embedded"), "{e}");
    let e = scene(r#"blank = { mesh = "flipped.inp" }"#, embedded);
    assert_eq!(e.field, "fabric.blank.mesh", "{e}");
    assert!(
        e.message.contains("flipped.inp:") && e.message.contains("element 2 is inverted"),
        "{e}"
    );
    let e = scene(r#"blank = { mesh = "strip.obj" }"#, embedded);
    assert!(e.message.contains(".msh"), "{e}");
}

/// No input makes a reader panic: every prefix of the shipped files and of
/// the test files, and bytes changed here and there, give a mesh or an error.
#[test]
fn readers_never_panic_on_damaged_files() {
    let meshes = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/meshes");
    let plate_msh = std::fs::read(meshes.join("plate.msh")).unwrap();
    let plate_inp = std::fs::read(meshes.join("plate.inp")).unwrap();
    let files = [
        (good_gmsh().into_bytes(), true),
        (plate_msh, true),
        (ABAQUS_STRIP.as_bytes().to_vec(), false),
        (plate_inp, false),
    ];
    let read = |bytes: &[u8], gmsh: bool| -> Result<ImportedMesh, String> {
        if gmsh {
            parse_gmsh(bytes, Path::new("x.msh")).map_err(|e| e.to_string())
        } else {
            let text = String::from_utf8_lossy(bytes);
            parse_abaqus(&text, Path::new("x.inp")).map_err(|e| e.to_string())
        }
    };
    // Counts and codes far out of range where a reader might allocate or
    // index by them.
    let text = good_gmsh();
    for (good, bad) in [
        ("4.1 0 8", "4.1 0 99999999999999999999"),
        ("3 8 1 8", "3 18446744073709551615 1 8"),
        ("3 8 1 8", "99999999999 8 1 8"),
        ("2 1 0 6", "2 1 0 999999999999"),
        ("2 1 0 6", "2 1 0 18446744073709551615"),
        ("1 1 0 1\n8", "1 1 0 1\n18446744073709551615"),
        ("2 1 3 2", "2 1 999999 2"),
        ("2 1 3 2", "2 1 -3 2"),
        ("3\n0 3", "99999999999\n0 3"),
    ] {
        let damaged = text.replacen(good, bad, 1);
        assert!(read(damaged.as_bytes(), true).is_err(), "{bad}");
    }
    for (bytes, gmsh) in &files {
        let step = (bytes.len() / 300).max(1);
        for cut in (0..bytes.len()).step_by(step) {
            let _ = read(&bytes[..cut], *gmsh);
        }
        for (i, junk) in (0..bytes.len())
            .step_by(step)
            .zip([b'9', b'-', b' ', b'\n', b'x', b'*', b','].iter().cycle())
        {
            let mut damaged = bytes.clone();
            damaged[i] = *junk;
            let _ = read(&damaged, *gmsh);
        }
    }
}

#[test]
fn unclosed_gmsh_sections_name_the_section_and_line() {
    let text = good_gmsh();
    let cut = text.replace("$EndNodes\n", "");
    let e = parse_gmsh(cut.as_bytes(), Path::new("cut.msh")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Syntax, "{e}");
    assert_eq!(e.line, Some(line_of(&cut, "$Nodes")), "{e}");
    assert!(
        e.message.contains(&format!(
            "`$EndNodes` before `$Elements` on line {}",
            line_of(&cut, "$Elements")
        )),
        "{e}"
    );
    let cut = text.replace("$EndElements\n", "");
    let e = parse_gmsh(cut.as_bytes(), Path::new("cut.msh")).unwrap_err();
    assert_eq!(e.line, Some(cut.lines().count()), "{e}");
    assert!(
        e.message.contains(&format!(
            "ends inside the `$Elements` section of line {}",
            line_of(&cut, "$Elements")
        )),
        "{e}"
    );
    assert!(e.to_string().starts_with("cut.msh:"), "{e}");
}

#[test]
fn unknown_gmsh_element_types_are_named_with_their_line() {
    for code in [99u32, 4, 1000] {
        let text = gmsh_strip(1, "6 3 5 6", code);
        let e = parse_gmsh(text.as_bytes(), Path::new("odd.msh")).unwrap_err();
        assert_eq!(e.kind, ImportErrorKind::UnsupportedElement, "{e}");
        assert_eq!(
            e.line,
            Some(line_of(&text, &format!("2 1 {code} 2"))),
            "{e}"
        );
        assert!(e.message.contains(&format!("element type {code} (")), "{e}");
    }
}

#[test]
fn abaqus_nodes_without_coordinates_are_at_zero() {
    let text = "*NODE\n1\n2, 1.0\n3, 1, 1\n4, , 1\n*ELEMENT, TYPE=M3D4\n1, 1, 2, 3, 4\n";
    let mesh = parse_abaqus(text, Path::new("axis.inp")).unwrap();
    assert_eq!(
        mesh.x0,
        vec![
            Vector3::zeros(),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0)
        ]
    );
}

#[test]
fn abaqus_set_names_are_case_insensitive_in_scenes_too() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "strip.inp", ABAQUS_STRIP);
    // The file writes `corners`, `Corners` and `elset=Quads`.
    for (sprung, clamped) in [("CORNERS", "ELSET:QUADS"), ("Corners", "elset:quads")] {
        let text = STRIP_SCENE
            .replace("MESH", "strip.inp")
            .replace("SPRUNG", sprung)
            .replace("CLAMPED", clamped);
        let scene = Scene::from_file(&write(dir.path(), "scene.toml", &text), &[])
            .unwrap_or_else(|e| panic!("{sprung}: {e}"));
        let model = &scene.model;
        assert_eq!(model.springs[0].nodes, model.node_sets["corners"]);
        assert_eq!(model.boundary[0].nodes, model.node_sets["elset:Quads"]);
    }
}
