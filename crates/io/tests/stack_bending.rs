//! Yarn bending in a stack: each ply bends its own yarns (its lines
//! through its own nodes, along its own warp, with its own material's
//! rigidity), on by default as in `[fabric]`; a one-ply stack with bending
//! runs bit for bit as `[fabric]` with bending.

use std::path::Path;

use drape_io::scene::Scene;
use drape_time::{Explicit, NoObserver};

/// The shipped hemisphere scene, coarse and short, bending as the
/// defaults say (the carbon preset has a rigidity).
fn hemisphere(extra: &str) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../scenes/hemisphere-0-90.toml");
    let text = std::fs::read_to_string(path).unwrap();
    let text = text
        .replace("cells = [40, 40]", "cells = [8, 8]")
        .replace("end_time = 1.0 ", "end_time = 0.02 ");
    assert!(text.contains("end_time = 0.02") && !text.contains("bending"));
    format!("{text}\n{extra}")
}

fn parse(text: &str) -> Scene {
    Scene::parse(text, Path::new("scene.toml"), &[]).unwrap()
}

fn run(scene: &Scene) -> drape_model::State {
    let mut state = scene.model.initial_state();
    Explicit::new(&scene.model, scene.settings.clone())
        .unwrap()
        .run(&mut state, &mut NoObserver)
        .unwrap();
    state
}

#[test]
fn a_one_ply_stack_with_bending_runs_bit_for_bit_as_the_fabric() {
    let fabric = parse(&hemisphere(""));
    let stack = parse(&hemisphere("[stack]\n[[stack.ply]]\nname = \"only\"\n"));
    assert_eq!(fabric.model.bending.len(), 1);
    assert_eq!(stack.model.bending.len(), 1);
    let (a, b) = (&fabric.model.bending[0], &stack.model.bending[0]);
    assert!(!a.is_empty());
    assert_eq!(a.nodes, b.nodes);
    assert_eq!(a.rigidity, b.rigidity);
    let (fabric, stack) = (run(&fabric), run(&stack));
    assert!(fabric.step > 100);
    assert_eq!(fabric.step, stack.step);
    assert_eq!(fabric.x, stack.x);
    assert_eq!(fabric.v, stack.v);
    assert_eq!(fabric.history, stack.history);
}

/// The unit direction of each triplet's first segment, in the reference.
fn segments(m: &drape_model::Model, batch: usize) -> Vec<nalgebra::Vector3<f64>> {
    m.bending[batch]
        .nodes
        .iter()
        .map(|&[i, j, _]| (m.x0[j as usize] - m.x0[i as usize]).normalize())
        .collect()
}

#[test]
fn each_ply_bends_its_own_yarns_with_its_own_rigidity() {
    let scene = parse(&hemisphere(
        "[stack]\n[[stack.ply]]\nname = \"p0\"\n[[stack.ply]]\nname = \"p45\"\n\
         orientation_deg = 45\nmaterial = \"glass-serge-4x3\"\n",
    ));
    let m = &scene.model;
    assert_eq!(m.bending.len(), 2, "{:?}", scene.warnings);
    let carbon = drape_constitutive::Material::preset("carbon-prepreg-2x2").unwrap();
    let glass = drape_constitutive::Material::preset("glass-serge-4x3").unwrap();
    assert_eq!(Some(m.bending[0].rigidity), carbon.bending_rigidity);
    assert_eq!(Some(m.bending[1].rigidity), glass.bending_rigidity);
    assert_ne!(m.bending[0].rigidity, m.bending[1].rigidity);
    for (p, ply) in m.plies.iter().enumerate() {
        let batch = &m.bending[p];
        // Its lines through its own nodes only...
        assert!(
            batch.nodes.iter().flatten().all(|n| ply.nodes.contains(n)),
            "ply {p}"
        );
        // ...a line of each family through every interior node of its
        // 8 × 8 grid (7 × 7 of them, 8 × 8 on the diagonal mesh)...
        assert!(batch.len() >= 2 * 49, "ply {p}: {}", batch.len());
        // ...along its own fibres: x and y for 0/90, the diagonals for ±45.
        let t = ply.orientation_deg.to_radians();
        let (warp, weft) = (
            nalgebra::Vector3::new(t.cos(), t.sin(), 0.0),
            nalgebra::Vector3::new(-t.sin(), t.cos(), 0.0),
        );
        for (k, d) in segments(m, p).iter().enumerate() {
            let along = if batch.family[k] == 0 { warp } else { weft };
            assert!(
                (d.dot(&along).abs() - 1.0).abs() < 1e-12,
                "ply {p} triplet {k}: {d:?}"
            );
        }
    }
}

