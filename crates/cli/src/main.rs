//! The `drape` command: run, new, sweep, inspect.
//!
//! Exit codes: 0 done, 1 the run failed (diverged or could not write its
//! results; what it reached is kept), 2 bad input (nothing is written).

use std::io::IsTerminal;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::time::Instant;

use anyhow::{Context, Result, anyhow};
use clap::{Parser, Subcommand};
use drape::{Checkpoint, RunControl, RunOptions, RunProgress, run_scene, run_scene_with};
use drape_io::results::Summary;
use drape_io::scene::Scene;
use indicatif::{ProgressBar, ProgressStyle};
use rayon::prelude::*;

#[derive(Parser)]
#[command(name = "drape", version, about = "Composite fabric forming simulation", long_about = None)]
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
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
        /// Write a restart file (checkpoint.json) every N steps.
        #[arg(long, value_name = "N")]
        checkpoint_every: Option<u64>,
        /// Continue the stopped run in DIR from its checkpoint, with the
        /// scene and overrides it was started with.
        #[arg(long, value_name = "DIR", conflicts_with_all = ["scene", "set", "out"])]
        resume: Option<PathBuf>,
    },
    /// Write a ready-to-run scene from a template.
    New {
        /// hemisphere, deep-drawing, picture-frame or bias-extension.
        template: String,
        /// Where to write it (default: <template>.toml).
        path: Option<PathBuf>,
    },
    /// Run every combination of values and write one table of results.
    Sweep {
        /// The scene file (TOML).
        scene: PathBuf,
        /// A key and its values: --set tools.0.friction=0,0.1,0.2 (repeatable).
        #[arg(long = "set", value_name = "KEY=V1,V2,…", required = true)]
        set: Vec<String>,
        /// Output directory (default: results/<scene name>-sweep).
        #[arg(long)]
        out: Option<PathBuf>,
        /// Worker threads (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Print the summary of a run's output directory.
    Inspect {
        /// The output directory.
        dir: PathBuf,
    },
}

/// Templates shipped with the binary.
const TEMPLATES: [(&str, &str); 4] = [
    (
        "hemisphere",
        include_str!("../../../scenes/hemisphere-0-90.toml"),
    ),
    (
        "deep-drawing",
        include_str!("../../../scenes/deep-drawing-0-90.toml"),
    ),
    (
        "picture-frame",
        include_str!("../../../scenes/picture-frame.toml"),
    ),
    (
        "bias-extension",
        include_str!("../../../scenes/bias-extension.toml"),
    ),
];

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

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run {
            scene,
            out,
            set,
            threads,
            checkpoint_every,
            resume,
        } => with_threads(threads, || match (resume, scene) {
            (Some(dir), _) => resume_run(&dir, checkpoint_every),
            (None, Some(scene)) => run(&scene, out, &set, checkpoint_every),
            (None, None) => Err(bad("give a scene file or --resume DIR")),
        }),
        Command::New { template, path } => new(&template, path),
        Command::Sweep {
            scene,
            set,
            out,
            threads,
        } => with_threads(threads, || sweep(&scene, out, &set)),
        Command::Inspect { dir } => inspect(&dir),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("error: {e:#}");
            if e.downcast_ref::<BadInput>().is_some() {
                ExitCode::from(2)
            } else {
                ExitCode::from(1)
            }
        }
    }
}

fn with_threads(
    threads: Option<usize>,
    f: impl FnOnce() -> Result<ExitCode> + Send,
) -> Result<ExitCode> {
    match threads {
        Some(0) => Err(bad("--threads must be at least 1")),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n)
            .build()
            .context("cannot start the thread pool")?
            .install(f),
        None => f(),
    }
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
    Scene::from_file(path, overrides).map_err(|e| bad(e.to_string()))
}

fn default_out(scene: &Path, suffix: &str) -> PathBuf {
    let stem = scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "run".into());
    Path::new("results").join(format!("{stem}{suffix}"))
}

/// A progress bar on a terminal, plain lines every 10 % otherwise.
struct Reporter {
    bar: Option<ProgressBar>,
    next_line: f64,
    started: Instant,
}

