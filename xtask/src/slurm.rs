//! `cargo xtask slurm`: `drape sweep --slurm` against a real Slurm.
//!
//! Starts a one-node Slurm cluster on this machine (Debian's `slurm-wlm`
//! and `munge`, installed with apt-get when missing; a generated munge key
//! and `slurm.conf`; `munged`, `slurmctld` and `slurmd` in a temporary
//! folder, no cgroups, no accounting database), submits a sweep through
//! `drape sweep --slurm`, requeues one task in the middle of its run
//! (`scontrol requeue`: Slurm stops it with SIGTERM and runs it again, and
//! the task must continue from its checkpoint), collects, and checks the
//! collected results against a local `drape sweep` of the same points: the
//! summaries' measures bit for bit. The daemons are stopped at the end,
//! also when a step fails (a guard's `Drop`).
//!
//! `--study` instead times the hemisphere study of the README (16 points
//! through Slurm with `--array-limit 2`, then the same sweep run locally).
//!
//! Needs root (the daemons run as root, apt-get installs). Not a way to
//! run Slurm for real work: one node, no accounting, state in a temporary
//! folder.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitCode, Stdio};
use std::time::{Duration, Instant};

/// `cargo xtask slurm [--quick] [--study] [--keep]`.
pub struct Options {
    /// The CI form: four short points.
    pub quick: bool,
    /// Time the 16-point hemisphere study through Slurm and locally.
    pub study: bool,
    /// Keep the temporary folder (daemon logs, the sweeps) afterwards.
    pub keep: bool,
}

impl Options {
    pub fn parse(args: &[String]) -> Result<Self, String> {
        let mut o = Options {
            quick: false,
            study: false,
            keep: false,
        };
        for a in args {
            match a.as_str() {
                "--quick" => o.quick = true,
                "--study" => o.study = true,
                "--keep" => o.keep = true,
                other => return Err(format!("slurm: unknown option `{other}`")),
            }
        }
        Ok(o)
    }
}

type Step<T> = Result<T, String>;

pub fn main(options: &Options, root: &Path, target: &Path) -> ExitCode {
    let work = target
        .join("slurm")
        .join(format!("run-{}", std::process::id()));
    let outcome = install()
        .and_then(|()| build(root, options.study))
        .and_then(|drape| {
            let cluster = Cluster::start(&work.join("cluster"))?;
            if options.study {
                study(&cluster, &drape, root, &work)
            } else {
                requeue_test(&cluster, &drape, root, &work, options.quick)
            }
            // The cluster is stopped here, before the folder goes.
        });
    if options.keep || outcome.is_err() {
        eprintln!("slurm: kept {}", work.display());
    } else {
        let _ = std::fs::remove_dir_all(&work);
    }
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("slurm: FAILED: {e}");
            ExitCode::FAILURE
        }
    }
}

/// Where `program` is: on the PATH or in the sbin folders (a non-login
/// root shell may lack them).
fn find(program: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin", "/sbin", "/usr/bin"].map(PathBuf::from))
        .map(|d| d.join(program))
        .find(|p| p.is_file())
}

/// Runs `cmd`; exit codes 0 and 1 pass (a sweep with failed points exits
/// 1, and its table is still the result); its standard output.
fn run_sweep(cmd: &mut Command) -> Step<String> {
    let out = cmd
        .output()
        .map_err(|e| format!("cannot start {cmd:?}: {e}"))?;
    match out.status.code() {
        Some(0 | 1) => Ok(String::from_utf8_lossy(&out.stdout).into_owned()),
        _ => Err(format!(
            "{cmd:?} failed ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr)
        )),
    }
}

fn run_ok(cmd: &mut Command) -> Step<String> {
    let out = cmd
        .output()
        .map_err(|e| format!("cannot start {cmd:?}: {e}"))?;
    if !out.status.success() {
        return Err(format!(
            "{cmd:?} failed ({}): {}{}",
            out.status,
            String::from_utf8_lossy(&out.stdout),
            String::from_utf8_lossy(&out.stderr)
        ));
    }
    Ok(String::from_utf8_lossy(&out.stdout).into_owned())
}