#[test]
fn bending_is_turned_off_per_ply_or_for_all_in_the_fabric() {
    let two = "[stack]\n[[stack.ply]]\nname = \"a\"\n[[stack.ply]]\nname = \"b\"\n";
    // Off in one ply: the other keeps its own, on its own nodes.
    let scene = parse(&hemisphere(&format!("{two}bending = false\n")));
    let m = &scene.model;
    assert_eq!(m.bending.len(), 1);
    assert!(
        m.bending[0]
            .nodes
            .iter()
            .flatten()
            .all(|n| m.plies[0].nodes.contains(n))
    );
    // Off in [fabric]: off in every ply, without a word...
    let off = hemisphere(two).replace(
        "fibres = \"trusses\"",
        "fibres = \"trusses\"\nbending = false",
    );
    let scene = parse(&off);
    assert!(scene.model.bending.is_empty());
    assert!(
        scene.warnings.iter().all(|w| !w.contains("bending")),
        "{:?}",
        scene.warnings
    );
    // ...unless a ply insists.
    let scene = parse(&format!("{off}bending = true\n"));
    assert_eq!(scene.model.bending.len(), 1);
    let top = &scene.model.plies[1].nodes;
    assert!(
        scene.model.bending[0]
            .nodes
            .iter()
            .flatten()
            .all(|n| top.contains(n))
    );
}

#[test]
fn a_ply_whose_lines_miss_its_yarns_runs_without_bending_and_says_so() {
    // Embedded fibres at 30° to the grid: no line follows the yarns.
    let scene = parse(&hemisphere(
        "[stack]\n[[stack.ply]]\nname = \"p0\"\n[[stack.ply]]\nname = \"p30\"\n\
         orientation_deg = 30\nfibres = \"embedded\"\n",
    ));
    let m = &scene.model;
    assert_eq!(m.bending.len(), 1);
    assert!(
        m.bending[0]
            .nodes
            .iter()
            .flatten()
            .all(|n| m.plies[0].nodes.contains(n))
    );
    let warned: Vec<_> = scene
        .warnings
        .iter()
        .filter(|w| w.contains("yarn bending is off"))
        .collect();
    assert_eq!(warned.len(), 1, "{:?}", scene.warnings);
    assert!(
        warned[0].contains("in ply `p30`") && warned[0].contains("interior nodes"),
        "{}",
        warned[0]
    );
}

#[test]
fn bending_a_ply_that_cannot_bend_names_the_ply_and_its_field() {
    // A material card without a rigidity, insisted on.
    let card = "[stack]\n[[stack.ply]]\n[[stack.ply]]\nname = \"soft\"\nbending = true\n\
        material = { name = \"m\", thickness = 0.5, fibre_volume_fraction = 0.5, density = 1e-9, \
        fibre = { modulus = 1000.0, crimp_strain = 0.0 }, resin = { young = 10.0, poisson = 0.3 } }\n";
    let e = Scene::parse(&hemisphere(card), Path::new("bad.toml"), &[]).unwrap_err();
    assert_eq!(e.field, "stack.ply[1].bending", "{e}");
    assert!(e.line.is_some(), "{e}");
    assert!(e.message.contains("bending_rigidity"), "{e}");

    // No line along its yarns at all (30° embedded), insisted on.
    let e = Scene::parse(
        &hemisphere(
            "[stack]\n[[stack.ply]]\n[[stack.ply]]\nname = \"p30\"\norientation_deg = 30\n\
             fibres = \"embedded\"\nbending = true\n",
        ),
        Path::new("bad.toml"),
        &[],
    )
    .unwrap_err();
    assert_eq!(e.field, "stack.ply[1].bending", "{e}");
    assert!(
        e.message.contains("ply `p30`") && e.message.contains("mesh lines along the yarns"),
        "{e}"
    );
}
