//! The small things a new user meets first, end to end: the mould `drape
//! kinematic` picks and names, the draw-in's reason when it is missing,
//! integer counts, sane ratios and a laminate's plies in `drape inspect`,
//! a closed pipe, `drape new`'s list,
//! `output.shear_range_deg` and the waviness picture.

use std::path::Path;

mod common;
use common::*;

/// A fixed disc (radius 70 mm, 10 mm under the blank) and a sphere above
/// the blank coming down onto it: the blank is pressed onto the disc.
const PRESSED: &str = r#"
[simulation]
end_time = 1.0

[fabric]
material = "glass-serge-4x3"
fibres = "embedded"
blank = { width = 120, height = 120, cells = [12, 12], center = [0, 0, 0] }

[[tools]]
name = "punch"
geometry = { kind = "sphere", center = [0, 0, 60], radius = 50 }
motion = { kind = "displacement", direction = [0, 0, -1], distance = 40, amplitude = { kind = "ramp", duration = 1.0 } }

[[tools]]
name = "table"
geometry = { kind = "revolution", origin = [0, 0, -10], profile = [{ kind = "line", from = [0, 0], to = [70, 0] }] }
"#;

fn write_scene(dir: &Path, text: &str) -> String {
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_owned()
}

/// The issue: a scene with a fixed mould and a moving punch was draped on
/// the punch, silently. Now the fixed tool the punch presses into is the
/// mould, the output names it and says how to choose another; and the
/// corners the net does not reach (the disc ends at 70 mm, the corners are
/// 85 mm out) leave DD missing with that reason, not "not a rectangular
/// blank", while DX and DY are measured (0 on a flat disc).
#[test]
fn kinematic_names_its_mould_and_why_a_draw_in_is_missing() {
    let dir = temp("pressed");
    let scene = write_scene(&dir, PRESSED);
    let out = dir.join("out");
    let o = drape(&["kinematic", &scene, "--out", out.to_str().unwrap()]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains(
            "mould             `table`: the fixed tool that the moving tool `punch` presses \
             the blank into (another: --set kinematic.mould=NAME)"
        ),
        "{t}"
    );
    assert!(
        t.contains(
            "draw-in           DX 0.00 mm, DY 0.00 mm, DD n/a (DD (a corner): not on the draped net"
        ),
        "{t}"
    );
    assert!(!t.contains("not a rectangular blank"), "{t}");
    let s = json(&out.join("summary.json"));
    assert_eq!(s["run"]["mould"], "table");
    assert!(s["draw_in_mm"]["dd"].is_null());
    assert!(s["draw_in_note"].as_str().unwrap().contains("a corner"));
    // On the disc, 10 mm down: flat, so no shear, and not on the punch.
    assert!(s["max_shear_deg"].as_f64().unwrap() < 1e-9, "{s}");
    assert!(
        (s["max_shear_at"][2].as_f64().unwrap() + 10.0).abs() < 1e-9,
        "{s}"
    );
    assert!(out.join("waviness_map.png").is_file());

    // Named, the punch is taken, and the output says so.
    let o = drape(&[
        "kinematic",
        &scene,
        "--out",
        out.to_str().unwrap(),
        "--set",
        "kinematic.mould=punch",
    ]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("mould             `punch`: given by kinematic.mould"),
        "{t}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// `drape new` alone lists the templates and exits 2 like a usage error,
/// writing nothing.
#[test]
fn new_without_a_template_lists_them() {
    let dir = temp("new");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_drape"))
        .arg("new")
        .current_dir(&dir)
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("drape new TEMPLATE [PATH]"), "{err}");
    let help = text(&drape(&["new", "--help"]));
    for name in [
        "hemisphere",
        "deep-drawing",
        "picture-frame",
        "bias-extension",
        "stack",
    ] {
        assert!(err.contains(&format!("\n  {name} ")), "{name}: {err}");
        assert!(
            help.contains(name),
            "`drape new --help` omits {name}: {help}"
        );
    }
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 0);
    // An unknown name gets the same list.
    let o = drape(&["new", "teapot"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(text(&o).contains("unknown template `teapot`; the templates are\n  hemisphere"));
    std::fs::remove_dir_all(dir).unwrap();
}

/// A summary as an unstrained, still moving blank leaves it (the ratio
/// null, the energies given) and a long run's step count: `drape inspect`
/// prints energies, not "4641261081691772420096.0 %", and the count as an
/// integer.
#[test]
fn inspect_prints_energies_for_an_unstrained_blank_and_counts_as_integers() {
    let dir = temp("inspect");
    let summary = r#"{
  "status": "completed",
  "scene": "s.toml",
  "time": 0.1,
  "max_shear_deg": 0.0,
  "max_shear_at": [0.0, 0.0, 0.0],
  "draw_in_mm": { "dx": null, "dy": null, "dd": null },
  "draw_in_note": "the blank is a mesh file: draw-in is measured at a rectangular blank's edge midpoints and corners",
  "max_fibre_tension_n": null,
  "area_above_locking_mm2": 0.0,
  "energy": { "balance_error": 1e-6, "kinetic_to_internal": null, "kinetic_mj": 12.5, "internal_mj": 2.7e-21 },
  "run": { "wall_s": 3.0, "steps": 52794, "threads": 2, "solver": "explicit" }
}"#;
    std::fs::write(dir.join("summary.json"), summary).unwrap();
    let o = drape(&["inspect", dir.to_str().unwrap()]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("E_kin 1.250e1 mJ, E_int 2.700e-21 mJ (the blank is barely strained: no ratio)"),
        "{t}"
    );
    assert!(t.contains("in 52794 steps"), "{t}");
    assert!(!t.contains("52794.0"), "{t}");
    assert!(
        t.contains("draw-in           DX n/a, DY n/a, DD n/a (the blank is a mesh file"),
        "{t}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A laminate's summary: `drape inspect` prints a line per ply, bottom
/// first, with what `summary.json`'s `plies` holds.
#[test]
fn inspect_prints_each_ply_of_a_laminate() {
    let dir = temp("inspect-plies");
    let ply = |name: &str, shear: f64, slip: f64| {
        format!(
            r#"{{ "name": "{name}", "max_shear_deg": {shear}, "max_waviness_deg": 12.5,
                "wrinkle_area_mm2": 0.0, "draw_in_mm": {{ "dx": 6.6, "dy": 6.55, "dd": 4.21 }},
                "max_slip_mm": {slip}, "max_pressure_mpa": 0.0057, "max_overlap_mm": 1.9e-5 }}"#
        )
    };
    let summary = format!(
        r#"{{
  "status": "completed",
  "scene": "s.toml",
  "time": 0.3,
  "max_shear_deg": 6.23,
  "max_shear_at": [0.0, 0.0, 0.0],
  "draw_in_mm": {{ "dx": 6.6, "dy": 6.55, "dd": 4.21 }},
  "max_fibre_tension_n": null,
  "area_above_locking_mm2": 0.0,
  "energy": {{ "balance_error": 1e-6, "kinetic_to_internal": 0.01, "kinetic_mj": 1.0, "internal_mj": 100.0 }},
  "run": {{ "wall_s": 3.0, "steps": 15003, "threads": 2, "solver": "explicit" }},
  "plies": [{}, {}]
}}"#,
        ply("p0", 6.23, 0.0),
        ply("p45", 1.94, 2.212)
    );
    std::fs::write(dir.join("summary.json"), summary).unwrap();
    let o = drape(&["inspect", dir.to_str().unwrap()]);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    let bottom = t.find("ply p0            max shear 6.23°").expect(&t);
    let top = t.find("ply p45           max shear 1.94°").expect(&t);
    assert!(bottom < top, "bottom ply first: {t}");
    assert!(
        t.contains("draw-in DX 6.60 mm, DY 6.55 mm, DD 4.21 mm; slip on the ply below 2.212 mm"),
        "{t}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// Output into a pipe nobody reads (`drape inspect DIR | head` once head
/// has what it wants) ends drape by SIGPIPE, as it ends `cat`, not by a
/// panic on the broken pipe.
#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_drape_without_a_panic() {
    use std::os::unix::process::ExitStatusExt;
    let dir = temp("closed-pipe");
    std::fs::write(
        dir.join("summary.json"),
        r#"{ "status": "completed", "scene": "s.toml", "time": 0.1, "max_shear_deg": 0.0,
            "max_shear_at": [0.0, 0.0, 0.0], "draw_in_mm": { "dx": 1.0, "dy": 1.0, "dd": 1.0 },
            "max_fibre_tension_n": null, "area_above_locking_mm2": 0.0,
            "energy": { "balance_error": 1e-6, "kinetic_to_internal": 0.01, "kinetic_mj": 1.0, "internal_mj": 100.0 },
            "run": { "wall_s": 3.0, "steps": 10, "threads": 2, "solver": "explicit" } }"#,
    )
    .unwrap();
    // The reading end is closed before drape starts: its first line meets
    // a broken pipe.
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(["inspect", dir.to_str().unwrap()])
        .stdout(writer)
        .stderr(std::process::Stdio::piped())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!err.contains("panicked"), "{err}");
    const SIGPIPE: i32 = 13;
    assert_eq!(o.status.signal(), Some(SIGPIPE), "{:?}: {err}", o.status);
    std::fs::remove_dir_all(dir).unwrap();
}

