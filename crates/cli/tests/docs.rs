//! Documentation that cannot rot: every `drape` command shown in a shell
//! block of README.md and docs/user-guide.md still works, and every relative
//! link of README.md and docs/ still resolves.
//!
//! A command with concrete arguments is run, in document order, in a
//! scratch folder holding a copy of `scenes/`, on a tiny version of its
//! scene (`--set simulation.end_time=…`: a few steps, so the whole file runs
//! in seconds); later commands see the results of earlier ones, as a reader
//! following the page would. A command written as a form — a placeholder in
//! capitals (`SCENE`, `PART.inp`) or optional parts in brackets — cannot be
//! run, so its subcommand's `--help` must succeed and name each `--flag`
//! the form shows. `cargo run --release -p drape -- ARGS` counts as
//! `drape ARGS`. What a page shows as a command's output is not checked:
//! its numbers change with the code.
//!
//! Not for the `cargo xtask …` and `cargo test` lines: those are the
//! developer's tools, checked by CI running them.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use common::{TempFolder, temp, text, workspace};

/// The pages whose commands are run.
const COMMAND_PAGES: [&str; 2] = ["README.md", "docs/user-guide.md"];

/// The simulated time a documented run is cut to: a few explicit steps of
/// every shipped scene (the hemisphere's mass-scaled step is 2e-5 s).
const TINY_END_TIME: &str = "2e-4";

/// A command shown in a page.
#[derive(Debug, Clone, PartialEq)]
struct Shown {
    /// `page:line`, for the failure message.
    at: String,
    /// The arguments after `drape`.
    args: Vec<String>,
}

/// Splits a shell line into words: whitespace-separated, with '…' and "…"
/// quoting (all the documented commands need).
fn words(line: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut word = String::new();
    let mut in_word = false;
    let mut quote: Option<char> = None;
    for c in line.chars() {
        match quote {
            Some(q) if c == q => quote = None,
            Some(_) => word.push(c),
            None if c == '\'' || c == '"' => {
                quote = Some(c);
                in_word = true;
            }
            None if c.is_whitespace() => {
                if in_word {
                    out.push(std::mem::take(&mut word));
                    in_word = false;
                }
            }
            None => {
                word.push(c);
                in_word = true;
            }
        }
    }
    if in_word {
        out.push(word);
    }
    out
}

/// The `drape` commands of a page's `sh` blocks, in order.
fn commands(page: &str, markdown: &str) -> Vec<Shown> {
    let mut out = Vec::new();
    let mut in_shell = false;
    let mut in_fence = false;
    for (i, line) in markdown.lines().enumerate() {
        let trimmed = line.trim_start();
        if let Some(info) = trimmed.strip_prefix("```") {
            in_shell = !in_fence && matches!(info.trim(), "sh" | "bash" | "shell" | "console");
            in_fence = !in_fence;
            continue;
        }
        if !in_shell {
            continue;
        }
        let line = trimmed.strip_prefix("$ ").unwrap_or(trimmed);
        // A trailing comment is prose about the command.
        let line = line.split(" #").next().unwrap_or(line);
        let mut w = words(line);
        let skip = if w.first().is_some_and(|s| s == "drape") {
            1
        } else if w
            .starts_with(&["cargo", "run", "--release", "-p", "drape", "--"].map(String::from))
        {
            6
        } else {
            continue;
        };
        w.drain(..skip);
        out.push(Shown {
            at: format!("{page}:{}", i + 1),
            args: w,
        });
    }
    out
}

/// A word standing for what the reader supplies: `SCENE`, `RUN_A`,
/// `PART.inp`, `N`, or optional and alternative parts (`[--out DIR]`,
/// `a|b`, `…`).
fn is_placeholder(word: &str) -> bool {
    let stem = word.split('.').next().unwrap_or(word);
    let capital = !stem.is_empty()
        && stem.chars().next().is_some_and(|c| c.is_ascii_uppercase())
        && stem
            .chars()
            .all(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || c == '_');
    capital || word.contains(['[', ']', '|', '…'])
}

/// The `drape` binary `cargo test` built.
fn drape() -> Command {
    Command::new(env!("CARGO_BIN_EXE_drape"))
}

