//! Values past their physical range are refused at the key that is wrong,
//! not met later as a consequence (a degenerate element or triangle, a
//! tool that "starts close" to the blank, a direction "not a unit vector").

use std::path::Path;

use drape_contact::ToolMotion;
use drape_io::scene::{MAX_COORDINATE_MM, Scene, SceneError};

fn scene(name: &str, sets: &[(&str, &str)]) -> Result<Scene, SceneError> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name);
    let sets: Vec<(String, String)> = sets
        .iter()
        .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
        .collect();
    Scene::from_file(&path, &sets)
}

/// The error of `name` with `key=value`: it must name `field` and say the
/// value came from that `--set`.
fn refused(name: &str, key: &str, value: &str, field: &str) -> SceneError {
    let e = match scene(name, &[(key, value)]) {
        Ok(_) => panic!("{name}: --set {key}={value} was accepted"),
        Err(e) => e,
    };
    assert_eq!(e.field, field, "{name}: --set {key}={value}: {e}");
    assert!(e.message.contains(&format!("--set {key}={value}")), "{e}");
    e
}

#[test]
fn a_mesh_blank_scaled_or_moved_out_of_range_names_the_key() {
    let e = refused(
        "imported-plate.toml",
        "fabric.blank.scale",
        "1e300",
        "fabric.blank.scale",
    );
    assert!(
        e.message
            .contains("`scale` scales the file's coordinates by 1e300"),
        "{e}"
    );
    assert!(!e.message.contains("degenerate"), "{e}");
    let e = refused(
        "imported-plate.toml",
        "fabric.blank.scale",
        "1e-300",
        "fabric.blank.scale",
    );
    assert!(e.message.contains("less than 1e-6 mm"), "{e}");
    let e = refused(
        "imported-plate.toml",
        "fabric.blank.offset",
        "[1e20, 0, 0]",
        "fabric.blank.offset",
    );
    assert!(e.message.contains("1e20 is not allowed"), "{e}");
    // Within range, however large, it reads.
    let at = format!("[{:e}, 0, 0]", 0.5 * MAX_COORDINATE_MM);
    scene("imported-plate.toml", &[("fabric.blank.offset", &at)]).unwrap();
}

#[test]
fn a_tool_mesh_scaled_or_moved_out_of_range_names_the_key() {
    let e = refused(
        "tray.toml",
        "tools.0.geometry.scale",
        "1e-300",
        "tools[0].geometry.scale",
    );
    assert!(e.message.contains("less than 1e-6 mm"), "{e}");
    assert!(!e.message.contains("degenerate"), "{e}");
    refused(
        "tray.toml",
        "tools.0.geometry.scale",
        "1e300",
        "tools[0].geometry.scale",
    );
    let e = refused(
        "tray.toml",
        "tools.1.geometry.offset",
        "[0, 0, 1e300]",
        "tools[1].geometry.offset",
    );
    assert!(e.message.contains("1e300 is not allowed"), "{e}");
    // Scaled by units into range but offset just inside: the sum is out.
    let e = refused(
        "tray.toml",
        "tools.1.geometry.offset",
        "[0, 0, 999999999]",
        "tools[1].geometry.offset",
    );
    assert!(e.message.contains("moves the mesh to"), "{e}");
}

#[test]
fn analytic_tools_out_of_range_name_the_key() {
    for (key, value, field) in [
        (
            "tools.0.geometry.pole",
            "[0, 0, 1e300]",
            "tools[0].geometry.pole",
        ),
        (
            "tools.0.geometry.radius",
            "1e300",
            "tools[0].geometry.radius",
        ),
        ("tools.0.geometry.shank", "1e20", "tools[0].geometry.shank"),
    ] {
        refused("hemisphere-0-90.toml", key, value, field);
    }
    refused(
        "hemisphere-ring.toml",
        "tools.1.geometry.outer_radius",
        "inf",
        "tools[1].geometry.outer_radius",
    );
    refused(
        "hemisphere-0-90.toml",
        "springs.0.anchor_offset",
        "[1e300, 0, 0]",
        "springs[0].anchor_offset",
    );
}

