//! A pressure-driven run under mass scaling says, at the start and in
//! summary.json, what the scaling does to its timing.

use std::process::Command;

const SCENE: &str = r#"[simulation]
end_time = 0.002
frames = 2
mass_scaling_dt = 1e-5

[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
blank = { width = 100, height = 100, cells = [10, 10] }

[[tools]]
name = "mould"
geometry = { kind = "plane", point = [0, 0, -5], normal = [0, 0, 1] }

[[pressure]]
value = 1e-4
towards = "mould"
amplitude = { kind = "smooth_step", duration = 0.002 }

[output]
vtu = false
pictures = false
"#;

#[test]
fn a_pressure_under_mass_scaling_warns_about_its_timing() {
    let dir = std::env::temp_dir().join(format!("drape-cli-{}-pressure", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("bag.toml");
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
    assert_eq!(o.status.code(), Some(0), "{printed}");
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    assert_eq!(summary["status"], "completed");
    let warnings: Vec<&str> = summary["warnings"]
        .as_array()
        .unwrap()
        .iter()
        .map(|w| w.as_str().unwrap())
        .collect();
    let timing = warnings
        .iter()
        .find(|w| w.contains("mass scaling makes the blank"))
        .unwrap_or_else(|| panic!("no timing warning in {warnings:?}"));
    // The blank is 5 mm above the mould: the distance to travel.
    for part in [
        "pressure acts on the physical mass",
        "over the 5.0 mm",
        "the end time 0.002 s is shorter",
    ] {
        assert!(timing.contains(part), "`{part}` in {timing}");
    }
    assert!(
        printed.contains("mass scaling makes the blank"),
        "{printed}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
