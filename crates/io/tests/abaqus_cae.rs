//! Abaqus/CAE files as they come: parts placed by the instances of an
//! assembly (translated, then rotated about an axis), rigid and shell
//! elements read as a tool's surface with quads split along their shorter
//! diagonal, the same surface from `.inp` and from STL giving the same
//! contact gaps, the units warning of a tool mesh, and errors that name the
//! file, the line and the culprit.

use std::path::{Path, PathBuf};

use drape_io::mesh_import::{
    ImportErrorKind, parse_abaqus, parse_abaqus_surface, read_mesh, split_quad,
};
use drape_io::scene::Scene;
use nalgebra::Vector3;

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drape-cae-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A CAE-style file: a 10 mm square mould part (one quad of `quad`) and a
/// triangular punch part (one triangle of `triangle`), each with a node
/// set; the mould instance translated by (1, 2, 3), the punch instance
/// translated by (10, 0, 0) and then turned 90° about the global z axis
/// (a = origin, b = (0, 0, 1)); an assembly-level reference point with
/// label 1 (like the parts' first nodes), a surface, a rigid body and a
/// step, all skipped.
fn cae(quad: &str, triangle: &str) -> String {
    format!(
        "*Heading
** Job name: mould Model name: Model-1
*Preprint, echo=NO, model=NO, history=NO, contact=NO
**
** PARTS
**
*Part, name=Mould
*Node
      1,           0.,           0.,           0.
      2,          10.,           0.,           0.
      3,          10.,          10.,           0.
      4,           0.,          10.,           0.
*Element, type={quad}
1, 1, 2, 3, 4
*Nset, nset=corner
 1,
*Elset, elset=face
 1,
*End Part
*Part, name=Punch
*Node
      1,           0.,           0.,           0.
      2,           5.,           0.,           0.
      3,           0.,           5.,           2.
*Element, type={triangle}
1, 1, 2, 3
*Nset, nset=corner
 2,
*End Part
**
** ASSEMBLY
**
*Assembly, name=Assembly
**
*Instance, name=Mould-1, part=Mould
          1.,           2.,           3.
*End Instance
**
*Instance, name=Punch-1, part=Punch
          10.,           0.,           0.
          0.,           0.,           0.,           0.,           0.,           1.,          90.
*End Instance
**
*Node
      1,           0.,           0.,          50.
*Nset, nset=Punch-1-RefPt_, internal
1,
*Nset, nset=tip, instance=Punch-1
 3,
*Elset, elset=_Surf-1_SPOS, internal, instance=Mould-1
 1,
*Surface, type=ELEMENT, name=Surf-1
_Surf-1_SPOS, SPOS
*Rigid Body, ref node=Punch-1-RefPt_, elset=Punch-1.corner
*End Assembly
*Material, name=steel
*Elastic
210000., 0.3
*Step, name=Step-1
*Static
*End Step
"
    )
}

/// The mould instance's nodes, translated by (1, 2, 3).
fn mould_nodes() -> Vec<Vector3<f64>> {
    vec![
        Vector3::new(1.0, 2.0, 3.0),
        Vector3::new(11.0, 2.0, 3.0),
        Vector3::new(11.0, 12.0, 3.0),
        Vector3::new(1.0, 12.0, 3.0),
    ]
}

/// The punch instance's nodes: translated by (10, 0, 0) first, then turned
/// 90° about z through the origin, (x, y, z) ↦ (−y, x, z): (0, 0, 0) →
/// (10, 0, 0) → (0, 10, 0); (5, 0, 0) → (15, 0, 0) → (0, 15, 0);
/// (0, 5, 2) → (10, 5, 2) → (−5, 10, 2). (Rotating first would give
/// (10, 0, 0), (10, 5, 0), (5, 0, 2).)
fn punch_nodes() -> Vec<Vector3<f64>> {
    vec![
        Vector3::new(0.0, 10.0, 0.0),
        Vector3::new(0.0, 15.0, 0.0),
        Vector3::new(-5.0, 10.0, 2.0),
    ]
}

fn assert_close(got: &[Vector3<f64>], want: &[Vector3<f64>]) {
    assert_eq!(got.len(), want.len(), "{got:?}");
    for (k, (g, w)) in got.iter().zip(want).enumerate() {
        // cos 90° is 6e-17 in floating point: rounding, not a tolerance on
        // the placement.
        assert!((g - w).norm() < 1e-12, "node {k}: {g} != {w}");
    }
}

