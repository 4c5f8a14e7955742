//! `[[pressure]]` in a scene: which way it pushes, what it loads, and bad
//! input named by field and line.

use std::path::Path;

use drape_io::scene::{Scene, SceneError};
use drape_model::pressure::vector_area;
use nalgebra::Vector3;

/// A 100 × 100 mm blank in z = 0 over a floor at z = −1, with `pressure`
/// appended (its first line is line 15).
fn scene(pressure: &str) -> Result<Scene, SceneError> {
    scene_of("", pressure)
}

/// [`scene`] with `stack` (whole lines) before the floor.
fn scene_of(stack: &str, pressure: &str) -> Result<Scene, SceneError> {
    let text = format!(
        r#"
[simulation]
end_time = 0.01

[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
blank = {{ width = 100, height = 100, cells = [4, 4] }}

{stack}[[tools]]
name = "floor"
geometry = {{ kind = "plane", point = [0, 0, -1], normal = [0, 0, 1] }}

[[pressure]]
{pressure}
"#
    );
    Scene::parse(&text, Path::new("bag.toml"), &[])
}

/// The total force of the scene's first pressure at the start (N).
fn total(scene: &Scene) -> Vector3<f64> {
    let p = &scene.model.pressure[0];
    (0..p.len())
        .map(|e| p.nodal_force(e, &scene.model.x0, 1.0) * p.element(e).len() as f64)
        .sum()
}

#[test]
fn a_pressure_pushes_towards_the_tool_or_to_the_side_asked() {
    // 0.1 MPa on 100 × 100 mm: 1 000 N.
    for (keys, z) in [
        ("value = 0.1\ntowards = \"floor\"", -1000.0),
        ("value = 0.1\nside = \"+\"", 1000.0),
        ("value = 0.1\nside = \"-\"", -1000.0),
    ] {
        let scene = scene(keys).unwrap();
        assert!(scene.model.features().pressure);
        let f = total(&scene);
        assert!(
            (f - Vector3::new(0.0, 0.0, z)).norm() < 1e-9,
            "{keys}: {f:?}"
        );
    }
    // A tool above the blank: towards it is +z.
    let above = Scene::parse(
        &format!(
            "{GOOD}\n[[tools]]\nname = \"lid\"\ngeometry = {{ kind = \"plane\", point = [0, 0, 5], normal = [0, 0, -1] }}\n\n[[pressure]]\nvalue = 0.1\ntowards = \"lid\"\n"
        ),
        Path::new("lid.toml"),
        &[],
    )
    .unwrap();
    assert!(total(&above).z > 999.0);
}

const GOOD: &str = r#"
[simulation]
end_time = 0.01

[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
blank = { width = 100, height = 100, cells = [4, 4] }
"#;

#[test]
fn a_node_selection_loads_the_elements_inside_it_and_amplitudes_are_kept() {
    let scene = scene(
        "value = 0.2\nside = \"+\"\nnodes = \"all\"\namplitude = { kind = \"ramp\", duration = 0.005 }",
    )
    .unwrap();
    let p = &scene.model.pressure[0];
    assert_eq!(p.len(), 16);
    assert_eq!(p.amplitude.value(0.0025), 0.5);
    let area: f64 = (0..p.len())
        .map(|e| vector_area(p.element(e), &scene.model.x0).norm())
        .sum();
    assert!((area - 1e4).abs() < 1e-9);
}

#[test]
fn bad_pressures_name_their_field_and_line() {
    let cases: [(&str, &str, usize, &str); 6] = [
        ("value = -0.1\nside = \"+\"", "pressure[0].value", 15, "≥ 0"),
        ("value = 0.1", "pressure[0]", 14, "exactly one of"),
        (
            "value = 0.1\nside = \"+\"\ntowards = \"floor\"",
            "pressure[0]",
            14,
            "exactly one of",
        ),
        (
            "value = 0.1\nside = \"up\"",
            "pressure[0].side",
            16,
            "\"+\"",
        ),
        (
            "value = 0.1\ntowards = \"mould\"",
            "pressure[0].towards",
            16,
            "the tools are: floor",
        ),
        (
            "value = 0.1\nside = \"+\"\nnodes = \"left\"",
            "pressure[0].nodes",
            17,
            "act on nothing",
        ),
    ];
    for (keys, field, line, says) in cases {
        let e = scene(keys).map(|_| ()).unwrap_err();
        assert_eq!(e.field, field, "{keys}: {e}");
        assert_eq!(e.line, Some(line), "{keys}: {e}");
        assert!(e.message.contains(says), "{keys}: {e}");
    }
}

#[test]
fn a_tool_edgewise_to_the_blank_is_no_side() {
    let text = format!(
        "{GOOD}\n[[tools]]\nname = \"wall\"\ngeometry = {{ kind = \"plane\", point = [200, 0, 0], normal = [-1, 0, 0] }}\n\n[[pressure]]\nvalue = 0.1\ntowards = \"wall\"\n"
    );
    let e = Scene::parse(&text, Path::new("wall.toml"), &[]).unwrap_err();
    assert_eq!(e.field, "pressure[0].towards", "{e}");
    assert!(e.message.contains("side"), "{e}");
}

#[test]
fn a_scene_without_pressure_has_none_and_writes_no_key() {
    let scene = Scene::parse(GOOD, Path::new("good.toml"), &[]).unwrap();
    assert!(scene.model.pressure.is_empty() && !scene.model.features().pressure);
    let json = serde_json::to_string(&scene.resolved_spec()).unwrap();
    assert!(!json.contains("pressure"), "{json}");
    // With one, the resolved scene (a checkpoint's) builds the same load.
    let with = scene_json_round_trip("value = 0.1\ntowards = \"floor\"");
    assert_eq!(with.0, with.1);
}

fn scene_json_round_trip(
    keys: &str,
) -> (
    Vec<drape_model::PressureLoad>,
    Vec<drape_model::PressureLoad>,
) {
    let scene = scene(keys).unwrap();
    let json = serde_json::to_string(&scene.resolved_spec()).unwrap();
    let again =
        Scene::from_spec(serde_json::from_str(&json).unwrap(), Path::new("x.toml")).unwrap();
    (scene.model.pressure, again.model.pressure)
}

/// On a stack a pressure loads only its outer ply on the side it comes
/// from: a bag over three plies on a floor presses the floor with 1 000 N,
/// not 3 000 N, and one pushing up loads the bottom ply. A selection
/// narrows within that ply, and one of another ply is an error naming it.
#[test]
fn a_pressure_on_a_stack_loads_its_outer_ply_on_the_side_it_comes_from() {
    let plies = "[stack]\n[[stack.ply]]\nname = \"a\"\n[[stack.ply]]\nname = \"b\"\n\
                 orientation_deg = 90\n[[stack.ply]]\nname = \"c\"\n\n";
    let stack = |pressure: &str| scene_of(plies, pressure);
    let loaded_ply = |scene: &Scene| {
        let p = &scene.model.pressure[0];
        let plies: Vec<usize> = (0..p.len())
            .map(|e| {
                let n = p.element(e)[0];
                let ply = scene
                    .model
                    .plies
                    .iter()
                    .position(|ply| ply.nodes.contains(&n));
                ply.expect("a ply's node")
            })
            .collect();
        assert!(plies.windows(2).all(|w| w[0] == w[1]), "{plies:?}");
        plies[0]
    };
    let down = stack("value = 0.1\ntowards = \"floor\"").unwrap();
    assert_eq!(loaded_ply(&down), 2);
    let f = total(&down);
    assert!((f - Vector3::new(0.0, 0.0, -1000.0)).norm() < 1e-9, "{f:?}");
    let up = stack("value = 0.1\nside = \"+\"").unwrap();
    assert_eq!(loaded_ply(&up), 0);
    assert!((total(&up) - Vector3::new(0.0, 0.0, 1000.0)).norm() < 1e-9);
    // Two plies named: the outer one of them is loaded.
    let named = stack("value = 0.1\nside = \"-\"\nnodes = [\"b\", \"c\"]").unwrap();
    assert_eq!(loaded_ply(&named), 2);
    assert!((total(&named) - Vector3::new(0.0, 0.0, -1000.0)).norm() < 1e-9);
    let inner = stack("value = 0.1\ntowards = \"floor\"\nnodes = \"b\"").unwrap_err();
    let message = inner.to_string();
    assert!(
        message.contains("pressure[0].nodes") && message.contains("top ply `c`"),
        "{message}"
    );
}