/// Debian's packages, unless every program is there already.
fn install() -> Step<()> {
    let programs = [
        "munged",
        "slurmctld",
        "slurmd",
        "sbatch",
        "squeue",
        "scontrol",
    ];
    if programs.iter().all(|p| find(p).is_some()) {
        return Ok(());
    }
    let uid = run_ok(Command::new("id").arg("-u"))?;
    if uid.trim() != "0" {
        return Err("Slurm and munge are not installed, and installing them needs root".into());
    }
    eprintln!("slurm: installing slurm-wlm and munge (apt-get)");
    let apt = |args: &[&str]| {
        Command::new("apt-get")
            .args(args)
            .env("DEBIAN_FRONTEND", "noninteractive")
            .stdout(Stdio::null())
            .status()
            .map_err(|e| format!("cannot start apt-get: {e}"))
    };
    let packages = ["install", "-y", "-q", "slurm-wlm", "munge"];
    if !apt(&packages)?.success() {
        // A fresh machine has no package lists yet.
        apt(&["update", "-q"])?;
        if !apt(&packages)?.success() {
            return Err("apt-get install slurm-wlm munge failed".into());
        }
    }
    match programs.iter().find(|p| find(p).is_none()) {
        Some(p) => Err(format!(
            "{p} is still missing after installing slurm-wlm and munge"
        )),
        None => Ok(()),
    }
}

/// The drape binary the tasks run (release for the timed study).
fn build(root: &Path, release: bool) -> Step<PathBuf> {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut cmd = Command::new(cargo);
    cmd.args(["build", "-q", "-p", "drape", "--bin", "drape"])
        .current_dir(root);
    if release {
        cmd.arg("--release");
    }
    let status = cmd
        .status()
        .map_err(|e| format!("cannot start cargo: {e}"))?;
    if !status.success() {
        return Err("cargo build -p drape failed".into());
    }
    let target = crate::target_dir();
    Ok(target
        .join(if release { "release" } else { "debug" })
        .join("drape"))
}

/// A one-node cluster: its daemons are stopped when it is dropped.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    /// munged, slurmctld, slurmd, in starting order.
    daemons: Vec<(&'static str, Child)>,
}

impl Cluster {
    fn start(dir: &Path) -> Step<Self> {
        let _ = std::fs::remove_dir_all(dir);
        for sub in ["state", "spool", "log"] {
            std::fs::create_dir_all(dir.join(sub))
                .map_err(|e| format!("{}: {e}", dir.display()))?;
        }
        let mut cluster = Cluster {
            dir: dir.to_owned(),
            conf: dir.join("slurm.conf"),
            daemons: Vec::new(),
        };
        let socket = dir.join("munge.socket");
        let key = dir.join("munge.key");
        // 1 KiB of randomness, as mungekey makes it.
        std::fs::write(&key, random_bytes(1024)?).map_err(|e| format!("{}: {e}", key.display()))?;
        set_mode(&key, 0o400)?;
        let d = dir.display();
        cluster.spawn(
            "munged",
            Command::new(find("munged").unwrap()).args([
                "-F".to_owned(),
                "-f".to_owned(),
                format!("--key-file={}", key.display()),
                format!("--socket={}", socket.display()),
                format!("--pid-file={d}/munged.pid"),
                format!("--log-file={d}/log/munged.log"),
                format!("--seed-file={d}/munged.seed"),
            ]),
        )?;
        wait_for(Duration::from_secs(20), "munged's socket", || {
            socket.exists().then_some(())
        })?;
        // The node as slurmd sees it (CPUs, sockets, memory), on one line.
        let node = run_ok(Command::new(find("slurmd").unwrap()).arg("-C"))?;
        let node = node
            .lines()
            .find(|l| l.starts_with("NodeName="))
            .ok_or("slurmd -C printed no NodeName line")?
            .to_owned();
        let host = node
            .split_whitespace()
            .next()
            .and_then(|f| f.strip_prefix("NodeName="))
            .unwrap_or("localhost")
            .to_owned();
        // Ports of this process's own, so that a cluster left running
        // elsewhere on the machine is not in the way.
        let port = 20000 + 2 * (std::process::id() % 10000);
        let conf = format!(
            "# drape's test cluster (cargo xtask slurm): one node, no cgroups, no accounting.\n\
             ClusterName=drapetest\n\
             SlurmctldHost={host}(127.0.0.1)\n\
             SlurmUser=root\n\
             SlurmdUser=root\n\
             SlurmctldPort={port}\n\
             SlurmdPort={}\n\
             AuthType=auth/munge\n\
             AuthInfo=socket={}\n\
             CredType=cred/munge\n\
             StateSaveLocation={d}/state\n\
             SlurmdSpoolDir={d}/spool\n\
             SlurmctldPidFile={d}/slurmctld.pid\n\
             SlurmdPidFile={d}/slurmd.pid\n\
             SlurmctldLogFile={d}/log/slurmctld.log\n\
             SlurmdLogFile={d}/log/slurmd.log\n\
             ProctrackType=proctrack/linuxproc\n\
             TaskPlugin=task/none\n\
             SelectType=select/cons_tres\n\
             SelectTypeParameters=CR_CPU\n\
             SchedulerType=sched/backfill\n\
             MpiDefault=none\n\
             ReturnToService=2\n\
             JobAcctGatherType=jobacct_gather/none\n\
             AccountingStorageType=accounting_storage/none\n\
             JobCompType=jobcomp/none\n\
             KillWait=30\n\
             MinJobAge=3600\n\
             {node} NodeAddr=127.0.0.1 State=UNKNOWN\n\
             PartitionName=debug Nodes=ALL Default=YES MaxTime=INFINITE State=UP\n",
            port + 1,
            socket.display(),
        );
        std::fs::write(&cluster.conf, conf).map_err(|e| format!("slurm.conf: {e}"))?;
        let conf = cluster.conf.display().to_string();
        cluster.spawn(
            "slurmctld",
            Command::new(find("slurmctld").unwrap()).args(["-D", "-c", "-f", &conf]),
        )?;
        cluster.spawn(
            "slurmd",
            Command::new(find("slurmd").unwrap()).args(["-D", "-f", &conf]),
        )?;
        wait_for(Duration::from_secs(60), "the node to be idle", || {
            let out = cluster
                .cmd("sinfo")
                .args(["-h", "-o", "%T"])
                .output()
                .ok()?;
            (String::from_utf8_lossy(&out.stdout).trim() == "idle").then_some(())
        })
        .map_err(|e| format!("{e}; {}", cluster.logs()))?;
        eprintln!("slurm: cluster up: node {host}, {}", cluster.conf.display());
        Ok(cluster)
    }