#[test]
fn instances_place_copies_of_their_parts_node_by_node() {
    let text = cae("R3D4", "R3D3");
    let s = parse_abaqus_surface(&text, Path::new("mould.inp"), None).unwrap();
    let mut want = mould_nodes();
    want.extend(punch_nodes());
    // The reference point (used by no element) is dropped.
    assert_close(&s.vertices, &want);
    // The square's diagonals tie: split along 0–2.
    assert_eq!(s.triangles, [[0, 1, 2], [0, 2, 3], [4, 5, 6]]);
    assert_eq!(s.instances, ["Mould-1", "Punch-1"]);

    // As a blank (shells), the same nodes, and the sets of two instances
    // named by instance; the assembly's set with INSTANCE= takes the
    // punch's node 3, the model-level set its own node.
    let mesh = parse_abaqus(&cae("S4R", "S3"), Path::new("mould.inp")).unwrap();
    assert_close(&mesh.x0, &want);
    assert_eq!(mesh.quads, [[0, 1, 2, 3]]);
    assert_eq!(mesh.triangles, [[4, 5, 6]]);
    assert_eq!(mesh.node_sets["Mould-1.corner"], [0]);
    assert_eq!(mesh.node_sets["Punch-1.corner"], [5]);
    assert_eq!(mesh.node_sets["elset:Mould-1.face"], [0, 1, 2, 3]);
    assert_eq!(mesh.node_sets["tip"], [6]);
    assert_eq!(mesh.node_sets["elset:_Surf-1_SPOS"], [0, 1, 2, 3]);
    assert!(!mesh.node_sets.contains_key("Punch-1-RefPt_"));
    assert_eq!(mesh.instances, ["Mould-1", "Punch-1"]);

    // Two instances of one part are two copies.
    let twice = cae("R3D4", "R3D3").replace(
        "*Instance, name=Punch-1, part=Punch",
        "*Instance, name=Mould-2, part=Mould\n 0., 0., 100.\n*End Instance\n\
         *Instance, name=Punch-1, part=Punch",
    );
    let s = parse_abaqus_surface(&twice, Path::new("twice.inp"), None).unwrap();
    assert_eq!(s.vertices.len(), 11);
    for k in 0..4 {
        assert_eq!(
            s.vertices[4 + k],
            mould_nodes()[k] - Vector3::new(1.0, 2.0, 3.0) + Vector3::new(0.0, 0.0, 100.0)
        );
    }
}

#[test]
fn a_rotation_about_an_axis_off_the_origin_follows_the_translation() {
    // Translation (0, 0, 10), then 180° about the axis through (1, 0, 10)
    // along y: (x, y, z) ↦ (2 − x, y, 20 − z) after the shift.
    let text = "*Part, name=P\n*Node\n1, 0, 0, 0\n2, 1, 0, 0\n3, 0, 1, 1\n\
                *Element, type=R3D3\n1, 1, 2, 3\n*End Part\n*Assembly, name=A\n\
                *Instance, name=P-1, part=P\n0, 0, 10\n1, 0, 10, 1, 1, 10, 180\n\
                *End Instance\n*End Assembly\n";
    let s = parse_abaqus_surface(text, Path::new("axis.inp"), None).unwrap();
    assert_close(
        &s.vertices,
        &[
            Vector3::new(2.0, 0.0, 10.0),
            Vector3::new(1.0, 0.0, 10.0),
            Vector3::new(2.0, 1.0, 9.0),
        ],
    );
    // A pure rotation: Abaqus's blank translation line (skipped), then the
    // rotation, 180° about the axis through (1, 0, 0) along y.
    let pure = text.replace(
        "0, 0, 10\n1, 0, 10, 1, 1, 10, 180",
        "\n1, 0, 0, 1, 1, 0, 180",
    );
    let s = parse_abaqus_surface(&pure, Path::new("axis.inp"), None).unwrap();
    assert_close(
        &s.vertices,
        &[
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(2.0, 1.0, -1.0),
        ],
    );
    // A third position line is refused (a missing *END INSTANCE).
    let third = text.replace("180\n", "180\n1, 2, 3\n");
    let e = parse_abaqus_surface(&third, Path::new("axis.inp"), None).unwrap_err();
    assert_eq!(e.line, Some(13), "{e}");
    assert!(e.message.contains("third data line"), "{e}");
}

