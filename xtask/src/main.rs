//! drape's developer tasks, run as `cargo xtask <task>` (alias in
//! `.cargo/config.toml`):
//!
//! - `validate [--quick] [--filter SUBSTR]`: the validation suite, analytic
//!   references against the crates' computed values (see [`validate`]);
//! - `bench [ARGS…]`: the criterion benches, `cargo bench -p drape-benches ARGS…`;
//! - `ci`: what CI runs, the script `.ci/run`.
//!
//! Only std and the workspace's own dependencies: an xtask that needs a
//! heavy dependency tree slows every CI run down on a 2-core machine.

use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

mod validate;

const USAGE: &str = "\
usage: cargo xtask <task> [options]

tasks:
  validate [--quick] [--filter SUBSTR]
      run the validation cases (analytic references vs computed values);
      --quick runs only the cases cheap enough for CI, --filter only the
      cases whose name contains SUBSTR. Writes target/validation/report.md.
  bench [ARGS...]
      run the criterion benches: cargo bench -p drape-benches ARGS...
      (e.g. cargo xtask bench -- --warm-up-time 1 --measurement-time 2)
  ci
      run what CI runs (.ci/run): the test suite, then the quick validation";

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
        "bench" => run(Command::new(cargo())
            .args(["bench", "-p", "drape-benches"])
            .args(rest)
            .current_dir(workspace_root())),
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

/// The cargo that runs us (cargo sets `CARGO` for `cargo run`), so a
/// toolchain override applies to the child build as well.
fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned())
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
