//! Imports that real files pass: units and placement of a blank mesh and a
//! tool mesh (`units`/`scale`, `rotate`, `offset`), the size warning of a
//! blank in the wrong unit, a mixed-winding blank or tool turned
//! consistently on request (`reorient`), degenerate tool triangles dropped
//! with a count (`drop_degenerate`). Each repair is refused, with the key
//! that would make it, when not asked for.

use std::path::{Path, PathBuf};

use drape_io::results::mapping::model_elements;
use drape_io::scene::Scene;
use nalgebra::{Rotation3, Vector3};

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drape-imports-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A 0.1 m square plate of 2 × 2 M3D4 elements, in metres, nodes 1–9 row
/// by row from (0, 0); `flip` turns the last element's node order over.
fn plate_inp(flip: bool) -> (String, Vec<Vector3<f64>>) {
    let mut nodes = Vec::new();
    let mut text = String::from("*HEADING\nplate in metres\n*NODE\n");
    for j in 0..3 {
        for i in 0..3 {
            let x = Vector3::new(0.05 * i as f64, 0.05 * j as f64, 0.0);
            text.push_str(&format!("{}, {}, {}, 0\n", nodes.len() + 1, x.x, x.y));
            nodes.push(x);
        }
    }
    text.push_str("*ELEMENT, TYPE=M3D4\n1, 1, 2, 5, 4\n2, 2, 3, 6, 5\n3, 4, 5, 8, 7\n");
    text.push_str(if flip {
        "4, 5, 8, 9, 6\n"
    } else {
        "4, 5, 6, 9, 8\n"
    });
    (text, nodes)
}