#[test]
fn quads_split_along_their_shorter_diagonal() {
    // A skewed quad whose diagonal 1–3 (7.1) is shorter than 0–2 (15.8).
    let skew = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(10.0, 0.0, 0.0),
        Vector3::new(15.0, 5.0, 0.0),
        Vector3::new(5.0, 5.0, 0.0),
    ];
    assert_eq!(split_quad(&skew, [0, 1, 2, 3]), [[0, 1, 3], [1, 2, 3]]);
    // Its mirror image: now 0–2 is the shorter one.
    let mirror = skew.map(|p| Vector3::new(15.0 - p.x, p.y, 0.0));
    assert_eq!(split_quad(&mirror, [1, 0, 3, 2]), [[1, 0, 3], [1, 3, 2]]);

    // Read from a file: the two triangles keep the quad's normal (+z).
    let text = "*Node\n1, 0, 0\n2, 10, 0\n3, 15, 5\n4, 5, 5\n*Element, type=R3D4\n\
                7, 1, 2, 3, 4\n";
    let s = parse_abaqus_surface(text, Path::new("skew.inp"), None).unwrap();
    assert_eq!(s.triangles, [[0, 1, 3], [1, 2, 3]]);
    for t in &s.triangles {
        let p = |i: usize| s.vertices[t[i] as usize];
        let n = (p(1) - p(0)).cross(&(p(2) - p(0)));
        assert!(n.z > 0.0 && n.x == 0.0 && n.y == 0.0, "{t:?}: {n}");
    }
    // Surface elements and shells too.
    for kind in ["SFM3D4R", "S4R", "M3D4"] {
        let s =
            parse_abaqus_surface(&text.replace("R3D4", kind), Path::new("skew.inp"), None).unwrap();
        assert_eq!(s.triangles, [[0, 1, 3], [1, 2, 3]], "{kind}");
    }
}

/// A 60 × 60 mm dish of 4 × 4 quads, z = (x² + y²)/100 (in the part's
/// coordinates, before the instance's translation by `shift`).
fn dish() -> (Vec<Vector3<f64>>, Vec<[usize; 4]>) {
    let mut nodes = Vec::new();
    for j in 0..5 {
        for i in 0..5 {
            let (x, y) = (-30.0 + 15.0 * i as f64, -30.0 + 15.0 * j as f64);
            nodes.push(Vector3::new(x, y, (x * x + y * y) / 100.0));
        }
    }
    let mut quads = Vec::new();
    for j in 0..4 {
        for i in 0..4 {
            let n = |a: usize, b: usize| (j + b) * 5 + i + a;
            quads.push([n(0, 0), n(1, 0), n(1, 1), n(0, 1)]);
        }
    }
    (nodes, quads)
}

