//! `[stack]` scenes: a one-ply stack runs bit for bit as `[fabric]`, the
//! plies are built and stacked, and bad stack keys name their field and
//! line.

use std::path::Path;

use drape_io::scene::Scene;
use drape_time::{Explicit, NoObserver};

/// The shipped hemisphere scene, coarse and short, without bending (with
/// it: `stack_bending.rs`).
fn hemisphere(extra: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/hemisphere-0-90.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let text = text
        .replace("cells = [40, 40]", "cells = [8, 8]")
        .replace("end_time = 1.0 ", "end_time = 0.02 ")
        .replace(
            "fibres = \"trusses\"",
            "fibres = \"trusses\"\nbending = false",
        );
    assert!(text.contains("end_time = 0.02"));
    format!("{text}\n{extra}")
}

fn run(text: &str) -> drape_model::State {
    let scene = Scene::parse(text, Path::new("scene.toml"), &[]).unwrap();
    let mut state = scene.model.initial_state();
    Explicit::new(&scene.model, scene.settings.clone())
        .unwrap()
        .run(&mut state, &mut NoObserver)
        .unwrap();
    state
}

#[test]
fn a_one_ply_stack_runs_bit_for_bit_as_the_fabric() {
    let fabric = run(&hemisphere(""));
    let stack = run(&hemisphere("[stack]\n[[stack.ply]]\nname = \"only\"\n"));
    assert!(fabric.step > 100);
    assert_eq!(fabric.step, stack.step);
    assert_eq!(fabric.x, stack.x);
    assert_eq!(fabric.v, stack.v);
    assert_eq!(fabric.history, stack.history);
}

#[test]
fn plies_take_fabric_defaults_and_their_own_keys() {
    let text = hemisphere(
        "[stack]\nfriction = 0.3\n[[stack.ply]]\n[[stack.ply]]\nname = \"top\"\norientation_deg = 45\nthickness = 0.5\nfriction = 0.1\nfibres = \"embedded\"\n",
    );
    let scene = Scene::parse(&text, Path::new("scene.toml"), &[]).unwrap();
    let m = &scene.model;
    assert_eq!(m.plies.len(), 2);
    assert_eq!(m.plies[0].name, "ply1");
    assert_eq!(m.plies[1].name, "top");
    assert_eq!(m.plies[1].friction_below, 0.1);
    assert_eq!(m.plies[1].orientation_deg, 45.0);
    assert_eq!(m.plies[1].thickness, 0.5);
    // The top ply half of each thickness above the bottom one.
    let h0 = m.plies[0].thickness;
    let z0 = m.x0[0].z;
    let z1 = m.x0[m.plies[1].nodes.start as usize].z;
    assert!((z1 - z0 - 0.5 * (h0 + 0.5)).abs() < 1e-12);
    // Embedded fibres in the top ply: no trusses on its nodes.
    let top = m.plies[1].nodes.clone();
    assert!(
        m.trusses
            .iter()
            .flat_map(|b| b.nodes.iter().flatten())
            .all(|n| !top.contains(n))
    );
    // The springs' node sets are the union over the plies.
    assert_eq!(
        m.node_set("corners").unwrap().len(),
        m.node_set("ply1.corners").unwrap().len() + m.node_set("top.corners").unwrap().len()
    );
}

fn error_of(extra: &str) -> drape_io::scene::SceneError {
    Scene::parse(&hemisphere(extra), Path::new("bad.toml"), &[]).unwrap_err()
}

#[test]
fn bad_stack_keys_name_their_field_and_line() {
    let e = error_of("[stack]\n[[stack.ply]]\nfriction = 0.2\n[[stack.ply]]\n");
    assert_eq!(e.field, "stack.ply[0].friction");
    assert!(e.line.is_some(), "{e}");
    assert!(e.message.contains("bottom ply"), "{e}");

    let e = error_of("[stack]\n[[stack.ply]]\n[[stack.ply]]\nfriction = -1\n");
    assert_eq!(e.field, "stack.ply[1].friction");
    assert!(e.line.is_some(), "{e}");

    let e = error_of("[stack]\n[[stack.ply]]\nname = \"a\"\n[[stack.ply]]\nname = \"a\"\n");
    assert_eq!(e.field, "stack.ply[1].name");

    let e = error_of("[stack]\n[[stack.ply]]\nname = \"top\"\n[[stack.ply]]\nname = \"Top\"\n");
    assert_eq!(e.field, "stack.ply[1].name");
    assert!(e.message.contains("only in case"), "{e}");

    let e = error_of("[stack]\n[[stack.ply]]\nname = \"a\\tb\"\n");
    assert_eq!(e.field, "stack.ply[0].name");

    let e = error_of("[stack]\n[[stack.ply]]\nthickness = 0\n");
    assert_eq!(e.field, "stack.ply[0].thickness");

    let e = error_of("[stack]\n[[stack.ply]]\nblank = { width = 100 }\n");
    assert!(e.field.starts_with("stack.ply[0].blank"), "{e}");

    let e = error_of("[stack]\n[[stack.ply]]\nmaterial = \"no-such\"\n");
    assert_eq!(e.field, "stack.ply[0].material");

    let e = error_of("[stack]\nply = []\n");
    assert_eq!(e.field, "stack");
}

