//! `drape sweep --slurm`: a sweep handed to a Slurm cluster as one job
//! array, and `drape sweep --collect` / `drape inspect` on it.
//!
//! Submitting writes the sweep folder (one resolved scene per point under
//! `points/`, the batch script `sweep.sbatch`, the plan `slurm.json`) and
//! submits the script with `sbatch --array`: array task `i` runs point `i`
//! into `run_NNN`, exactly the folder a local sweep writes. The script is
//! idempotent: a completed point is left alone, a stopped one (pre-empted,
//! requeued, out of time) continues from its checkpoint. Collecting reads
//! the points' summaries and writes `sweep.csv` / `sweep.png` through the
//! local sweep's own code ([`crate::sweep_table`]).
//!
//! Not a scheduler, nor a pool of workers: Slurm places, runs, requeues and
//! accounts the tasks; drape only writes, submits and reads.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};

use anyhow::{Context, Result, anyhow};
use drape_io::results::{OutputLock, Summary};
use drape_io::scene::Scene;
use serde::{Deserialize, Serialize};

use crate::sweep_table::{self, Axis, Point, run_name};
use crate::{bad, default_out, inspect_sweep, load, unusable_output};

/// The plan of a Slurm sweep, in its folder.
pub const PLAN: &str = "slurm.json";
/// The batch script, in the sweep folder.
const SCRIPT: &str = "sweep.sbatch";
/// Steps between checkpoints when not given: a task that is stopped loses
/// at most this many steps (a few seconds of a typical run).
const DEFAULT_CHECKPOINT_EVERY: u64 = 2000;
/// Seconds before its time limit at which Slurm asks a task to stop
/// (SIGTERM), so that it writes its last frame and summary in time.
const SIGNAL_GRACE_S: u32 = 120;

/// `drape sweep`'s options for a Slurm cluster.
#[derive(clap::Args, Debug, Default)]
pub struct SlurmArgs {
    /// Submit the sweep to Slurm as one job array (one point per array
    /// task) instead of running it here.
    #[arg(long, conflicts_with = "collect")]
    pub slurm: bool,
    /// Slurm partition (queue) to run in (default: the cluster's default).
    #[arg(long, requires = "slurm")]
    pub partition: Option<String>,
    /// Time limit of each task, as sbatch takes it: 30, 2:00:00, 1-00:00:00.
    #[arg(long, requires = "slurm")]
    pub time: Option<String>,
    /// CPUs of each task; the run uses as many threads.
    #[arg(long, requires = "slurm", value_name = "N")]
    pub cpus_per_task: Option<u32>,
    /// At most this many tasks of the sweep run at once (--array=…%N).
    #[arg(long, requires = "slurm", value_name = "N")]
    pub array_limit: Option<u32>,
    /// Account to charge the tasks to.
    #[arg(long, requires = "slurm")]
    pub account: Option<String>,
    /// Any other sbatch option, written into the script as an #SBATCH
    /// line: --sbatch-arg=--mem=4G (repeatable).
    #[arg(long = "sbatch-arg", requires = "slurm", value_name = "OPTION")]
    pub sbatch_args: Vec<String>,
    /// Write the sweep folder and its batch script, submit nothing.
    #[arg(long, requires = "slurm")]
    pub dry_run: bool,
    /// Steps between a task's checkpoints (default 2000): how much a
    /// pre-empted or requeued task runs again.
    #[arg(long, requires = "slurm", value_name = "N")]
    pub checkpoint_every: Option<u64>,
    /// Gather a Slurm sweep's finished points into DIR/sweep.csv and
    /// sweep.png and list the others.
    #[arg(long, value_name = "DIR", conflicts_with_all = ["scene", "set", "out", "threads"])]
    pub collect: Option<PathBuf>,
    /// With --collect: resubmit the points that were stopped or never ran
    /// (stopped ones continue from their checkpoint).
    #[arg(long, requires = "collect")]
    pub retry: bool,
}

/// What the tasks are submitted with, kept for `--retry`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JobOptions {
    pub partition: Option<String>,
    pub time: Option<String>,
    pub cpus_per_task: u32,
    pub array_limit: Option<u32>,
    pub account: Option<String>,
    pub sbatch_args: Vec<String>,
    pub checkpoint_every: u64,
}

/// One `sbatch` of the sweep: its job id and the points it ran.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Submission {
    pub job_id: String,
    pub points: Vec<usize>,
}

/// A Slurm sweep's plan (`slurm.json`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Plan {
    /// The scene file the points were resolved from.
    pub scene: PathBuf,
    pub axes: Vec<Axis>,
    pub points: Vec<Point>,
    /// The drape binary the tasks run.
    pub drape: PathBuf,
    pub options: JobOptions,
    /// Every submission, the first one first.
    pub submissions: Vec<Submission>,
}