fn scene_with_tool(dir: &Path, geometry: &str) -> Scene {
    let text = format!(
        "[simulation]\nend_time = 0.01\n\n[fabric]\nmaterial = \"glass-serge-4x3\"\n\
         fibres = \"trusses\"\nblank = {{ width = 10, height = 10, cells = [2, 2] }}\n\n\
         [[tools]]\nname = \"mould\"\ngeometry = {geometry}\n"
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    Scene::from_file(&path, &[]).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn the_same_surface_from_inp_and_stl_gives_identical_gaps() {
    let dir = temp("gaps");
    let (nodes, quads) = dish();
    let shift = Vector3::new(5.0, -3.0, 2.0);
    // The .inp: a part in a CAE file, its instance translated by `shift`,
    // in cm (scaled in the scene).
    let mut inp = String::from("*Part, name=Dish\n*Node\n");
    for (k, p) in nodes.iter().enumerate() {
        inp.push_str(&format!(
            "{}, {}, {}, {}\n",
            k + 1,
            p.x / 10.0,
            p.y / 10.0,
            p.z / 10.0
        ));
    }
    inp.push_str("*Element, type=R3D4\n");
    for (k, q) in quads.iter().enumerate() {
        inp.push_str(&format!(
            "{}, {}, {}, {}, {}\n",
            k + 1,
            q[0] + 1,
            q[1] + 1,
            q[2] + 1,
            q[3] + 1
        ));
    }
    inp.push_str(&format!(
        "*End Part\n*Assembly, name=A\n*Instance, name=Dish-1, part=Dish\n{}, {}, {}\n\
         *End Instance\n*End Assembly\n",
        shift.x / 10.0,
        shift.y / 10.0,
        shift.z / 10.0
    ));
    std::fs::write(dir.join("dish.inp"), inp).unwrap();
    // The STL: the same triangles, each quad split along its shorter
    // diagonal (decided here, not by drape), placed, in mm.
    let mut stl = String::from("solid dish\n");
    let placed = |k: usize| (nodes[k] / 10.0 + shift / 10.0) * 10.0;
    for q in &quads {
        let d02 = (nodes[q[2]] - nodes[q[0]]).norm();
        let d13 = (nodes[q[3]] - nodes[q[1]]).norm();
        let tris = if d02 <= d13 {
            [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
        } else {
            [[q[0], q[1], q[3]], [q[1], q[2], q[3]]]
        };
        for t in tris {
            stl.push_str(" facet normal 0 0 0\n  outer loop\n");
            for k in t {
                let p = placed(k);
                stl.push_str(&format!("   vertex {} {} {}\n", p.x, p.y, p.z));
            }
            stl.push_str("  endloop\n endfacet\n");
        }
    }
    stl.push_str("endsolid dish\n");
    std::fs::write(dir.join("dish.stl"), stl).unwrap();

    let from_inp = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "dish.inp", units = "cm", flip_normals = false }"#,
    );
    // The side as the files have it (the blank is behind the dish's
    // normals, which would be turned with a warning otherwise).
    let from_stl = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "dish.stl", flip_normals = false }"#,
    );
    assert!(from_inp.warnings.is_empty(), "{:?}", from_inp.warnings);
    let (a, b) = (&from_inp.model.tools[0], &from_stl.model.tools[0]);
    let mut probes = 0;
    for j in 0..9 {
        for i in 0..9 {
            for z in [-4.0, 1.0, 7.5, 30.0] {
                let p = Vector3::new(-35.0 + 9.0 * i as f64, -35.0 + 9.0 * j as f64, z);
                let (pa, pb) = (a.project(&p, 0.0), b.project(&p, 0.0));
                assert_eq!(pa.gap, pb.gap, "{p}");
                assert_eq!(pa.point, pb.point, "{p}");
                probes += 1;
            }
        }
    }
    assert_eq!(probes, 324);
    // And gaps that are right: the dish's lowest point (the part's origin,
    // moved by `shift`) is on it, and 4 mm below it is 4 mm away (every
    // face rises from there).
    assert!(a.project(&shift, 0.0).gap.abs() < 1e-12);
    let below = a.project(&(shift - Vector3::new(0.0, 0.0, 4.0)), 0.0);
    assert!((below.gap.abs() - 4.0).abs() < 1e-12, "{below:?}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_tool_mesh_in_the_wrong_unit_warns_naming_units() {
    let dir = temp("units");
    // The same 10 mm square read as metres (10 km) and as 10 µm; its side
    // and rim given, since in the wrong unit no node lies over it.
    std::fs::write(dir.join("mould.inp"), cae("R3D4", "R3D3")).unwrap();
    let big = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "mould.inp", units = "m", flip_normals = false, rim_extension = 0 }"#,
    );
    assert_eq!(big.warnings.len(), 1, "{:?}", big.warnings);
    let w = &big.warnings[0];
    assert!(
        w.contains("tools[0].geometry.units")
            && w.contains("mm across")
            && w.contains("units = \"m\""),
        "{w}"
    );
    let small = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "mould.inp", scale = 0.0001, flip_normals = false, rim_extension = 0 }"#,
    );
    assert_eq!(small.warnings.len(), 1, "{:?}", small.warnings);
    let fine = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "mould.inp", flip_normals = false, rim_extension = 0 }"#,
    );
    assert!(fine.warnings.is_empty(), "{:?}", fine.warnings);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn cae_errors_name_the_file_line_and_culprit() {
    let text = cae("R3D4", "R3D3");
    let line_of = |t: &str, content: &str| t.lines().position(|l| l.trim() == content).unwrap() + 1;
    // An element type a tool cannot use.
    let bad = cae("C3D8R", "R3D3");
    let e = parse_abaqus_surface(&bad, Path::new("m.inp"), None).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::UnsupportedElement);
    assert_eq!(e.line, Some(line_of(&bad, "*Element, type=C3D8R")));
    assert!(
        e.to_string().starts_with("m.inp:") && e.message.contains("C3D8R"),
        "{e}"
    );
    // Rigid elements in a blank: refused, pointing at the tool's use.
    let e = parse_abaqus(&text, Path::new("m.inp")).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::UnsupportedElement);
    assert!(
        e.message.contains("R3D4") && e.message.contains("tool"),
        "{e}"
    );
    // An instance of an unknown part.
    let bad = text.replace("part=Punch", "part=Pnuch");
    let e = parse_abaqus_surface(&bad, Path::new("m.inp"), None).unwrap_err();
    assert_eq!(
        e.line,
        Some(line_of(&bad, "*Instance, name=Punch-1, part=Pnuch"))
    );
    assert!(
        e.message.contains("instance Punch-1 is of part Pnuch")
            && e.message.contains("Mould, Punch"),
        "{e}"
    );
    // A node label the part does not define.
    let bad = text.replace("1, 1, 2, 3, 4", "1, 1, 2, 3, 9");
    let e = parse_abaqus_surface(&bad, Path::new("m.inp"), None).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::UndefinedNode);
    assert_eq!(e.line, Some(line_of(&bad, "1, 1, 2, 3, 9")));
    assert!(
        e.message
            .contains("element 1 uses node 9, which part Mould (instance Mould-1) does not define"),
        "{e}"
    );
    // A set naming an instance that does not exist.
    let bad = text.replace("instance=Punch-1", "instance=Punch-2");
    let e = parse_abaqus_surface(&bad, Path::new("m.inp"), None).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::UndefinedSet);
    assert!(e.message.contains("set tip names instance Punch-2"), "{e}");
    // A rotation line that is cut short, and an axis of one point.
    let bad = text.replace(
        "0.,           0.,           0.,           0.,           0.,           1.,          90.",
        "0., 0., 0., 0., 0., 1.",
    );
    let e = parse_abaqus_surface(&bad, Path::new("m.inp"), None).unwrap_err();
    assert_eq!(e.line, Some(line_of(&bad, "0., 0., 0., 0., 0., 1.")));
    assert!(e.message.contains("expected 7"), "{e}");
    let bad = text.replace(
        "0.,           0.,           0.,           0.,           0.,           1.,          90.",
        "1., 1., 1., 1., 1., 1., 90.",
    );
    let e = parse_abaqus_surface(&bad, Path::new("m.inp"), None).unwrap_err();
    assert!(e.message.contains("two different points"), "{e}");
    // A part left open.
    let bad = text.replacen("*End Part\n", "", 1);
    let e = parse_abaqus_surface(&bad, Path::new("m.inp"), None).unwrap_err();
    assert_eq!(e.line, Some(line_of(&bad, "*Part, name=Punch")));
    assert!(e.message.contains("*END PART is missing"), "{e}");
    // A duplicate node within one part, but not across parts.
    let bad = text.replace(
        "      4,           0.,          10.",
        "      3,           0.,          10.",
    );
    let e = parse_abaqus_surface(&bad, Path::new("m.inp"), None).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Duplicate);
    assert!(e.message.contains("node 3 is defined twice"), "{e}");
    // No surface element at all.
    let e = parse_abaqus_surface("*Node\n1, 0, 0\n", Path::new("none.inp"), None).unwrap_err();
    assert_eq!(e.kind, ImportErrorKind::Empty);
}

