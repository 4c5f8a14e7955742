//! The `drape` command: run, new, sweep, inspect, kinematic, compare,
//! export.
//!
//! Exit codes: 0 done, 1 the run failed (diverged or could not write its
//! results; what it reached is kept), 2 bad input (a bad scene, an output
//! folder that cannot be written or that another run is writing into;
//! nothing is written), 130 stopped by Ctrl-C (the last frame, the energy
//! history and a summary with status "stopped" are written). The same
//! contract for every command, with the output-folder claim and the
//! signals: `exit.rs`.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use clap::{Parser, Subcommand};
use drape::{Checkpoint, RunControl, RunOptions, RunProgress, open_output, run_in, run_scene};
use drape_io::results::{OutputLock, ResultsError, Summary};
use drape_io::scene::{Device, Scene};
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

mod exit;
mod fit_cmd;
mod slurm;
mod sweep_table;
mod terminal;
use terminal::*;

#[derive(Parser)]
#[command(
    name = "drape",
    version,
    about = "Composite fabric forming simulation",
    long_about = None,
    after_help = "Exit codes: 0 done, 1 the run failed (what it reached is kept), 2 bad input \
                  (nothing written), 130 stopped by Ctrl-C (last frame and summary written)."
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene and write its results.
    Run {
        /// The scene file (TOML).
        #[arg(required_unless_present = "resume")]
        scene: Option<PathBuf>,
        /// Output directory (default: results/<scene name>).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene value: --set tools.0.friction=0.2 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// Worker threads (default: all cores; more than the machine runs
        /// at once is brought down to that).
        #[arg(long)]
        threads: Option<usize>,
        /// Where the explicit steps run: cpu (the default) or gpu (an
        /// NVIDIA GPU; the same as --set simulation.device=gpu). With
        /// --resume, continue the stopped run on that device instead of
        /// the one it ran on.
        #[arg(long, value_name = "DEVICE")]
        device: Option<String>,
        /// Write a restart file (checkpoint.json) every N steps; a run that
        /// completes removes it.
        #[arg(long, value_name = "N")]
        checkpoint_every: Option<u64>,
        /// Continue the stopped run in DIR from its checkpoint, with the
        /// scene it started with (every value, overrides included, is kept
        /// in the checkpoint: the scene file is not read again, and an
        /// edited one is reported and ignored). Works from any directory.
        #[arg(long, value_name = "DIR", conflicts_with_all = ["scene", "set", "out"])]
        resume: Option<PathBuf>,
    },
    /// Write a ready-to-run scene from a template.
    New {
        /// hemisphere, deep-drawing, picture-frame, bias-extension or stack
        /// (without it: the list, and exit code 2 as for any usage error).
        template: Option<String>,
        /// Where to write it (default: <template>.toml).
        path: Option<PathBuf>,
    },
    /// Run every combination of values and write one table of results.
    Sweep {
        /// The scene file (TOML).
        #[arg(required_unless_present = "collect")]
        scene: Option<PathBuf>,
        /// A key and its values: --set tools.0.friction=0,0.1,0.2 (repeatable).
        #[arg(
            long = "set",
            value_name = "KEY=V1,V2,…",
            required_unless_present = "collect"
        )]
        set: Vec<String>,
        /// Output directory (default: results/<scene name>-sweep).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores; more than the machine runs
        /// at once is brought down to that).
        #[arg(long)]
        threads: Option<usize>,
        /// On a Slurm cluster: --slurm and its options, --collect, --retry.
        #[command(flatten)]
        slurm: slurm::SlurmArgs,
    },
    /// Print the summary of a run's output directory.
    Inspect {
        /// The output directory.
        dir: PathBuf,
    },
    /// Drape the scene's blank on its mould as a pin-jointed net (kinematic
    /// draping, in milliseconds) and write the results a run writes.
    Kinematic {
        /// The scene file (TOML); its [kinematic] table or the defaults.
        scene: PathBuf,
        /// Output directory (default: results/<scene name>-kinematic).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Override a scene value: --set kinematic.spacing=5 (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
    },
    /// Compare two runs' results folders (RUN_A RUN_B: their measures side
    /// by side and a map of their shear difference), or run one scene both
    /// ways (SCENE: the kinematic net against the forming run).
    #[command(after_long_help = "\