fn scene_with_blank(dir: &Path, blank: &str) -> Result<Scene, String> {
    let text = format!(
        "[simulation]\nend_time = 0.01\n\n[fabric]\nmaterial = \"glass-serge-4x3\"\n\
         fibres = \"embedded\"\nblank = {blank}\n"
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    Scene::from_file(&path, &[]).map_err(|e| e.to_string())
}

#[test]
fn a_blank_in_metres_is_scaled_rotated_and_moved() {
    let dir = temp("blank");
    let (inp, file_nodes) = plate_inp(false);
    std::fs::write(dir.join("plate.inp"), inp).unwrap();
    let scene = scene_with_blank(
        &dir,
        r#"{ mesh = "plate.inp", units = "m", rotate = [0, 0, 90], offset = [1, 2, 5] }"#,
    )
    .unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), 90f64.to_radians());
    let x0 = &scene.model.x0;
    assert_eq!(x0.len(), 9);
    // The import keeps the file's node order.
    for (x, f) in x0.iter().zip(&file_nodes) {
        let expected = Vector3::new(1.0, 2.0, 5.0) + turn * (1000.0 * f);
        assert!((x - expected).norm() < 1e-12, "{x} vs {expected}");
    }
    // `scale = 1000` is `units = "m"`.
    let scaled = scene_with_blank(
        &dir,
        r#"{ mesh = "plate.inp", scale = 1000, rotate = [0, 0, 90], offset = [1, 2, 5] }"#,
    )
    .unwrap();
    assert_eq!(&scaled.model.x0, x0);

    // The file read as millimetres: 0.14 mm across, a warning that says
    // what to give.
    let small = scene_with_blank(&dir, r#"{ mesh = "plate.inp" }"#).unwrap();
    assert_eq!(small.warnings.len(), 1, "{:?}", small.warnings);
    let w = &small.warnings[0];
    assert!(
        w.contains("fabric.blank.mesh")
            && w.contains("1.414e-1 mm across")
            && w.contains("units = \"m\""),
        "{w}"
    );
    // 14 m across: also a warning.
    let large = scene_with_blank(&dir, r#"{ mesh = "plate.inp", scale = 1e5 }"#).unwrap();
    assert_eq!(large.warnings.len(), 1, "{:?}", large.warnings);
    // Both keys, or a scale that is not a factor: errors naming the key.
    for (blank, says) in [
        (
            r#"{ mesh = "plate.inp", units = "m", scale = 1000 }"#,
            "not both",
        ),
        (r#"{ mesh = "plate.inp", scale = -1 }"#, "positive factor"),
        (r#"{ mesh = "plate.inp", units = "km" }"#, "fabric.blank"),
    ] {
        let e = scene_with_blank(&dir, blank).unwrap_err();
        assert!(
            e.contains("fabric.blank") && e.contains(says),
            "{blank}: {e}"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

/// Normal of each element of the scene's blank (first three nodes).
fn normals(scene: &Scene) -> Vec<Vector3<f64>> {
    let x = &scene.model.x0;
    model_elements(&scene.model)
        .iter()
        .map(|e| {
            let p = |k: usize| x[e[k] as usize];
            (p(1) - p(0)).cross(&(p(2) - p(0))).normalize()
        })
        .collect()
}

#[test]
fn a_mixed_winding_blank_is_turned_on_request() {
    let dir = temp("winding");
    let (inp, _) = plate_inp(true);
    std::fs::write(dir.join("plate.inp"), inp).unwrap();
    let e = scene_with_blank(&dir, r#"{ mesh = "plate.inp", units = "m" }"#).unwrap_err();
    assert!(e.contains("reorient = true"), "{e}");
    let scene = scene_with_blank(
        &dir,
        r#"{ mesh = "plate.inp", units = "m", reorient = true }"#,
    )
    .unwrap();
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0].contains("turned 1 element over"),
        "{:?}",
        scene.warnings
    );
    // The majority's side: every element faces +z.
    let n = normals(&scene);
    assert_eq!(n.len(), 4);
    assert!(n.iter().all(|n| (n - Vector3::z()).norm() < 1e-12), "{n:?}");
    std::fs::remove_dir_all(dir).unwrap();
}

fn scene_with_tool(dir: &Path, geometry: &str) -> Result<Scene, String> {
    let text = format!(
        "[simulation]\nend_time = 0.01\n\n[fabric]\nmaterial = \"glass-serge-4x3\"\n\
         fibres = \"trusses\"\nblank = {{ width = 10, height = 10, cells = [2, 2] }}\n\n\
         [[tools]]\nname = \"floor\"\ngeometry = {geometry}\n"
    );
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    Scene::from_file(&path, &[]).map_err(|e| e.to_string())
}

/// A 4 × 4 floor of two triangles at z = −1, in cm; `extra` faces are added
/// (1-based OBJ indices; vertices 5–6 lie on the edge 1–2, vertex 7 beside
/// the edge 2–3).
fn floor_obj(dir: &Path, second: &str, extra: &str) {
    let text = format!(
        "v -2 -2 -1\nv 2 -2 -1\nv 2 2 -1\nv -2 2 -1\nv 0 -2 -1\nv 1 -2 -1\nv 3 0 -1\n\
         f 1 2 3\nf {second}\n{extra}"
    );
    std::fs::write(dir.join("floor.obj"), text).unwrap();
}

#[test]
fn a_tool_mesh_is_placed_and_repaired_on_request() {
    let dir = temp("tool");
    // Placement: cm to mm, then turned 180° about x (the floor faces
    // down, at z = +10), then moved 5 mm down; its open rim not extended,
    // so its box is the file's.
    floor_obj(&dir, "1 3 4", "");
    let scene = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "floor.obj", units = "cm", rotate = [180, 0, 0], offset = [0, 0, -5], rim_extension = 0 }"#,
    )
    .unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let surface = &scene.model.tools[0].surface;
    let b = surface.aabb();
    assert!(
        (b.min.z - 5.0).abs() < 1e-9 && (b.max.z - 5.0).abs() < 1e-9,
        "{b:?}"
    );
    assert!(
        (b.min.x + 20.0).abs() < 1e-9 && (b.max.y - 20.0).abs() < 1e-9,
        "{b:?}"
    );
    // Turned over, its normal points down: a point below is outside.
    let below = surface.project(&Vector3::new(1.0, 1.0, 0.0));
    assert!((below.gap - 5.0).abs() < 1e-9, "{below:?}");

    // A degenerate triangle (three vertices on a line): refused, then
    // dropped and counted.
    floor_obj(&dir, "1 3 4", "f 1 5 6\n");
    let e = scene_with_tool(&dir, r#"{ kind = "mesh", file = "floor.obj" }"#).unwrap_err();
    assert!(e.contains("drop_degenerate = true"), "{e}");
    let scene = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "floor.obj", drop_degenerate = true }"#,
    )
    .unwrap();
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0].contains("dropped 1 degenerate triangle (")
            && scene.warnings[0].contains("triangle 2"),
        "{:?}",
        scene.warnings
    );

    // The second triangle wound the other way (a third one beside the
    // first makes +z the side of most of the area): refused, then turned.
    floor_obj(&dir, "1 4 3", "f 2 7 3\n");
    let e = scene_with_tool(&dir, r#"{ kind = "mesh", file = "floor.obj" }"#).unwrap_err();
    assert!(e.contains("reorient = true"), "{e}");
    let scene = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "floor.obj", reorient = true }"#,
    )
    .unwrap();
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0].contains("turned 1 triangle over"),
        "{:?}",
        scene.warnings
    );
    // Both triangles now face +z: a point above either is outside.
    let surface = &scene.model.tools[0].surface;
    for p in [Vector3::new(1.0, -1.0, 0.0), Vector3::new(-1.0, 1.0, 0.0)] {
        let q = surface.project(&p);
        assert!((q.gap - 1.0).abs() < 1e-9, "{p}: {q:?}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn an_open_tool_mesh_takes_the_blanks_side_or_says_why_it_cannot() {
    let dir = temp("sides");
    // The 4 × 4 mm floor 1 mm under the blank, wound down: its normals
    // point away from the blank, so they are turned, with a warning.
    let down = "v -2 -2 -1\nv 2 -2 -1\nv 2 2 -1\nv -2 2 -1\nf 1 3 2\nf 1 4 3\n";
    std::fs::write(dir.join("floor.obj"), down).unwrap();
    let scene = scene_with_tool(&dir, r#"{ kind = "mesh", file = "floor.obj" }"#).unwrap();
    assert_eq!(scene.warnings.len(), 1, "{:?}", scene.warnings);
    assert!(
        scene.warnings[0].contains("normals point away from the blank")
            && scene.warnings[0].contains("flip_normals = false"),
        "{:?}",
        scene.warnings
    );
    let surface = &scene.model.tools[0].surface;
    assert!((surface.project(&Vector3::new(0.5, 0.5, 0.0)).gap - 1.0).abs() < 1e-12);
    // The default rim extension: the blank's overhang (its corner (5, 5, 0)
    // is √19 mm from the floor's corner (2, 2, −1)) and three of its 5 mm
    // elements.
    assert!(
        (surface.aabb().min.x + 17.0 + 19f64.sqrt()).abs() < 1e-9,
        "{:?}",
        surface.aabb()
    );
    // `flip_normals = false` keeps the file's side: the blank is behind.
    let scene = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "floor.obj", flip_normals = false }"#,
    )
    .unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let surface = &scene.model.tools[0].surface;
    assert!((surface.project(&Vector3::new(0.5, 0.5, 0.0)).gap + 1.0).abs() < 1e-12);
    let e = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "floor.obj", rim_extension = -1 }"#,
    )
    .unwrap_err();
    assert!(
        e.contains("rim_extension") && e.contains("expected a length ≥ 0"),
        "{e}"
    );
    // A 40 × 40 mm floor tilted 20° through the blank's centre line: the
    // blank's nodes at y = −5 are above it, those at y = 5 under it.
    floor_obj(&dir, "1 3 4", "");
    let e = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "floor.obj", units = "cm", rotate = [20, 0, 0], offset = [0, 0, 10.6418] }"#,
    )
    .unwrap_err();
    for part in [
        "both sides of the open mesh `floor`",
        "3 nodes in front",
        "3 behind",
        "flip_normals",
    ] {
        assert!(e.contains(part), "{part}: {e}");
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_rim_extension_laid_under_the_blank_is_refused_or_shortened() {
    let dir = temp("speck");
    // A 0.5 mm speck of a mould in the blank's own plane, 3 mm beside its
    // edge (x = 5): the surface has no node of the blank on it, but its
    // rim extended in that plane would lie under the blank, within the
    // half thickness that the first step throws every such node off.
    let speck = "v 8 0 0\nv 8.5 0 0\nv 8.5 0.5 0\nv 8 0.5 0\nf 1 2 3\nf 1 3 4\n";
    std::fs::write(dir.join("speck.obj"), speck).unwrap();
    let e = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "speck.obj", flip_normals = false, rim_extension = 10 }"#,
    )
    .unwrap_err();
    for part in [
        "rim_extension",
        "`floor`: the rim extended by 10 mm lies under the blank within half its thickness",
        "first node",
        "shorter rim_extension",
    ] {
        assert!(e.contains(part), "{part}: {e}");
    }
    // Unset, the default (the overhang and three elements) is halved until
    // it stays clear of the blank, and the scene says by how much.
    let scene = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "speck.obj", flip_normals = false }"#,
    )
    .unwrap();
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("its open rim is extended by") && w.contains("lies under it")),
        "{:?}",
        scene.warnings
    );
    let drape_contact::Surface::Mesh(mesh) = &scene.model.tools[0].surface else {
        panic!("a mesh tool");
    };
    assert_eq!(mesh.touching(&scene.model.x0, 0.285).0, 0);
    assert!(mesh.aabb().min.x > 5.0, "{:?}", mesh.aabb());
    // Far enough from the blank, the extension is the default.
    let far = "v 30 0 0\nv 30.5 0 0\nv 30.5 0.5 0\nv 30 0.5 0\nf 1 2 3\nf 1 3 4\n";
    std::fs::write(dir.join("speck.obj"), far).unwrap();
    let scene = scene_with_tool(
        &dir,
        r#"{ kind = "mesh", file = "speck.obj", flip_normals = false, rim_extension = 10 }"#,
    )
    .unwrap();
    assert!(
        !scene.warnings.iter().any(|w| w.contains("rim")),
        "{:?}",
        scene.warnings
    );
    std::fs::remove_dir_all(dir).unwrap();
}
