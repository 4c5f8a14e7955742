//! drape's developer tasks, run as `cargo xtask <task>` (alias in
//! `.cargo/config.toml`):
//!
//! - `validate [--quick] [--filter SUBSTR]`: the validation suite, analytic
//!   references against the crates' computed values (see [`validate`]);
//! - `stress [--quick] [--filter SUBSTR] [--seed N]`: extremes and hostile
//!   input through the facade, one table of case, expectation and outcome
//!   (see [`stress`]);
//! - `fit-shear CSV --side L --material M [--terms N] [--out FILE]`: a
//!   shear-locking law fitted from a picture-frame curve, as a material
//!   card (see [`fit`]);
//! - `bench [--quick] [--profile-only] [ARGS…]`: the explicit step's per-pass
//!   profile, the mesh/analytic tray mould ratio and the 1- vs 2-thread
//!   table (`benches/benches/step_profile.rs`), then the work-precision
//!   study, both written into `docs/performance.md` ([`perf_page`]), then
//!   the criterion benches, `cargo bench -p drape-benches ARGS…`;
//! - `bench work-precision [--quick] [--filter SUBSTR] [--fresh-reference]
//!   [--timeout S] [--reference-cells N] [--time wall|cpu]`: run time against error for the hemisphere's ways to go
//!   faster (see [`work_precision`]);
//! - `mould OUT [--triangles N] [--punch FILE] [--offset MM] [--depth MM]
//!   [--corner MM]`: a generated
//!   open female tray mould (and its matched punch) as STL or OBJ (see
//!   [`mould`]);
//! - `slurm [--quick] [--study] [--keep]`: `drape sweep --slurm` against a
//!   real one-node Slurm cluster started here (see [`slurm`]);
//! - `ci`: what CI runs, the script `.ci/run`.
//!
//! Only std and the workspace's own dependencies: an xtask that needs a
//! heavy dependency tree slows every CI run down on a 2-core machine.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

mod fit;
mod holding;
mod mould;
mod pages;
mod perf_page;
mod slurm;
mod stress;
mod validate;
mod work_precision;

const USAGE: &str = "\
usage: cargo xtask <task> [options]

