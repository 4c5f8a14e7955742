//! `drape sweep --slurm` and `--collect` without a Slurm cluster: the
//! batch script run by bash as Slurm would run each array task, and fake
//! `sbatch`/`squeue` commands on the PATH that record what drape asks.
//! The real cluster test is `cargo xtask slurm`.

use std::path::Path;
use std::process::{Command, Output};

mod common;
use common::*;

/// A picture-frame sweep of two points, a few steps each.
const SETS: [&str; 10] = [
    "--set",
    "boundary.0.motion.shear_deg=20,40",
    "--set",
    "simulation.frames=1",
    "--set",
    "simulation.end_time=0.01",
    "--set",
    "boundary.0.motion.amplitude.duration=0.01",
    "--set",
    "output.vtu=false",
];

/// `drape ARGS…` with `PATH` set to `path`.
fn drape_with_path(args: &[&str], path: &Path) -> Output {
    Command::new(env!("CARGO_BIN_EXE_drape"))
        .args(args)
        .current_dir(workspace())
        .env("PATH", path)
        .output()
        .unwrap()
}

/// Runs array task `i` of the sweep's batch script, as Slurm would.
fn run_task(sweep: &Path, i: usize) {
    let o = Command::new("bash")
        .arg(sweep.join("sweep.sbatch"))
        .env("SLURM_ARRAY_TASK_ID", i.to_string())
        .env("SLURM_CPUS_PER_TASK", "1")
        .output()
        .unwrap();
    assert!(o.status.success(), "task {i}: {}", text(&o));
}

/// A summary without what differs between two runs of one scene (the wall
/// time, the thread count and the path of the scene file it was read
/// from).
fn measures(run: &Path) -> serde_json::Value {
    let mut v = json(&run.join("summary.json"));
    let o = v.as_object_mut().unwrap();
    o.remove("scene");
    let run = o["run"].as_object_mut().unwrap();
    run.remove("wall_s");
    run.remove("threads");
    v
}

/// The table without its wall-time column.
fn table_without_wall_time(dir: &Path) -> String {
    let t = std::fs::read_to_string(dir.join("sweep.csv")).unwrap();
    let header: Vec<&str> = t.lines().next().unwrap().split(',').collect();
    let wall = header.iter().position(|h| *h == "wall_s").unwrap();
    t.lines()
        .map(|l| {
            let mut f: Vec<&str> = l.split(',').collect();
            if f.len() > wall {
                f[wall] = "";
            }
            f.join(",")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn a_slurm_sweep_collects_what_the_local_sweep_writes() {
    let dir = temp("collect");
    let sweep = dir.join("slurm");
    let s = sweep.to_str().unwrap();
    let mut args = vec!["sweep", "scenes/picture-frame.toml"];
    args.extend(SETS);
    args.extend([
        "--slurm",
        "--dry-run",
        "--checkpoint-every",
        "3",
        "--out",
        s,
    ]);
    let o = drape(&args);
    assert!(o.status.success(), "{}", text(&o));
    for f in [
        "points/point_000.toml",
        "points/point_001.toml",
        "sweep.sbatch",
        "slurm.json",
    ] {
        assert!(sweep.join(f).is_file(), "no {f}: {}", text(&o));
    }
    // The point's own file holds its value.
    let point = std::fs::read_to_string(sweep.join("points/point_001.toml")).unwrap();
    assert!(point.contains("shear_deg = 40"), "{point}");
    // A second submission into the same folder is refused.
    let again = drape(&args);
    assert_eq!(again.status.code(), Some(2), "{}", text(&again));
    assert!(text(&again).contains("holds a Slurm sweep already"));

    // Nothing ran: both points listed, the table says why.
    let o = drape(&["sweep", "--collect", s]);
    assert_eq!(o.status.code(), Some(1), "{}", text(&o));
    let t = text(&o);
    assert!(t.contains("collected 0 of 2 points"), "{t}");
    assert!(
        t.contains("run_001  task -  no result: never submitted"),
        "{t}"
    );

    run_task(&sweep, 0);
    let o = drape(&["sweep", "--collect", s]);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(1), "{t}");
    assert!(t.contains("collected 1 of 2 points"), "{t}");
    assert!(!t.contains("run_000  task"), "{t}");
    // Running a task again leaves a completed point alone.
    let before = std::fs::read(sweep.join("run_000/summary.json")).unwrap();
    run_task(&sweep, 0);
    assert_eq!(
        std::fs::read(sweep.join("run_000/summary.json")).unwrap(),
        before
    );

    run_task(&sweep, 1);
    let o = drape(&["sweep", "--collect", s]);
    assert!(o.status.success(), "{}", text(&o));
    let inspected = drape(&["inspect", s]);
    let t = text(&inspected);
    assert!(inspected.status.success(), "{t}");
    assert!(t.contains("2 points, 2 completed"), "{t}");
    assert!(t.contains("sweep.png"), "{t}");

    let local = dir.join("local");
    let mut args = vec!["sweep", "scenes/picture-frame.toml"];
    args.extend(SETS);
    args.extend(["--out", local.to_str().unwrap()]);
    let o = drape(&args);
    assert!(o.status.success(), "{}", text(&o));
    for run in ["run_000", "run_001"] {
        assert_eq!(
            measures(&sweep.join(run)),
            measures(&local.join(run)),
            "{run}"
        );
    }
    assert_eq!(
        table_without_wall_time(&sweep),
        table_without_wall_time(&local)
    );
    std::fs::remove_dir_all(dir).unwrap();
}

fn write_exe(path: &Path, text: &str) {
    use std::os::unix::fs::PermissionsExt;
    std::fs::write(path, text).unwrap();
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(0o755)).unwrap();
}

#[test]
fn submission_is_refused_without_sbatch_or_by_slurm_and_writes_nothing() {
    let dir = temp("refused");
    let out = dir.join("sweep");
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let mut args = vec!["sweep", "scenes/picture-frame.toml"];
    args.extend(SETS);
    args.extend(["--slurm", "--out", out.to_str().unwrap()]);

    let o = drape_with_path(&args, &bin);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(2), "{t}");
    assert!(t.contains("sbatch: not found on the PATH"), "{t}");
    assert!(!out.exists());

    // Slurm's own words for an unknown partition.
    write_exe(
        &bin.join("sbatch"),
        "#!/bin/sh\necho 'sbatch: error: invalid partition specified: nope' >&2\n\
         echo 'allocation failure: Invalid partition name specified' >&2\nexit 1\n",
    );
    let mut with_partition = args.clone();
    with_partition.extend(["--partition", "nope"]);
    let o = drape_with_path(&with_partition, &bin);
    let t = text(&o);
    assert_eq!(o.status.code(), Some(2), "{t}");
    assert!(
        t.contains(
            "sbatch refused the job: sbatch: error: invalid partition specified: nope; \
             allocation failure: Invalid partition name specified"
        ),
        "{t}"
    );
    assert!(!out.exists());
    std::fs::remove_dir_all(dir).unwrap();
}