impl Plan {
    /// The Slurm task that last ran (or was asked to run) point `i`:
    /// `JOBID_i`.
    pub fn task(&self, i: usize) -> Option<String> {
        self.submissions
            .iter()
            .rev()
            .find(|s| s.points.contains(&i))
            .map(|s| format!("{}_{i}", s.job_id))
    }
}

/// Whether `dir` holds a Slurm sweep.
pub fn is_slurm_sweep(dir: &Path) -> bool {
    dir.join(PLAN).is_file()
}

/// Quotes a string for bash, whatever it holds.
fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', r"'\''"))
}

/// The `--array` value for `points`: runs of consecutive indices as
/// ranges, then `%limit`.
pub fn array_spec(points: &[usize], limit: Option<u32>) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < points.len() {
        let mut j = i;
        while j + 1 < points.len() && points[j + 1] == points[j] + 1 {
            j += 1;
        }
        parts.push(if j == i {
            points[i].to_string()
        } else {
            format!("{}-{}", points[i], points[j])
        });
        i = j + 1;
    }
    let mut spec = parts.join(",");
    if let Some(l) = limit {
        spec.push_str(&format!("%{l}"));
    }
    spec
}

/// The batch script: one point per array task, idempotent (a completed
/// point is left alone, a stopped one resumes from its checkpoint, a
/// failed or absent one starts afresh).
pub fn script(name: &str, out: &Path, drape: &Path, o: &JobOptions) -> String {
    let out_s = out.to_string_lossy();
    let mut s = String::from("#!/bin/bash\n");
    let mut sbatch = |line: String| {
        s.push_str("#SBATCH ");
        s.push_str(&line);
        s.push('\n');
    };
    sbatch(format!("--job-name=drape-{name}"));
    sbatch(format!("--output={out_s}/slurm/%A_%a.out"));
    // A requeued task appends to its log: what it did before stays.
    sbatch("--open-mode=append".into());
    sbatch(format!("--chdir={out_s}"));
    sbatch("--ntasks=1".into());
    sbatch(format!("--cpus-per-task={}", o.cpus_per_task));
    // Pre-emption and node failures put the task back in the queue.
    sbatch("--requeue".into());
    // SIGTERM to the script (drape itself, by exec) before the time limit.
    sbatch(format!("--signal=B:TERM@{SIGNAL_GRACE_S}"));
    if let Some(p) = &o.partition {
        sbatch(format!("--partition={p}"));
    }
    if let Some(t) = &o.time {
        sbatch(format!("--time={t}"));
    }
    if let Some(a) = &o.account {
        sbatch(format!("--account={a}"));
    }
    for extra in &o.sbatch_args {
        sbatch(extra.clone());
    }
    s.push_str(&format!(
        r#"#
# Written by `drape sweep --slurm`; submitted as a job array, one point of
# the sweep per task (sbatch --array=0-N%LIMIT {SCRIPT}). Running it again
# is safe: a completed point is left alone, a stopped one (pre-empted,
# requeued, out of time) continues from its checkpoint.
set -u
i=${{SLURM_ARRAY_TASK_ID:?submit this script as a job array: sbatch --array=...}}
n=$(printf '%03d' "$i")
sweep={sweep}
drape={drape}
dir="$sweep/run_$n"
threads=${{SLURM_CPUS_PER_TASK:-1}}
echo "drape: point run_$n, task ${{SLURM_ARRAY_JOB_ID:-?}}_$i on $(hostname), restart ${{SLURM_RESTART_COUNT:-0}}"
summary="$dir/summary.json"
if [ -f "$summary" ] && grep -q '^  "status": "completed"' "$summary"; then
    echo "drape: run_$n has completed already: nothing to do"
    exit 0
fi
if [ -f "$dir/checkpoint.json" ] && ! grep -q '^  "status": "failed"' "$summary" 2>/dev/null; then
    exec "$drape" run --resume "$dir" --threads "$threads"
fi
exec "$drape" run "$sweep/points/point_$n.toml" --out "$dir" --threads "$threads" --checkpoint-every {every}
"#,
        sweep = shell_quote(&out_s),
        drape = shell_quote(&drape.to_string_lossy()),
        every = o.checkpoint_every,
    ));
    s
}

/// File systems that a cluster's nodes share.
const SHARED_FS: [&str; 16] = [
    "nfs",
    "nfs4",
    "lustre",
    "gpfs",
    "beegfs",
    "ceph",
    "fuse.ceph",
    "cephfs",
    "cifs",
    "smb3",
    "glusterfs",
    "fuse.glusterfs",
    "panfs",
    "wekafs",
    "pvfs2",
    "orangefs",
];

/// Undoes /proc/mounts' octal escapes (`\040` for a space).
fn unescape_mount(s: &str) -> String {
    let mut out = String::new();
    let mut chars = s.chars().peekable();
    while let Some(c) = chars.next() {
        if c == '\\' {
            let code: String = chars.clone().take(3).collect();
            if let Ok(v) = u8::from_str_radix(&code, 8) {
                out.push(char::from(v));
                chars.nth(2);
                continue;
            }
        }
        out.push(c);
    }
    out
}