#[test]
fn a_structural_cae_file_reads_as_a_mesh_with_its_instance() {
    // One shell part in a CAE file with a reference point at the assembly
    // level (node 1, like the part's) and a rotated instance: what `drape
    // export --onto` reads.
    let dir = temp("structural");
    let text = "*Heading\n*Part, name=Skin\n*Node\n1, 0, 0, 0\n2, 1, 0, 0\n3, 1, 1, 0\n4, 0, 1, 0\n\
                *Element, type=S4R\n11, 1, 2, 3, 4\n*Shell Section, elset=all, material=cfrp\n\
                1.\n*End Part\n*Assembly, name=Assembly\n*Instance, name=Skin-1, part=Skin\n\
                0., 0., 0.\n0., 0., 0., 1., 0., 0., 90.\n*End Instance\n*Node\n1, 5., 5., 5.\n\
                *End Assembly\n";
    let path = dir.join("skin.inp");
    std::fs::write(&path, text).unwrap();
    let mesh = read_mesh(&path).unwrap();
    assert_eq!(mesh.quad_labels, [11]);
    // 90° about x: (x, y, z) ↦ (x, −z, y).
    assert_close(
        &mesh.x0,
        &[
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 1.0),
            Vector3::new(0.0, 0.0, 1.0),
        ],
    );
    assert_eq!(mesh.instances, ["Skin-1"]);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_mesh_inside_an_instance_and_in_an_included_file_is_placed_too() {
    // The nodes and elements written inside the *INSTANCE block belong to
    // it and move with it; the part's mesh comes from an *INCLUDE.
    let dir = temp("inside");
    std::fs::write(
        dir.join("part-mesh.inp"),
        "*Node\n1, 0, 0, 0\n2, 4, 0, 0\n3, 4, 4, 0\n4, 0, 4, 0\n*Element, type=R3D4\n1, 1, 2, 3, 4\n",
    )
    .unwrap();
    let text = "*Part, name=Base\n*Include, input=part-mesh.inp\n*End Part\n\
                *Part, name=Empty\n*End Part\n*Assembly, name=A\n\
                *Instance, name=Base-1, part=Base\n*End Instance\n\
                *Instance, name=Lid-1, part=Empty\n0, 0, 5\n*Node\n1, 0, 0, 0\n2, 1, 0, 0\n\
                3, 0, 1, 0\n*Element, type=R3D3\n1, 1, 2, 3\n*End Instance\n*End Assembly\n";
    let path = dir.join("main.inp");
    std::fs::write(&path, text).unwrap();
    let s = drape_io::mesh_import::read_abaqus_surface(&path, None).unwrap();
    assert_close(
        &s.vertices,
        &[
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(4.0, 0.0, 0.0),
            Vector3::new(4.0, 4.0, 0.0),
            Vector3::new(0.0, 4.0, 0.0),
            Vector3::new(0.0, 0.0, 5.0),
            Vector3::new(1.0, 0.0, 5.0),
            Vector3::new(0.0, 1.0, 5.0),
        ],
    );
    assert_eq!(s.triangles, [[0, 1, 2], [0, 2, 3], [4, 5, 6]]);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn one_instance_of_a_file_is_picked_as_a_tool() {
    let text = cae("R3D4", "R3D3");
    // Names are case-insensitive, as in Abaqus.
    let s = parse_abaqus_surface(&text, Path::new("m.inp"), Some("punch-1")).unwrap();
    assert_close(&s.vertices, &punch_nodes());
    assert_eq!(s.triangles, [[0, 1, 2]]);
    let e = parse_abaqus_surface(&text, Path::new("m.inp"), Some("Die-1")).unwrap_err();
    assert!(
        e.message
            .contains("no such instance (it has Mould-1, Punch-1)"),
        "{e}"
    );
    // In a scene: the key `instance`, refused for an STL.
    let dir = temp("pick");
    std::fs::write(dir.join("tools.inp"), &text).unwrap();
    let scene = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "tools.inp", instance = "Mould-1", rim_extension = 0 }"#,
    );
    // (No rim extension: the box is the instance's own.)
    let b = scene.model.tools[0].surface.aabb();
    assert_eq!((b.min, b.max), (mould_nodes()[0], mould_nodes()[2]));
    std::fs::write(dir.join("t.stl"), "solid t\nendsolid t\n").unwrap();
    let path = dir.join("scene.toml");
    std::fs::write(
        &path,
        std::fs::read_to_string(&path)
            .unwrap()
            .replace("tools.inp", "t.stl"),
    )
    .unwrap();
    let e = Scene::from_file(&path, &[]).unwrap_err().to_string();
    assert!(
        e.contains("tools[0].geometry.instance") && e.contains("Abaqus .inp"),
        "{e}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
