//! Issue 29, the implicit solver's part, end to end: settings that cannot
//! work together are refused before anything is written (exit 2, naming
//! the keys and values), and a run that ends with the blank inside a tool
//! is "failed" with its results kept, whatever its settings let through.

mod common;
use common::*;

/// The shipped hemisphere, implicit, on a 4 × 4 blank.
const SMALL: [&str; 4] = [
    "--set",
    "simulation.solver=\"implicit\"",
    "--set",
    "fabric.blank.cells=[4,4]",
];

/// `drape run` of the shipped hemisphere with `sets` on top of [`SMALL`]:
/// exit 2, nothing written into the output folder, the message naming
/// every string of `named`.
fn refused(name: &str, sets: &[&str], named: &[&str]) {
    let out = temp(name);
    let target = out.join("run");
    let mut args = vec![
        "run",
        "scenes/hemisphere-0-90.toml",
        "--out",
        target.to_str().unwrap(),
    ];
    args.extend_from_slice(&SMALL);
    for s in sets {
        args.extend_from_slice(&["--set", s]);
    }
    let o = drape(&args);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(2), "{t}");
    for n in named {
        assert!(t.contains(n), "`{n}` not in: {t}");
    }
    assert!(!target.join("summary.json").exists(), "{t}");
}

/// Fault: `initial_increment` or `max_increment` below `min_increment`
/// ran and ended "residual is not finite".
#[test]
fn increments_below_the_smallest_are_refused_naming_the_keys() {
    refused(
        "initial",
        &[
            "simulation.initial_increment=1e-6",
            "simulation.min_increment=1e-5",
        ],
        &[
            "simulation.initial_increment",
            "1e-6 s",
            "simulation.min_increment",
            "1e-5 s",
        ],
    );
    // The smallest at its default (1e-9 of the end time, 1 s).
    refused(
        "largest",
        &["simulation.max_increment=1e-10"],
        &[
            "simulation.max_increment",
            "1e-10 s",
            "simulation.min_increment",
            "1e-9 s (the default",
        ],
    );
}

/// Fault 5: `gap_tolerance = 1e8` ended "completed" with nodes 33 mm
/// inside the punch. Refused before the run: above the end check's
/// tolerance (a tenth of the prepreg's 0.3 mm thickness).
#[test]
fn a_gap_tolerance_deeper_than_the_end_check_allows_is_refused() {
    refused(
        "gap",
        &["simulation.gap_tolerance=1e8"],
        &["simulation.gap_tolerance", "1e8 mm", "3.000e-2 mm"],
    );
    refused(
        "force",
        &["simulation.force_tolerance=1"],
        &["simulation.force_tolerance", "expected below 1"],
    );
}

/// Fault 5's mechanism, past the scene's refusal (the settings changed in
/// the parsed scene, as a library user could): the implicit run's Newton
/// accepts the blank through the punch; the run ends "failed" with the
/// node, the tool, the depth and the key to change, and its results (the
/// frames, the summary of the end state) are kept.
#[test]
fn a_run_ending_inside_a_tool_is_failed_with_its_results_kept() {
    let out = temp("through");
    let path = workspace().join("scenes/hemisphere-0-90.toml");
    let sets: Vec<(String, String)> = [
        ("simulation.solver", "\"implicit\""),
        ("fabric.blank.cells", "[4,4]"),
        ("simulation.frames", "4"),
    ]
    .iter()
    .map(|(k, v)| (k.to_string(), v.to_string()))
    .collect();
    let mut scene = drape_io::scene::Scene::from_file(&path, &sets).unwrap();
    scene.implicit.gap_tolerance = 1e8;
    // The condensed solver stops at the gap tolerance; the active set
    // holds its rows exactly and would not let the blank through.
    scene.implicit.contact_solver = drape_time::ContactSolver::Condensed;
    let report = drape::run_scene(&scene, &out, &mut |_| drape::RunControl::Continue).unwrap();
    let s = &report.summary;
    let reason = s.reason.clone().unwrap_or_default();
    assert_eq!(s.status, "failed", "{reason}");
    for part in [
        "inside tool `punch`",
        "node ",
        "simulation.gap_tolerance",
        "the results are those of t = 1.000000e0 s",
    ] {
        assert!(reason.contains(part), "`{part}` not in: {reason}");
    }
    assert!((s.time - 1.0).abs() < 1e-12);
    let summary = json(&out.join("summary.json"));
    assert_eq!(summary["status"], "failed");
    // The end frame is kept, as every frame before it.
    assert!(out.join("frames/frame_00004.vtu").exists());
}
