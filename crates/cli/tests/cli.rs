//! The `drape` command end to end: runs, templates, sweeps, inspection,
//! exit codes, and bad input that must exit 2 and write nothing.

use std::path::Path;
use std::process::{Command, Output};

mod common;
use common::*;

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
fn a_sweep_tables_each_tool_s_largest_force() {
    // The punch's largest mean force per run, as its summary has it, in a
    // column before the table's last (which the table's reader checks).
    let dir = temp("sweep-tools");
    let scene = dir.join("draped.toml");
    std::fs::write(&scene, DRAPED).unwrap();
    let out = dir.join("sweep");
    let o = drape(&[
        "sweep",
        scene.to_str().unwrap(),
        "--set",
        "tools.0.friction=0.1,0.3",
        "--set",
        "output.vtu=false",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let table = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let rows: Vec<Vec<&str>> = table.lines().map(|l| l.split(',').collect()).collect();
    assert!(
        rows[0]
            .join(",")
            .ends_with(",peak_time_s,punch_max_force_n,max_fibre_tension_n_per_mm"),
        "{table}"
    );
    assert!(rows.iter().all(|r| r.len() == rows[0].len()), "{table}");
    for run in 0..2 {
        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(format!("run_{run:03}/summary.json"))).unwrap(),
        )
        .unwrap();
        let force = summary["tools"][0]["max_force_n"].as_f64().unwrap();
        assert!(force > 0.0, "{summary}");
        let column = rows[0].len() - 2;
        assert_eq!(rows[run + 1][column], format!("{force:.1}"), "{table}");
    }
    let o = drape(&["inspect", out.to_str().unwrap()]);
    assert!(text(&o).contains("(2 runs)"), "{}", text(&o));
}