    fn spawn(&mut self, name: &'static str, cmd: &mut Command) -> Step<()> {
        let log = std::fs::File::create(self.dir.join("log").join(format!("{name}.out")))
            .map_err(|e| format!("{name}'s log: {e}"))?;
        let child = cmd
            .env("SLURM_CONF", &self.conf)
            .stdout(log.try_clone().map_err(|e| e.to_string())?)
            .stderr(log)
            .spawn()
            .map_err(|e| format!("cannot start {name}: {e}"))?;
        self.daemons.push((name, child));
        Ok(())
    }

    /// A Slurm (or drape) command that talks to this cluster.
    fn cmd(&self, program: impl AsRef<std::ffi::OsStr>) -> Command {
        let mut c = Command::new(program);
        c.env("SLURM_CONF", &self.conf);
        c
    }

    /// The ends of the daemons' logs, for an error message.
    fn logs(&self) -> String {
        ["slurmctld.log", "slurmd.log", "slurmctld.out", "slurmd.out"]
            .iter()
            .map(|f| {
                let text =
                    std::fs::read_to_string(self.dir.join("log").join(f)).unwrap_or_default();
                let tail: Vec<&str> = text.lines().rev().take(8).collect();
                format!(
                    "{f}:\n{}",
                    tail.into_iter().rev().collect::<Vec<_>>().join("\n")
                )
            })
            .collect::<Vec<_>>()
            .join("\n")
    }

    /// Task id → state of the jobs Slurm still has.
    fn queue(&self, job: &str) -> BTreeMap<String, String> {
        let out = self
            .cmd("squeue")
            .args(["-h", "-r", "-j", job, "-o", "%i %T"])
            .output();
        let Ok(out) = out else {
            return BTreeMap::new();
        };
        String::from_utf8_lossy(&out.stdout)
            .lines()
            .filter_map(|l| {
                let (id, state) = l.trim().split_once(' ')?;
                Some((id.to_owned(), state.to_owned()))
            })
            .collect()
    }

    /// Waits until Slurm has none of `job`'s tasks, printing each change
    /// of their states; `each` sees every poll's states.
    fn wait_job(
        &self,
        job: &str,
        limit: Duration,
        mut each: impl FnMut(&BTreeMap<String, String>) -> Step<()>,
    ) -> Step<()> {
        let start = Instant::now();
        let mut last = None;
        loop {
            let q = self.queue(job);
            if last.as_ref() != Some(&q) {
                let states: Vec<String> = q.iter().map(|(k, v)| format!("{k} {v}")).collect();
                eprintln!(
                    "slurm: {:5.1} s  {}",
                    start.elapsed().as_secs_f64(),
                    if states.is_empty() {
                        "queue empty".to_owned()
                    } else {
                        states.join(", ")
                    }
                );
                last = Some(q.clone());
            }
            each(&q)?;
            if q.is_empty() {
                return Ok(());
            }
            if start.elapsed() > limit {
                return Err(format!("job {job} still in the queue after {limit:?}"));
            }
            std::thread::sleep(Duration::from_millis(250));
        }
    }

