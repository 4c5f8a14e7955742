//! A tool forced through the blank in one step stops the run as a contact
//! fault (exit 1, frames and a failed summary kept), instead of the contact
//! pass throwing the fabric out of it.

use std::path::Path;
use std::process::Command;

const SCENE: &str = r#"[simulation]
end_time = 0.004
frames = 4
mass_scaling_dt = 1e-5

[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
blank = { width = 100, height = 100, cells = [10, 10] }

# A plate 1 mm above the blank that, at t = 2 ms, drops 20 mm in 10 µs:
# about one step.
[[tools]]
name = "plate"
geometry = { kind = "plane", point = [0, 0, 1], normal = [0, 0, -1] }
motion = { kind = "displacement", direction = [0, 0, -1], distance = 20, amplitude = { kind = "table", points = [[0, 0], [0.002, 0], [0.00201, 1]] } }
"#;

#[test]
fn a_tool_forced_through_the_blank_in_one_step_is_a_contact_fault() {
    let dir = std::env::temp_dir().join(format!("drape-cli-{}-fault", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("plate.toml");
    std::fs::write(&scene, SCENE).unwrap();
    let out = dir.join("out");
    let o = Command::new(env!("CARGO_BIN_EXE_drape"))
        .args([
            "run",
            scene.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ])
        .output()
        .unwrap();
    let printed = format!(
        "{}{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(o.status.code(), Some(1), "{printed}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "failed");
    let reason = summary["reason"].as_str().unwrap();
    for part in ["contact fault", "node", "tool `plate`", "gap", "step"] {
        assert!(reason.contains(part), "{part}: {reason}");
    }
    // Stopped at the drop (t = 2 ms), with the frames before it.
    let time = summary["time"].as_f64().unwrap();
    assert!((0.002..0.00202).contains(&time), "{time}");
    for frame in ["frame_00000.vtu", "frame_00001.vtu"] {
        assert!(
            Path::new(&out.join("frames").join(frame)).is_file(),
            "{frame}"
        );
    }
    // Not absorbed: nothing was thrown 19 mm down.
    assert!(summary["draw_in_mm"]["dx"].as_f64().unwrap().abs() < 1.0);
    std::fs::remove_dir_all(dir).unwrap();
}