impl Reporter {
    fn new() -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar = ProgressBar::new(1000);
            bar.set_style(
                ProgressStyle::with_template("{spinner} [{bar:32}] {percent:>3}% {msg} ETA {eta}")
                    .expect("valid template")
                    .progress_chars("=> "),
            );
            bar
        });
        Self {
            bar,
            next_line: 0.1,
            started: Instant::now(),
        }
    }

    fn update(&mut self, p: &RunProgress) -> RunControl {
        let fraction = if p.progress.end_time > 0.0 {
            p.progress.time / p.progress.end_time
        } else {
            1.0
        };
        let message = format!(
            "step {} t = {:.4e} s, max shear {:.1}°",
            p.progress.step, p.progress.time, p.max_shear_deg
        );
        match &self.bar {
            Some(bar) => {
                bar.set_position((fraction * 1000.0) as u64);
                bar.set_message(message);
            }
            None => {
                if fraction >= self.next_line {
                    eprintln!(
                        "{:>3.0}% {message} ({:.1} s)",
                        fraction * 100.0,
                        self.started.elapsed().as_secs_f64()
                    );
                    while self.next_line <= fraction {
                        self.next_line += 0.1;
                    }
                }
            }
        }
        RunControl::Continue
    }

    fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

fn print_summary(s: &Summary, out: &Path) {
    println!("status            {}", s.status);
    if let Some(r) = &s.reason {
        println!("reason            {r}");
    }
    println!("scene             {}", s.scene);
    println!("time reached      {:.6} s in {} steps", s.time, s.run.steps);
    println!(
        "max shear         {:.2}° at ({:.1}, {:.1}, {:.1}) mm",
        s.max_shear_deg, s.max_shear_at[0], s.max_shear_at[1], s.max_shear_at[2]
    );
    if s.draw_in_mm.dx.is_finite() {
        println!(
            "draw-in           DX {:.2} mm, DY {:.2} mm, DD {:.2} mm",
            s.draw_in_mm.dx, s.draw_in_mm.dy, s.draw_in_mm.dd
        );
    } else {
        println!("draw-in           n/a (not a rectangular blank)");
    }
    println!("max fibre tension {:.1} N", s.max_fibre_tension_n);
    println!("above locking     {:.0} mm²", s.area_above_locking_mm2);
    println!(
        "energy            balance error {:.2e}, E_kin/E_int {:.2e}",
        s.energy.balance_error, s.energy.kinetic_to_internal
    );
    println!(
        "run               {:.1} s wall, {} threads, {}",
        s.run.wall_s, s.run.threads, s.run.solver
    );
    for w in &s.warnings {
        println!("warning           {w}");
    }
    println!("results           {}", out.display());
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

fn resume_run(dir: &Path, checkpoint_every: Option<u64>) -> Result<ExitCode> {
    let checkpoint = Checkpoint::read(dir).map_err(bad)?;
    let scene = load(&checkpoint.scene, &checkpoint.overrides)?;
    if checkpoint.state.x.len() != scene.model.node_count() {
        return Err(bad(format!(
            "{}: the checkpoint does not belong to {} as it is now",
            Checkpoint::path(dir).display(),
            checkpoint.scene.display()
        )));
    }
    eprintln!(
        "resuming {} at step {}, t = {:.6} s",
        checkpoint.scene.display(),
        checkpoint.state.step,
        checkpoint.state.time
    );
    let options = RunOptions {
        checkpoint_every: checked_interval(checkpoint_every)?,
        overrides: checkpoint.overrides.clone(),
        resume: Some(checkpoint),
    };
    finish_run(&scene, dir, options)
}

fn finish_run(scene: &Scene, out: &Path, options: RunOptions) -> Result<ExitCode> {
    let mut reporter = Reporter::new();
    let report = run_scene_with(scene, out, options, &mut |p| reporter.update(p))
        .with_context(|| format!("writing results to {}", out.display()))?;
    reporter.finish();
    print_summary(&report.summary, out);
    Ok(if report.summary.status == "failed" {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

fn new(template: &str, path: Option<PathBuf>) -> Result<ExitCode> {
    let Some((name, text)) = TEMPLATES.iter().find(|(n, _)| *n == template) else {
        let names: Vec<&str> = TEMPLATES.iter().map(|(n, _)| *n).collect();
        return Err(bad(format!(
            "unknown template `{template}`: expected one of {}",
            names.join(", ")
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
    let axes: Vec<(String, Vec<String>)> = parse_sets(set)?
        .into_iter()
        .map(|(k, v)| (k, v.split(',').map(|s| s.trim().to_owned()).collect()))
        .collect();
    let mut combos: Vec<Vec<(String, String)>> = vec![Vec::new()];
    for (key, values) in &axes {
        combos = combos
            .into_iter()
            .flat_map(|c| {
                values.iter().map(move |v| {
                    let mut c = c.clone();
                    c.push((key.clone(), v.clone()));
                    c
                })
            })
            .collect();
    }
    // Every combination must load before anything runs or is written.
    let scenes: Vec<Scene> = combos
        .iter()
        .map(|c| load(scene_path, c))
        .collect::<Result<_>>()?;
    let out = out.unwrap_or_else(|| default_out(scene_path, "-sweep"));
    std::fs::create_dir_all(&out).with_context(|| format!("creating {}", out.display()))?;
    eprintln!("sweep: {} runs into {}", scenes.len(), out.display());
    let reports: Vec<Result<Summary>> = scenes
        .par_iter()
        .enumerate()
        .map(|(i, scene)| {
            let dir = out.join(format!("run_{i:03}"));
            let report = run_scene(scene, &dir, &mut |_| RunControl::Continue)
                .with_context(|| format!("writing {}", dir.display()))?;
            eprintln!(
                "  run_{i:03} {} max shear {:.2}°",
                report.summary.status, report.summary.max_shear_deg
            );
            Ok(report.summary)
        })
        .collect();
    let mut table = String::from("run");
    for (key, _) in &axes {
        table.push(',');
        table.push_str(key);
    }
    table.push_str(",status,max_shear_deg,draw_in_dx_mm,draw_in_dy_mm,draw_in_dd_mm,max_fibre_tension_n,balance_error,steps,wall_s\n");
    let mut failed = false;
    for (i, (combo, report)) in combos.iter().zip(&reports).enumerate() {
        table.push_str(&format!("run_{i:03}"));
        for (_, v) in combo {
            table.push(',');
            table.push_str(v);
        }
        match report {
            Ok(s) => {
                failed |= s.status == "failed";
                table.push_str(&format!(
                    ",{},{:.4},{:.4},{:.4},{:.4},{:.3},{:.3e},{},{:.2}\n",
                    s.status,
                    s.max_shear_deg,
                    s.draw_in_mm.dx,
                    s.draw_in_mm.dy,
                    s.draw_in_mm.dd,
                    s.max_fibre_tension_n,
                    s.energy.balance_error,
                    s.run.steps,
                    s.run.wall_s
                ));
            }
            Err(e) => {
                failed = true;
                table.push_str(&format!(
                    ",error: {},,,,,,,,\n",
                    e.to_string().replace(',', ";")
                ));
            }
        }
    }
    let path = out.join("sweep.csv");
    drape_io::atomic::write(&path, table.as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    print!("{table}");
    Ok(if failed {
        ExitCode::from(1)
    } else {
        ExitCode::SUCCESS
    })
}

fn inspect(dir: &Path) -> Result<ExitCode> {
    let path = dir.join("summary.json");
    let text =
        std::fs::read_to_string(&path).map_err(|e| bad(format!("{}: {e}", path.display())))?;
    let summary: Summary = serde_json::from_str(&text)
        .map_err(|e| bad(format!("{}: not a drape summary: {e}", path.display())))?;
    print_summary(&summary, dir);
    let frames = std::fs::read_dir(dir.join("frames"))
        .map(|d| d.count())
        .unwrap_or(0);
    println!("frames            {frames}");
    Ok(ExitCode::SUCCESS)
}