    /// Each task's final state as slurmctld keeps it (no accounting here).
    fn task_states(&self, job: &str) -> Step<Vec<String>> {
        let text = run_ok(self.cmd("scontrol").args(["-o", "show", "job", job]))?;
        Ok(text
            .lines()
            .map(|l| {
                let field = |k: &str| {
                    l.split_whitespace()
                        .find_map(|f| f.strip_prefix(k))
                        .unwrap_or("?")
                        .to_owned()
                };
                format!(
                    "{}_{}: {} (exit {}, restarts {})",
                    field("ArrayJobId="),
                    field("ArrayTaskId="),
                    field("JobState="),
                    field("ExitCode="),
                    field("Restarts=")
                )
            })
            .collect())
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // The tasks first: a slurmstepd whose slurmd is gone lingers.
        let _ = self.cmd("scancel").args(["-u", "root"]).output();
        let _ = wait_for(Duration::from_secs(40), "the queue to empty", || {
            let out = self.cmd("squeue").arg("-h").output().ok()?;
            String::from_utf8_lossy(&out.stdout)
                .trim()
                .is_empty()
                .then_some(())
        });
        for (name, child) in self.daemons.iter_mut().rev() {
            let _ = Command::new("kill")
                .args(["-TERM", &child.id().to_string()])
                .status();
            let stopped = wait_for(Duration::from_secs(10), name, || {
                child.try_wait().ok().flatten().map(|_| ())
            });
            if stopped.is_err() {
                let _ = child.kill();
                let _ = child.wait();
            }
        }
        eprintln!("slurm: daemons stopped");
    }
}

/// Polls `f` until it gives a value, or fails after `limit`.
fn wait_for<T>(limit: Duration, what: &str, mut f: impl FnMut() -> Option<T>) -> Step<T> {
    let start = Instant::now();
    loop {
        if let Some(v) = f() {
            return Ok(v);
        }
        if start.elapsed() > limit {
            return Err(format!("timed out after {limit:?} waiting for {what}"));
        }
        std::thread::sleep(Duration::from_millis(200));
    }
}

fn set_mode(path: &Path, mode: u32) -> Step<()> {
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(path, std::fs::Permissions::from_mode(mode))
        .map_err(|e| format!("{}: {e}", path.display()))
}

/// `n` random bytes from the kernel.
fn random_bytes(n: usize) -> Step<Vec<u8>> {
    use std::io::Read;
    let mut bytes = vec![0; n];
    std::fs::File::open("/dev/urandom")
        .and_then(|mut f| f.read_exact(&mut bytes))
        .map_err(|e| format!("/dev/urandom: {e}"))?;
    Ok(bytes)
}

/// A summary's JSON without what differs between two runs of one scene:
/// the wall time, the thread count and the scene file's path.
fn measures(run: &Path) -> Step<String> {
    let path = run.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    // Line-wise on the pretty JSON: std only (see the crate's docs).
    Ok(text
        .lines()
        .filter(|l| {
            let l = l.trim_start();
            !(l.starts_with("\"wall_s\"")
                || l.starts_with("\"threads\"")
                || l.starts_with("\"scene\""))
        })
        .collect::<Vec<_>>()
        .join("\n"))
}

/// `drape sweep` locally, timed.
fn local_sweep(drape: &Path, scene: &Path, sets: &[String], out: &Path) -> Step<f64> {
    let start = Instant::now();
    let mut cmd = Command::new(drape);
    cmd.arg("sweep").arg(scene);
    for s in sets {
        cmd.args(["--set", s]);
    }
    cmd.arg("--out").arg(out).stdout(Stdio::null());
    run_sweep(&mut cmd)?;
    Ok(start.elapsed().as_secs_f64())
}