#[test]
fn submission_and_retry_ask_sbatch_for_the_right_tasks() {
    let dir = temp("submit");
    let out = dir.join("sweep");
    let o_s = out.to_str().unwrap();
    let bin = dir.join("bin");
    std::fs::create_dir_all(&bin).unwrap();
    let calls = dir.join("calls");
    write_exe(
        &bin.join("sbatch"),
        &format!(
            "#!/bin/sh\necho \"$@\" >> '{}'\ncase \"$*\" in *--test-only*) \
             echo 'sbatch: Job 1 to start' >&2; exit 0;; esac\n\
             if [ -e '{first}' ]; then echo '4243;cluster'; else : > '{first}'; echo 4242; fi\n",
            calls.display(),
            first = dir.join("first").display()
        ),
    );
    // The first task is still waiting its turn.
    write_exe(
        &bin.join("squeue"),
        "#!/bin/sh\necho '4242_1|PENDING|JobArrayTaskLimit'\n",
    );
    let mut args = vec!["sweep", "scenes/picture-frame.toml"];
    args.extend(SETS);
    args.extend([
        "--slurm",
        "--array-limit",
        "1",
        "--partition",
        "short",
        "--out",
        o_s,
    ]);
    let o = drape_with_path(&args, &bin);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(t.contains("submitted job 4242: 2 tasks"), "{t}");
    assert!(t.contains("squeue -j 4242"), "{t}");
    let script = std::fs::read_to_string(out.join("sweep.sbatch")).unwrap();
    assert!(script.contains("#SBATCH --partition=short\n"), "{script}");

    // Task 0 ended without a summary; task 1 is queued: only 0 is
    // resubmitted, with the same limit.
    let o = drape_with_path(&["sweep", "--collect", o_s, "--retry"], &bin);
    let t = text(&o);
    assert!(o.status.success(), "{t}");
    assert!(
        t.contains("run_000  task 4242_0  no result: never ran"),
        "{t}"
    );
    assert!(
        t.contains("run_001  task 4242_1  in Slurm: PENDING (JobArrayTaskLimit)"),
        "{t}"
    );
    assert!(t.contains("resubmitted 1 points (0) as job 4243"), "{t}");
    let calls = std::fs::read_to_string(&calls).unwrap();
    let calls: Vec<&str> = calls.lines().collect();
    assert_eq!(calls.len(), 3, "{calls:?}");
    assert!(
        calls[0].starts_with("--array=0-1%1 --test-only "),
        "{calls:?}"
    );
    assert!(
        calls[1].starts_with("--array=0-1%1 --parsable "),
        "{calls:?}"
    );
    assert!(calls[2].starts_with("--array=0%1 --parsable "), "{calls:?}");
    let plan = json(&out.join("slurm.json"));
    assert_eq!(plan["submissions"][1]["job_id"], "4243");
    std::fs::remove_dir_all(dir).unwrap();
}