/// A warning when `path` (absolute, resolved) is not on a file system the
/// compute nodes share, from the mount table `mounts` (/proc/mounts).
pub fn shared_fs_warning(path: &Path, mounts: &str, what: &str) -> Option<String> {
    let (mount, fs) = mounts
        .lines()
        .filter_map(|l| {
            let mut f = l.split_whitespace();
            let (_, at, fs) = (f.next()?, f.next()?, f.next()?);
            Some((PathBuf::from(unescape_mount(at)), fs.to_owned()))
        })
        .filter(|(at, _)| path.starts_with(at))
        .max_by_key(|(at, _)| at.components().count())?;
    let node_local = ["/tmp", "/var/tmp", "/dev/shm"]
        .iter()
        .any(|d| path.starts_with(d));
    if !node_local && SHARED_FS.contains(&fs.as_str()) {
        return None;
    }
    Some(format!(
        "{what} {} is on a {} file system ({fs} at {}): the compute nodes may not see it and \
         the tasks would fail or write elsewhere; put it on a file system the nodes share \
         (home, project or scratch: NFS, Lustre, GPFS, BeeGFS…)",
        path.display(),
        if node_local { "node-local" } else { "local" },
        mount.display()
    ))
}

/// Warns when `path` is not on a shared file system (silent when the mount
/// table cannot be read).
fn warn_if_local(path: &Path, what: &str) {
    let resolved = path
        .ancestors()
        .find_map(|a| a.canonicalize().ok().map(|c| (a, c)))
        .map(|(a, c)| match path.strip_prefix(a) {
            Ok(rest) if !rest.as_os_str().is_empty() => c.join(rest),
            _ => c,
        })
        .unwrap_or_else(|| path.to_owned());
    if let Ok(mounts) = std::fs::read_to_string("/proc/mounts") {
        if let Some(w) = shared_fs_warning(&resolved, &mounts, what) {
            eprintln!("warning: {w}");
        }
    }
}

/// The path of `program` on the PATH.
fn on_path(program: &str) -> Option<PathBuf> {
    std::env::var_os("PATH").and_then(|paths| {
        std::env::split_paths(&paths)
            .map(|d| d.join(program))
            .find(|p| p.is_file())
    })
}

/// `sbatch`, or bad input saying that it is missing.
fn sbatch() -> Result<PathBuf> {
    on_path("sbatch").ok_or_else(|| {
        bad(
            "sbatch: not found on the PATH: --slurm submits the sweep with Slurm's sbatch; run \
             drape on a machine that submits to the cluster (a login node), or add --dry-run \
             to only write the sweep folder and its batch script",
        )
    })
}

/// Slurm's own words from sbatch's error output.
fn slurm_message(stderr: &[u8]) -> String {
    let text = String::from_utf8_lossy(stderr);
    let lines: Vec<&str> = text
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    if lines.is_empty() {
        "no message".to_owned()
    } else {
        lines.join("; ")
    }
}

/// Runs sbatch on the script: `--test-only` asks Slurm whether it would
/// take the job, without submitting it. Returns sbatch's standard output.
fn run_sbatch(sbatch: &Path, array: &str, script: &Path, test_only: bool) -> Result<String> {
    let mut cmd = Command::new(sbatch);
    cmd.arg(format!("--array={array}"));
    if test_only {
        cmd.arg("--test-only");
    } else {
        cmd.arg("--parsable");
    }
    let out = cmd
        .arg(script)
        .stdin(Stdio::null())
        .output()
        .with_context(|| format!("cannot start {}", sbatch.display()))?;
    if !out.status.success() {
        return Err(bad(format!(
            "sbatch refused the job: {}",
            slurm_message(&out.stderr)
        )));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// The job id in `sbatch --parsable`'s output (`JOBID` or `JOBID;CLUSTER`).
pub fn parse_job_id(stdout: &str) -> Option<String> {
    let id = stdout.trim().split(';').next()?.trim();
    (!id.is_empty() && id.chars().all(|c| c.is_ascii_digit())).then(|| id.to_owned())
}

fn write_plan(dir: &Path, plan: &Plan) -> Result<()> {
    let path = dir.join(PLAN);
    let mut json = serde_json::to_vec_pretty(plan)?;
    json.push(b'\n');
    drape_io::atomic::write(&path, &json).with_context(|| format!("writing {}", path.display()))
}

fn read_plan(dir: &Path) -> Result<Plan> {
    let path = dir.join(PLAN);
    let text = std::fs::read_to_string(&path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            bad(format!(
                "{}: not a Slurm sweep (no {PLAN}): --collect takes the folder of a \
                 `drape sweep --slurm`",
                dir.display()
            ))
        } else {
            bad(format!("{}: {e}", path.display()))
        }
    })?;
    serde_json::from_str(&text)
        .map_err(|e| bad(format!("{}: not a drape Slurm plan: {e}", path.display())))
}

