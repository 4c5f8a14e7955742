//! The generator of unusable output folders: every writing subcommand of
//! the `drape` binary (`run`, `sweep`, `kinematic`, `compare SCENE`,
//! `compare RUN_A RUN_B`, `export --onto`) against an output folder that is
//! a file, one that a running run holds (its lock taken here, as a run
//! takes it), a read-only file system and a full one. Each must keep the
//! exit-code contract and leave no partial file:
//!
//! - a file, a held or a read-only folder: exit 2, the folder as it was;
//! - a full file system: exit 1 or 2 (2 when refused before writing),
//!   no temporary left behind and every JSON file there whole.
//!
//! The read-only and the full file systems are tmpfs mounts (`mount -t
//! tmpfs -o ro` and `-o size=64k`, the latter filled to 8 KiB short of
//! full before each command): where this process may not mount (not
//! root, or no CAP_SYS_ADMIN, as on most CI runners) those two kinds are
//! skipped and the row says so. The binary is the workspace's dev build
//! (`cargo build -p drape`, a no-op when it is fresh).

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use super::{Context, Expect, Row};

/// A forming run of a few hundred steps over a sphere.
const SCENE: &str = r#"[simulation]
end_time = 0.001
frames = 2
mass_scaling_dt = 2e-6

[fabric]
material = "carbon-prepreg-2x2"
fibres = "trusses"
blank = { width = 60, height = 60, cells = [6, 6] }

[[tools]]
name = "punch"
geometry = { kind = "sphere", center = [0, 0, -40.2], radius = 40 }
motion = { kind = "displacement", direction = [0, 0, 1], distance = 2, amplitude = { kind = "smooth_step", duration = 0.001 } }

[[springs]]
nodes = ["corners"]
stiffness = 2.0
"#;

/// A flat triangle under the ply, for `export --onto`.
const MESH: &str = "*Node\n1, 0, 0, 0\n2, 10, 0, 0\n3, 0, 10, 0\n*Element, type=S3\n1, 1, 2, 3\n";

/// What kind of unusable folder.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Kind {
    File,
    Held,
    ReadOnly,
    Full,
}

/// A tmpfs mounted for the duration of a check, unmounted when dropped.
struct Mount(PathBuf);

impl Mount {
    fn new(dir: &Path, options: &str) -> Result<Self, String> {
        std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
        let o = Command::new("mount")
            .args(["-t", "tmpfs", "-o", options, "tmpfs"])
            .arg(dir)
            .output()
            .map_err(|e| format!("mount: {e}"))?;
        if o.status.success() {
            Ok(Self(dir.to_owned()))
        } else {
            Err(String::from_utf8_lossy(&o.stderr).trim().to_owned())
        }
    }
}

impl Drop for Mount {
    fn drop(&mut self) {
        let _ = Command::new("umount").arg(&self.0).status();
    }
}

/// The names under `dir`, recursively, with their sizes (sorted).
fn listing(dir: &Path) -> Vec<(String, u64)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_owned()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            continue;
        };
        for e in entries.flatten() {
            let path = e.path();
            if path.is_dir() {
                stack.push(path.clone());
            }
            let size = e.metadata().map_or(0, |m| m.len());
            let name = path
                .strip_prefix(dir)
                .unwrap_or(&path)
                .display()
                .to_string();
            out.push((name, size));
        }
    }
    out.sort();
    out
}

/// Why what a command left in a full `dir` is partial, if it is: a
/// temporary of drape's atomic writes, or a JSON file that does not parse.
fn partial(dir: &Path) -> Option<String> {
    for (name, _) in listing(dir) {
        let file = Path::new(&name)
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .unwrap_or_default();
        if drape_io::atomic::is_temporary(&file) {
            return Some(format!("temporary {name} left"));
        }
        if name.ends_with(".json") {
            let text = std::fs::read_to_string(dir.join(&name)).unwrap_or_default();
            if serde_json::from_str::<serde_json::Value>(&text).is_err() {
                return Some(format!("{name} is not whole JSON"));
            }
        }
    }
    None
}