/// Viridis' top colour, which only the most sheared element and the top
/// of the colour bar take.
const YELLOW: [u8; 3] = [253, 231, 37];

/// Pixels of `colour` left of the colour-bar column of `shear_map.png`.
fn map_pixels_of(png_path: &Path, colour: [u8; 3]) -> usize {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(png_path).unwrap(),
    ));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgb);
    let (w, h) = (info.width as usize, info.height as usize);
    (0..h)
        .flat_map(|y| (0..w - 190).map(move |x| (x, y)))
        .filter(|&(x, y)| buf[3 * (y * w + x)..3 * (y * w + x) + 3] == colour)
        .count()
}

/// `output.shear_range_deg` colours the shear map over the given range:
/// on the hemisphere's net (largest shear 85°), [0, 10] paints every
/// element sheared past 10° in viridis' top colour, where the net's own
/// range (0 to 85°) gives that colour to hardly any. A range that is not
/// increasing is bad input naming the key.
#[test]
fn a_fixed_shear_range_recolours_the_map_and_is_checked() {
    let dir = temp("range");
    let own = dir.join("own");
    let fixed = dir.join("fixed");
    let o = drape(&[
        "kinematic",
        "scenes/hemisphere-0-90.toml",
        "--out",
        own.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let largest = json(&own.join("summary.json"))["max_shear_deg"]
        .as_f64()
        .unwrap();
    assert!(largest > 20.0, "{largest}");
    let o = drape(&[
        "kinematic",
        "scenes/hemisphere-0-90.toml",
        "--out",
        fixed.to_str().unwrap(),
        "--set",
        "output.shear_range_deg=[0, 10]",
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let (before, after) = (
        map_pixels_of(&own.join("shear_map.png"), YELLOW),
        map_pixels_of(&fixed.join("shear_map.png"), YELLOW),
    );
    assert!(after > 20 * before.max(500), "{before} → {after}");

    let bad = write_scene(
        &dir,
        &format!("{PRESSED}\n[output]\nshear_range_deg = [30, 10]\n"),
    );
    let out = dir.join("bad");
    let o = drape(&["kinematic", &bad, "--out", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    let t = text(&o);
    assert!(t.contains("output.shear_range_deg"), "{t}");
    assert!(t.contains("0 ≤ min < max"), "{t}");
    assert!(!out.exists());
    std::fs::remove_dir_all(dir).unwrap();
}