/// `drape sweep --slurm`: the job id.
fn submit(
    cluster: &Cluster,
    drape: &Path,
    scene: &Path,
    sets: &[String],
    out: &Path,
    extra: &[&str],
) -> Step<String> {
    let mut cmd = cluster.cmd(drape);
    cmd.arg("sweep").arg(scene);
    for s in sets {
        cmd.args(["--set", s]);
    }
    cmd.args(["--slurm", "--out"]).arg(out).args(extra);
    let o = cmd
        .output()
        .map_err(|e| format!("cannot start drape: {e}"))?;
    let text = String::from_utf8_lossy(&o.stdout).into_owned();
    print!("{text}{}", String::from_utf8_lossy(&o.stderr));
    if !o.status.success() {
        return Err(format!("drape sweep --slurm failed ({})", o.status));
    }
    text.lines()
        .find_map(|l| l.strip_prefix("submitted job "))
        .and_then(|l| l.split(':').next())
        .map(str::to_owned)
        .ok_or_else(|| format!("no job id in drape's output:\n{text}"))
}

fn requeue_test(
    cluster: &Cluster,
    drape: &Path,
    root: &Path,
    work: &Path,
    quick: bool,
) -> Step<()> {
    // Picture-frame shears of a few seconds each: long enough to requeue
    // one in its middle, short enough for CI on two cores.
    let (points, end) = if quick {
        ("20,35,50,60", "0.2")
    } else {
        ("20,30,40,50,55,60", "0.4")
    };
    let sets: Vec<String> = [
        format!("boundary.0.motion.shear_deg={points}"),
        format!("simulation.end_time={end}"),
        format!("boundary.0.motion.amplitude.duration={end}"),
        "output.vtu=false".to_owned(),
    ]
    .into();
    let scene = root.join("scenes/picture-frame.toml");
    let sweep = work.join("slurm-sweep");
    // A partition the cluster does not have: bad input with Slurm's own
    // words, and nothing written.
    let refused = work.join("refused-sweep");
    let mut cmd = cluster.cmd(drape);
    cmd.arg("sweep").arg(&scene);
    for s in &sets {
        cmd.args(["--set", s]);
    }
    let o = cmd
        .args(["--slurm", "--partition", "nope", "--out"])
        .arg(&refused)
        .output()
        .map_err(|e| format!("cannot start drape: {e}"))?;
    let said = String::from_utf8_lossy(&o.stderr);
    if o.status.code() != Some(2) || !said.contains("invalid partition") || refused.exists() {
        return Err(format!(
            "--partition nope: expected exit 2 with Slurm's message and nothing written, got {} \
             and: {said}",
            o.status
        ));
    }
    println!("unknown partition: exit 2, {}", said.trim());
    let job = submit(
        cluster,
        drape,
        &scene,
        &sets,
        &sweep,
        &["--array-limit", "2", "--checkpoint-every", "4000"],
    )?;
    // The first task that has written a checkpoint and is still running
    // is requeued: Slurm stops it (SIGTERM, the run writes a stopped
    // summary) and starts it again.
    let mut requeued: Option<(String, usize)> = None;
    let mut released = false;
    cluster.wait_job(&job, Duration::from_secs(900), |q| {
        match &requeued {
            None => {
                for (task, state) in q {
                    let i: usize = task
                        .rsplit('_')
                        .next()
                        .and_then(|i| i.parse().ok())
                        .unwrap_or(0);
                    let run = sweep.join(format!("run_{i:03}"));
                    if state == "RUNNING"
                        && run.join("checkpoint.json").is_file()
                        && !run.join("summary.json").is_file()
                    {
                        run_ok(cluster.cmd("scontrol").args(["requeue", task]))?;
                        eprintln!(
                            "slurm: requeued {task} in the middle of its run (it has a checkpoint)"
                        );
                        requeued = Some((task.clone(), i));
                        break;
                    }
                }
            }
            // Slurm holds a requeued task back for a while (its begin
            // time): let it go at once.
            Some((task, _)) if !released && q.get(task).is_some_and(|s| s == "PENDING") => {
                run_ok(cluster.cmd("scontrol").args([
                    "update",
                    &format!("jobid={task}"),
                    "StartTime=now",
                ]))?;
                released = true;
            }
            _ => {}
        }
        Ok(())
    })?;
    let (task, i) = requeued.ok_or("no task was caught running with a checkpoint to requeue")?;
    println!("job {job}, task states:");
    for line in cluster.task_states(&job)? {
        println!("  {line}");
    }
    let log_path = sweep.join("slurm").join(format!("{task}.out"));
    let log =
        std::fs::read_to_string(&log_path).map_err(|e| format!("{}: {e}", log_path.display()))?;
    println!("log of the requeued task {task}:");
    for l in log.lines().filter(|l| {
        l.starts_with("drape:")
            || l.contains("REQUEUE")
            || l.contains("resuming")
            || l.contains("stopping")
    }) {
        println!("  {l}");
    }
    if !log.contains("DUE TO JOB REQUEUE") || !log.contains("resuming") {
        return Err(format!(
            "{}: the requeued task did not stop and resume from its checkpoint",
            log_path.display()
        ));
    }
    let collected = run_ok(cluster.cmd(drape).args(["sweep", "--collect"]).arg(&sweep))?;
    print!("collected:\n{collected}");
    let local = work.join("local-sweep");
    local_sweep(drape, &scene, &sets, &local)?;
    let n = points.split(',').count();
    for p in 0..n {
        let run = format!("run_{p:03}");
        let (a, b) = (measures(&sweep.join(&run))?, measures(&local.join(&run))?);
        if a != b {
            return Err(format!(
                "{run}: the Slurm sweep's summary differs from the local one:\n{a}\n---\n{b}"
            ));
        }
    }
    let strip = |dir: &Path| -> Step<String> {
        let t = std::fs::read_to_string(dir.join("sweep.csv")).map_err(|e| e.to_string())?;
        let wall = t
            .lines()
            .next()
            .and_then(|h| h.split(',').position(|c| c == "wall_s"))
            .ok_or("sweep.csv has no wall_s column")?;
        Ok(t.lines()
            .map(|l| {
                let mut f: Vec<&str> = l.split(',').collect();
                if f.len() > wall {
                    f[wall] = "";
                }
                f.join(",")
            })
            .collect::<Vec<_>>()
            .join("\n"))
    };
    if strip(&sweep)? != strip(&local)? {
        return Err(
            "sweep.csv of the Slurm sweep differs from the local one (beyond wall_s)".into(),
        );
    }
    println!(
        "slurm: PASSED: job {job}, {n} points, {task} requeued and resumed from its checkpoint \
         (run_{i:03}); every summary's measures equal the local sweep's bit for bit, and \
         sweep.csv is the local one but for wall_s"
    );
    Ok(())
}

