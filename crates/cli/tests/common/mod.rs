//! What every end-to-end test of the `drape` binary uses: running it from
//! the workspace, a fresh temporary folder, its output as text, a JSON file.
//! Each test file uses part of it.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

/// `drape ARGS…` run from the workspace root, to its end.
pub fn drape(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .current_dir(workspace())
        .output()
        .expect("the drape binary runs")
}

/// The workspace root (scenes are named relative to it).
pub fn workspace() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// An empty folder of this test file and process, named `name`, removed
/// when the test that made it passes (kept after a failure, to look at).
pub fn temp(name: &str) -> TempFolder {
    let dir = std::env::temp_dir().join(format!(
        "drape-{}-{}-{name}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    TempFolder(dir)
}

/// [`temp`]'s folder: a path, removed on drop unless the thread is
/// panicking (a failed assertion).
pub struct TempFolder(PathBuf);

impl std::ops::Deref for TempFolder {
    type Target = Path;
    fn deref(&self) -> &Path {
        &self.0
    }
}

impl AsRef<Path> for TempFolder {
    fn as_ref(&self) -> &Path {
        &self.0
    }
}

impl Drop for TempFolder {
    fn drop(&mut self) {
        if !std::thread::panicking() {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}

/// Standard output and error together.
pub fn text(o: &Output) -> String {
    format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    )
}

/// A JSON file, parsed.
pub fn json(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A 100 mm carbon blank (±45 trusses: 221 nodes) pressed onto a sphere,
/// mass-scaled to 2e-6 s: a few hundred steps.
pub const DRAPED: &str = r#"gravity = [0, 0, -9810]

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

/// `drape run` of DRAPED with `set` into `dir/name`, given at most a
/// minute (a run that would not end is a failure, not a hung test).
pub fn run_draped(dir: &Path, name: &str, set: &[&str]) -> (PathBuf, Output) {
    let scene = dir.join("draped.toml");
    if !scene.exists() {
        std::fs::write(&scene, DRAPED).unwrap();
    }
    let out = dir.join(name);
    let mut args = vec![
        "run".to_owned(),
        scene.display().to_string(),
        "--out".to_owned(),
        out.display().to_string(),
    ];
    for s in set {
        args.extend(["--set".to_owned(), (*s).to_owned()]);
    }
    (out, within_a_minute(&args))
}

pub fn within_a_minute(args: &[String]) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .current_dir(workspace())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            let o = child.wait_with_output().unwrap();
            panic!("drape {args:?} still running after a minute:\n{}", text(&o));
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    child.wait_with_output().unwrap()
}

/// `scene` run to step `stop` with a checkpoint every `every` steps into
/// `out` (a run stopped there, as by a job's time limit): the checkpoint
/// it leaves.
pub fn stopped_with_checkpoint(
    scene: &drape_io::scene::Scene,
    out: &Path,
    stop: u64,
    every: u64,
) -> drape::Checkpoint {
    use drape::{Checkpoint, RunControl, RunOptions, run_scene_with};
    let mut interrupted = scene.clone();
    interrupted.settings.max_steps = Some(stop);
    let options = RunOptions {
        checkpoint_every: Some(every),
        ..RunOptions::default()
    };
    let first = run_scene_with(&interrupted, out, options, &mut |_| RunControl::Continue).unwrap();
    assert_eq!(first.summary.status, "stopped");
    Checkpoint::read(out).unwrap()
}

/// `scene` resumed in `out` from `checkpoint` to its end.
pub fn resumed_from(
    scene: &drape_io::scene::Scene,
    out: &Path,
    checkpoint: drape::Checkpoint,
) -> drape::RunReport {
    use drape::{RunControl, RunOptions, run_scene_with};
    let options = RunOptions {
        resume: Some(checkpoint),
        ..RunOptions::default()
    };
    run_scene_with(scene, out, options, &mut |_| RunControl::Continue).unwrap()
}

/// A state's positions and velocities, bit for bit.
pub fn state_bits(s: &drape_model::State) -> Vec<u64> {
    s.x.iter()
        .chain(&s.v)
        .flat_map(|p| p.iter().map(|v| v.to_bits()))
        .collect()
}
