//! `drape run --device gpu` where the GPU cannot run the scene, or there is
//! no GPU: bad input (exit 2) that says what, and nothing written. (The
//! GPU runs themselves are checked on a GPU by `scripts/gpu-check`.)

mod common;
use common::*;

fn text(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

#[test]
fn a_scene_the_gpu_does_not_do_is_refused_naming_what() {
    let dir = temp("gpu-refused");
    let out = dir.join("run");
    let out_arg = out.to_str().unwrap();
    let o = drape(&[
        "run",
        "scenes/deep-drawing-0-90.toml",
        "--device",
        "gpu",
        "--out",
        out_arg,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let message = text(&o);
    assert!(message.contains("more than one tool"), "{message}");
    assert!(message.contains("a force-driven tool"), "{message}");
    assert!(!out.exists(), "nothing written");
    // The implicit solver is refused too, and a device that is none.
    let o = drape(&[
        "run",
        "scenes/hemisphere-0-90.toml",
        "--device",
        "gpu",
        "--set",
        "simulation.solver=implicit",
        "--out",
        out_arg,
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("explicit"), "{}", text(&o));
    let o = drape(&["run", "scenes/hemisphere-0-90.toml", "--device", "tpu"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("`cpu` or `gpu`"), "{}", text(&o));
}

#[test]
fn without_a_gpu_a_gpu_run_is_refused_saying_what_is_missing() {
    if drape_gpu::probe().is_ok() {
        eprintln!("skipped: this machine has a GPU (scripts/gpu-check runs it)");
        return;
    }
    let dir = temp("gpu-none");
    let out = dir.join("run");
    let o = drape(&[
        "run",
        "scenes/hemisphere-0-90.toml",
        "--device",
        "gpu",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let message = text(&o);
    assert!(
        message.contains("no usable GPU") && message.contains("was not found"),
        "{message}"
    );
    assert!(!out.exists(), "nothing written");
}

/// A run stopped on one device and resumed on the other: `--resume DIR
/// --device D` switches, and the run ends where an uninterrupted one does
/// (both drivers carry the same checkpoint). The GPU run's checkpoint is
/// written here by switching a CPU run's, so that no GPU is needed; on a
/// machine without one, resuming it where it ran is refused and leaves it
/// as it was.
#[test]
fn a_stopped_run_resumes_on_the_other_device() {
    use drape_io::scene::{Device, Scene};
    let dir = temp("gpu-switch");
    let path = dir.join("draped.toml");
    std::fs::write(&path, DRAPED).unwrap();
    let scene = Scene::from_file(&path, &[]).unwrap();
    let straight = drape::run_scene(&scene, &dir.join("straight"), &mut |_| {
        drape::RunControl::Continue
    })
    .unwrap();
    assert_eq!(straight.summary.status, "completed");
    let out = dir.join("stopped");
    let mut checkpoint = stopped_with_checkpoint(&scene, &out, 300, 70);
    checkpoint.switch_device(Device::Gpu);
    let file = drape::Checkpoint::path(&out);
    std::fs::write(&file, serde_json::to_vec(&checkpoint).unwrap()).unwrap();
    let written = std::fs::read(&file).unwrap();
    let out_arg = out.to_str().unwrap();
    let o = drape(&["run", "--resume", out_arg, "--device", "tpu"]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("`cpu` or `gpu`"), "{}", text(&o));
    if drape_gpu::probe().is_err() {
        let o = drape(&["run", "--resume", out_arg]);
        assert_eq!(o.status.code(), Some(2), "{}", text(&o));
        assert!(text(&o).contains("no usable GPU"), "{}", text(&o));
        assert_eq!(
            std::fs::read(&file).unwrap(),
            written,
            "the checkpoint as it was"
        );
    }
    let o = drape(&["run", "--resume", out_arg, "--device", "cpu"]);
    assert!(o.status.success(), "{}", text(&o));
    let csv = |d: &std::path::Path| std::fs::read_to_string(d.join("energy.csv")).unwrap();
    assert_eq!(csv(&out), csv(&dir.join("straight")));
    let summary = json(&out.join("summary.json"));
    assert_eq!(summary["status"], "completed");
}
