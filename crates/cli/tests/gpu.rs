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
    // The implicit solver and checkpoints are refused too.
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
