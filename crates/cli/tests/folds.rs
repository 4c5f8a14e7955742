//! The fold check end to end: a run whose ply folds over itself ends with
//! a warning that says where and what to change (and its numbers in
//! `summary.json`), still exiting 0; a ply formed smoothly is silent.

mod common;
use common::*;

/// A 100 × 40 mm glass strip without bending, its left edge held and its
/// right edge carried 80 mm back over it and 3 mm up: the membrane must
/// double over itself somewhere between.
const FOLDED: &str = r#"gravity = [0, 0, -9810]

[simulation]
end_time = 0.05
frames = 5
mass_scaling_dt = 5e-6
damping = 50

[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
blank = { width = 100, height = 40, cells = [10, 4] }
bending = false

[[tools]]
name = "floor"
friction = 0.2
geometry = { kind = "plane", point = [0, 0, -0.3], normal = [0, 0, 1] }

[[boundary]]
nodes = "left"
motion = { kind = "fixed" }

[[boundary]]
nodes = "right"
motion = { kind = "displacement", value = [-80, 0, 3], amplitude = { kind = "smooth_step", duration = 0.04 } }
"#;

/// A 100 × 100 mm carbon blank on the defaults (yarn bending on) draped
/// 10 mm over a sphere of radius 40 mm, held by springs: formed smoothly.
const DRAPED: &str = r#"gravity = [0, 0, -9810]

[simulation]
end_time = 0.004
frames = 4
mass_scaling_dt = 2e-6

[fabric]
material = "carbon-prepreg-2x2"
fibres = "trusses"
blank = { width = 100, height = 100, cells = [10, 10] }

[[tools]]
name = "punch"
friction = 0.2
geometry = { kind = "sphere", center = [0, 0, -40.2], radius = 40 }
motion = { kind = "displacement", direction = [0, 0, 1], distance = 10, amplitude = { kind = "smooth_step", duration = 0.004 } }

[[springs]]
nodes = ["corners", "edge_midpoints"]
stiffness = 2.0
"#;

fn run(dir: &std::path::Path, name: &str, scene: &str) -> (String, serde_json::Value) {
    let file = dir.join(format!("{name}.toml"));
    std::fs::write(&file, scene).unwrap();
    let out = dir.join(name);
    let o = drape(&[
        "run",
        file.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    // A fold is a warning, not a failure: the run completes and exits 0.
    assert!(o.status.success(), "{}", text(&o));
    (text(&o), json(&out.join("summary.json")))
}

#[test]
fn a_membrane_folded_over_itself_warns_where_and_what_to_change() {
    let dir = temp("folded");
    let (printed, summary) = run(&dir, "folded", FOLDED);
    assert_eq!(summary["status"], "completed");
    let fold = &summary["fold"];
    assert_eq!(fold["folded"], true, "{fold}");
    assert!(fold["turned_back_elements"].as_u64().unwrap() > 0, "{fold}");
    let worst = &fold["worst"];
    assert!(worst["turn_deg"].as_f64().unwrap() > 90.0, "{fold}");
    // The site is on the strip as it lies: between the held edge
    // (x = −50) and where the carried edge ends (x = −30).
    let x = worst["at"][0].as_f64().unwrap();
    assert!((-50.0..=50.0).contains(&x), "{fold}");
    let warning = summary["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .filter_map(|w| w.as_str())
        .find(|w| w.starts_with("the ply folds"))
        .unwrap_or_else(|| panic!("no fold warning in {}", summary["warnings"]))
        .to_owned();
    let element = worst["element"].as_u64().unwrap();
    assert!(
        warning.contains(&format!("element {element} at ("))
            && warning.contains("turn back over a neighbour")
            && warning.contains("Yarn bending was off")
            && warning.contains("fabric.bending = true"),
        "{warning}"
    );
    assert!(printed.contains("the ply folds"), "{printed}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_smoothly_draped_ply_on_the_defaults_is_silent() {
    let dir = temp("draped");
    let (printed, summary) = run(&dir, "draped", DRAPED);
    assert_eq!(summary["status"], "completed");
    let fold = &summary["fold"];
    assert_eq!(fold["folded"], false, "{fold}");
    assert_eq!(fold["turned_back_elements"], 0, "{fold}");
    assert_eq!(fold["wavy_area_mm2"], 0.0, "{fold}");
    // The preset has a rigidity and the mesh follows the yarns: bending
    // is on, so no warning says it is off.
    assert!(
        !printed.contains("the ply folds") && !printed.contains("yarn bending is off"),
        "{printed}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