#[test]
fn new_writes_templates_that_load() {
    let dir = temp("new");
    for t in [
        "hemisphere",
        "deep-drawing",
        "picture-frame",
        "bias-extension",
        "stack",
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

/// 10⁹ N on the edge midpoints of a clamped blank: it is torn apart, and
/// the run fails.
const TORN: &str = r#"[simulation]
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
"#;

#[test]
fn a_diverging_run_exits_1_and_keeps_what_it_reached() {
    let dir = temp("diverge");
    let out = dir.join("out");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, TORN).unwrap();
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
    // The blank's frames (trusses_ and tools_ files sit beside them).
    let frames = std::fs::read_dir(out.join("frames"))
        .unwrap()
        .filter(|e| {
            e.as_ref()
                .unwrap()
                .file_name()
                .to_string_lossy()
                .starts_with("frame_")
        })
        .count();
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

#[test]
fn a_resumed_run_ends_where_an_uninterrupted_one_does() {
    use drape::{RunControl, run_scene};
    use drape_io::scene::Scene;
    let dir = temp("resume");
    let path = dir.join("draped.toml");
    std::fs::write(&path, DRAPED).unwrap();
    let scene = Scene::from_file(&path, &[]).unwrap();
    let straight = run_scene(&scene, &dir.join("straight"), &mut |_| RunControl::Continue).unwrap();
    assert_eq!(straight.summary.status, "completed");

    // Stopped after 300 steps with a checkpoint every 70, then resumed.
    let out = dir.join("resumed");
    let checkpoint = stopped_with_checkpoint(&scene, &out, 300, 70);
    assert_eq!(checkpoint.state.step, 280);
    // The file keeps the membranes' history element after element, not in
    // the lane blocks the run keeps it in (quads of four elements): the
    // state of a run stopped at that step, converted.
    let mut at_checkpoint = scene.clone();
    at_checkpoint.settings.max_steps = Some(280);
    let same = run_scene(&at_checkpoint, &dir.join("at-checkpoint"), &mut |_| {
        RunControl::Continue
    })
    .unwrap();
    assert_eq!(same.state.step, 280);
    let history = scene.model.history_to_element_major(&same.state.history);
    assert_ne!(history, same.state.history, "the run keeps lane blocks");
    assert_eq!(checkpoint.state.history, history);
    let resumed = resumed_from(&scene, &out, checkpoint);
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
    // Same energy history, tool forces and frames as the uninterrupted run.
    let csv = |d: &str| std::fs::read_to_string(dir.join(d).join("energy.csv")).unwrap();
    assert_eq!(csv("resumed"), csv("straight"));
    let forces = |d: &str| std::fs::read_to_string(dir.join(d).join("tool_forces.csv")).unwrap();
    assert_eq!(forces("resumed"), forces("straight"));
    // A row per frame (5) for the one tool; the punch pushes the blank up
    // against its springs: a positive mean force once it presses.
    let straight_forces = forces("straight");
    let lines: Vec<&str> = straight_forces.lines().collect();
    assert_eq!(lines.len(), 6, "{straight_forces}");
    assert_eq!(lines[0], drape_io::results::TOOL_FORCES_HEADER);
    assert!(
        lines[1].ends_with(','),
        "no mean at the first frame: {}",
        lines[1]
    );
    let mean: f64 = lines[5].rsplit(',').next().unwrap().parse().unwrap();
    assert!(mean > 0.0, "{straight_forces}");
    // The summary's tool is the file's: its last mean, its largest.
    let tool = &straight.summary.tools[0];
    assert_eq!((tool.name.as_str(), tool.force_n), ("punch", mean));
    let means = lines[2..]
        .iter()
        .map(|l| l.rsplit(',').next().unwrap().parse::<f64>().unwrap());
    assert_eq!(tool.max_force_n, means.fold(f64::MIN, f64::max));
    assert_eq!(resumed.summary.tools, straight.summary.tools);
    assert!(out.join("frames/frame_00004.vtu").is_file());

    // The same resumed through the command line, from another directory,
    // with the scene file gone: the checkpoint carries the scene.
    let cli = dir.join("cli");
    stopped_with_checkpoint(&scene, &cli, 300, 70);
    std::fs::remove_file(&path).unwrap();
    let o = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["run", "--resume", cli.to_str().unwrap()])
        .current_dir(std::env::temp_dir())
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("resuming"), "{}", text(&o));
    assert!(
        text(&o).contains("cannot be read as it was"),
        "{}",
        text(&o)
    );
    assert_eq!(csv("cli"), csv("straight"));
    assert!(
        !cli.join("checkpoint.json").exists(),
        "a completed run keeps none"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// The implicit driver through the facade: the summary reports its
/// totals, a checkpoint carries its accelerations and contact pairs, and a
/// resumed run ends where an uninterrupted one does, bit for bit; an
/// explicit checkpoint is refused by the implicit driver.
#[test]
fn an_implicit_run_resumes_bit_for_bit() {
    use drape::{Checkpoint, RunControl, RunOptions, run_scene, run_scene_with};
    use drape_io::scene::Scene;
    let dir = temp("resume-implicit");
    let path = dir.join("draped.toml");
    std::fs::write(&path, DRAPED).unwrap();
    let set = [("simulation.solver".to_owned(), "implicit".to_owned())];
    let scene = Scene::from_file(&path, &set).unwrap();
    let straight = run_scene(&scene, &dir.join("straight"), &mut |_| RunControl::Continue).unwrap();
    assert_eq!(
        straight.summary.status, "completed",
        "{:?}",
        straight.summary.reason
    );
    assert_eq!(straight.summary.run.solver, "implicit");
    let totals = straight.summary.run.implicit.expect("implicit totals");
    assert!(totals.newton_iterations >= straight.state.step);
    assert!(totals.factorisations >= totals.newton_iterations);
    assert!((0.0..1.0).contains(&totals.factor_share));
    let increments = straight.state.step;
    assert!(increments > 6, "{increments} increments");

    let mut interrupted = scene.clone();
    interrupted.implicit.max_increments = Some(increments - 2);
    let out = dir.join("resumed");
    let options = RunOptions {
        checkpoint_every: Some(3),
        ..RunOptions::default()
    };
    let first = run_scene_with(&interrupted, &out, options, &mut |_| RunControl::Continue).unwrap();
    assert_eq!(first.summary.status, "stopped");
    let checkpoint = Checkpoint::read(&out).unwrap();
    assert!(checkpoint.state.step > 0 && checkpoint.state.step < increments);

    // An explicit run of the same scene cannot pick it up.
    let mut explicit = scene.clone();
    explicit.spec.simulation.solver = drape_io::scene::Solver::Explicit;
    let refused = run_scene_with(
        &explicit,
        &dir.join("wrong"),
        RunOptions {
            resume: Some(checkpoint.clone()),
            ..RunOptions::default()
        },
        &mut |_| RunControl::Continue,
    );
    let reason = refused.map(|r| r.summary.reason.unwrap_or_default());
    assert!(
        format!("{reason:?}").contains("written by the implicit driver"),
        "{reason:?}"
    );

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
    let csv = |d: &str| std::fs::read_to_string(dir.join(d).join("energy.csv")).unwrap();
    assert_eq!(csv("resumed"), csv("straight"));
    let forces = |d: &str| std::fs::read_to_string(dir.join(d).join("tool_forces.csv")).unwrap();
    assert_eq!(forces("resumed"), forces("straight"));
    std::fs::remove_dir_all(dir).unwrap();
}

/// An implicit run lists every attempt it cut back in `cutbacks.csv`,
/// one row each, with the reasons the summary counts; a resumed run lists
/// the ones before its checkpoint too (the same file as an uninterrupted
/// run's). Eight Newton iterations per attempt make the draped blank cut
/// back a few times in half its stroke with the condensed contact solver
/// (the active set's run had cut back no attempt by its last checkpoint).
#[test]
fn an_implicit_run_lists_its_cutbacks() {
    use drape::{Checkpoint, RunControl, RunOptions, run_scene, run_scene_with};
    use drape_io::scene::Scene;
    let dir = temp("cutbacks");
    let path = dir.join("draped.toml");
    std::fs::write(&path, DRAPED).unwrap();
    let set: Vec<(String, String)> = [
        ("simulation.solver", "implicit"),
        ("simulation.max_iterations", "8"),
        ("simulation.end_time", "0.002"),
        ("simulation.contact_solver", "condensed"),
    ]
    .iter()
    .map(|(k, v)| ((*k).to_owned(), (*v).to_owned()))
    .collect();
    let scene = Scene::from_file(&path, &set).unwrap();
    let straight = run_scene(&scene, &dir.join("straight"), &mut |_| RunControl::Continue).unwrap();
    assert_eq!(straight.summary.status, "completed");
    let totals = straight.summary.run.implicit.expect("implicit totals");
    assert!(totals.cutbacks > 0, "{totals:?}");
    let csv = |d: &str| std::fs::read_to_string(dir.join(d).join("cutbacks.csv")).unwrap();
    let text = csv("straight");
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("step,time,increment,reason,message"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.splitn(5, ',').collect()).collect();
    assert_eq!(rows.len() as u64, totals.cutbacks, "{text}");
    let count = |reason: &str| rows.iter().filter(|r| r[3] == reason).count() as u64;
    let reasons = &totals.cutback_reasons;
    assert_eq!(count("newton_limit"), reasons.newton_limit, "{text}");
    assert_eq!(
        count("friction_chatter"),
        reasons.friction_chatter,
        "{text}"
    );
    assert_eq!(count("diverged"), reasons.diverged, "{text}");
    for r in &rows {
        let step: u64 = r[0].parse().unwrap();
        let (time, increment): (f64, f64) = (r[1].parse().unwrap(), r[2].parse().unwrap());
        assert!(step >= 1 && step <= straight.state.step, "{r:?}");
        assert!((0.0..0.002).contains(&time) && increment > 0.0, "{r:?}");
        assert!(
            r[4].starts_with("\"8 Newton iterations") && r[4].ends_with('"'),
            "{r:?}"
        );
    }
    // Stopped part way with checkpoints, then resumed.
    let mut interrupted = scene.clone();
    interrupted.implicit.max_increments = Some(straight.state.step - 5);
    let out = dir.join("resumed");
    let options = RunOptions {
        checkpoint_every: Some(4),
        ..RunOptions::default()
    };
    let first = run_scene_with(&interrupted, &out, options, &mut |_| RunControl::Continue).unwrap();
    assert_eq!(first.summary.status, "stopped");
    let checkpoint = Checkpoint::read(&out).unwrap();
    assert!(!checkpoint.cutbacks.is_empty(), "the checkpoint keeps them");
    let options = RunOptions {
        resume: Some(checkpoint),
        ..RunOptions::default()
    };
    let resumed = run_scene_with(&scene, &out, options, &mut |_| RunControl::Continue).unwrap();
    assert_eq!(resumed.summary.status, "completed");
    assert_eq!(csv("resumed"), text);
    std::fs::remove_dir_all(dir).unwrap();
}

/// A draping run far longer than any test waits for (10 s of forming at
/// a 2e-6 s step: millions of steps), stopped by SIGINT.
fn long_draped() -> String {
    DRAPED
        .replace("end_time = 0.004", "end_time = 10")
        .replace("duration = 0.004", "duration = 10")
}

/// Starts `drape` with `args` in `cwd`, its output captured.
fn spawn(cwd: &Path, args: &[&str]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .current_dir(cwd)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("the drape binary starts")
}

/// Waits (up to a minute) until `ready` holds.
fn wait_for(what: &str, mut ready: impl FnMut() -> bool) {
    let start = std::time::Instant::now();
    while !ready() {
        assert!(start.elapsed().as_secs() < 60, "gave up waiting for {what}");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
}

/// The step of the checkpoint in `out`, if one is there.
fn checkpoint_step(out: &Path) -> Option<u64> {
    let text = std::fs::read_to_string(out.join("checkpoint.json")).ok()?;
    let c: serde_json::Value = serde_json::from_str(&text).ok()?;
    c["state"]["step"].as_u64()
}

/// Sends `signal` (Ctrl-C's INT, or a scheduler's TERM) to `child` and
/// waits for it.
#[cfg(unix)]
fn interrupt(child: std::process::Child, signal: &str) -> Output {
    let killed = Command::new("kill")
        .args([&format!("-{signal}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(killed.success());
    child.wait_with_output().unwrap()
}

fn summary_of(out: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap()
}

/// One long run, seen through everything that happens to a folder: a
/// second run into it is refused, Ctrl-C stops it with a last frame and a
/// "stopped" summary, it resumes from another directory with its own scene
/// although the file was edited, counts all its steps, SIGTERM stops it as
/// cleanly, and a new run into
/// the folder removes the stale checkpoint.
#[cfg(unix)]
#[test]
fn lock_ctrl_c_resume_elsewhere_and_stale_checkpoint() {
    let dir = temp("lifecycle");
    std::fs::write(dir.join("scene.toml"), long_draped()).unwrap();
    // A temporary that a killed run left: cleared by the next run.
    std::fs::create_dir_all(dir.join("out/frames")).unwrap();
    std::fs::write(dir.join("out/frames/.frame_00009.vtu.tmp77"), b"half").unwrap();
    let out = dir.join("out");
    // Started from the scene's directory with relative paths, as a user
    // would.
    let child = spawn(
        &dir,
        &[
            "run",
            "scene.toml",
            "--out",
            "out",
            "--checkpoint-every",
            "100",
        ],
    );
    let pid = child.id();
    wait_for("a checkpoint", || checkpoint_step(&out).is_some());
    assert!(!out.join("frames/.frame_00009.vtu.tmp77").exists());

    // A second run into the same folder: refused, nothing touched.
    let o = drape(&[
        "run",
        "scenes/picture-frame.toml",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains(&format!(
            "another drape run (process {pid}) is writing into"
        )),
        "{}",
        text(&o)
    );
    assert!(out.join("frames/frame_00000.vtu").is_file());
    let o = drape(&["run", "--resume", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));

    // Ctrl-C: a clean stop.
    let o = interrupt(child, "INT");
    assert_eq!(o.status.code(), Some(130), "{}", text(&o));
    assert!(text(&o).contains("drape run --resume out"), "{}", text(&o));
    let summary = summary_of(&out);
    assert_eq!(summary["status"], "stopped");
    let reason = summary["reason"].as_str().unwrap();
    assert!(reason.contains("stopped on request"), "{reason}");
    assert!(
        reason.contains("resumed from the checkpoint at step"),
        "{reason}"
    );
    let stopped_at = summary["time"].as_f64().unwrap();
    let first_steps = summary["run"]["steps"].as_u64().unwrap();
    // The last frame is where it stopped, and so is the energy history.
    let pvd = std::fs::read_to_string(out.join("series.pvd")).unwrap();
    assert_eq!(pvd.matches("<DataSet ").count(), 2, "{pvd}");
    assert!(pvd.contains("frames/frame_00001.vtu"), "{pvd}");
    assert!(out.join("frames/frame_00001.vtu").is_file());
    let energy = std::fs::read_to_string(out.join("energy.csv")).unwrap();
    let last_time: f64 = energy
        .lines()
        .last()
        .unwrap()
        .split(',')
        .next()
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(last_time, stopped_at);
    let o = drape(&["inspect", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("stopped"), "{}", text(&o));

    // The scene file is edited (a different friction) and the run resumed
    // from another directory: it goes on with the scene it started with.
    let edited = long_draped().replace("friction = 0.2", "friction = 0.7");
    std::fs::write(dir.join("scene.toml"), edited).unwrap();
    let elsewhere = temp("lifecycle-elsewhere");
    let resumed_from = checkpoint_step(&out).unwrap();
    let child = spawn(&elsewhere, &["run", "--resume", out.to_str().unwrap()]);
    wait_for("a later checkpoint", || {
        checkpoint_step(&out).is_some_and(|s| s > first_steps)
    });
    // SIGTERM (a batch scheduler's time limit, `timeout`): as clean.
    let o = interrupt(child, "TERM");
    assert_eq!(o.status.code(), Some(130), "{}", text(&o));
    let shown = text(&o);
    assert!(
        shown.contains(&format!("at step {resumed_from}")),
        "{shown}"
    );
    assert!(
        shown.contains("has changed since the run started"),
        "{shown}"
    );
    let checkpoint: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("checkpoint.json")).unwrap())
            .unwrap();
    assert_eq!(checkpoint["scene"]["tools"][0]["friction"], 0.2);
    assert_eq!(checkpoint["checkpoint_every"], 100, "the interval is kept");
    let summary = summary_of(&out);
    assert_eq!(summary["status"], "stopped");
    // Every step since the start, not only the resumed ones.
    assert!(summary["run"]["steps"].as_u64().unwrap() > first_steps);

    // A new run into the folder (one that fails at once) leaves no stale
    // checkpoint behind to resume.
    let torn = dir.join("torn.toml");
    std::fs::write(&torn, TORN).unwrap();
    let o = drape(&[
        "run",
        torn.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    assert!(!out.join("checkpoint.json").exists());
    let o = drape(&["run", "--resume", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("the run failed"), "{}", text(&o));
    std::fs::remove_dir_all(dir).unwrap();
    std::fs::remove_dir_all(elsewhere).unwrap();
}

#[test]
fn a_finished_run_has_nothing_to_resume() {
    let dir = temp("finished");
    std::fs::write(dir.join("scene.toml"), DRAPED).unwrap();
    let out = dir.join("out");
    let o = drape(&[
        "run",
        dir.join("scene.toml").to_str().unwrap(),
        "--checkpoint-every",
        "100",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        !out.join("checkpoint.json").exists(),
        "a finished run keeps no checkpoint"
    );
    let before = std::fs::read_to_string(out.join("summary.json")).unwrap();
    let o = drape(&["run", "--resume", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(text(&o).contains("the run is finished"), "{}", text(&o));
    assert!(text(&o).contains("nothing to resume"), "{}", text(&o));
    assert_eq!(
        std::fs::read_to_string(out.join("summary.json")).unwrap(),
        before
    );
    // A folder with no run in it.
    let o = drape(&["run", "--resume", dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        text(&o).contains("no checkpoint to resume from"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn an_unwritable_output_folder_is_bad_input() {
    let dir = temp("unwritable");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, GOOD).unwrap();
    let file = dir.join("a-file");
    std::fs::write(&file, b"x").unwrap();
    for out in [file.clone(), file.join("run")] {
        let o = drape(&[
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", text(&o));
        let shown = String::from_utf8_lossy(&o.stderr).into_owned();
        assert_eq!(shown.lines().count(), 1, "one message: {shown}");
        assert!(shown.contains("a-file is a file, not a folder"), "{shown}");
        assert!(!shown.contains("os error"), "{shown}");
    }
    // A read-only folder (meaningless for root, who may write anyway).
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let locked = dir.join("read-only");
        std::fs::create_dir(&locked).unwrap();
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o555)).unwrap();
        if std::fs::write(locked.join("probe"), b"").is_err() {
            let out = locked.join("run");
            let o = drape(&[
                "run",
                scene.to_str().unwrap(),
                "--out",
                out.to_str().unwrap(),
            ]);
            assert_eq!(o.status.code(), Some(2), "{}", text(&o));
            let shown = String::from_utf8_lossy(&o.stderr).into_owned();
            assert_eq!(shown.lines().count(), 1, "one message: {shown}");
            assert!(shown.contains("permission denied"), "{shown}");
        }
        std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn threads_and_frames_have_bounds() {
    let dir = temp("bounds");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, GOOD).unwrap();
    let out = dir.join("out");
    let o = drape(&[
        "run",
        scene.to_str().unwrap(),
        "--threads",
        "99999999999",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let cores = std::thread::available_parallelism().map_or(1, usize::from);
    assert!(
        text(&o).contains(&format!(
            "--threads 99999999999 is more than this machine runs at once; using {cores}"
        )),
        "{}",
        text(&o)
    );
    assert_eq!(summary_of(&out)["run"]["threads"], cores);
    for frames in ["9223372036854775807", "18446744073709551615"] {
        let o = drape(&[
            "run",
            scene.to_str().unwrap(),
            "--set",
            &format!("simulation.frames={frames}"),
            "--out",
            dir.join("o").to_str().unwrap(),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", text(&o));
        assert!(text(&o).contains("simulation.frames"), "{}", text(&o));
        assert!(!dir.join("o").exists());
    }
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn set_errors_name_the_key_and_the_set() {
    let o = drape(&[
        "run",
        "scenes/hemisphere-0-90.toml",
        "--set",
        "tools.0.friction=-1",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let shown = text(&o);
    assert!(
        shown.contains("hemisphere-0-90.toml: tools[0].friction: -1 is not allowed"),
        "{shown}"
    );
    assert!(
        shown.contains("(the value comes from --set tools.0.friction=-1)"),
        "{shown}"
    );
    let o = drape(&[
        "run",
        "scenes/picture-frame.toml",
        "--set",
        "simulation.end_time=abc",
    ]);
    assert_eq!(o.status.code(), Some(2));
    let shown = text(&o);
    assert!(
        shown.contains("simulation.end_time: the text \"abc\" is not allowed: expected a number"),
        "{shown}"
    );
    assert!(shown.contains("--set simulation.end_time=abc"), "{shown}");
    assert!(!shown.contains("f64"), "{shown}");
}