/// A point's scene as its own file: every value after the point's `--set`,
/// the files it reads as absolute paths.
fn point_file(scene_path: &Path, point: &Point, scene: &Scene) -> Result<String> {
    let mut text = format!(
        "# A point of the sweep of {} ({}), written by `drape sweep --slurm`:\n# the scene as it \
         runs, every value resolved.\n",
        scene_path.display(),
        point
            .iter()
            .map(|(k, v)| format!("{k} = {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    text.push_str(&toml::to_string(&scene.resolved_spec()).context("writing a point's scene")?);
    Ok(text)
}

/// The options as they go into `#SBATCH` lines: one word each (a space or
/// a line break would end the line early or start another), and
/// `--sbatch-arg` an option.
pub fn check_options(args: &SlurmArgs) -> Result<()> {
    let words = [
        ("--partition", &args.partition),
        ("--time", &args.time),
        ("--account", &args.account),
    ];
    for (name, value) in words {
        if let Some(v) = value {
            if v.is_empty() || v.contains(char::is_whitespace) {
                return Err(bad(format!(
                    "{name} `{v}`: expected one word (an #SBATCH line of the batch script)"
                )));
            }
        }
    }
    for a in &args.sbatch_args {
        if !a.starts_with('-') || a.contains(['\n', '\r']) {
            return Err(bad(format!(
                "--sbatch-arg `{a}`: expected one sbatch option on one line, as \
                 --sbatch-arg=--mem=4G"
            )));
        }
    }
    match args.cpus_per_task {
        Some(0) => Err(bad("--cpus-per-task must be at least 1")),
        _ if args.array_limit == Some(0) => Err(bad("--array-limit must be at least 1")),
        _ if args.checkpoint_every == Some(0) => Err(bad("--checkpoint-every must be at least 1")),
        _ => Ok(()),
    }
}

/// `drape sweep SCENE --set … --slurm`.
pub fn submit(
    scene_path: &Path,
    out: Option<PathBuf>,
    set: &[String],
    args: &SlurmArgs,
) -> Result<ExitCode> {
    check_options(args)?;
    let (axes, combos) = sweep_table::points(set)?;
    // Every point must load and be runnable before anything is written or
    // submitted: a cluster queue is a slow place to find a typo.
    let mut scenes = Vec::with_capacity(combos.len());
    for c in &combos {
        let scene = load(scene_path, c)?;
        drape::check_scene(&scene)
            .map_err(|reason| bad(format!("{}: {reason}", scene_path.display())))?;
        scenes.push(scene);
    }
    let sbatch = if args.dry_run { None } else { Some(sbatch()?) };
    let out = out.unwrap_or_else(|| default_out(scene_path, "-sweep"));
    let out = std::path::absolute(&out).unwrap_or(out);
    if is_slurm_sweep(&out) {
        return Err(bad(format!(
            "{}: holds a Slurm sweep already: collect it with drape sweep --collect {}, or give \
             another folder with --out",
            out.display(),
            out.display()
        )));
    }
    let drape = std::env::current_exe().context("cannot tell where the drape binary is")?;
    let options = JobOptions {
        partition: args.partition.clone(),
        time: args.time.clone(),
        cpus_per_task: args.cpus_per_task.unwrap_or(1),
        array_limit: args.array_limit,
        account: args.account.clone(),
        sbatch_args: args.sbatch_args.clone(),
        checkpoint_every: args.checkpoint_every.unwrap_or(DEFAULT_CHECKPOINT_EVERY),
    };
    let name = scene_path
        .file_stem()
        .map_or_else(|| "sweep".to_owned(), |s| s.to_string_lossy().into_owned());
    let text = script(&name, &out, &drape, &options);
    let all: Vec<usize> = (0..combos.len()).collect();
    let array = array_spec(&all, options.array_limit);
    if let Some(sbatch) = &sbatch {
        // Slurm's verdict on the options (partition, account, time) before
        // anything is written: a refused job is bad input, with Slurm's
        // own message.
        let probe = std::env::temp_dir().join(format!("drape-sbatch-{}.sh", std::process::id()));
        std::fs::write(&probe, &text).with_context(|| format!("writing {}", probe.display()))?;
        let verdict = run_sbatch(sbatch, &array, &probe, true);
        let _ = std::fs::remove_file(&probe);
        verdict?;
    }
    warn_if_local(&out, "the sweep folder");
    warn_if_local(&drape, "the drape binary the tasks run,");
    let _lock = OutputLock::acquire(&out).map_err(|e| unusable_output(&out, &e))?;
    let points_dir = out.join("points");
    for dir in [&points_dir, &out.join("slurm")] {
        std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    }
    for (i, (point, scene)) in combos.iter().zip(&scenes).enumerate() {
        let path = points_dir.join(format!("point_{i:03}.toml"));
        drape_io::atomic::write(&path, point_file(scene_path, point, scene)?.as_bytes())
            .with_context(|| format!("writing {}", path.display()))?;
        // The task runs this file: it must be the very scene the local
        // sweep would run.
        let again = Scene::from_file(&path, &[]).map_err(|e| anyhow!("{e}"))?;
        if again.spec != scene.resolved_spec() {
            return Err(anyhow!(
                "{}: does not read back as the scene it was written from",
                path.display()
            ));
        }
    }
    let script_path = out.join(SCRIPT);
    drape_io::atomic::write(&script_path, text.as_bytes())
        .with_context(|| format!("writing {}", script_path.display()))?;
    let mut plan = Plan {
        scene: std::path::absolute(scene_path).unwrap_or(scene_path.to_owned()),
        axes,
        points: combos,
        drape,
        options,
        submissions: Vec::new(),
    };
    write_plan(&out, &plan)?;
    let n = plan.points.len();
    let Some(sbatch) = sbatch else {
        println!(
            "wrote {} points and {} into {} (nothing submitted)\nsubmit them with: drape sweep \
             --collect {} --retry",
            n,
            SCRIPT,
            out.display(),
            out.display()
        );
        return Ok(ExitCode::SUCCESS);
    };
    let stdout = run_sbatch(&sbatch, &array, &script_path, false).map_err(|e| {
        anyhow!(
            "{}; the sweep folder {} is written: submit it with drape sweep --collect {} --retry",
            crate::describe(&e),
            out.display(),
            out.display()
        )
    })?;
    let job = parse_job_id(&stdout).ok_or_else(|| {
        anyhow!(
            "sbatch --parsable printed `{}`, not a job id",
            stdout.trim()
        )
    })?;
    plan.submissions.push(Submission {
        job_id: job.clone(),
        points: all,
    });
    write_plan(&out, &plan)?;
    print_submitted(&job, n, &plan.options, &out);
    Ok(ExitCode::SUCCESS)
}

fn print_submitted(job: &str, n: usize, o: &JobOptions, out: &Path) {
    let at_once = o
        .array_limit
        .map_or_else(String::new, |l| format!(", at most {l} at once"));
    println!(
        "submitted job {job}: {n} tasks (array {job}_0 … {job}_{}{at_once})",
        n - 1
    );
    println!("follow it:  squeue -j {job}   (afterwards: sacct -j {job})");
    println!(
        "task logs:  {}",
        out.join("slurm").join(format!("{job}_N.out")).display()
    );
    println!("collect:    drape sweep --collect {}", out.display());
}

/// Where a point stands.
#[derive(Debug, Clone, PartialEq)]
pub enum PointState {
    /// Its summary says so (completed, failed or stopped).
    Finished(Box<Summary>),
    /// Slurm still has it (pending or running): Slurm's state and reason.
    InSlurm(String),
    /// No summary and not in Slurm's queue: why, as far as can be told.
    NoResult(String),
}

impl PointState {
    /// Whether `--retry` resubmits it: stopped points (they resume) and
    /// those with no result. A failed run is drape's result for its scene
    /// (it would fail again the same way) and is not resubmitted.
    pub fn retry(&self) -> bool {
        match self {
            Self::Finished(s) => s.status == "stopped",
            Self::InSlurm(_) => false,
            Self::NoResult(_) => true,
        }
    }
}

/// The last line of a task's log that says what went wrong (an error
/// line, else the last line), for a point that left no summary.
pub fn log_reason(log: &str) -> Option<String> {
    let lines: Vec<&str> = log
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty())
        .collect();
    lines
        .iter()
        .rev()
        .find(|l| l.contains("error") || l.contains("CANCELLED") || l.contains("DUE TO"))
        .or(lines.last())
        .map(|l| (*l).to_owned())
}

/// Where each point stands: its summary, else Slurm's queue (`live`: task
/// id → state), else its task's log.
pub fn point_states(dir: &Path, plan: &Plan, live: &BTreeMap<String, String>) -> Vec<PointState> {
    (0..plan.points.len())
        .map(|i| {
            let run = dir.join(run_name(i));
            let task = plan.task(i);
            if let Some(state) = task.as_ref().and_then(|t| live.get(t)) {
                return PointState::InSlurm(state.clone());
            }
            let summary = run.join("summary.json");
            match std::fs::read_to_string(&summary) {
                Ok(text) => {
                    return match serde_json::from_str::<Summary>(&text) {
                        Ok(s) => PointState::Finished(Box::new(s)),
                        Err(e) => PointState::NoResult(format!(
                            "{}: not a drape summary: {e}",
                            summary.display()
                        )),
                    };
                }
                Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
                    return PointState::NoResult(format!("{}: {e}", summary.display()));
                }
                Err(_) => {}
            }
            let Some(task) = task else {
                return PointState::NoResult("never submitted".to_owned());
            };
            let log = dir.join("slurm").join(format!("{task}.out"));
            match std::fs::read_to_string(&log) {
                Ok(text) => PointState::NoResult(format!(
                    "left no summary; its log ends: {}",
                    log_reason(&text).unwrap_or_else(|| "(empty)".to_owned())
                )),
                Err(_) => PointState::NoResult(format!(
                    "never ran (no log {}): cancelled, or the node could not write the sweep \
                     folder",
                    log.display()
                )),
            }
        })
        .collect()
}

/// Parses `squeue -h -r -o %i|%T|%r` into task id → "STATE (reason)".
pub fn parse_squeue(text: &str) -> BTreeMap<String, String> {
    text.lines()
        .filter_map(|l| {
            let mut f = l.trim().split('|');
            let (id, state) = (f.next()?.trim(), f.next()?.trim());
            let reason = f.next().map(str::trim).unwrap_or("");
            (!id.is_empty()).then(|| {
                let state = if reason.is_empty() || reason == "None" {
                    state.to_owned()
                } else {
                    format!("{state} ({reason})")
                };
                (id.to_owned(), state)
            })
        })
        .collect()
}

/// The tasks of the plan's jobs that Slurm still has; `None` when squeue
/// cannot be asked.
fn live_tasks(plan: &Plan) -> Option<BTreeMap<String, String>> {
    if plan.submissions.is_empty() {
        return Some(BTreeMap::new());
    }
    let squeue = on_path("squeue")?;
    let jobs: Vec<&str> = plan.submissions.iter().map(|s| s.job_id.as_str()).collect();
    let out = Command::new(squeue)
        .args(["-h", "-r", "-o", "%i|%T|%r", "-j", &jobs.join(",")])
        .output()
        .ok()?;
    // squeue fails on job ids it has forgotten (all finished long ago):
    // then nothing is queued.
    Some(if out.status.success() {
        parse_squeue(&String::from_utf8_lossy(&out.stdout))
    } else {
        BTreeMap::new()
    })
}

/// The states and the lines that list the points that have not completed.
fn report(dir: &Path, plan: &Plan) -> (Vec<PointState>, Vec<String>) {
    let live = live_tasks(plan).unwrap_or_else(|| {
        eprintln!(
            "note: squeue is not on the PATH: points still queued or running are listed as \
             having no result"
        );
        BTreeMap::new()
    });
    let states = point_states(dir, plan, &live);
    let lines = states
        .iter()
        .enumerate()
        .filter_map(|(i, s)| {
            let what = match s {
                PointState::Finished(s) if s.status == "completed" => return None,
                PointState::Finished(s) => format!(
                    "{}: {}",
                    s.status,
                    s.reason.as_deref().unwrap_or("no reason recorded")
                ),
                PointState::InSlurm(state) => format!("in Slurm: {state}"),
                PointState::NoResult(why) => format!("no result: {why}"),
            };
            let task = plan.task(i).unwrap_or_else(|| "-".to_owned());
            Some(format!("  {}  task {task}  {what}", run_name(i)))
        })
        .collect();
    (states, lines)
}

/// `drape sweep --collect DIR [--retry]`.
pub fn collect(dir: &Path, retry: bool) -> Result<ExitCode> {
    let mut plan = read_plan(dir)?;
    let _lock = OutputLock::acquire(dir).map_err(|e| unusable_output(dir, &e))?;
    let (states, lines) = report(dir, &plan);
    let reports: Vec<Result<Summary, String>> = states
        .iter()
        .enumerate()
        .map(|(i, s)| match s {
            PointState::Finished(s) => Ok((**s).clone()),
            PointState::InSlurm(state) => Err(format!(
                "in Slurm as task {}: {state}",
                plan.task(i).unwrap_or_default()
            )),
            PointState::NoResult(why) => Err(why.clone()),
        })
        .collect();
    let (table, _) = sweep_table::write(dir, &plan.axes, &plan.points, &reports)?;
    print!("{table}");
    let completed = states
        .iter()
        .filter(|s| matches!(s, PointState::Finished(s) if s.status == "completed"))
        .count();
    let in_slurm = states
        .iter()
        .filter(|s| matches!(s, PointState::InSlurm(_)))
        .count();
    eprintln!(
        "collected {completed} of {} points into {}",
        states.len(),
        dir.join("sweep.csv").display()
    );
    if !lines.is_empty() {
        eprintln!("not completed:");
        for l in &lines {
            eprintln!("{l}");
        }
    }
    let again: Vec<usize> = (0..states.len()).filter(|&i| states[i].retry()).collect();
    if retry && !again.is_empty() {
        let sbatch = sbatch()?;
        let script = dir.join(SCRIPT);
        let array = array_spec(&again, plan.options.array_limit);
        let stdout = run_sbatch(&sbatch, &array, &script, false)?;
        let job = parse_job_id(&stdout).ok_or_else(|| {
            anyhow!(
                "sbatch --parsable printed `{}`, not a job id",
                stdout.trim()
            )
        })?;
        plan.submissions.push(Submission {
            job_id: job.clone(),
            points: again.clone(),
        });
        write_plan(dir, &plan)?;
        eprintln!(
            "resubmitted {} points ({}) as job {job}: squeue -j {job}, then collect again",
            again.len(),
            array_spec(&again, None)
        );
        return Ok(ExitCode::SUCCESS);
    }
    if retry {
        eprintln!("nothing to resubmit");
    } else if !again.is_empty() {
        eprintln!(
            "resubmit the {} stopped or missing points with: drape sweep --collect {} --retry",
            again.len(),
            dir.display()
        );
    }
    if in_slurm > 0 {
        eprintln!("{in_slurm} points are still in Slurm's queue: collect again when they are done");
    }
    Ok(if completed + in_slurm == states.len() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(1)
    })
}

