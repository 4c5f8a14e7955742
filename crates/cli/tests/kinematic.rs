//! `drape kinematic` and `drape compare` end to end: the results folder of
//! a kinematic drape, the defaults of the `[kinematic]` table, bad input
//! (exit 2, nothing written), and a small comparison.

mod common;
use common::*;

#[test]
fn a_forming_scene_drapes_kinematically_into_the_same_results_folder() {
    let dir = temp("hemisphere");
    let out = dir.join("out");
    let o = drape(&[
        "kinematic",
        "scenes/hemisphere-0-90.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("1600 of 1600 cells draped"),
        "{}",
        text(&o)
    );
    for f in [
        "series.pvd",
        "energy.csv",
        "profiles.csv",
        "summary.json",
        "shear_map.png",
        "profiles.png",
        "frames/frame_00000.vtu",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let summary = json(&out.join("summary.json"));
    assert_eq!(summary["status"], "completed");
    assert_eq!(summary["run"]["solver"], "kinematic");
    assert!(summary.get("reason").is_none());
    // The net lies on the punch moved up its 300 mm: the largest shear is
    // on the shank, in the corners, below the pole at z = 299.8.
    let at_z = summary["max_shear_at"][2].as_f64().unwrap();
    assert!(at_z < 299.8 && at_z > 299.8 - 320.0, "{at_z}");
    let vtu = std::fs::read_to_string(out.join("frames/frame_00000.vtu")).unwrap();
    assert!(vtu.contains("NumberOfPoints=\"1681\" NumberOfCells=\"1600\""));
    assert!(vtu.contains("Name=\"fibre_direction_warp\""));
    // The diagonal profile: 40 cells, symmetric about the centre.
    let profiles = std::fs::read_to_string(out.join("profiles.csv")).unwrap();
    let diagonal: Vec<f64> = profiles
        .lines()
        .filter(|l| l.starts_with("diagonal,"))
        .map(|l| l.split(',').nth(2).unwrap().parse().unwrap())
        .collect();
    assert_eq!(diagonal.len(), 40);
    for k in 0..20 {
        assert!(
            (diagonal[k] - diagonal[39 - k]).abs() < 1e-9,
            "{diagonal:?}"
        );
    }
    std::fs::remove_dir_all(dir).unwrap();
}

const TWO_TOOLS: &str = r#"[simulation]
end_time = 0.001

[fabric]
material = "glass-serge-4x3"
fibres = "embedded"
blank = { width = 100, height = 100, cells = [10, 10] }

[[tools]]
name = "dome"
geometry = { kind = "sphere", center = [0, 0, -60.1], radius = 60 }

[[tools]]
name = "floor"
geometry = { kind = "plane", point = [0, 0, -80], normal = [0, 0, 1] }
"#;

/// Runs `drape kinematic` on `scene` and checks exit code 2, every
/// `expect` in the message, and no output directory.
fn bad(name: &str, scene: &str, expect: &[&str]) {
    let dir = temp(name);
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    let out = dir.join("out");
    let o = drape(&[
        "kinematic",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    for e in expect {
        assert!(text(&o).contains(e), "`{e}` not in: {}", text(&o));
    }
    assert!(!out.exists(), "results were written for bad input");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn the_mould_must_be_named_when_it_is_not_obvious() {
    // Two fixed tools: the scene runs, but the net needs to know its mould.
    drape_io::scene::Scene::parse(TWO_TOOLS, "two.toml".as_ref(), &[]).unwrap();
    bad(
        "ambiguous",
        TWO_TOOLS,
        &["kinematic.mould", "2 tools (dome, floor)"],
    );
    let named = format!("{TWO_TOOLS}\n[kinematic]\nmould = \"dome\"\nspacing = 5\n");
    let dir = temp("named");
    let path = dir.join("scene.toml");
    std::fs::write(&path, named).unwrap();
    let o = drape(&[
        "kinematic",
        path.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("400 of 400 cells draped"), "{}", text(&o));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn bad_kinematic_input_exits_2_names_the_place_and_writes_nothing() {
    bad(
        "no-such-mould",
        &format!("{TWO_TOOLS}\n[kinematic]\nmould = \"punch\"\n"),
        &[
            "scene.toml:18",
            "kinematic.mould",
            "expected one of dome, floor",
        ],
    );
    bad(
        "seed-off-blank",
        &format!("{TWO_TOOLS}\n[kinematic]\nmould = \"dome\"\nseed = [80, 0]\n"),
        &["scene.toml:19", "kinematic.seed", "not on the blank"],
    );
    bad(
        "spacing",
        &format!("{TWO_TOOLS}\n[kinematic]\nmould = \"dome\"\nspacing = -2\n"),
        &["scene.toml:19", "kinematic.spacing"],
    );
    bad(
        "unknown-key",
        &format!("{TWO_TOOLS}\n[kinematic]\nmold = \"dome\"\n"),
        &["scene.toml:18", "mold"],
    );
    // Draped upwards, away from the dome: the seed's line misses it.
    bad(
        "misses",
        &format!(
            "{TWO_TOOLS}\n[kinematic]\nmould = \"dome\"\ndirection = [1, 0, 0]\nseed = [0, 45]\n"
        ),
        &["kinematic", "does not meet the mould"],
    );
    // A blank from a mesh file has no rectangle to stop at.
    let dir = temp("meshed");
    std::fs::create_dir_all(dir.join("meshes")).unwrap();
    std::fs::copy(
        workspace().join("scenes/meshes/plate.msh"),
        dir.join("meshes/plate.msh"),
    )
    .unwrap();
    let path = dir.join("plate.toml");
    std::fs::copy(workspace().join("scenes/imported-plate.toml"), &path).unwrap();
    let o = drape(&[
        "kinematic",
        path.to_str().unwrap(),
        "--out",
        dir.join("out").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("rectangular blank"), "{}", text(&o));
    assert!(!dir.join("out").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

const FALLING: &str = r#"gravity = [0, 0, -1e7]

[simulation]
end_time = 0.015
frames = 2
mass_scaling_dt = 2e-6
damping = 400

[fabric]
fibres = "trusses"
blank = { width = 80, height = 80, cells = [8, 8] }

[fabric.material]
name = "soft"
thickness = 0.3
fibre_volume_fraction = 0.5
density = 1.5e-9
fibre = { modulus = 230000, crimp_strain = 0.005 }
resin = { young = 0.45, poisson = 0.45 }

[[tools]]
name = "dome"
geometry = { kind = "sphere", center = [0, 0, -100.2], radius = 100 }

[[boundary]]
nodes = [40]
components = "xy"
motion = { kind = "fixed" }

[[boundary]]
nodes = [41]
components = "y"
motion = { kind = "fixed" }
"#;

#[test]
fn compare_writes_both_runs_and_their_difference() {
    let dir = temp("compare");
    let path = dir.join("falling.toml");
    std::fs::write(&path, FALLING).unwrap();
    let out = dir.join("out");
    let o = drape(&[
        "compare",
        path.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("mould             `dome`: the scene's only tool"),
        "{}",
        text(&o)
    );
    for f in [
        "kinematic/summary.json",
        "mechanical/summary.json",
        "mechanical/frames/frame_00002.vtu",
        "comparison.json",
        "comparison.csv",
        "profiles.csv",
        "comparison.png",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let c = json(&out.join("comparison.json"));
    assert_eq!(c["elements"], 64);
    assert_eq!(c["compared"], 64);
    assert_eq!(c["diagonal"]["points"], 8);
    // An 80 mm blank on a dome of radius 100 pressed by a body force
    // (yarn tension ≈ ρ·h·a·R/2 = 0.2 N/mm) lies on it: the run follows the
    // net (largest shear 7°) up to the resin's share of the shear
    // resistance (about 1 %) and what is left of the fall's motion.
    assert_eq!(c["on_mould"], 64, "{c}");
    assert!(
        c["all"]["max_abs_on_mould_deg"].as_f64().unwrap() < 0.5,
        "{c}"
    );
    assert!(c["all"]["rms_on_mould_deg"].as_f64().unwrap() < 0.25, "{c}");
    let kinematic = c["kinematic_max_shear_deg"].as_f64().unwrap();
    assert!((kinematic - 7.0).abs() < 0.1, "{c}");
    let rows = std::fs::read_to_string(out.join("comparison.csv")).unwrap();
    assert_eq!(rows.lines().count(), 65);
    std::fs::remove_dir_all(dir).unwrap();
}