tasks:
  validate [--quick] [--filter SUBSTR]
      run the validation cases (analytic references vs computed values);
      --quick runs only the cases cheap enough for CI, --filter only the
      cases whose name contains SUBSTR. Writes target/validation/report.md
      and the results of the cases run into docs/validation.md.
  stress [--quick] [--filter SUBSTR] [--seed N]
      run drape at its extremes and on hostile input (stiff and soft
      materials, uncrimped yarns, high friction, fast tools, coarse and
      fine meshes, time steps near the critical one, degenerate tools,
      random scenes and damaged mesh files) and print one table: case,
      expectation, what happened. Every row must complete with a sane
      energy balance or stop with a diagnosis; none may panic, hang or
      write NaN. --quick is the subset CI runs, --seed changes the
      generators' seed. Writes target/stress/report.md.
  fit-shear CSV --side L --material PRESET|card.toml [--terms N] [--out FILE]
      fit a shear-locking law τ = c1·γ + c3·γ³ + … (N terms, default 3) to a
      picture-frame curve (CSV of shear angle in degrees, frame force in N;
      frame side L in mm) and print (or write) the material card: the base
      material with resin.shear_locking set.
  bench [--quick] [--profile-only] [ARGS...]
      print the explicit step's per-pass profile (hemisphere scene and a
      200x200 blank, 1 and 2 threads), the step of a 7 104-triangle open tray
      mould against its surface of revolution (the mesh/analytic ratio) and
      the ms/step table of the shipped scenes on 1 and 2 threads, then the
      work-precision study below, then the criterion benches:
      cargo bench -p drape-benches ARGS... (e.g. cargo xtask bench --
      --warm-up-time 1 --measurement-time 2). --quick profiles shorter
      windows and runs the criterion benches with short warm-up and
      measurement times; --profile-only stops after the tables. Writes the
      tables and the study into docs/performance.md (a quick run beside, not
      over, a full run's).
      DRAPE_BENCH_CLOCK=thread-cpu times one-thread figures by CPU time.
  bench work-precision [--quick] [--filter SUBSTR] [--fresh-reference] [--timeout S]
                       [--reference-cells N] [--time wall|cpu]
      the hemisphere's run time against its error for each way to run it
      faster (mesh, mass scaling, process time, fibres, threads, implicit
      increments), against a cached reference solution; writes
      target/bench/work-precision.{csv,png,md} and, without --filter, its
      section of docs/performance.md. --quick is the coarse version CI can
      afford.
  mould OUT.stl|OUT.obj [--triangles N] [--punch PUNCH.stl|.obj] [--offset MM]
                        [--depth MM] [--corner MM]
      write a generated open female mould: a double-curved 600 x 400 mm tray,
      80 mm deep, open at its flange's outer rim, normals pointing away from
      the cavity, about N triangles (default 3000); --punch also writes the
      matched punch, the same surface moved MM (default 0.57, the glass
      ply's thickness) along its normals. --depth (default 80) and --corner
      (the opening's corner radius, default 90) change the cavity.
  slurm [--quick] [--study] [--keep]
      start a one-node Slurm cluster here (installs slurm-wlm and munge with
      apt-get when missing; needs root), submit a sweep with drape sweep
      --slurm, requeue one task mid-run, collect, and check the results
      against a local drape sweep bit for bit; the daemons are stopped at
      the end. --quick is the CI form (4 short points); --study times the
      16-point hemisphere study through Slurm (--array-limit 2) and
      locally; --keep keeps target/slurm/run-PID (logs, sweeps).
  ci
      run what CI runs (.ci/run): the test suite, the quick validation,
      the quick stress suite, the quick work-precision bench and the
      quick Slurm sweep test";

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some((task, rest)) = args.split_first() else {
        eprintln!("{USAGE}");
        return ExitCode::from(2);
    };
    match task.as_str() {
        "validate" => match validate::Options::parse(rest) {
            Ok(options) => validate::main(&options, &workspace_root()),
            Err(message) => usage_error(&message),
        },
        "stress" => match stress::Options::parse(rest) {
            Ok(options) => stress::main(&options, &workspace_root(), &target_dir()),
            Err(message) => usage_error(&message),
        },
        "fit-shear" => match fit::Options::parse(rest) {
            Ok(options) => fit::main(&options),
            Err(message) => usage_error(&message),
        },
        "bench" => bench(rest),
        "mould" => match mould::Options::parse(rest) {
            Ok(options) => mould::main(&options),
            Err(message) => usage_error(&message),
        },
        "slurm" => match slurm::Options::parse(rest) {
            Ok(options) => slurm::main(&options, &workspace_root(), &target_dir()),
            Err(message) => usage_error(&message),
        },
        "ci" if rest.is_empty() => run(Command::new("bash")
            .arg(workspace_root().join(".ci/run"))
            .current_dir(workspace_root())),
        "ci" => usage_error(&format!(
            "`ci` takes no arguments, got `{}`",
            rest.join(" ")
        )),
        "-h" | "--help" | "help" => {
            println!("{USAGE}");
            ExitCode::SUCCESS
        }
        other => usage_error(&format!("unknown task `{other}`")),
    }
}

/// The step profile, then (unless `--profile-only`) the criterion benches.
fn bench(args: &[String]) -> ExitCode {
    if let Some(("work-precision", rest)) = args.split_first().map(|(a, r)| (a.as_str(), r)) {
        return match work_precision::Options::parse(rest) {
            Ok(options) => work_precision::main(&options, &workspace_root(), &target_dir()),
            Err(message) => usage_error(&message),
        };
    }
    let quick = args.iter().any(|a| a == "--quick");
    let profile_only = args.iter().any(|a| a == "--profile-only");
    let mut rest: Vec<&str> = args
        .iter()
        .map(String::as_str)
        .filter(|a| !matches!(*a, "--quick" | "--profile-only"))
        .collect();
    let mut profile = Command::new(cargo());
    profile
        .args(["bench", "-p", "drape-benches", "--bench", "step_profile"])
        .current_dir(workspace_root());
    if quick {
        profile.args(["--", "--quick"]);
    }
    let status = match run_captured(&mut profile) {
        Ok(table) => match perf_page::update(
            &workspace_root(),
            "step-profile",
            quick,
            &format!("```text\n{}\n```", table.trim_end()),
        ) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("error: {e}");
                ExitCode::FAILURE
            }
        },
        Err(code) => code,
    };
    if profile_only || status != ExitCode::SUCCESS {
        return status;
    }
    let quick_flag = if quick {
        vec!["--quick".to_owned()]
    } else {
        Vec::new()
    };
    let precision = work_precision::Options::parse(&quick_flag).expect("the quick flag parses");
    let status = work_precision::main(&precision, &workspace_root(), &target_dir());
    if status != ExitCode::SUCCESS {
        return status;
    }
    if quick && !rest.contains(&"--") {
        rest.extend(["--", "--warm-up-time", "0.5", "--measurement-time", "1"]);
    }
    let mut criterion = Command::new(cargo());
    criterion.args(["bench", "-p", "drape-benches"]);
    for name in ["kernels", "elements", "explicit", "contact", "fishnet"] {
        criterion.args(["--bench", name]);
    }
    run(criterion.args(rest).current_dir(workspace_root()))
}

fn usage_error(message: &str) -> ExitCode {
    eprintln!("error: {message}\n\n{USAGE}");
    ExitCode::from(2)
}

/// The workspace root: xtask's manifest sits one level below it.
fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives inside the workspace")
        .to_path_buf()
}

/// Cargo's target directory: `CARGO_TARGET_DIR` when set, else
/// `<workspace>/target`.
fn target_dir() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => workspace_root().join("target"),
    }
}

/// The cargo that runs us (cargo sets `CARGO` for `cargo run`), so a
/// toolchain override applies to the child build as well.
fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned())
}

/// Runs `command`, echoing its standard output line by line as it comes
/// and returning it.
fn run_captured(command: &mut Command) -> Result<String, ExitCode> {
    use std::io::BufRead as _;
    let mut child = command
        .stdout(std::process::Stdio::piped())
        .spawn()
        .map_err(|err| {
            eprintln!("error: could not start {command:?}: {err}");
            ExitCode::FAILURE
        })?;
    let mut out = String::new();
    if let Some(stdout) = child.stdout.take() {
        for line in std::io::BufReader::new(stdout).lines() {
            let line = line.unwrap_or_default();
            println!("{line}");
            out.push_str(&line);
            out.push('\n');
        }
    }
    match child.wait() {
        Ok(status) if status.success() => Ok(out),
        Ok(status) => {
            eprintln!("error: {command:?} failed: {status}");
            Err(ExitCode::FAILURE)
        }
        Err(err) => {
            eprintln!("error: {command:?}: {err}");
            Err(ExitCode::FAILURE)
        }
    }
}

fn run(command: &mut Command) -> ExitCode {
    match command.status() {
        Ok(status) if status.success() => ExitCode::SUCCESS,
        Ok(status) => {
            eprintln!("error: {command:?} failed: {status}");
            ExitCode::FAILURE
        }
        Err(err) => {
            eprintln!("error: could not start {command:?}: {err}");
            ExitCode::FAILURE
        }
    }
}