/// Checks one shown command in the scratch folder `dir`.
fn check(shown: &Shown, dir: &Path) -> Result<(), String> {
    let Some(sub) = shown.args.first() else {
        return Err(format!("{}: `drape` without a command", shown.at));
    };
    if shown.args.iter().any(|w| is_placeholder(w)) {
        let out = drape()
            .args([sub.as_str(), "--help"])
            .current_dir(dir)
            .output()
            .map_err(|e| e.to_string())?;
        let help = text(&out);
        if !out.status.success() {
            return Err(format!(
                "{}: `drape {sub} --help` failed ({}):\n{help}",
                shown.at, out.status
            ));
        }
        for flag in shown.args.iter().flat_map(|w| {
            // `[--set key=value]…` names `--set`.
            w.trim_matches(['[', ']', '…'])
                .split('=')
                .next()
                .map(str::to_owned)
        }) {
            if flag.starts_with("--") && !help.contains(&flag) {
                return Err(format!(
                    "{}: `drape {}` shows {flag}, which `drape {sub} --help` does not know:\n{help}",
                    shown.at,
                    shown.args.join(" ")
                ));
            }
        }
        return Ok(());
    }
    let mut args = shown.args.clone();
    // A subcommand that forms a scene is cut to a few steps; `compare` with
    // two results folders runs nothing.
    let runs_a_scene = match sub.as_str() {
        "run" | "sweep" | "kinematic" => !args.iter().any(|a| a == "--resume"),
        "compare" => args.iter().skip(1).any(|a| a.ends_with(".toml")),
        _ => false,
    };
    if runs_a_scene {
        args.extend([
            "--set".into(),
            format!("simulation.end_time={TINY_END_TIME}"),
        ]);
    }
    let out = drape()
        .args(&args)
        .current_dir(dir)
        .output()
        .map_err(|e| e.to_string())?;
    if out.status.success() {
        Ok(())
    } else {
        Err(format!(
            "{}: `drape {}` failed ({}):\n{}",
            shown.at,
            args.join(" "),
            out.status,
            text(&out)
        ))
    }
}

/// A scratch folder with a copy of the shipped scenes, as a clone has them.
fn scratch(name: &str) -> TempFolder {
    fn copy(from: &Path, to: &Path) {
        std::fs::create_dir_all(to).unwrap();
        for entry in std::fs::read_dir(from).unwrap() {
            let entry = entry.unwrap();
            let target = to.join(entry.file_name());
            if entry.file_type().unwrap().is_dir() {
                copy(&entry.path(), &target);
            } else {
                std::fs::copy(entry.path(), target).unwrap();
            }
        }
    }
    let dir = temp(name);
    copy(&workspace().join("scenes"), &dir.join("scenes"));
    dir
}

#[test]
fn every_documented_command_works() {
    let mut failures = Vec::new();
    let mut count = 0;
    for page in COMMAND_PAGES {
        let markdown = std::fs::read_to_string(workspace().join(page)).unwrap();
        let dir = scratch(&page.replace('/', "-"));
        for shown in commands(page, &markdown) {
            count += 1;
            if let Err(e) = check(&shown, &dir) {
                failures.push(e);
            }
        }
    }
    assert!(
        count >= 10,
        "only {count} commands found: is the extraction broken?"
    );
    assert!(failures.is_empty(), "{}", failures.join("\n\n"));
}

/// The test of the test: a documented command broken on purpose fails it,
/// run or form, and the extraction finds what a page shows.
#[test]
fn a_broken_command_fails_the_check() {
    let page = "\
```sh
cargo run --release -p drape -- run scenes/picture-frame.toml
drape run scenes/picture-frame.toml --set fabric.no_such_key=1
drape kinematic scenes/no-such-scene.toml
drape run SCENE [--out DIR] [--no-such-flag N]
drape frobnicate SCENE
```

```
drape run output shown, not run
```
";
    let shown = commands("page.md", page);
    assert_eq!(shown.len(), 5, "{shown:?}");
    assert_eq!(shown[0].args, ["run", "scenes/picture-frame.toml"]);
    assert_eq!(shown[3].at, "page.md:5");
    let dir = scratch("broken");
    let results: Vec<Result<(), String>> = shown.iter().map(|s| check(s, &dir)).collect();
    let _ = std::fs::remove_dir_all(&dir);
    assert!(results[0].is_ok(), "{:?}", results[0]);
    for (r, what) in results[1..].iter().zip([
        "no_such_key",
        "no-such-scene",
        "--no-such-flag",
        "frobnicate",
    ]) {
        let e = r.as_ref().expect_err(what);
        assert!(e.contains(what), "{e}");
    }
}

#[test]
fn placeholders_are_told_from_arguments() {
    for p in ["SCENE", "RUN_A", "PART.inp", "N", "[--out", "DIR]…", "a|b"] {
        assert!(is_placeholder(p), "{p}");
    }
    for a in [
        "scenes/tray.toml",
        "--set",
        "tools.0.friction=0,0.1",
        "results/tray",
        "m",
    ] {
        assert!(!is_placeholder(a), "{a}");
    }
    assert_eq!(words("a 'b c' \"d\"  e"), ["a", "b c", "d", "e"]);
}

// ---- links ----

/// The anchor GitHub gives a heading: lower case, punctuation but `-` and
/// `_` dropped, spaces turned into `-`.
fn slug(heading: &str) -> String {
    heading
        .trim()
        .to_lowercase()
        .chars()
        .filter_map(|c| match c {
            ' ' => Some('-'),
            c if c.is_alphanumeric() || c == '-' || c == '_' => Some(c),
            _ => None,
        })
        .collect()
}

/// The anchors of a page's headings (a repeated heading gets `-1`, `-2`…).
fn anchors(markdown: &str) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut in_fence = false;
    for line in markdown.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence || !line.starts_with('#') {
            continue;
        }
        let base = slug(line.trim_start_matches('#'));
        let mut anchor = base.clone();
        let mut n = 0;
        while out.contains(&anchor) {
            n += 1;
            anchor = format!("{base}-{n}");
        }
        out.push(anchor);
    }
    out
}

/// The link targets of a page, with their line: `[text](target)`,
/// `![alt](target)` and `[label]: target`, outside code.
fn links(markdown: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    let mut in_fence = false;
    for (i, line) in markdown.lines().enumerate() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        // Inline code is not a link: drop the spans between backticks.
        let prose: String = line
            .split('`')
            .enumerate()
            .map(|(k, part)| if k % 2 == 0 { part } else { " " })
            .collect();
        let mut rest = prose.as_str();
        while let Some(at) = rest.find("](") {
            let after = &rest[at + 2..];
            let end = after.find(')').unwrap_or(after.len());
            let target = after[..end].split_whitespace().next().unwrap_or("");
            out.push((i + 1, target.trim_matches(['<', '>']).to_owned()));
            rest = &after[end..];
        }
        let t = prose.trim_start();
        if t.starts_with('[')
            && let Some((_, target)) = t.split_once("]: ")
        {
            out.push((i + 1, target.trim().to_owned()));
        }
    }
    out
}

