//! A forming engineer's day after a run, end to end: what a run writes
//! beside its frames (trusses, tools, the oblique picture, the exported
//! orientations, peaks and set-up in the summary), `drape compare RUN_A
//! RUN_B`, `drape export --onto`, `drape inspect` of a sweep and
//! `sweep.png`.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

mod common;
use common::*;

/// (width, height, distinct colours, fraction of pixels that are not white).
fn png_stats(path: &Path) -> (u32, u32, usize, f64) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(
        &bytes[..8],
        b"\x89PNG\r\n\x1a\n",
        "{} is not a PNG",
        path.display()
    );
    let decoder = png::Decoder::new(std::io::Cursor::new(bytes));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    let pixels: Vec<&[u8]> = buf[..info.buffer_size()].chunks_exact(3).collect();
    let inked = pixels.iter().filter(|p| **p != [255, 255, 255]).count();
    let mut colours = pixels.clone();
    colours.sort_unstable();
    colours.dedup();
    (
        info.width,
        info.height,
        colours.len(),
        inked as f64 / pixels.len() as f64,
    )
}

/// `drape run` of the shared draped scene, which must complete.
fn run(dir: &Path, name: &str, set: &[&str]) -> (PathBuf, Output) {
    let (out, o) = run_draped(dir, name, set);
    assert!(o.status.success(), "{}", text(&o));
    (out, o)
}

fn has_meshio() -> bool {
    Command::new("python3")
        .args(["-c", "import meshio"])
        .output()
        .is_ok_and(|o| o.status.success())
}

fn check_vtu(args: &[&str]) {
    let script = workspace().join("tests/check_vtu.py");
    let o = Command::new("python3")
        .arg(script)
        .args(args)
        .output()
        .unwrap();
    assert!(o.status.success(), "check_vtu.py {args:?}:\n{}", text(&o));
}

