//! `drape run` on scene values of the wrong shape or past their range:
//! exit 2 before anything is written, the message naming the key (and the
//! file's line, or the `--set` that gave the value), never a consequence.

mod common;
use common::*;

/// `drape run SCENE --out OUT ARGS…`: its exit code and text, and
/// whether it wrote its output folder.
fn run(scene: &str, out: &std::path::Path, args: &[&str]) -> (Option<i32>, String, bool) {
    let out_arg = out.to_string_lossy().into_owned();
    let mut all = vec!["run", scene, "--out", &out_arg];
    all.extend_from_slice(args);
    let o = drape(&all);
    (o.status.code(), text(&o), out.exists())
}

#[test]
fn a_stray_comma_in_gravity_is_bad_input_naming_it() {
    let dir = temp("stray-comma");
    let out = dir.join("out");
    let (code, text, wrote) = run(
        "scenes/hemisphere-0-90.toml",
        &out,
        &["--set", "gravity=[0,0,-9,810]"],
    );
    assert_eq!(code, Some(2), "{text}");
    assert!(!wrote, "{text}");
    assert!(
        text.contains("gravity: a list of 4 values is not allowed: expected 3"),
        "{text}"
    );
    assert!(text.contains("--set gravity=[0,0,-9,810]"), "{text}");

    // The same in the file: its line.
    let scene = std::fs::read_to_string(workspace().join("scenes/hemisphere-0-90.toml"))
        .unwrap()
        .replace("gravity = [0, 0, -9810]", "gravity = [0, 0, -9,810]");
    let path = dir.join("comma.toml");
    std::fs::write(&path, &scene).unwrap();
    let line = scene
        .lines()
        .position(|l| l.starts_with("gravity"))
        .unwrap()
        + 1;
    let (code, text, wrote) = run(&path.to_string_lossy(), &out, &[]);
    assert_eq!(code, Some(2), "{text}");
    assert!(!wrote, "{text}");
    assert!(
        text.contains(&format!("comma.toml:{line}: gravity: a list of 4 values")),
        "{text}"
    );
}

#[test]
fn a_tool_moved_far_away_or_a_huge_scale_is_named_not_a_consequence() {
    let dir = temp("far-tool");
    let out = dir.join("out");
    let (code, text, wrote) = run(
        "scenes/tray.toml",
        &out,
        &["--set", "tools.1.geometry.offset=[0,0,1e300]"],
    );
    assert_eq!(code, Some(2), "{text}");
    assert!(!wrote, "{text}");
    assert!(
        text.contains("tools[1].geometry.offset: 1e300 is not allowed"),
        "{text}"
    );
    assert!(!text.contains("close to"), "{text}");
    let (code, text, _) = run(
        "scenes/imported-plate.toml",
        &out,
        &["--set", "fabric.blank.scale=1e300"],
    );
    assert_eq!(code, Some(2), "{text}");
    assert!(
        text.contains("fabric.blank.scale: `scale` scales"),
        "{text}"
    );
    assert!(!text.contains("degenerate"), "{text}");
}