Which is which: the number of arguments decides.
  drape compare RUN_A RUN_B   two results folders of any runs (`drape run`,
                              `drape kinematic`, a sweep's run_NNN, `drape
                              compare SCENE`'s mechanical/ and kinematic/).
                              Nothing is run. A is the reference: differences
                              are B - A, on A's mesh at A's flat (reference)
                              positions; B is carried onto it by closest point
                              when the meshes differ. Writes comparison.json,
                              comparison.csv and comparison.png.
  drape compare SCENE         one scene file, run both ways: the kinematic net
                              into OUT/kinematic, the forming run into
                              OUT/mechanical, and their comparison into OUT.
                              --set and --threads apply to this form only.")]
    Compare {
        /// Two results folders, or one scene file (TOML).
        #[arg(required = true, num_args = 1..=2, value_name = "RUN_A RUN_B | SCENE")]
        inputs: Vec<PathBuf>,
        /// Output directory (default: results/<A>-vs-<B>, or
        /// results/<scene name>-compare).
        #[arg(long)]
        out: Option<PathBuf>,
        /// With a scene: override a scene value, --set tools.0.friction=0
        /// (repeatable).
        #[arg(long = "set", value_name = "KEY=VALUE")]
        set: Vec<String>,
        /// With a scene: worker threads of the forming run (default: all
        /// cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Carry a run's draped fibre orientations onto a structural mesh by
    /// closest point (an Abaqus include and a CSV table).
    Export {
        /// The run's results folder (it holds orientations.inp).
        run: PathBuf,
        /// The structural mesh: Gmsh .msh (4.1) or Abaqus .inp (an
        /// Abaqus/CAE file with parts and one instance included), triangles
        /// and quads, in the formed part's coordinates.
        #[arg(long, value_name = "MESH")]
        onto: PathBuf,
        /// The unit of the mesh's coordinates; the include written is in it
        /// (its thicknesses), distances are reported in mm.
        #[arg(long, value_enum, default_value = "mm", conflicts_with = "scale")]
        units: ExportUnit,
        /// Millimetres per unit of the mesh's coordinates, for a unit
        /// --units does not name.
        #[arg(long, value_name = "MM_PER_UNIT")]
        scale: Option<f64>,
        /// Output directory (default: the run's folder).
        #[arg(long)]
        out: Option<PathBuf>,
    },
    /// Fit a material law to a lab's characterisation test and write a
    /// material card (with a plot and the residuals).
    Fit {
        #[command(subcommand)]
        test: fit_cmd::FitTest,
    },
}

/// The unit of a structural mesh for `drape export --units`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
enum ExportUnit {
    Mm,
    Cm,
    M,
    In,
}

/// Templates shipped with the binary: name, what it is, the scene.
const TEMPLATES: [(&str, &str, &str); 5] = [
    (
        "hemisphere",
        "carbon prepreg laid up on a hemispherical punch (El Hami et al. 2009, §5.1)",
        include_str!("../../../scenes/hemisphere-0-90.toml"),
    ),
    (
        "deep-drawing",
        "glass fabric drawn by a punch through a die under a blank holder (§5.2)",
        include_str!("../../../scenes/deep-drawing-0-90.toml"),
    ),
    (
        "picture-frame",
        "picture-frame shear test of a glass fabric square, to 60°",
        include_str!("../../../scenes/picture-frame.toml"),
    ),
    (
        "bias-extension",
        "bias-extension test of a ±45 glass fabric strip",
        include_str!("../../../scenes/bias-extension.toml"),
    ),
    (
        "stack",
        "two plies (0/90 under ±45) formed together on a hemisphere, ply–ply friction",
        include_str!("../../../scenes/hemisphere-stack.toml"),
    ),
];

/// The templates, one a line, for `drape new` without a name.
fn template_list() -> String {
    TEMPLATES
        .iter()
        .map(|(name, what, _)| format!("  {name:<15} {what}"))
        .collect::<Vec<_>>()
        .join("\n")
}

/// Bad input: exit 2.
#[derive(Debug)]
struct BadInput(String);
impl std::fmt::Display for BadInput {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}
impl std::error::Error for BadInput {}

fn bad(message: impl Into<String>) -> anyhow::Error {
    anyhow!(BadInput(message.into()))
}

/// Set by the first Ctrl-C (or SIGTERM, SIGHUP): runs stop after their
/// current step and write what they reached.
static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// The exit code of a run stopped by Ctrl-C (128 + SIGINT, as shells do),
/// also when SIGTERM or SIGHUP stopped it.
const INTERRUPTED_EXIT: u8 = 130;

/// The first Ctrl-C asks the runs to stop cleanly; a second one quits at
/// once (every file is still whole: each is written to a temporary and
/// renamed, and the next run into the folder clears the temporaries).
fn handle_ctrl_c() {
    let installed = ctrlc::set_handler(|| {
        let repeated = INTERRUPTED.swap(true, Ordering::SeqCst);
        if exit::signal_quits_at_once() {
            exit::quit_now();
        }
        if repeated {
            eprintln!("\nquitting now: the results are those of the last frame written");
            std::process::exit(i32::from(INTERRUPTED_EXIT));
        }
        eprintln!(
            "\nstopping after this step: writing the last frame, the energy history and the \
             summary (Ctrl-C again to quit at once)"
        );
    });
    if let Err(e) = installed {
        eprintln!("note: Ctrl-C will not stop runs cleanly: {e}");
    }
}

fn interrupted() -> bool {
    INTERRUPTED.load(Ordering::SeqCst)
}

/// The error and its causes on one line, each cause once (a cause that an
/// outer message already quotes is not repeated).
fn describe(e: &anyhow::Error) -> String {
    let mut text = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

fn main() -> ExitCode {
    quit_on_a_closed_pipe();
    // Before anything is read: a signal must never wait on a blocked read.
    handle_ctrl_c();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            scene,
            out,
            set,
            threads,
            device,
            checkpoint_every,
            resume,
        } => with_threads(threads, || match (resume, scene) {
            (Some(dir), _) => resume_run(&dir, checkpoint_every, device.as_deref()),
            (None, Some(scene)) => {
                let mut set = set;
                if let Some(d) = device {
                    set.push(format!("simulation.device={d}"));
                }
                run(&scene, out, &set, checkpoint_every)
            }
            (None, None) => Err(bad("give a scene file or --resume DIR")),
        }),
        Command::New { template, path } => new(template.as_deref(), path),
        Command::Sweep {
            scene,
            set,
            out,
            threads,
            slurm,
        } => match (&slurm.collect, scene) {
            (Some(dir), _) => slurm::collect(dir, slurm.retry),
            (None, Some(scene)) if slurm.slurm => match threads {
                Some(_) => Err(bad(
                    "--threads is for a sweep run here; each Slurm task runs with \
                     --cpus-per-task threads",
                )),
                None => slurm::submit(&scene, out, &set, &slurm),
            },
            (None, Some(scene)) => with_threads(threads, || sweep(&scene, out, &set)),
            (None, None) => Err(bad("give a scene file, or --collect DIR")),
        },
        Command::Inspect { dir } => inspect(&dir),
        Command::Kinematic { scene, out, set } => kinematic(&scene, out, &set),
        Command::Compare {
            inputs,
            out,
            set,
            threads,
        } => match inputs.as_slice() {
            [scene] => with_threads(threads, || compare(scene, out, &set)),
            [a, b] if set.is_empty() && threads.is_none() => compare_folders(a, b, out),
            _ => Err(bad(
                "--set and --threads belong to `drape compare SCENE` (a scene run both \
                 ways), not to two results folders",
            )),
        },
        Command::Export {
            run,
            onto,
            units,
            scale,
            out,
        } => export(&run, &onto, units, scale, out),
        Command::Fit { test } => fit_cmd::run(test, bad),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {}", describe(&e));
            if e.downcast_ref::<BadInput>().is_some() {
                ExitCode::from(exit::BAD_INPUT)
            } else {
                ExitCode::from(exit::FAILED)
            }
        }
    }
}

fn with_threads(
    threads: Option<usize>,
    f: impl FnOnce() -> Result<ExitCode> + Send,
) -> Result<ExitCode> {
    let available = std::thread::available_parallelism().map_or(1, usize::from);
    match threads {
        Some(0) => Err(bad("--threads must be at least 1")),
        Some(n) => {
            // More threads than the machine runs at once only adds
            // switching (and results do not depend on the count).
            let n = if n > available {
                eprintln!(
                    "note: --threads {n} is more than this machine runs at once; using {available}"
                );
                available
            } else {
                n
            };
            rayon::ThreadPoolBuilder::new()
                .num_threads(n)
                .build()
                .context("cannot start the thread pool")?
                .install(f)
        }
        // The run itself on a worker of the global pool, not on the main
        // thread: from outside, every parallel pass of every step is a job
        // injected into the pool that the main thread sleeps on (measured
        // on the hemisphere scene: 34 context switches a step and 8 % more
        // CPU time, against 0.04 from inside).
        None => rayon::scope(|_| f()),
    }
}

/// An output folder that cannot be used, as bad input: the folder, what
/// is wrong with it, and what to do.
fn unusable_output(out: &Path, e: &ResultsError) -> anyhow::Error {
    use std::io::ErrorKind;
    let kind = e.source.kind();
    if kind == ErrorKind::ResourceBusy {
        return bad(format!(
            "{}: {}: wait for it to finish, or give another output folder with --out",
            out.display(),
            e.source
        ));
    }
    if let Some(file) = out.ancestors().find(|a| a.is_file()) {
        let inside = if file == out {
            String::new()
        } else {
            format!(" (inside {})", out.display())
        };
        return bad(format!(
            "{} is a file, not a folder{inside}: give --out a folder (it is created if needed)",
            file.display()
        ));
    }
    let why = match kind {
        ErrorKind::PermissionDenied => "permission denied".to_owned(),
        ErrorKind::ReadOnlyFilesystem => "the file system is read-only".to_owned(),
        _ if e.path == out => e.source.to_string(),
        _ => format!("{}: {}", e.path.display(), e.source),
    };
    bad(format!(
        "cannot write results into {}: {why}; give another output folder with --out",
        out.display()
    ))
}

fn parse_sets(set: &[String]) -> Result<Vec<(String, String)>> {
    set.iter()
        .map(|s| {
            s.split_once('=')
                .map(|(k, v)| (k.trim().to_owned(), v.trim().to_owned()))
                .filter(|(k, _)| !k.is_empty())
                .ok_or_else(|| bad(format!("--set {s}: expected KEY=VALUE")))
        })
        .collect()
}

fn load(path: &Path, overrides: &[(String, String)]) -> Result<Scene> {
    let scene =
        exit::reading(|| Scene::from_file(path, overrides)).map_err(|e| bad(e.to_string()))?;
    for warning in &scene.warnings {
        eprintln!("warning: {warning}");
    }
    Ok(scene)
}

fn default_out(scene: &Path, suffix: &str) -> PathBuf {
    let stem = scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    Path::new("results").join(format!("{stem}{suffix}"))
}

fn run(
    scene_path: &Path,
    out: Option<PathBuf>,
    set: &[String],
    checkpoint_every: Option<u64>,
) -> Result<ExitCode> {
    let overrides = parse_sets(set)?;
    let scene = load(scene_path, &overrides)?;
    // What cannot run is bad input: refused before anything is written.
    let warnings = drape::check_scene(&scene)
        .map_err(|reason| bad(format!("{}: {reason}", scene_path.display())))?;
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    let out = out.unwrap_or_else(|| default_out(scene_path, ""));
    drape::limits::check_output(&[&scene], &out)
        .map_err(|reason| bad(format!("{}: {reason}", scene_path.display())))?;
    let options = RunOptions {
        checkpoint_every: checked_interval(checkpoint_every)?,
        overrides,
        resume: None,
    };
    finish_run(&scene, &out, options)
}

fn checked_interval(every: Option<u64>) -> Result<Option<u64>> {
    match every {
        Some(0) => Err(bad("--checkpoint-every must be at least 1")),
        other => Ok(other),
    }
}

/// The summary a run left in `dir`, if it left a readable one.
fn read_summary(dir: &Path) -> Option<Summary> {
    let text = std::fs::read_to_string(dir.join("summary.json")).ok()?;
    serde_json::from_str(&text).ok()
}

fn resume_run(dir: &Path, checkpoint_every: Option<u64>, device: Option<&str>) -> Result<ExitCode> {
    let device = match device {
        None => None,
        Some("cpu") => Some(Device::Cpu),
        Some("gpu") => Some(Device::Gpu),
        Some(other) => {
            return Err(bad(format!("--device {other}: expected `cpu` or `gpu`")));
        }
    };
    if !dir.is_dir() {
        return Err(bad(format!(
            "{}: {}: --resume takes the output folder of a stopped run",
            dir.display(),
            if dir.exists() {
                "not a folder"
            } else {
                "no such folder"
            }
        )));
    }
    let checkpoint_every = checked_interval(checkpoint_every)?;
    match read_summary(dir) {
        Some(s) if s.status == "completed" => {
            println!(
                "{}: the run is finished (completed at t = {:.6} s in {} steps): nothing to resume",
                dir.display(),
                s.time,
                s.run.steps
            );
            return Ok(ExitCode::SUCCESS);
        }
        // A run stopped by a full disk continues once there is room.
        Some(s)
            if s.status == "failed"
                && !s
                    .reason
                    .as_deref()
                    .is_some_and(|r| r.starts_with("disk full")) =>
        {
            return Err(bad(format!(
                "{}: the run failed ({}): resuming it would repeat the failure with the same \
                 scene; change the scene and start a new run",
                dir.display(),
                s.reason.as_deref().unwrap_or("no reason recorded")
            )));
        }
        _ => {}
    }
    let mut checkpoint = Checkpoint::read(dir).map_err(bad)?;
    if let Some(d) = device {
        checkpoint.switch_device(d);
    }
    let scene = checkpoint.scene().map_err(|e| {
        bad(format!(
            "{}: cannot resume: {e}",
            Checkpoint::path(dir).display()
        ))
    })?;
    // What cannot run is refused before the folder is touched, as for a
    // new run: the stopped run's summary and checkpoint stay as they were.
    drape::check_scene(&scene).map_err(|reason| {
        bad(format!(
            "{}: cannot resume: {reason}",
            Checkpoint::path(dir).display()
        ))
    })?;
    let file = checkpoint.scene_file.display();
    match checkpoint.scene_file_matches() {
        Some(true) => {}
        Some(false) => eprintln!(
            "note: {file} has changed since the run started (the file was edited, or this \
             drape reads it with other defaults); the run continues with the scene it started \
             with (kept in the checkpoint). Start a new run to use the scene as it reads now."
        ),
        None => eprintln!(
            "note: {file} cannot be read as it was (moved, deleted or broken); the run continues \
             with the scene it started with (kept in the checkpoint)."
        ),
    }
    let options = RunOptions {
        checkpoint_every,
        overrides: Vec::new(),
        resume: Some(checkpoint),
    };
    finish_run(&scene, dir, options)
}

fn finish_run(scene: &Scene, out: &Path, options: RunOptions) -> Result<ExitCode> {
    // The folder first: a run that cannot write its results must not start.
    let results =
        open_output(out, options.resume.as_ref()).map_err(|e| unusable_output(out, &e))?;
    if let Some(c) = &options.resume {
        eprintln!(
            "resuming {} at step {}, t = {:.6} s",
            c.scene_file.display(),
            c.state.step,
            c.state.time
        );
    }
    if let Some(setup) = drape::run_setup(scene) {
        print_setup(&setup, scene.spec.simulation.solver);
        if scene.spec.simulation.device == Device::Gpu {
            eprintln!("device            GPU (the steps on the GPU, frames and energies here)");
        }
    }
    let mut reporter = Reporter::new();
    let report = run_in(scene, results, options, &mut |p| reporter.update(p))
        .with_context(|| format!("writing results to {}", out.display()))?;
    reporter.finish();
    print_summary(&report.summary, out);
    Ok(match report.summary.status.as_str() {
        "failed" => ExitCode::from(1),
        "stopped" if interrupted() => {
            if Checkpoint::path(out).is_file() {
                eprintln!("continue it with: drape run --resume {}", out.display());
            }
            ExitCode::from(INTERRUPTED_EXIT)
        }
        _ => ExitCode::SUCCESS,
    })
}

fn new(template: Option<&str>, path: Option<PathBuf>) -> Result<ExitCode> {
    // Without a name, the list: a usage error (exit 2, as clap's own), so
    // a script that forgot the name stops.
    let Some(template) = template else {
        return Err(bad(format!(
            "give a template: drape new TEMPLATE [PATH]; the templates are\n{}",
            template_list()
        )));
    };
    let Some((name, _, text)) = TEMPLATES.iter().find(|(n, _, _)| *n == template) else {
        return Err(bad(format!(
            "unknown template `{template}`; the templates are\n{}",
            template_list()
        )));
    };
    let path = path.unwrap_or_else(|| PathBuf::from(format!("{name}.toml")));
    if path.exists() {
        return Err(bad(format!(
            "{} exists already: not overwritten",
            path.display()
        )));
    }
    drape_io::atomic::write(&path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    println!(
        "wrote {}; run it with: drape run {}",
        path.display(),
        path.display()
    );
    Ok(ExitCode::SUCCESS)
}

fn sweep(scene_path: &Path, out: Option<PathBuf>, set: &[String]) -> Result<ExitCode> {
    let (axes, combos) = sweep_table::points(set)?;
    // Every combination must load, and pass the checks of `drape run`,
    // before anything runs or is written.
    let scenes: Vec<Scene> = combos
        .iter()
        .map(|c| load(scene_path, c))
        .collect::<Result<_>>()?;
    for (scene, combo) in scenes.iter().zip(&combos) {
        drape::check_scene(scene).map_err(|reason| {
            let set: Vec<String> = combo.iter().map(|(k, v)| format!("{k}={v}")).collect();
            bad(format!(
                "{} with {}: {reason}",
                scene_path.display(),
                set.join(" ")
            ))
        })?;
    }
    let out = out.unwrap_or_else(|| default_out(scene_path, "-sweep"));
    let all: Vec<&Scene> = scenes.iter().collect();
    drape::limits::check_output(&all, &out)
        .map_err(|reason| bad(format!("{}: {reason}", scene_path.display())))?;
    // One sweep per folder, as one run per folder; each run's own folder
    // is locked by the run.
    let _lock = OutputLock::acquire(&out).map_err(|e| unusable_output(&out, &e))?;
    eprintln!("sweep: {} runs into {}", scenes.len(), out.display());
    let reports: Vec<Result<Summary, String>> = scenes
        .par_iter()
        .enumerate()
        .map(|(i, scene)| {
            let dir = out.join(format!("run_{i:03}"));
            let report = run_scene(scene, &dir, &mut |_| {
                if interrupted() {
                    RunControl::Stop
                } else {
                    RunControl::Continue
                }
            })
            .with_context(|| format!("writing {}", dir.display()))
            .map_err(|e| describe(&e))?;
            eprintln!(
                "  run_{i:03} {} max shear {:.2}°",
                report.summary.status, report.summary.max_shear_deg
            );
            Ok(report.summary)
        })
        .collect();
    let (table, failed) = sweep_table::write(&out, &axes, &combos, &reports)?;
    print!("{table}");
    Ok(if failed {
        ExitCode::from(1)
    } else if interrupted() {
        ExitCode::from(INTERRUPTED_EXIT)
    } else {
        ExitCode::SUCCESS
    })
}

fn inspect(dir: &Path) -> Result<ExitCode> {
    if !dir.is_dir() {
        return Err(bad(format!(
            "{}: {}: inspect takes a run's or a sweep's output folder",
            dir.display(),
            if dir.exists() {
                "not a folder"
            } else {
                "no such folder"
            }
        )));
    }
    if slurm::is_slurm_sweep(dir) {
        return slurm::inspect(dir);
    }
    let sweep = dir.join("sweep.csv");
    if sweep.is_file() && !dir.join("summary.json").exists() {
        return inspect_sweep(dir, &sweep);
    }
    let path = dir.join("summary.json");
    let text = std::fs::read_to_string(&path).map_err(|e| {
        if e.kind() == std::io::ErrorKind::NotFound {
            match drape::reserve::unfinished(dir) {
                Some(why) => anyhow!("{}: no summary.json: {why}", dir.display()),
                None => bad(format!(
                    "{}: no summary.json (nor a sweep's sweep.csv): no run has finished writing \
                     here (one may still be running, or was killed)",
                    dir.display()
                )),
            }
        } else {
            bad(format!("{}: {e}", path.display()))
        }
    })?;
    let summary: Summary = serde_json::from_str(&text)
        .map_err(|e| bad(format!("{}: not a drape summary: {e}", path.display())))?;
    print_summary(&summary, dir);
    let frames = std::fs::read_dir(dir.join("frames"))
        .map(|d| {
            d.filter_map(|e| e.ok())
                .filter(|e| e.file_name().to_string_lossy().starts_with("frame_"))
                .count()
        })
        .unwrap_or(0);
    println!("frames            {frames}");
    if let Some(setup) = &summary.setup {
        println!(
            "model             {} nodes, {} membrane elements, {} trusses ({} fibres)",
            setup.nodes, setup.membrane_elements, setup.trusses, setup.fibres
        );
        println!(
            "time step         stable {:.3e} s, started at {:.3e} s, added mass {:.1} %",
            setup.stable_time_step_s,
            setup.time_step_s,
            100.0 * setup.added_mass_fraction
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// How many run_NNN folders `dir` holds.
fn run_folders(dir: &Path) -> usize {
    std::fs::read_dir(dir).map_or(0, |entries| {
        entries
            .filter_map(|e| e.ok())
            .filter(|e| {
                e.file_name().to_str().is_some_and(|n| {
                    n.strip_prefix("run_")
                        .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
                }) && e.path().is_dir()
            })
            .count()
    })
}

/// A sweep's table, aligned in columns, and where its runs are.
fn inspect_sweep(dir: &Path, table: &Path) -> Result<ExitCode> {
    let text =
        std::fs::read_to_string(table).map_err(|e| bad(format!("{}: {e}", table.display())))?;
    let rows =
        drape::sweep_check::check(&text).map_err(|why| anyhow!("{}: {why}", table.display()))?;
    let columns = rows.iter().map(Vec::len).max().unwrap_or(0);
    let width: Vec<usize> = (0..columns)
        .map(|c| {
            rows.iter()
                .filter_map(|r| r.get(c))
                .map(|v| v.chars().count())
                .max()
                .unwrap_or(0)
        })
        .collect();
    println!(
        "sweep             {} ({} runs)",
        dir.display(),
        rows.len().saturating_sub(1)
    );
    for row in &rows {
        let line: Vec<String> = row
            .iter()
            .enumerate()
            .map(|(c, v)| format!("{v:>w$}", w = width[c]))
            .collect();
        println!("{}", line.join("  ").trim_end());
    }
    if dir.join("sweep.png").is_file() {
        println!("picture           {}", dir.join("sweep.png").display());
    }
    println!("each run's folder {}", dir.join("run_NNN").display());
    if let Some(note) = drape::sweep_check::note(rows.len() - 1, run_folders(dir)) {
        println!("note              {note}");
    }
    Ok(ExitCode::SUCCESS)
}

fn kinematic_error(e: drape::KinematicError) -> anyhow::Error {
    match e {
        drape::KinematicError::Input(message) => bad(message),
        drape::KinematicError::Output(e) => unusable_output(&e.path.clone(), &e),
        drape::KinematicError::Results(e) => anyhow!(e).context("writing results"),
        drape::KinematicError::Failed(reason) | drape::KinematicError::Stopped(reason) => {
            anyhow!(reason)
        }
    }
}

fn print_net(stats: &drape_fishnet::NetStats) {
    println!(
        "net               {} of {} cells draped, {} crossings placed, {} surface queries",
        stats.draped_cells, stats.outline_cells, stats.placed, stats.queries
    );
}

fn kinematic(scene_path: &Path, out: Option<PathBuf>, set: &[String]) -> Result<ExitCode> {
    let scene = load(scene_path, &parse_sets(set)?)?;
    let out = out.unwrap_or_else(|| default_out(scene_path, "-kinematic"));
    // Checked before the drape (which can take minutes); the library
    // claims the folder itself when it writes.
    let claim = exit::claim_output(&out)?.release();
    exit::quit_at_once_on_signal();
    let report = drape::kinematic_scene(&scene, &out).map_err(kinematic_error);
    let report = exit::settle(vec![claim], report)?;
    print_summary(&report.summary, &out);
    print_net(&report.stats);
    Ok(if report.summary.status == "completed" {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(exit::FAILED)
    })
}

fn compare(scene_path: &Path, out: Option<PathBuf>, set: &[String]) -> Result<ExitCode> {
    if scene_path.is_dir() {
        return Err(bad(format!(
            "{}: a folder: `drape compare SCENE` takes one scene file; to compare two runs' \
             results folders give both: `drape compare RUN_A RUN_B`",
            scene_path.display()
        )));
    }
    let scene = load(scene_path, &parse_sets(set)?)?;
    if let Err(e) = &scene.kinematic {
        return Err(bad(e.to_string()));
    }
    let out = out.unwrap_or_else(|| default_out(scene_path, "-compare"));
    // The comparison's folder for the whole command, and the two runs'
    // folders checked now: all refused before anything is written.
    let mut claims = vec![exit::claim_output(&out)?];
    for sub in ["kinematic", "mechanical"] {
        let claim = exit::claim_output(&out.join(sub)).map(exit::OutputClaim::release);
        let claim = exit::settle(std::mem::take(&mut claims), claim)?;
        claims.push(claim);
    }
    let mut reporter = Reporter::new();
    let report = drape::compare_scene(&scene, &out, &mut |p| reporter.update(p));
    reporter.finish();
    let report = match report {
        Err(drape::KinematicError::Stopped(why)) => {
            eprintln!("stopped: {why}");
            return Ok(ExitCode::from(exit::STOPPED));
        }
        other => exit::settle(claims, other.map_err(kinematic_error))?,
    };
    let s = &report.comparison.summary;
    println!("kinematic net     {}", out.join("kinematic").display());
    print_mould(&report.kinematic.summary);
    print_net(&report.kinematic.stats);
    println!(
        "forming run       {} ({}), {}",
        report.mechanical.summary.status,
        out.join("mechanical").display(),
        forming_run_note(&report.mechanical.summary)
    );
    println!(
        "max shear         run {:.2}°, net {:.2}°",
        s.mechanical_max_shear_deg, s.kinematic_max_shear_deg
    );
    println!(
        "compared          {} of {} elements, {} on the mould",
        s.compared, s.elements, s.on_mould
    );
    for (name, d) in [
        ("all elements", &s.all),
        ("diagonal", &s.diagonal),
        ("median", &s.median),
    ] {
        println!(
            "{name:<17} |Δγ| max {:.2}°, rms {:.2}° ({} elements); on the mould max {:.2}°, rms {:.2}° ({})",
            d.max_abs_deg,
            d.rms_deg,
            d.points,
            d.max_abs_on_mould_deg,
            d.rms_on_mould_deg,
            d.points_on_mould
        );
    }
    println!("comparison        {}", out.display());
    Ok(if report.mechanical.summary.status == "failed" {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

fn compare_error(e: drape::CompareError) -> anyhow::Error {
    compare_error_writing(e, "writing the comparison")
}

/// [`compare_error`] for a command that writes something else.
fn compare_error_writing(e: drape::CompareError, writing: &'static str) -> anyhow::Error {
    match e {
        drape::CompareError::Input(message) => bad(message),
        drape::CompareError::Results(e) => anyhow!(e).context(writing),
        drape::CompareError::Failed(reason) => anyhow!(reason),
    }
}

/// The last part of a folder's path, for default names.
fn folder_name(p: &Path) -> String {
    std::path::absolute(p)
        .ok()
        .and_then(|a| a.file_name().map(|n| n.to_string_lossy().into_owned()))
        .unwrap_or_else(|| "run".to_owned())
}

fn compare_folders(a: &Path, b: &Path, out: Option<PathBuf>) -> Result<ExitCode> {
    for dir in [a, b] {
        if !dir.is_dir() {
            return Err(bad(format!(
                "{}: {}: `drape compare RUN_A RUN_B` takes two results folders (or one scene \
                 file: `drape compare SCENE`)",
                dir.display(),
                if dir.exists() {
                    "not a folder"
                } else {
                    "no such folder"
                }
            )));
        }
    }
    let out = out.unwrap_or_else(|| {
        Path::new("results").join(format!("{}-vs-{}", folder_name(a), folder_name(b)))
    });
    let claim = exit::claim_output(&out)?;
    exit::quit_at_once_on_signal();
    let c = exit::settle(
        vec![claim],
        drape::compare_runs(a, b, &out).map_err(compare_error),
    )?;
    let s = &c.summary;
    println!("{:<34} {:>14} {:>14} {:>14}", "", "A", "B", "B − A");
    println!(
        "{:<34} {:>14} {:>14}",
        "folder",
        folder_name(a),
        folder_name(b)
    );
    println!("{:<34} {:>14} {:>14}", "status", s.status_a, s.status_b);
    for m in &s.measures {
        let name = if m.unit.is_empty() {
            m.name.clone()
        } else {
            format!("{} ({})", m.name, m.unit)
        };
        let difference = m.show(m.a.zip(m.b).map(|(a, b)| b - a));
        println!(
            "{name:<34} {:>14} {:>14} {difference:>14}",
            m.show(m.a),
            m.show(m.b)
        );
    }
    println!(
        "shear, element by element: {} of {} elements compared ({:.1} %, {}); |γB − γA| largest \
         {:.3}° at ({:.1}, {:.1}, {:.1}) mm (A's flat blank), rms {:.3}°, mean {:+.3}°",
        s.compared,
        s.elements,
        100.0 * s.compared_fraction,
        if s.same_mesh {
            "the same mesh"
        } else {
            "B carried onto A's mesh by closest point"
        },
        s.max_abs_difference_deg,
        s.max_difference_at[0],
        s.max_difference_at[1],
        s.max_difference_at[2],
        s.rms_difference_deg,
        s.mean_difference_deg
    );
    for p in &s.profiles {
        println!(
            "shear along the {}: {} points compared; |γB − γA| largest {:.3}°, rms {:.3}°",
            p.line, p.points, p.max_abs_difference_deg, p.rms_difference_deg
        );
    }
    // Two laminates: each ply with B's ply of its name.
    for p in &s.plies {
        println!(
            "ply {}: {} of {} elements compared ({}); |γB − γA| largest {:.3}°, rms {:.3}°",
            p.name,
            p.compared,
            p.elements,
            if p.same_mesh {
                "the same mesh"
            } else {
                "B's ply carried onto A's by closest point"
            },
            p.max_abs_difference_deg,
            p.rms_difference_deg
        );
        for d in &p.profiles {
            println!(
                "  shear along its {}: {} points compared; |γB − γA| largest {:.3}°, rms {:.3}°",
                d.line, d.points, d.max_abs_difference_deg, d.rms_difference_deg
            );
        }
    }
    for (name, status) in [("A", &s.status_a), ("B", &s.status_b)] {
        if status != "completed" {
            eprintln!(
                "note: run {name} {status}: its values are those of its last frame, not of a \
                 finished run (comparison.json records both statuses)"
            );
        }
    }
    println!("comparison        {}", out.display());
    Ok(ExitCode::SUCCESS)
}

fn export(
    run: &Path,
    mesh: &Path,
    units: ExportUnit,
    scale: Option<f64>,
    out: Option<PathBuf>,
) -> Result<ExitCode> {
    if !run.is_dir() {
        return Err(bad(format!(
            "{}: {}: export takes a run's results folder",
            run.display(),
            if run.exists() {
                "not a folder"
            } else {
                "no such folder"
            }
        )));
    }
    let out = out.unwrap_or_else(|| run.to_owned());
    let units = match (scale, units) {
        (Some(s), _) if !(s.is_finite() && s > 0.0) => {
            return Err(bad(format!(
                "--scale {s}: expected a positive number of mm per unit of the mesh"
            )));
        }
        (Some(s), _) => drape::MeshUnits {
            name: format!("mesh units (1 = {s} mm)"),
            millimetres: s,
        },
        (None, u) => {
            let (name, millimetres) = match u {
                ExportUnit::Mm => ("mm", 1.0),
                ExportUnit::Cm => ("cm", 10.0),
                ExportUnit::M => ("m", 1000.0),
                ExportUnit::In => ("in", 25.4),
            };
            drape::MeshUnits {
                name: name.into(),
                millimetres,
            }
        }
    };
    let claim = exit::claim_output(&out)?;
    exit::quit_at_once_on_signal();
    let r = exit::settle(
        vec![claim],
        drape::map_orientations(run, mesh, &units, &out)
            .map_err(|e| compare_error_writing(e, "writing the orientations")),
    )?;
    if let Some(first) = r.mapped.plies.first() {
        // A laminate: each ply mapped onto the same elements.
        let names: Vec<&str> = r.mapped.plies.iter().map(|p| p.name.as_str()).collect();
        println!(
            "mapped            {} elements of {} onto each of the {} plies of {} ({})",
            first.elements.len(),
            mesh.display(),
            names.len(),
            run.display(),
            names.join(", ")
        );
    } else {
        println!(
            "mapped            {} elements of {} onto the formed part of {}",
            r.mapped.len(),
            mesh.display(),
            run.display()
        );
    }
    println!(
        "distance          largest {:.4} mm (element {}), mean {:.4} mm",
        r.max_distance.0, r.max_distance.1, r.mean_distance
    );
    if !(1.0..=10_000.0).contains(&r.mesh_across_mm) {
        eprintln!(
            "warning: the mesh is {:.3e} mm across in {}: is it in another unit? give --units \
             (mm, cm, m, in) or --scale",
            r.mesh_across_mm, units.name
        );
    }
    if r.beyond_thickness > 0 {
        eprintln!(
            "warning: {} elements lie farther from the formed part than its thickness \
             ({} mm): is the mesh the same part, placed as the formed one, and in {} (else give \
             --units)?",
            r.beyond_thickness, r.thickness, units.name
        );
    }
    println!(
        "written           {} (lengths in {})",
        r.inp.display(),
        units.name
    );
    println!("                  {} (lengths in mm)", r.csv.display());
    if let Some((label, why)) = r.missing.first() {
        eprintln!(
            "warning: {} elements have no orientation (listed in the include's set {}, empty \
             fields in the table); element {label}: {why}",
            r.missing.len(),
            if r.mapped.plies.is_empty() {
                drape_io::results::export::names::NO_ORIENTATION
            } else {
                "PLY_NO_ORIENTATION of each ply"
            }
        );
    }
    if let Some(why) = &r.source_unknown {
        eprintln!("note: {why} (the include's header says so too)");
    }
    // A partial drape exported looks like a finished one to whatever reads
    // the files next: the header says so, and the exit code does.
    Ok(match &r.source_not_completed {
        Some(why) => {
            eprintln!("error: {why} (the include's header says so too)");
            ExitCode::from(exit::FAILED)
        }
        None => ExitCode::SUCCESS,
    })
}