/// The broken links of the page at `path`.
fn broken_links(path: &Path) -> Vec<String> {
    let markdown = std::fs::read_to_string(path).unwrap();
    let dir = path.parent().unwrap();
    let mut out = Vec::new();
    for (line, target) in links(&markdown) {
        if target.contains("://") || target.starts_with("mailto:") {
            continue;
        }
        let (file, anchor) = target.split_once('#').unwrap_or((&target, ""));
        let resolved = if file.is_empty() {
            path.to_path_buf()
        } else {
            dir.join(file)
        };
        let shown = path.strip_prefix(workspace()).unwrap_or(path);
        let at = format!("{}:{line}: `{target}`", shown.display());
        if !resolved.exists() {
            out.push(format!("{at}: no such file"));
        } else if !anchor.is_empty() && resolved.extension().is_some_and(|e| e == "md") {
            let headings = anchors(&std::fs::read_to_string(&resolved).unwrap());
            if !headings.iter().any(|a| a == anchor) {
                out.push(format!("{at}: no heading there has the anchor #{anchor}"));
            }
        }
    }
    out
}

/// README.md and every Markdown page under docs/.
fn pages() -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for entry in std::fs::read_dir(dir).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                walk(&path, out);
            } else if path.extension().is_some_and(|e| e == "md") {
                out.push(path);
            }
        }
    }
    let mut out = vec![workspace().join("README.md")];
    walk(&workspace().join("docs"), &mut out);
    out.sort();
    out
}

#[test]
fn every_relative_link_resolves() {
    let pages = pages();
    assert!(pages.len() >= 4, "{pages:?}");
    let broken: Vec<String> = pages.iter().flat_map(|p| broken_links(p)).collect();
    assert!(broken.is_empty(), "{}", broken.join("\n"));
}

/// The test of the link check: a missing file and a missing heading are
/// found, code is not read as links, and anchors follow GitHub's rule.
#[test]
fn a_broken_link_fails_the_check() {
    let dir = temp("links");
    std::fs::write(dir.join("other.md"), "# Other page\n\n## `[simulation]`\n").unwrap();
    let page = dir.join("page.md");
    std::fs::write(
        &page,
        "# Title\n\n## The implicit solver\n\n\
         [ok](other.md#simulation) [ok](#the-implicit-solver) [ok](#title)\n\
         [gone](missing.md) [no heading](other.md#nowhere)\n\
         `[code](not-a-link.md)` ![pic](missing.png)\n\n\
         ```\n[in a block](also-not.md)\n```\n\n[ref]: gone-too.md\n",
    )
    .unwrap();
    let broken = broken_links(&page);
    let _ = std::fs::remove_dir_all(&dir);
    let found: Vec<&str> = ["missing.md", "#nowhere", "missing.png", "gone-too.md"]
        .into_iter()
        .filter(|t| broken.iter().any(|b| b.contains(t)))
        .collect();
    assert_eq!(found.len(), 4, "{broken:#?}");
    assert_eq!(broken.len(), 4, "{broken:#?}");
    assert_eq!(
        slug(" Checkpoints and `--resume`"),
        "checkpoints-and---resume"
    );
    assert_eq!(slug("What a run writes"), "what-a-run-writes");
}