#[test]
fn the_implicit_solver_refuses_a_stack_naming_the_feature() {
    let text = hemisphere("[stack]\n[[stack.ply]]\n[[stack.ply]]\n")
        .replace("[simulation]", "[simulation]\nsolver = \"implicit\"");
    let e = Scene::parse(&text, Path::new("bad.toml"), &[]).unwrap_err();
    assert_eq!(e.field, "simulation.solver");
    assert!(e.message.contains("ply–ply contact"), "{e}");
    assert!(e.line.is_some());
}

/// A two-ply stack's orientations: written as a layup and read back, each
/// ply's directions are that ply's fibre directions (to the last bit), under
/// its name; carried onto the bottom ply's own formed mesh, each ply is
/// mapped on its own: the bottom ply onto itself (distance 0, its own
/// directions), the top one from just above it, its 45° kept.
#[test]
fn a_stacks_orientations_are_each_plys_own_and_map_ply_by_ply() {
    use drape_io::mesh_import::ImportedMesh;
    use drape_io::results::export::Orientations;
    use drape_io::results::mapping::map_onto;

    let text = hemisphere(
        "[stack]\n[[stack.ply]]\nname = \"p0\"\n[[stack.ply]]\nname = \"p45\"\norientation_deg = 45\n",
    );
    let scene = Scene::parse(&text, Path::new("scene.toml"), &[]).unwrap();
    let m = &scene.model;
    let state = run(&text);
    let fields = m.element_fields(&state).unwrap();
    let tmp = tempfile::tempdir().unwrap();
    let path = tmp.path().join("orientations.inp");
    let written = Orientations::of_frame(m, &state, &fields, "two plies");
    std::fs::write(&path, written.to_inp()).unwrap();
    let inp = std::fs::read_to_string(&path).unwrap();
    for line in [
        "** plies, bottom to top: p0, p45\n",
        "*ELSET, ELSET=p0\n1, 2,",
        "*ORIENTATION, NAME=p0_WARP,",
        "*ORIENTATION, NAME=p45_WEFT,",
        "*DISTRIBUTION, NAME=p45_AXES,",
    ] {
        assert!(inp.contains(line), "{line}");
    }
    let back = Orientations::read_inp(&path).unwrap();
    assert_eq!(back.plies.len(), 2);
    let mut mean_angle = Vec::new();
    for (part, ply) in back.plies.iter().zip(&m.plies) {
        assert_eq!(part.name, ply.name);
        assert_eq!(part.elements, ply.elements);
        assert_eq!(part.nominal_thickness, ply.thickness);
        let mut sum = 0.0;
        for e in ply.elements.clone() {
            assert_eq!(back.warp[e], fields.fibre_direction[e][0], "element {e}");
            assert_eq!(back.weft[e], fields.fibre_direction[e][1], "element {e}");
            sum += back.warp[e].y.atan2(back.warp[e].x).to_degrees();
        }
        mean_angle.push(sum / ply.elements.len() as f64);
    }
    // The plies are told apart: their warps 45° apart (nearly flat still).
    assert!(
        (mean_angle[1] - mean_angle[0] - 45.0).abs() < 0.5,
        "{mean_angle:?}"
    );

    // The bottom ply's formed quads as a structural mesh.
    let bottom = &m.plies[0];
    let quads: Vec<[u32; 4]> = m.membranes[bottom.membranes.clone()]
        .iter()
        .flat_map(|b| (0..b.len()).map(move |e| b.element_nodes(e).try_into().unwrap()))
        .collect();
    let n = quads.len();
    assert_eq!(n, bottom.elements.len());
    let target = ImportedMesh {
        x0: state.x.clone(),
        quad_labels: (1..=n as i64).collect(),
        quads,
        triangles: Vec::new(),
        node_sets: Default::default(),
        triangle_labels: Vec::new(),
        instances: Vec::new(),
    };
    let mapped = map_onto(&back, &target).unwrap();
    assert_eq!(mapped.plies.len(), 2);
    assert_eq!(mapped.len(), 2 * n);
    let distance = mapped.distance.as_ref().unwrap();
    let spacing = 0.5 * (m.plies[0].thickness + m.plies[1].thickness);
    for e in 0..n {
        let (own, top) = (e, n + e);
        assert_eq!(mapped.labels[own], mapped.labels[top]);
        assert!(distance[own] < 1e-9, "element {e}: {}", distance[own]);
        let turn = |a: &nalgebra::Vector3<f64>, b: &nalgebra::Vector3<f64>| {
            a.dot(b).clamp(-1.0, 1.0).acos().to_degrees()
        };
        assert!(turn(&mapped.warp[own], &back.warp[e]) < 1e-3, "element {e}");
        // The top ply's element above: its warp (45° off the bottom's).
        let above = m.plies[1].elements.start + e;
        // Above it: never nearer than the ply contact allows (1 % of it),
        // and not elsewhere (the plies are not yet pressed together
        // everywhere: gaps of 0.1 mm here).
        assert!(
            (0.99 * spacing..2.0 * spacing).contains(&distance[top]),
            "element {e}: {} against {spacing}",
            distance[top]
        );
        assert!(
            turn(&mapped.warp[top], &back.warp[above]) < 1.0,
            "element {e}"
        );
    }
    let csv = mapped.to_csv();
    assert!(csv.starts_with("ply,element,"));
    assert_eq!(csv.lines().filter(|l| l.starts_with("p45,")).count(), n);
}