/// `drape inspect DIR` on a Slurm sweep: where each point stands and the
/// last collected table; writes nothing.
pub fn inspect(dir: &Path) -> Result<ExitCode> {
    let plan = read_plan(dir)?;
    let (states, lines) = report(dir, &plan);
    let completed = states
        .iter()
        .filter(|s| matches!(s, PointState::Finished(s) if s.status == "completed"))
        .count();
    let jobs: Vec<&str> = plan.submissions.iter().map(|s| s.job_id.as_str()).collect();
    println!(
        "slurm sweep       {} ({} points, {completed} completed; jobs {})",
        dir.display(),
        states.len(),
        if jobs.is_empty() {
            "none submitted".to_owned()
        } else {
            jobs.join(", ")
        }
    );
    for l in &lines {
        println!("{l}");
    }
    let table = dir.join("sweep.csv");
    if table.is_file() {
        inspect_sweep(dir, &table)?;
    } else {
        println!(
            "no sweep.csv yet: gather the finished points with drape sweep --collect {}",
            dir.display()
        );
    }
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn options() -> JobOptions {
        JobOptions {
            partition: Some("short".into()),
            time: Some("1:00:00".into()),
            cpus_per_task: 4,
            array_limit: Some(2),
            account: None,
            sbatch_args: vec!["--mem=4G".into()],
            checkpoint_every: 500,
        }
    }

    #[test]
    fn array_spec_compresses_runs_and_adds_the_limit() {
        assert_eq!(array_spec(&[0, 1, 2, 3], Some(2)), "0-3%2");
        assert_eq!(array_spec(&[0, 2, 3, 4, 7, 9, 10], None), "0,2-4,7,9-10");
        assert_eq!(array_spec(&[5], Some(1)), "5%1");
    }

    #[test]
    fn script_has_the_options_and_runs_one_point_per_task() {
        let s = script(
            "hemi",
            Path::new("/shared/it's here"),
            Path::new("/opt/drape"),
            &options(),
        );
        for line in [
            "#SBATCH --job-name=drape-hemi\n",
            "#SBATCH --cpus-per-task=4\n",
            "#SBATCH --partition=short\n",
            "#SBATCH --time=1:00:00\n",
            "#SBATCH --mem=4G\n",
            "#SBATCH --requeue\n",
            "#SBATCH --signal=B:TERM@120\n",
            "#SBATCH --output=/shared/it's here/slurm/%A_%a.out\n",
            "sweep='/shared/it'\\''s here'\n",
            "drape='/opt/drape'\n",
            "--threads \"$threads\" --checkpoint-every 500\n",
            "exec \"$drape\" run --resume \"$dir\"",
        ] {
            assert!(s.contains(line), "no `{line}` in\n{s}");
        }
        assert!(!s.contains("--account"), "{s}");
    }

    /// The script run by bash, with a fake drape that prints its arguments:
    /// the branch each folder state takes.
    #[test]
    fn script_resumes_skips_or_starts_by_what_the_folder_holds() {
        let dir = std::env::temp_dir().join(format!("drape-slurm-script-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("run_007")).unwrap();
        let fake = dir.join("fake-drape");
        std::fs::write(&fake, "#!/bin/sh\necho \"$@\"\n").unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
        let path = dir.join(SCRIPT);
        std::fs::write(&path, script("t", &dir, &fake, &options())).unwrap();
        let run = || {
            let out = Command::new("bash")
                .arg(&path)
                .env("SLURM_ARRAY_TASK_ID", "7")
                .env("SLURM_CPUS_PER_TASK", "3")
                .output()
                .unwrap();
            assert!(out.status.success(), "{out:?}");
            String::from_utf8(out.stdout).unwrap()
        };
        let d = dir.display();
        let fresh = format!(
            "run {d}/points/point_007.toml --out {d}/run_007 --threads 3 --checkpoint-every 500"
        );
        assert!(run().contains(&fresh), "{}", run());
        std::fs::write(dir.join("run_007/checkpoint.json"), "{}").unwrap();
        std::fs::write(
            dir.join("run_007/summary.json"),
            "{\n  \"status\": \"stopped\"\n}\n",
        )
        .unwrap();
        assert!(run().contains(&format!("run --resume {d}/run_007 --threads 3")));
        // A failed run's checkpoint would only repeat the failure.
        std::fs::write(
            dir.join("run_007/summary.json"),
            "{\n  \"status\": \"failed\"\n}\n",
        )
        .unwrap();
        assert!(run().contains(&fresh));
        std::fs::write(
            dir.join("run_007/summary.json"),
            "{\n  \"status\": \"completed\"\n}\n",
        )
        .unwrap();
        assert!(run().contains("completed already"));
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn options_that_would_break_the_script_are_refused() {
        let err = |args: SlurmArgs| check_options(&args).unwrap_err().to_string();
        let e = err(SlurmArgs {
            partition: Some("short\n#SBATCH --x".into()),
            ..Default::default()
        });
        assert!(e.starts_with("--partition `short"), "{e}");
        assert!(e.contains("expected one word"), "{e}");
        let e = err(SlurmArgs {
            sbatch_args: vec!["mem=4G".into()],
            ..Default::default()
        });
        assert!(
            e.contains("--sbatch-arg `mem=4G`: expected one sbatch option"),
            "{e}"
        );
        let e = err(SlurmArgs {
            array_limit: Some(0),
            ..Default::default()
        });
        assert_eq!(e, "--array-limit must be at least 1");
        assert!(
            check_options(&SlurmArgs {
                time: Some("1-00:00:00".into()),
                sbatch_args: vec!["--mem=4G".into(), "--constraint=a&b".into()],
                ..Default::default()
            })
            .is_ok()
        );
    }

    #[test]
    fn job_ids_from_parsable_output() {
        assert_eq!(parse_job_id("1234\n").as_deref(), Some("1234"));
        assert_eq!(parse_job_id("1234;cluster\n").as_deref(), Some("1234"));
        assert_eq!(parse_job_id("Submitted batch job 1234"), None);
        assert_eq!(parse_job_id(""), None);
    }

    #[test]
    fn local_and_node_local_folders_are_warned_about() {
        let mounts = "overlay / overlay rw 0 0\n\
                      tmpfs /tmp tmpfs rw 0 0\n\
                      srv:/home /home nfs4 rw 0 0\n\
                      srv:/scratch /scratch\\040space lustre rw 0 0\n\
                      srv:/tmp /home/x/tmp nfs rw 0 0\n";
        let warn = |p: &str| shared_fs_warning(Path::new(p), mounts, "the sweep folder");
        assert_eq!(warn("/home/ann/study"), None);
        assert_eq!(warn("/scratch space/ann"), None);
        assert_eq!(warn("/home/x/tmp/a"), None);
        let w = warn("/tmp/study").unwrap();
        assert!(
            w.contains("/tmp/study is on a node-local file system (tmpfs at /tmp)"),
            "{w}"
        );
        let w = warn("/work/study").unwrap();
        assert!(w.contains("a local file system (overlay at /)"), "{w}");
        // Not a path prefix: /homework is not under /home.
        assert!(warn("/homework/a").is_some());
    }

    #[test]
    fn squeue_lines_become_task_states() {
        let live = parse_squeue("12_3|PENDING|JobArrayTaskLimit\n12_0|RUNNING|None\n\n");
        assert_eq!(live["12_3"], "PENDING (JobArrayTaskLimit)");
        assert_eq!(live["12_0"], "RUNNING");
        assert_eq!(live.len(), 2);
    }

    #[test]
    fn the_last_submission_of_a_point_names_its_task() {
        let plan = Plan {
            scene: "s.toml".into(),
            axes: vec![("a".into(), vec!["1".into(), "2".into(), "3".into()])],
            points: vec![vec![("a".into(), "1".into())]; 3],
            drape: "drape".into(),
            options: options(),
            submissions: vec![
                Submission {
                    job_id: "10".into(),
                    points: vec![0, 1, 2],
                },
                Submission {
                    job_id: "11".into(),
                    points: vec![1],
                },
            ],
        };
        assert_eq!(plan.task(0).as_deref(), Some("10_0"));
        assert_eq!(plan.task(1).as_deref(), Some("11_1"));
        let json = serde_json::to_string(&plan).unwrap();
        assert_eq!(serde_json::from_str::<Plan>(&json).unwrap(), plan);
    }

    #[test]
    fn a_log_names_why_a_task_left_no_summary() {
        let log = "drape: point run_002, task 5_2 on n1, restart 0\n\
                   slurmstepd: error: *** JOB 8 ON n1 CANCELLED AT 2026-11-28T02:36:37 DUE TO TIME LIMIT ***\n\
                   \n";
        assert!(log_reason(log).unwrap().contains("DUE TO TIME LIMIT"));
        assert_eq!(log_reason("just this\n").as_deref(), Some("just this"));
        assert_eq!(log_reason("\n\n"), None);
    }
}
