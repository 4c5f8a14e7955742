//! A laminate end to end: a two-ply run writes one shear map, oblique
//! view and waviness map per ply and its orientations as a layup (a `ply`
//! column in the table), and `drape export --onto` carries every ply onto
//! a structural mesh; a one-ply run writes no per-ply picture. Its shear
//! profiles are each ply's own (`profiles.csv` with a `ply` column,
//! `profiles_<ply>.png`), `drape compare` of two laminates compares
//! them ply by ply, by name, a sweep's table has each ply's columns, and
//! `drape compare SCENE` compares one ply with its own kinematic net.

use std::path::Path;

mod common;
use common::*;

/// `scenes/hemisphere-stack.toml` (plies `p0` under `p45`), coarse and
/// short; with `plies` 1, as `[fabric]` alone (`stack` false) or as a
/// stack of its bottom ply.
fn scene(dir: &Path, plies: usize, stack: bool) -> String {
    let text = std::fs::read_to_string(workspace().join("scenes/hemisphere-stack.toml")).unwrap();
    let mut text = text
        .replace("cells = [24, 24]", "cells = [6, 6]")
        .replace("end_time = 1.0 ", "end_time = 0.05 ")
        .replace("frames = 20 ", "frames = 2 ");
    assert!(text.contains("end_time = 0.05") && text.contains("cells = [6, 6]"));
    if plies == 1 {
        let (start, end) = (
            text.find("\n[stack]\n").unwrap(),
            text.find("[[tools]]").unwrap(),
        );
        let one = if stack {
            "\n[stack]\n[[stack.ply]]\nname = \"p0\"\n\n"
        } else {
            "\n"
        };
        text.replace_range(start..end, one);
        text = text.replace("blank = {", "bending = false\nblank = {");
    }
    let path = dir.join(format!("{plies}-{stack}.toml"));
    std::fs::write(&path, text).unwrap();
    path.to_str().unwrap().to_owned()
}

/// A flat structural mesh of two S4R quads, 40 × 20 mm about the axis at
/// z = −5 mm (under the plies, which the punch lifts).
const PLATE: &str = "\
*NODE
1, -20, -10, -5
2, 0, -10, -5
3, 20, -10, -5
4, -20, 10, -5
5, 0, 10, -5
6, 20, 10, -5
*ELEMENT, TYPE=S4R, ELSET=PLATE
11, 1, 2, 5, 4
12, 2, 3, 6, 5
";

/// The angle of the warp columns of a CSV row to x, degrees (0..180).
fn warp_angle(row: &[&str], header: &[&str]) -> f64 {
    let col = |name: &str| header.iter().position(|h| *h == name).unwrap();
    let (x, y): (f64, f64) = (
        row[col("warp_x")].parse().unwrap(),
        row[col("warp_y")].parse().unwrap(),
    );
    y.atan2(x).to_degrees().rem_euclid(180.0)
}