/// The README's hemisphere study: 16 points at 10 × 10 cells, through
/// Slurm two at a time, then the same sweep here.
fn study(cluster: &Cluster, drape: &Path, root: &Path, work: &Path) -> Step<()> {
    std::fs::create_dir_all(work).map_err(|e| e.to_string())?;
    let text = std::fs::read_to_string(root.join("scenes/hemisphere-ring.toml"))
        .map_err(|e| e.to_string())?;
    let coarse = text.replace("cells = [40, 40]", "cells = [10, 10]");
    if coarse == text {
        return Err("scenes/hemisphere-ring.toml: no `cells = [40, 40]` to coarsen".into());
    }
    let scene = work.join("hemisphere-ring-10x10.toml");
    std::fs::write(&scene, coarse).map_err(|e| e.to_string())?;
    let sets: Vec<String> = [
        "fabric.orientation_deg=0,45",
        "tools.0.friction=0,0.1,0.2,0.5",
        "tools.2.motion.force=4000,8000",
        "output.vtu=false",
    ]
    .map(str::to_owned)
    .into();
    let sweep = work.join("study-slurm");
    let start = Instant::now();
    let job = submit(
        cluster,
        drape,
        &scene,
        &sets,
        &sweep,
        &["--array-limit", "2"],
    )?;
    cluster.wait_job(&job, Duration::from_secs(3600), |_| Ok(()))?;
    let collected = run_sweep(cluster.cmd(drape).args(["sweep", "--collect"]).arg(&sweep))?;
    let slurm_s = start.elapsed().as_secs_f64();
    print!("{collected}");
    let local_s = local_sweep(drape, &scene, &sets, &work.join("study-local"))?;
    let table = std::fs::read_to_string(sweep.join("sweep.csv")).map_err(|e| e.to_string())?;
    let completed = table.matches(",completed,").count();
    for p in 0..16 {
        let run = format!("run_{p:03}");
        if measures(&sweep.join(&run))? != measures(&work.join("study-local").join(&run))? {
            return Err(format!("{run}: the Slurm and local summaries differ"));
        }
    }
    println!(
        "study: 16 points, hemisphere-ring at 10 x 10: through Slurm (--array-limit 2, 1 CPU a \
         task, submit to collect) {slurm_s:.1} s, locally (drape sweep, all cores) {local_s:.1} s; \
         {completed} of 16 completed; summaries equal bit for bit"
    );
    Ok(())
}
