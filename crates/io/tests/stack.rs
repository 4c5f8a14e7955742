//! `[stack]` scenes: a one-ply stack runs bit for bit as `[fabric]`, the
//! plies are built and stacked, and bad stack keys name their field and
//! line.

use std::path::Path;

use drape_io::scene::Scene;
use drape_time::{Explicit, NoObserver};

/// The shipped hemisphere scene, coarse and short, without bending (a
/// stack has none yet), so both forms describe the same model.
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