/// A sweep of the ply–ply friction tabulates each ply of a laminate: its
/// largest shear, waviness and slip on the ply below, as its run's
/// `summary.json` has them; a one-ply sweep has no ply columns.
#[test]
fn a_sweep_of_a_stack_has_each_plys_columns() {
    let dir = temp("stack-sweep");
    let out = dir.join("sweep");
    let scene_path = scene(&dir, 2, true);
    let o = drape(&[
        "sweep",
        &scene_path,
        "--set",
        "stack.friction=0,0.5",
        "--out",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let table = std::fs::read_to_string(out.join("sweep.csv")).unwrap();
    let rows: Vec<Vec<&str>> = table.lines().map(|l| l.split(',').collect()).collect();
    let header = &rows[0];
    assert_eq!(
        header.last(),
        Some(&"max_fibre_tension_n_per_mm"),
        "{table}"
    );
    let col = |name: &str| {
        header
            .iter()
            .position(|h| *h == name)
            .unwrap_or_else(|| panic!("no column {name}: {table}"))
    };
    for (run, row) in rows[1..].iter().enumerate() {
        let summary: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(out.join(format!("run_{run:03}/summary.json"))).unwrap(),
        )
        .unwrap();
        let plies = summary["plies"].as_array().unwrap();
        assert_eq!(plies.len(), 2);
        for ply in plies {
            let name = ply["name"].as_str().unwrap();
            for key in ["max_shear_deg", "max_waviness_deg", "max_slip_mm"] {
                let value = ply[key].as_f64().unwrap();
                assert_eq!(
                    row[col(&format!("{name}_{key}"))],
                    format!("{value:.4}"),
                    "run {run}, {name}: {table}"
                );
            }
        }
    }
    let slip = |run: usize| {
        rows[run + 1][col("p45_max_slip_mm")]
            .parse::<f64>()
            .unwrap()
    };
    assert!(
        slip(0) > 0.0,
        "the top ply slides on the bottom one: {table}"
    );
    // One ply: no ply columns.
    let one = dir.join("one");
    let o = drape(&[
        "sweep",
        &scene(&dir, 1, false),
        "--set",
        "tools.0.friction=0.1",
        "--out",
        one.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o));
    let table = std::fs::read_to_string(one.join("sweep.csv")).unwrap();
    assert!(!table.contains("p0_"), "{table}");
    std::fs::remove_dir_all(dir).unwrap();
}

/// `drape compare SCENE` of a laminate drapes one ply's net (the bottom
/// one unless `kinematic.ply` names another, at that ply's orientation)
/// and compares it with that ply's elements only: the two plies' counts
/// add up to the run's elements, and the summary names the ply.
#[test]
fn a_laminate_compares_one_ply_with_its_own_net() {
    let dir = temp("stack-compare");
    let scene_path = scene(&dir, 2, true);
    let compared = |ply: Option<&str>| {
        let out = dir.join(format!("compare-{}", ply.unwrap_or("default")));
        let mut args = vec!["compare", &scene_path, "--out", out.to_str().unwrap()];
        let set = ply.map(|p| format!("kinematic.ply={p}"));
        if let Some(set) = &set {
            args.extend(["--set", set]);
        }
        let o = drape(&args);
        assert!(o.status.success(), "{}", text(&o));
        let json = |path: &Path| -> serde_json::Value {
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
        };
        let comparison = json(&out.join("comparison.json"));
        let net = json(&out.join("kinematic/summary.json"));
        let run = json(&out.join("mechanical/summary.json"));
        let rows = std::fs::read_to_string(out.join("comparison.csv"))
            .unwrap()
            .lines()
            .count()
            - 1;
        let elements = comparison["elements"].as_u64().unwrap() as usize;
        assert_eq!(rows, elements, "a row per compared ply's element");
        (
            elements,
            net["run"]["ply"].as_str().unwrap().to_owned(),
            run["setup"]["membrane_elements"].as_u64().unwrap() as usize,
        )
    };
    let (bottom, name, all) = compared(None);
    assert_eq!(name, "p0");
    assert_eq!(bottom, 36, "the bottom ply's 6 × 6 cells");
    let (top, name, _) = compared(Some("p45"));
    assert_eq!(name, "p45");
    assert_eq!(bottom + top, all);
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn a_stack_pictures_and_exports_every_ply() {
    let dir = temp("stack");
    let out = dir.join("out");
    let o = drape(&["run", &scene(&dir, 2, true), "--out", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o));

    // Each ply's largest overlap with the ply below over the run, within
    // the 1 % of the 0.3 mm thickness (none below the bottom one).
    let summary = json(&out.join("summary.json"));
    let overlap = |p: usize| summary["plies"][p]["max_overlap_mm"].as_f64().unwrap();
    assert_eq!(overlap(0), 0.0);
    assert!((0.0..=3e-3).contains(&overlap(1)), "{}", overlap(1));

    // One picture per ply beside the overlaid one, on the same frame.
    let size = |name: &str| {
        let decoder = png::Decoder::new(std::io::BufReader::new(
            std::fs::File::open(out.join(name)).unwrap(),
        ));
        let reader = decoder.read_info().unwrap();
        let info = reader.info();
        (info.width, info.height)
    };
    let whole = size("shear_map.png");
    assert_eq!(size("shear_map_p0.png"), whole);
    assert_eq!(size("shear_map_p45.png"), whole);
    let bytes = |name: &str| std::fs::read(out.join(name)).unwrap();
    assert_ne!(bytes("shear_map_p0.png"), bytes("shear_map_p45.png"));
    // The oblique view and the waviness map one per ply only: overlaid,
    // the plies speckle through each other (3D) or the top one hides the
    // rest (the flat blank).
    for picture in ["shear_3d", "waviness_map", "profiles"] {
        assert!(!out.join(format!("{picture}.png")).exists(), "{picture}");
        let [p0, p45] = ["p0", "p45"].map(|p| bytes(&format!("{picture}_{p}.png")));
        assert_ne!(p0, p45, "{picture}");
    }

    // Each ply's own profiles, under a ply column, bottom ply first.
    let profiles = std::fs::read_to_string(out.join("profiles.csv")).unwrap();
    let plies_of = |line: &str| {
        profiles
            .lines()
            .skip(1)
            .filter(|r| r.split(',').nth(1) == Some(line))
            .map(|r| r.split(',').next().unwrap().to_owned())
            .collect::<Vec<_>>()
    };
    assert!(profiles.starts_with("ply,line,distance_mm,shear_deg\np0,diagonal,"));
    for line in ["diagonal", "median"] {
        let plies = plies_of(line);
        let p0 = plies.iter().filter(|p| *p == "p0").count();
        // Both plies, each along its own blank's line (p45's cells turned
        // with its warp: fewer centroids within the band).
        assert!(p0 > 0 && plies.len() > p0, "{line}: {profiles}");
        assert!(plies[..p0].iter().all(|p| p == "p0"), "{profiles}");
    }

    // The table: a ply column, each ply's rows with its own warp.
    let csv = std::fs::read_to_string(out.join("orientations.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    assert_eq!(header[..2], ["ply", "element"]);
    let inp = std::fs::read_to_string(out.join("orientations.inp")).unwrap();
    assert!(inp.contains("** plies, bottom to top: p0, p45\n"));
    assert!(inp.contains("*ELSET, ELSET=p45\n"));
    assert!(inp.contains("*ORIENTATION, NAME=p45_WARP,"));

    // Onto a structural mesh: both plies over its two elements.
    std::fs::write(dir.join("plate.inp"), PLATE).unwrap();
    let mapped = dir.join("mapped");
    let o = drape(&[
        "export",
        out.to_str().unwrap(),
        "--onto",
        dir.join("plate.inp").to_str().unwrap(),
        "--out",
        mapped.to_str().unwrap(),
    ]);
    let said = text(&o);
    assert!(o.status.success(), "{said}");
    assert!(
        said.contains("mapped            2 elements of")
            && said.contains("onto each of the 2 plies of")
            && said.contains("(p0, p45)"),
        "{said}"
    );
    let csv = std::fs::read_to_string(mapped.join("orientations_plate.csv")).unwrap();
    let mut lines = csv.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(header[..2], ["ply", "element"]);
    assert_eq!(header.last(), Some(&"distance_mm"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    let plies: Vec<(&str, &str)> = rows.iter().map(|r| (r[0], r[1])).collect();
    assert_eq!(
        plies,
        [("p0", "11"), ("p0", "12"), ("p45", "11"), ("p45", "12")]
    );
    let distance = |r: &Vec<&str>| r.last().unwrap().parse::<f64>().unwrap();
    for (k, r) in rows.iter().enumerate() {
        // Near the pole the plies are still flat: their warps at 0° and 45°.
        let want = if k < 2 { 0.0 } else { 45.0 };
        let a = warp_angle(r, &header);
        let off = (a - want).abs().min(180.0 - (a - want).abs());
        assert!(off < 2.0, "row {k}: warp at {a}°: {csv}");
        assert!(distance(r) < 10.0, "row {k}: {csv}");
    }
    // The top ply above the bottom one.
    for k in 0..2 {
        assert!(distance(&rows[k + 2]) > distance(&rows[k]), "{csv}");
    }
    let inp = std::fs::read_to_string(mapped.join("orientations_plate.inp")).unwrap();
    for name in ["p0_WARP", "p45_WARP", "p0_AXES", "p45_THICKNESS"] {
        assert!(inp.contains(&format!("NAME={name},")), "{name}: {inp}");
    }

    // One ply, as [fabric] or as a stack of one: no picture per ply, the
    // one-ply files, the same bytes both ways.
    let mut tables = Vec::new();
    let mut views = Vec::new();
    for stack in [false, true] {
        let one = dir.join(format!("one-{stack}"));
        let o = drape(&[
            "run",
            &scene(&dir, 1, stack),
            "--out",
            one.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", text(&o));
        let mut pictures: Vec<String> = std::fs::read_dir(&one)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .filter(|n| n.ends_with(".png"))
            .collect();
        pictures.sort();
        assert_eq!(
            pictures,
            [
                "profiles.png",
                "shear_3d.png",
                "shear_map.png",
                "waviness_map.png"
            ]
        );
        let read = |name: &str| std::fs::read(one.join(name)).unwrap();
        views.push([read("shear_3d.png"), read("waviness_map.png")]);
        let csv = std::fs::read_to_string(one.join("orientations.csv")).unwrap();
        assert!(csv.starts_with("element,x_mm,"));
        tables.push(csv);
    }
    assert_eq!(tables[0], tables[1]);
    assert!(views[0] == views[1], "one ply's pictures differ as a stack");

    // Two laminates compare ply by ply: the run with a copy of itself.
    let copy = dir.join("copy");
    std::fs::create_dir_all(copy.join("frames")).unwrap();
    for entry in walk(&out) {
        let to = copy.join(entry.strip_prefix(&out).unwrap());
        std::fs::copy(&entry, to).unwrap();
    }
    let compare = |b: &Path, into: &str| {
        drape(&[
            "compare",
            out.to_str().unwrap(),
            b.to_str().unwrap(),
            "--out",
            dir.join(into).to_str().unwrap(),
        ])
    };
    let o = compare(&copy, "c-copy");
    assert!(o.status.success(), "{}", text(&o));
    let c = json(&dir.join("c-copy/comparison.json"));
    let plies = c["plies"].as_array().unwrap();
    let names: Vec<&str> = plies.iter().map(|p| p["name"].as_str().unwrap()).collect();
    assert_eq!(names, ["p0", "p45"], "{c}");
    let elements = c["elements"].as_u64().unwrap();
    for p in plies {
        // Each ply with itself: element by element, all of them, no difference.
        assert_eq!(p["same_mesh"], true, "{p}");
        assert_eq!(p["compared"], p["elements"], "{p}");
        assert_eq!(p["max_abs_difference_deg"].as_f64(), Some(0.0), "{p}");
        // Its own profiles, as many points as its rows in profiles.csv.
        let name = p["name"].as_str().unwrap();
        for d in p["profiles"].as_array().unwrap() {
            let line = d["line"].as_str().unwrap();
            let rows = plies_of(line).iter().filter(|q| *q == name).count();
            assert_eq!(d["points"].as_u64(), Some(rows as u64), "{d}");
        }
        assert_eq!(p["profiles"].as_array().unwrap().len(), 2, "{p}");
    }
    let count = |p: usize| plies[p]["elements"].as_u64().unwrap();
    assert_eq!(count(0) + count(1), elements, "{c}");
    assert_eq!(c["profiles"].as_array().unwrap().len(), 0, "{c}");
    let written: Vec<String> = std::fs::read_dir(dir.join("c-copy"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".png"))
        .collect();
    let mut written = written;
    written.sort();
    assert_eq!(written, ["comparison_p0.png", "comparison_p45.png"]);
    let table = std::fs::read_to_string(dir.join("c-copy/comparison.csv")).unwrap();
    assert!(table.starts_with("ply,element,x0_mm,"), "{table}");
    let rows = table.lines().filter(|l| l.starts_with("p45,")).count();
    assert_eq!(rows as u64, count(1));

    // A ply of A that B lacks (renamed in B's summary): an error naming it.
    let summary = std::fs::read_to_string(copy.join("summary.json")).unwrap();
    assert!(summary.contains("\"name\": \"p45\""));
    std::fs::write(
        copy.join("summary.json"),
        summary.replace("\"name\": \"p45\"", "\"name\": \"top\""),
    )
    .unwrap();
    let o = compare(&copy, "c-renamed");
    assert!(!o.status.success());
    assert!(
        text(&o).contains("no ply `p45` (its plies: p0, top)"),
        "{}",
        text(&o)
    );
    // A laminate and a single ply do not compare.
    let o = compare(&dir.join("one-false"), "c-one");
    assert!(!o.status.success());
    assert!(
        text(&o).contains("is a single ply but") && text(&o).contains("plies p0, p45"),
        "{}",
        text(&o)
    );
    std::fs::remove_dir_all(dir).unwrap();
}

/// The files under `dir`, at any depth.
fn walk(dir: &Path) -> Vec<std::path::PathBuf> {
    let mut files = Vec::new();
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            files.extend(walk(&path));
        } else {
            files.push(path);
        }
    }
    files
}

/// A laminate stopped and resumed from its checkpoint ends bit for bit
/// where the uninterrupted run does: the ply pass's warm starts, its
/// broad phase, the plies' slip and peaks travel in the checkpoint, as
/// the tools' states do.
#[test]
fn a_resumed_stack_ends_where_an_uninterrupted_one_does() {
    use drape::{RunControl, RunOptions, run_scene, run_scene_with};
    use drape_io::scene::Scene;
    let dir = temp("stack-resume");
    let path = scene(&dir, 2, true);
    let scene = Scene::from_file(Path::new(&path), &[]).unwrap();
    let straight = run_scene(&scene, &dir.join("straight"), &mut |_| RunControl::Continue).unwrap();
    assert_eq!(straight.summary.status, "completed");

    let out = dir.join("resumed");
    let checkpoint = stopped_with_checkpoint(&scene, &out, 1300, 1200);
    assert_eq!(checkpoint.state.step, 1200);
    let carry = checkpoint
        .driver
        .plies
        .as_ref()
        .expect("the ply pass carried");
    assert!(carry.pass > 0 && carry.slip.iter().any(|&s| s > 0.0));

    // A checkpoint an older drape wrote (no ply state) still resumes, and
    // says that the run is not the uninterrupted one.
    let mut older = checkpoint.clone();
    older.driver.plies = None;
    let options = RunOptions {
        resume: Some(older),
        ..RunOptions::default()
    };
    let cold = run_scene_with(&scene, &dir.join("cold"), options, &mut |_| {
        RunControl::Continue
    })
    .unwrap();
    assert_eq!(cold.summary.status, "completed");
    assert!(
        cold.summary
            .warnings
            .iter()
            .any(|w| w.contains("carries no ply contact state")),
        "{:?}",
        cold.summary.warnings
    );

    let resumed = resumed_from(&scene, &out, checkpoint);
    assert_eq!(resumed.summary.status, "completed");
    assert_eq!(resumed.state.step, straight.state.step);
    assert!(
        state_bits(&resumed.state) == state_bits(&straight.state),
        "the states differ"
    );
    let csv = |d: &str| std::fs::read_to_string(dir.join(d).join("energy.csv")).unwrap();
    assert_eq!(csv("resumed"), csv("straight"));
    let plies = |d: &str| json(&dir.join(d).join("summary.json"))["plies"].clone();
    assert_eq!(plies("resumed"), plies("straight"));
    std::fs::remove_dir_all(dir).unwrap();
}
