//! The `drape` command end to end: runs, templates, sweeps, inspection,
//! exit codes, and bad input that must exit 2 and write nothing.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn drape(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .current_dir(workspace())
        .output()
        .expect("the drape binary runs")
}

fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

fn temp(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("drape-cli-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

#[test]
fn picture_frame_runs_and_writes_results() {
    let dir = temp("pf");
    let out = dir.join("out");
    let o = drape(&[
        "run",
        "scenes/picture-frame.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    for f in [
        "series.pvd",
        "energy.csv",
        "profiles.csv",
        "summary.json",
        "shear_map.png",
        "profiles.png",
        "frames/frame_00010.vtu",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "completed");
    let shear = summary["max_shear_deg"].as_f64().unwrap();
    assert!((shear - 60.0).abs() < 0.2, "{shear}");
    let o = drape(&["inspect", out.to_str().unwrap()]);
    assert!(o.status.success());
    assert!(text(&o).contains("max shear"), "{}", text(&o));
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn sweep_writes_one_table() {
    let dir = temp("sweep");
    let o = drape(&[
        "sweep",
        "scenes/picture-frame.toml",
        "--set",
        "boundary.0.motion.shear_deg=20,40",
        "--set",
        "simulation.frames=2",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let table = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    let rows: Vec<&str> = table.lines().collect();
    assert_eq!(rows.len(), 3, "{table}");
    assert!(
        rows[0]
            .starts_with("run,boundary.0.motion.shear_deg,simulation.frames,status,max_shear_deg")
    );
    let shear: f64 = rows[2].split(',').nth(4).unwrap().parse().unwrap();
    assert!((shear - 40.0).abs() < 0.2, "{table}");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn new_writes_templates_that_load() {
    let dir = temp("new");
    for t in [
        "hemisphere",
        "deep-drawing",
        "picture-frame",
        "bias-extension",
    ] {
        let path = dir.join(format!("{t}.toml"));
        let o = drape(&["new", t, path.to_str().unwrap()]);
        assert!(o.status.success(), "{}", text(&o));
        drape_io::scene::Scene::from_file(&path, &[]).unwrap();
    }
    let o = drape(&[
        "new",
        "hemisphere",
        dir.join("hemisphere.toml").to_str().unwrap(),
    ]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "an existing file is not overwritten"
    );
    let o = drape(&["new", "teapot"]);
    assert_eq!(o.status.code(), Some(2));
    std::fs::remove_dir_all(dir).unwrap();
}

/// Writes `scene` into a fresh directory, runs it, and checks exit code 2,
/// a message with `expect` in it, and no output directory.
fn bad_input(name: &str, scene: &str, expect: &[&str]) {
    let dir = temp(name);
    let path = dir.join("scene.toml");
    std::fs::write(&path, scene).unwrap();
    let out = dir.join("out");
    let o = drape(&[
        "run",
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

const GOOD: &str = r#"[simulation]
end_time = 0.001

[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
blank = { width = 100, height = 100, cells = [4, 4] }

[[tools]]
name = "floor"
friction = 0.1
geometry = { kind = "plane", point = [0, 0, -1], normal = [0, 0, 1] }
"#;

#[test]
fn bad_input_exits_2_names_the_place_and_writes_nothing() {
    bad_input("broken", "[simulation\nend_time = 1\n", &["scene.toml:1"]);
    bad_input(
        "unknown-key",
        &GOOD.replace("friction = 0.1", "frition = 0.1"),
        &["scene.toml:11", "frition"],
    );
    bad_input(
        "negative-modulus",
        &GOOD.replace(
            "material = \"glass-serge-4x3\"",
            "material = { name = \"m\", thickness = 0.5, fibre_volume_fraction = 0.5, density = 1e-9, fibre = { modulus = -1, crimp_strain = 0.01 }, resin = { young = 30, poisson = 0.4 } }",
        ),
        &["scene.toml:5", "fabric.material.fibre.modulus"],
    );
    bad_input(
        "friction",
        &GOOD.replace("friction = 0.1", "friction = -0.1"),
        &["scene.toml:11", "tools[0].friction"],
    );
    bad_input(
        "missing-tool-file",
        &GOOD.replace(
            "geometry = { kind = \"plane\", point = [0, 0, -1], normal = [0, 0, 1] }",
            "geometry = { kind = \"mesh\", file = \"nowhere.stl\" }",
        ),
        &["scene.toml:12", "tools[0].geometry.file", "nowhere.stl"],
    );
    let dir = temp("no-scene");
    let o = drape(&["run", dir.join("absent.toml").to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("absent.toml"), "{}", text(&o));
    let o = drape(&[
        "run",
        "scenes/picture-frame.toml",
        "--set",
        "simulation.end_time=-1",
        "--out",
        dir.join("o").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("simulation.end_time"), "{}", text(&o));
    assert!(!dir.join("o").exists());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_diverging_run_exits_1_and_keeps_what_it_reached() {
    let dir = temp("diverge");
    let out = dir.join("out");
    // 10⁹ N on the edge midpoints: the blank is torn apart.
    let scene = dir.join("scene.toml");
    std::fs::write(
        &scene,
        r#"[simulation]
end_time = 0.001
frames = 10

[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
blank = { width = 100, height = 100, cells = [4, 4] }

[[boundary]]
nodes = "left"
motion = { kind = "fixed" }

[[loads]]
nodes = "edge_midpoints"
force = [0, 0, 1e9]
amplitude = { kind = "ramp", duration = 0.001 }
"#,
    )
    .unwrap();
    let o = drape(&[
        "run",
        scene.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "failed");
    let reason = summary["reason"].as_str().unwrap();
    assert!(reason.contains("step"), "{reason}");
    // What the summary reports is the last frame written, which passed
    // every check, not the torn state of the failing step.
    assert!(reason.contains("the last output frame"), "{reason}");
    let failed_at: f64 = reason["step ".len()..]
        .split("t = ")
        .nth(1)
        .and_then(|t| t.split(' ').next())
        .unwrap()
        .parse()
        .unwrap();
    let time = summary["time"].as_f64().unwrap();
    assert!(time < failed_at, "{time} vs {failed_at}");
    let frames = std::fs::read_dir(out.join("frames")).unwrap().count();
    let frame_dt = 0.001 / 10.0;
    assert!(
        ((frames - 1) as f64 * frame_dt - time).abs() < 0.1 * frame_dt,
        "{frames} frames, t = {time}"
    );
    assert!(out.join("frames/frame_00000.vtu").is_file());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_scene_that_cannot_run_stably_is_bad_input() {
    // A time step 50 times the stable one.
    bad_input(
        "forced-step",
        &format!("{GOOD}\n").replace("end_time = 0.001", "end_time = 0.001\ntime_step = 3e-4"),
        &[
            "scene.toml",
            "the time step 3.0000e-4 s is",
            "the stable time step",
        ],
    );
    // The blank in the floor.
    bad_input(
        "inside",
        &GOOD.replace("point = [0, 0, -1]", "point = [0, 0, 2]"),
        &["starts inside tool `floor`", "25 nodes"],
    );
    // A holder whose force flings it through the blank in one step.
    bad_input(
        "holder",
        &format!(
            "{GOOD}\n{}",
            r#"[[tools]]
name = "holder"
geometry = { kind = "ring", center = [0, 0, 0.3], inner_radius = 10, outer_radius = 40 }
motion = { kind = "force", direction = [0, 0, -1], force = 1e15, mass = 1e-3 }
"#
        ),
        &[
            "force-driven tool `holder` would travel",
            "pass through the blank",
        ],
    );
}

const DRAPED: &str = r#"gravity = [0, 0, -9810]

[simulation]
end_time = 0.004
frames = 4
mass_scaling_dt = 2e-6

[fabric]
material = "carbon-prepreg-2x2"
fibres = "trusses"
orientation_deg = 45
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

#[test]
fn a_resumed_run_ends_where_an_uninterrupted_one_does() {
    use drape::{Checkpoint, RunControl, RunOptions, run_scene, run_scene_with};
    use drape_io::scene::Scene;
    let dir = temp("resume");
    let path = dir.join("draped.toml");
    std::fs::write(&path, DRAPED).unwrap();
    let scene = Scene::from_file(&path, &[]).unwrap();
    let straight = run_scene(&scene, &dir.join("straight"), &mut |_| RunControl::Continue).unwrap();
    assert_eq!(straight.summary.status, "completed");

    // Stopped after 300 steps with a checkpoint every 70, then resumed.
    let mut interrupted = scene.clone();
    interrupted.settings.max_steps = Some(300);
    let out = dir.join("resumed");
    let options = RunOptions {
        checkpoint_every: Some(70),
        ..RunOptions::default()
    };
    let first = run_scene_with(&interrupted, &out, options, &mut |_| RunControl::Continue).unwrap();
    assert_eq!(first.summary.status, "stopped");
    let checkpoint = Checkpoint::read(&out).unwrap();
    assert_eq!(checkpoint.state.step, 280);
    let options = RunOptions {
        resume: Some(checkpoint),
        ..RunOptions::default()
    };
    let resumed = run_scene_with(&scene, &out, options, &mut |_| RunControl::Continue).unwrap();
    assert_eq!(resumed.summary.status, "completed");
    assert_eq!(resumed.state.step, straight.state.step);
    let bits = |s: &drape_model::State| -> Vec<u64> {
        s.x.iter()
            .flat_map(|p| p.iter().map(|v| v.to_bits()))
            .collect()
    };
    assert_eq!(bits(&resumed.state), bits(&straight.state));
    assert_eq!(
        resumed.summary.max_shear_deg,
        straight.summary.max_shear_deg
    );
    // Same energy history and frames as the uninterrupted run.
    let csv = |d: &str| std::fs::read_to_string(dir.join(d).join("energy.csv")).unwrap();
    assert_eq!(csv("resumed"), csv("straight"));
    assert!(out.join("frames/frame_00004.vtu").is_file());

    // The same through the command line.
    let cli = dir.join("cli");
    let o = drape(&[
        "run",
        path.to_str().unwrap(),
        "--checkpoint-every",
        "100",
        "--out",
        cli.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(cli.join("checkpoint.json").is_file());
    let o = drape(&["run", "--resume", cli.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("resuming"), "{}", text(&o));
    std::fs::remove_dir_all(dir).unwrap();
}