#[test]
fn a_direction_of_huge_or_tiny_components_is_that_direction() {
    for (value, expected) in [
        ("[1e300, 1e300, 0]", [0.5f64.sqrt(), 0.5f64.sqrt(), 0.0]),
        ("[0, 5e-324, 0]", [0.0, 1.0, 0.0]),
        ("[-1e308, 0, 1e308]", [-(0.5f64.sqrt()), 0.0, 0.5f64.sqrt()]),
    ] {
        let s = scene(
            "hemisphere-0-90.toml",
            &[("tools.0.motion.direction", value)],
        )
        .unwrap_or_else(|e| panic!("{value}: {e}"));
        let ToolMotion::Displacement { direction, .. } = &s.model.tools[0].motion else {
            panic!("the punch moves by displacement");
        };
        for (got, want) in direction.iter().zip(expected) {
            assert!((got - want).abs() <= 1e-15, "{value}: {direction:?}");
        }
    }
    let e = refused(
        "hemisphere-0-90.toml",
        "tools.0.motion.direction",
        "[0, 0, 0]",
        "tools[0].motion.direction",
    );
    assert!(e.message.contains("must not be zero"), "{e}");
}

#[test]
fn a_rectangle_past_the_range_names_its_size() {
    for (key, value, field) in [
        ("fabric.blank.width", "1e300", "fabric.blank.width"),
        ("fabric.blank.height", "2e9", "fabric.blank.height"),
        (
            "fabric.blank.center",
            "[0, -1e10, 0]",
            "fabric.blank.center",
        ),
    ] {
        let e = refused("picture-frame.toml", key, value, field);
        assert!(!e.message.contains("non-finite"), "{e}");
    }
}

#[test]
fn radii_rest_lengths_and_durations_are_named_at_their_key() {
    refused(
        "hemisphere-ring.toml",
        "tools.2.geometry.edge_radius",
        "1e300",
        "tools[2].geometry.edge_radius",
    );
    refused(
        "hemisphere-0-90.toml",
        "springs.0.rest_length",
        "1e300",
        "springs[0].rest_length",
    );
    let e = refused(
        "hemisphere-0-90.toml",
        "tools.0.motion.amplitude.duration",
        "0",
        "tools[0].motion.amplitude.duration",
    );
    assert!(e.message.contains("must be positive"), "{e}");
}

#[test]
fn a_spring_of_subnormal_length_names_its_anchor_offset() {
    let e = refused(
        "hemisphere-0-90.toml",
        "springs.0.anchor_offset",
        "[0, 0, 5e-324]",
        "springs[0].anchor_offset",
    );
    assert!(e.message.contains("no usable direction"), "{e}");
    scene(
        "hemisphere-0-90.toml",
        &[("springs.0.anchor_offset", "[0, 0, 1e-3]")],
    )
    .unwrap();
}

#[test]
fn a_spring_stiffer_or_stronger_than_physical_names_its_key() {
    // Past 1e300 N/mm the stable step underflowed and the fault surfaced
    // as mass scaling's (`simulation.mass_scaling_dt`), not the spring's.
    let e = refused(
        "imported-plate.toml",
        "springs.0.stiffness",
        "1.7976931348623157e308",
        "springs[0].stiffness",
    );
    assert!(e.message.contains("N/mm"), "{e}");
    refused(
        "imported-plate.toml",
        "springs.0.stiffness",
        "2e12",
        "springs[0].stiffness",
    );
    refused(
        "imported-plate.toml",
        "springs.0.preload",
        "1e300",
        "springs[0].preload",
    );
    assert!(scene("imported-plate.toml", &[("springs.0.stiffness", "1e11")]).is_ok());
}