#[test]
fn a_draping_run_writes_what_the_engineer_carries_on() {
    let dir = temp("carry");
    let (out, o) = run(&dir, "run", &[]);
    let said = text(&o);
    // The set-up, printed before the run.
    assert!(
        said.contains("model             221 nodes, 220 membrane elements, 400 trusses"),
        "{said}"
    );
    assert!(said.contains("mass-scaled to 2.000e-6 s"), "{said}");
    for f in [
        "trusses.pvd",
        "tools.pvd",
        "frames/trusses_00004.vtu",
        "frames/tools_00004.vtu",
        "shear_3d.png",
        "orientations.inp",
        "orientations.csv",
    ] {
        assert!(out.join(f).is_file(), "{f} missing");
    }
    let s = json(&out.join("summary.json"));
    // A 4 ms stroke ends with the blank still moving (E_kin/E_int ≈ 1.7):
    // the run says its answer carries inertia, on the screen and in the
    // summary.
    let share = s["energy"]["kinetic_to_internal"].as_f64().unwrap();
    assert!(share > drape::QUASI_STATIC_KINETIC_SHARE, "{s}");
    let moving = format!(
        "the kinetic energy at the end is {:.1} % of the internal energy",
        100.0 * share
    );
    assert!(
        s["warnings"]
            .as_array()
            .unwrap()
            .iter()
            .any(|w| w.as_str().unwrap().contains(&moving)),
        "{s}"
    );
    assert!(
        said.contains(&format!("warning           {moving}")),
        "{said}"
    );
    let (end, peak) = (
        s["max_shear_deg"].as_f64().unwrap(),
        s["peak"]["max_shear_deg"].as_f64().unwrap(),
    );
    assert!(peak >= end && end > 1.0, "{s}");
    let when = s["peak"]["max_shear_time_s"].as_f64().unwrap();
    assert!((0.0..=0.004 + 1e-12).contains(&when), "{s}");
    // Trusses: a force in N and the tension per width in N/mm, both
    // reported (the io tests check that one is the other over the strip).
    let force = s["max_fibre_tension_n"].as_f64().unwrap();
    let per_width = s["max_fibre_tension_n_per_mm"].as_f64().unwrap();
    assert!(force > 0.0 && per_width > 0.0, "{s}");
    assert!(s["peak"]["max_fibre_tension_n_per_mm"].as_f64().unwrap() >= per_width);
    let setup = &s["setup"];
    assert_eq!(setup["nodes"], 221);
    assert_eq!(setup["fibres"], "trusses");
    assert_eq!(setup["mass_scaling_dt_s"], 2e-6);
    assert!(setup["added_mass_t"].as_f64().unwrap() > 0.0, "{setup}");
    let (expected, steps) = (
        setup["expected_steps"].as_f64().unwrap(),
        s["run"]["steps"].as_f64().unwrap(),
    );
    assert!(
        (expected / steps - 1.0).abs() < 0.2,
        "{expected} vs {steps}"
    );

    let (w, h, colours, inked) = png_stats(&out.join("shear_3d.png"));
    assert_eq!((w, h), (1000, 820));
    assert!(
        colours > 50 && inked > 0.1,
        "{colours} colours, {inked} inked"
    );

    // Read back by meshio: the fibres against the shear of a real run, the
    // trusses' stretch, the punch moved its 10 mm.
    if has_meshio() {
        check_vtu(&[
            out.join("series.pvd").to_str().unwrap(),
            "--fibres-vs-shear",
            "1e-9",
            "--frames",
            "5",
        ]);
        check_vtu(&[
            out.join("trusses.pvd").to_str().unwrap(),
            "--cell-type",
            "line",
            "--truss-stretch",
        ]);
        check_vtu(&[
            out.join("tools.pvd").to_str().unwrap(),
            "--cell-type",
            "triangle",
            "--cell-data",
            "tool",
            "--shift",
            "0,0,10",
        ]);
    } else {
        eprintln!("note: python3 with meshio not found; skipping tests/check_vtu.py");
    }

    // The orientations onto a structural mesh: here the formed mesh itself
    // (the include's S4R/S3 elements), so every element is on the part.
    let mapped = dir.join("mapped");
    let o = drape(&[
        "export",
        out.to_str().unwrap(),
        "--onto",
        out.join("orientations.inp").to_str().unwrap(),
        "--out",
        mapped.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    assert!(
        text(&o).contains("mapped            220 elements"),
        "{}",
        text(&o)
    );
    let csv = std::fs::read_to_string(mapped.join("orientations_orientations.csv")).unwrap();
    assert_eq!(csv.lines().count(), 221);
    let largest = csv
        .lines()
        .skip(1)
        .map(|l| l.rsplit(',').next().unwrap().parse::<f64>().unwrap())
        .fold(0.0, f64::max);
    assert!(largest < 0.05, "largest distance {largest} mm");
    assert!(mapped.join("orientations_orientations.inp").is_file());
    // A folder without orientations is bad input.
    let o = drape(&[
        "export",
        dir.to_str().unwrap(),
        "--onto",
        "scenes/meshes/plate.msh",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("no orientations.inp"), "{}", text(&o));

    let o = drape(&["inspect", out.to_str().unwrap()]);
    assert!(o.status.success());
    assert!(
        text(&o).contains("yarn tension") && text(&o).contains("time step"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn compare_two_results_folders() {
    let dir = temp("compare");
    let (a, _) = run(&dir, "a", &[]);
    let (b, _) = run(&dir, "b", &["tools.0.friction=0.5"]);
    let (fine, _) = run(&dir, "fine", &["fabric.blank.cells=[20,20]"]);

    let out = dir.join("a-vs-b");
    let o = drape(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let said = text(&o);
    assert!(
        said.contains("largest |shear| over the run (deg)"),
        "{said}"
    );
    let c = json(&out.join("comparison.json"));
    assert_eq!(c["same_mesh"], true);
    assert_eq!(c["elements"], 220);
    assert_eq!(c["compared"], 220);
    let max = c["max_abs_difference_deg"].as_f64().unwrap();
    assert!(max > 0.0, "friction changes the shear: {c}");
    // The side-by-side measures are the two summaries'.
    let (sa, sb) = (json(&a.join("summary.json")), json(&b.join("summary.json")));
    let row = c["measures"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "largest |shear| at the end")
        .unwrap()
        .clone();
    assert_eq!(row["a"], sa["max_shear_deg"]);
    assert_eq!(row["b"], sb["max_shear_deg"]);
    let csv = std::fs::read_to_string(out.join("comparison.csv")).unwrap();
    assert_eq!(csv.lines().count(), 221);
    // The profiles, point by point: the RMS along each line from the two
    // runs' profiles.csv.
    let profile = |dir: &Path, line: &str| -> Vec<f64> {
        std::fs::read_to_string(dir.join("profiles.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .filter(|l| l.starts_with(&format!("{line},")))
            .map(|l| l.rsplit(',').next().unwrap().parse().unwrap())
            .collect()
    };
    let profiles = c["profiles"].as_array().unwrap();
    assert_eq!(profiles.len(), 2, "{c}");
    for (p, line) in profiles.iter().zip(["diagonal", "median"]) {
        let (ga, gb) = (profile(&a, line), profile(&b, line));
        assert!(!ga.is_empty() && ga.len() == gb.len());
        let rms = (ga
            .iter()
            .zip(&gb)
            .map(|(x, y)| (y - x).powi(2))
            .sum::<f64>()
            / ga.len() as f64)
            .sqrt();
        assert_eq!(p["line"], line);
        assert_eq!(p["points"], ga.len());
        let got = p["rms_difference_deg"].as_f64().unwrap();
        assert!(
            rms > 0.0 && (got - rms).abs() <= 1e-12 * rms,
            "{got} vs {rms}"
        );
        assert!(p["max_abs_difference_deg"].as_f64().unwrap() >= rms);
    }
    assert!(said.contains("shear along the diagonal: "), "{said}");
    // The difference map: three panels, drawn.
    let (w, h, colours, inked) = png_stats(&out.join("comparison.png"));
    assert_eq!((w, h), (3 * 620, 720));
    assert!(
        colours > 50 && inked > 0.2,
        "{colours} colours, {inked} inked"
    );

    // A run against itself: no difference at all.
    let o = drape(&[
        "compare",
        a.to_str().unwrap(),
        a.to_str().unwrap(),
        "--out",
        dir.join("same").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let c = json(&dir.join("same/comparison.json"));
    assert_eq!(c["max_abs_difference_deg"], 0.0);
    for p in c["profiles"].as_array().unwrap() {
        assert_eq!(p["rms_difference_deg"], 0.0, "{c}");
    }

    // A finer mesh of the same blank: carried onto A's mesh by closest
    // point, every element of A on it.
    let o = drape(&[
        "compare",
        a.to_str().unwrap(),
        fine.to_str().unwrap(),
        "--out",
        dir.join("fine-vs-a").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let c = json(&dir.join("fine-vs-a/comparison.json"));
    assert_eq!(c["same_mesh"], false);
    assert_eq!(c["compared"], 220, "{c}");
    // Profiles sampled at other distances are not compared.
    assert_eq!(c["profiles"].as_array().unwrap().len(), 0, "{c}");

    // Bad input: a broken profiles.csv (named, with its line), a folder
    // that is not a run's, and --set with two folders.
    std::fs::write(
        b.join("profiles.csv"),
        "line,distance_mm,shear_deg\ndiagonal,1.0,x\n",
    )
    .unwrap();
    let o = drape(&["compare", a.to_str().unwrap(), b.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("profiles.csv line 2: expected a line name and two finite numbers"),
        "{}",
        text(&o)
    );
    let o = drape(&["compare", a.to_str().unwrap(), dir.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(text(&o).contains("no summary.json"), "{}", text(&o));
    let o = drape(&[
        "compare",
        a.to_str().unwrap(),
        b.to_str().unwrap(),
        "--set",
        "a=1",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    // One folder alone: the scene form, which says how to compare folders.
    let o = drape(&["compare", a.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", text(&o));
    assert!(
        text(&o).contains("drape compare RUN_A RUN_B"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// A forming run against its kinematic net: the scene comparison (`drape
/// compare SCENE`, the net read bilinearly between its cell centres) and
/// the folder comparison of its two results folders (the net's shear
/// carried by closest point on its flat mesh) agree.
#[test]
fn a_folder_comparison_agrees_with_the_scene_comparison() {
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
    let dir = temp("net");
    let scene = dir.join("falling.toml");
    std::fs::write(&scene, FALLING).unwrap();
    let both = dir.join("both");
    let o = drape(&[
        "compare",
        scene.to_str().unwrap(),
        "--out",
        both.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    // The forming run's line says what its summary warns of.
    let run = json(&both.join("mechanical/summary.json"));
    let warnings = run["warnings"].as_array().unwrap().len();
    let said = match warnings {
        0 => "no warning".to_string(),
        1 => "1 warning (see its summary.json)".to_string(),
        n => format!("{n} warnings (see its summary.json)"),
    };
    assert_eq!(run["fold"]["folded"], false, "{run}");
    assert!(
        text(&o).contains(&format!(
            "forming run       completed ({}), {said}",
            both.join("mechanical").display()
        )),
        "{}",
        text(&o)
    );
    let scene_way = json(&both.join("comparison.json"));
    let o = drape(&[
        "compare",
        both.join("mechanical").to_str().unwrap(),
        both.join("kinematic").to_str().unwrap(),
        "--out",
        dir.join("folders").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let folder_way = json(&dir.join("folders/comparison.json"));
    assert_eq!(folder_way["same_mesh"], false);
    assert_eq!(
        folder_way["compared"], scene_way["compared"],
        "{folder_way}"
    );
    let (r1, r2) = (
        scene_way["all"]["rms_deg"].as_f64().unwrap(),
        folder_way["rms_difference_deg"].as_f64().unwrap(),
    );
    // The net's flat mesh is the run's (8 × 8 cells, other node numbers):
    // each element's centroid is a cell centre of the net, where both ways
    // read the cell's own shear.
    assert!((r1 - r2).abs() < 1e-9, "rms {r1} (scene) vs {r2} (folders)");
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_sweep_draws_its_measure_and_inspect_reads_its_folder() {
    let dir = temp("sweep");
    let out = dir.join("sweep");
    let o = drape(&[
        "sweep",
        "scenes/picture-frame.toml",
        "--set",
        "boundary.0.motion.shear_deg=20,40",
        "--set",
        "fabric.material=glass-serge-4x3,carbon-prepreg-2x2",
        "--set",
        "simulation.frames=1",
        "--set",
        "simulation.end_time=0.01",
        "--set",
        "boundary.0.motion.amplitude.duration=0.01",
        "--set",
        "output.vtu=false",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let (w, h, colours, inked) = png_stats(&out.join("sweep.png"));
    // Two swept keys across; max shear, DX and DD down (a rectangle).
    assert_eq!((w, h), (2 * 560, 3 * 400));
    assert!(
        colours > 10 && inked > 0.03,
        "{colours} colours, {inked} inked"
    );
    let table = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    assert!(
        table
            .lines()
            .next()
            .unwrap()
            .ends_with(",peak_max_shear_deg,peak_time_s,max_fibre_tension_n_per_mm")
    );
    let o = drape(&["inspect", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));
    let said = text(&o);
    assert!(
        said.contains("(4 runs)") && said.contains("run_003"),
        "{said}"
    );
    std::fs::remove_dir_all(dir).unwrap();
}