/// Empties the file system at `out` and fills it to [`ROOM`] bytes short of
/// full (in 4 KiB files under `out/.filler`, the page size tmpfs counts
/// in): room for the folder's lock file and a small file, not for a run's
/// results, so every command meets the full disk part-way.
fn fill(out: &Path) -> std::io::Result<()> {
    for e in std::fs::read_dir(out)?.flatten() {
        let p = e.path();
        if p.is_dir() {
            std::fs::remove_dir_all(&p)?;
        } else {
            std::fs::remove_file(&p)?;
        }
    }
    let filler = out.join(".filler");
    std::fs::create_dir(&filler)?;
    let page = [0u8; 4096];
    let mut written = Vec::new();
    loop {
        let path = filler.join(written.len().to_string());
        match std::fs::write(&path, page) {
            Ok(()) => written.push(path),
            Err(e) if e.raw_os_error() == Some(28) => {
                // ENOSPC: a file may have been created empty.
                let _ = std::fs::remove_file(&path);
                break;
            }
            Err(e) => return Err(e),
        }
        if written.len() > 100_000 {
            return Err(std::io::Error::other("the file system does not fill"));
        }
    }
    for path in written.iter().rev().take(ROOM / page.len()) {
        std::fs::remove_file(path)?;
    }
    Ok(())
}

/// Bytes left free on the full file system.
const ROOM: usize = 8192;

/// The inputs every command reads: the scene, a results folder, a mesh.
struct Inputs {
    scene: PathBuf,
    run: PathBuf,
    mesh: PathBuf,
}

fn prepare(drape: &Path, dir: &Path) -> Result<Inputs, String> {
    let _ = std::fs::remove_dir_all(dir);
    std::fs::create_dir_all(dir).map_err(|e| e.to_string())?;
    let scene = dir.join("scene.toml");
    let mesh = dir.join("flat.inp");
    std::fs::write(&scene, SCENE).map_err(|e| e.to_string())?;
    std::fs::write(&mesh, MESH).map_err(|e| e.to_string())?;
    let run = dir.join("source");
    let o = Command::new(drape)
        .args(["kinematic", &scene.display().to_string(), "--out"])
        .arg(&run)
        .output()
        .map_err(|e| e.to_string())?;
    if !o.status.success() {
        return Err(format!(
            "the source drape failed: {}",
            String::from_utf8_lossy(&o.stderr)
        ));
    }
    Ok(Inputs { scene, run, mesh })
}

/// The argument lists of every writing command into `out`.
fn commands(i: &Inputs, out: &Path) -> Vec<(&'static str, Vec<String>)> {
    let p = |p: &Path| p.display().to_string();
    let out = p(out);
    vec![
        (
            "run",
            vec!["run".into(), p(&i.scene), "--out".into(), out.clone()],
        ),
        (
            "sweep",
            vec![
                "sweep".into(),
                p(&i.scene),
                "--set".into(),
                "tools.0.friction=0,0.1".into(),
                "--out".into(),
                out.clone(),
            ],
        ),
        (
            "kinematic",
            vec!["kinematic".into(), p(&i.scene), "--out".into(), out.clone()],
        ),
        (
            "compare SCENE",
            vec!["compare".into(), p(&i.scene), "--out".into(), out.clone()],
        ),
        (
            "compare RUN_A RUN_B",
            vec![
                "compare".into(),
                p(&i.run),
                p(&i.run),
                "--out".into(),
                out.clone(),
            ],
        ),
        (
            "export --onto",
            vec![
                "export".into(),
                p(&i.run),
                "--onto".into(),
                p(&i.mesh),
                "--out".into(),
                out,
            ],
        ),
    ]
}

/// Runs `args` into the unusable folder of `kind` under `base` and says
/// what is wrong with how it ended, if anything.
fn check(
    drape: &Path,
    base: &Path,
    kind: Kind,
    args: &[String],
    codes: &mut Vec<i32>,
) -> Option<String> {
    let out = match kind {
        Kind::File => base.join("a-file"),
        Kind::Held | Kind::ReadOnly | Kind::Full => base.join("out"),
    };
    let before = listing(base);
    let o = match Command::new(drape).args(args).output() {
        Ok(o) => o,
        Err(e) => return Some(format!("could not start: {e}")),
    };
    let code = o.status.code();
    codes.push(code.unwrap_or(-1));
    let stderr = String::from_utf8_lossy(&o.stderr);
    let fault = match kind {
        Kind::File | Kind::Held | Kind::ReadOnly => {
            if code != Some(2) {
                Some(format!("exit {code:?}, not 2"))
            } else if listing(base) != before {
                Some("changed the folder".to_owned())
            } else {
                None
            }
        }
        Kind::Full => {
            if !matches!(code, Some(1 | 2)) {
                Some(format!("exit {code:?}, not 1 or 2"))
            } else {
                partial(&out)
            }
        }
    };
    fault.map(|f| {
        let last = stderr.lines().last().unwrap_or("").to_owned();
        format!("{f} ({})", last.chars().take(120).collect::<String>())
    })
}

/// The row: every writing command against every kind of unusable folder.
pub fn unusable_folders(ctx: &Context) -> Row {
    let started = Instant::now();
    let row = |pass: bool, happened: String| Row {
        case: ctx.name.to_owned(),
        expect: Expect::Caught,
        happened,
        pass,
        seconds: started.elapsed().as_secs_f64(),
    };
    let built = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned()))
        .args(["build", "--quiet", "-p", "drape"])
        .current_dir(&ctx.root)
        .status();
    if !matches!(built, Ok(s) if s.success()) {
        return row(
            false,
            format!("could not build the drape binary: {built:?}"),
        );
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .filter(|d| !d.is_empty())
        .map_or_else(|| ctx.root.join("target"), PathBuf::from);
    let drape = target.join("debug").join("drape");
    let inputs = match prepare(&drape, &ctx.dir.join("inputs")) {
        Ok(i) => i,
        Err(e) => return row(false, e),
    };
    let mut faults = Vec::new();
    let mut checked = 0;
    let mut skipped = Vec::new();
    let mut full_codes = Vec::new();
    for kind in [Kind::File, Kind::Held, Kind::ReadOnly, Kind::Full] {
        let base = ctx.dir.join(format!("{kind:?}").to_lowercase());
        let _ = std::fs::remove_dir_all(&base);
        if let Err(e) = std::fs::create_dir_all(&base) {
            return row(false, format!("{}: {e}", base.display()));
        }
        let out = base.join("out");
        // What makes the folder unusable, held for the kind's commands.
        let mut _lock = None;
        let mut _mount = None;
        match kind {
            Kind::File => {
                if let Err(e) = std::fs::write(base.join("a-file"), "x") {
                    return row(false, e.to_string());
                }
            }
            Kind::Held => match drape_io::results::OutputLock::acquire(&out) {
                Ok(lock) => _lock = Some(lock),
                Err(e) => return row(false, format!("could not hold {}: {e}", out.display())),
            },
            Kind::ReadOnly | Kind::Full => {
                let options = if kind == Kind::ReadOnly {
                    "ro,size=64k"
                } else {
                    "size=64k"
                };
                match Mount::new(&out, options) {
                    Ok(m) => _mount = Some(m),
                    Err(e) => {
                        skipped.push(format!("{kind:?} (cannot mount a tmpfs here: {e})"));
                        continue;
                    }
                }
            }
        }
        full_codes.clear();
        let into = if kind == Kind::File {
            base.join("a-file")
        } else {
            out.clone()
        };
        for (name, args) in commands(&inputs, &into) {
            if kind == Kind::Full
                && let Err(e) = fill(&out)
            {
                return row(false, format!("could not fill {}: {e}", out.display()));
            }
            checked += 1;
            if let Some(fault) = check(&drape, &base, kind, &args, &mut full_codes) {
                faults.push(format!("{name} into {kind:?}: {fault}"));
            }
        }
    }
    // The last kind run is the full one, when it ran: how its commands
    // ended (1: met the full disk while writing; 2: refused before).
    let full = if skipped.iter().any(|k| k.starts_with("Full")) {
        String::new()
    } else {
        format!(
            " (full disk: exit codes {})",
            full_codes
                .iter()
                .map(i32::to_string)
                .collect::<Vec<_>>()
                .join(" ")
        )
    };
    let mut happened = if faults.is_empty() {
        format!(
            "{checked} commands into unusable folders: every one kept the exit-code contract \
             and left no partial file{full}"
        )
    } else {
        format!(
            "{} of {checked} broke the contract: {}",
            faults.len(),
            faults.join("; ")
        )
    };
    if !skipped.is_empty() {
        happened.push_str(&format!("; skipped {}", skipped.join(", ")));
    }
    row(faults.is_empty(), happened)
}
