//! The validation runner: named cases, each a list of [`Check`]s that put a
//! value computed by drape's crates beside a reference from an analytic
//! formula (or an independent computation), with a stated tolerance.
//!
//! Adding a case is a function returning `Vec<Check>` and one [`Case`] entry
//! in its crate's module's `CASES`; a new crate's module is one line in
//! [`registry`]. Rules for a case: the computed side calls the crates, the
//! reference side never does (it re-derives from the formula or the preset's
//! raw parameters); tolerances are stated from the expected error (round-off
//! or a known truncation term), never widened to make a check pass.
//!
//! The runner prints one aligned table per case, ends with the line
//! `N passed, N failed`, writes the same tables as Markdown to
//! `<target>/validation/report.md`, puts each case's result into
//! `docs/validation.md` ([`page`]; what a case checks is one line in
//! [`describe`]) and exits non-zero on any failure. A
//! panicking case counts as one failed check carrying the panic message.

use std::cell::RefCell;
use std::fmt::Write as _;
use std::panic::{self, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::process::ExitCode;

mod bending;
mod cao2008;
mod constitutive;
mod contact;
mod describe;
mod explicit;
mod fishnet;
mod implicit;
mod kinematics;
mod locking;
mod page;
mod paper;
mod plies;
mod pressure;
mod scenes;
mod tray;
mod wrinkling;

/// Every case of every crate, in the order they run and are reported.
pub fn registry() -> Vec<Case> {
    [
        kinematics::CASES,
        constitutive::CASES,
        explicit::CASES,
        contact::CASES,
        fishnet::CASES,
        implicit::CASES,
        scenes::CASES,
        tray::CASES,
        bending::CASES,
        locking::CASES,
        wrinkling::CASES,
        paper::CASES,
        pressure::CASES,
        cao2008::CASES,
        plies::CASES,
    ]
    .concat()
}

/// One validation case.
#[derive(Debug, Clone, Copy)]
pub struct Case {
    /// `crate/what`, e.g. `kinematics/polar-decomposition`; `--filter`
    /// matches a substring of it.
    pub name: &'static str,
    /// Cheap enough for CI (`--quick`): seconds, not minutes.
    pub quick: bool,
    /// Computes the checks.
    pub run: fn() -> Vec<Check>,
}

/// How far a computed value may be from its reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tolerance {
    /// |computed − reference| ≤ tol.
    Abs(f64),
    /// |computed − reference| ≤ tol·|reference|.
    Rel(f64),
}

/// One compared quantity.
#[derive(Debug, Clone, PartialEq)]
pub struct Check {
    /// What is compared, with its unit or condition.
    pub quantity: String,
    /// The analytic (or independently computed) value.
    pub reference: f64,
    /// The crates' value.
    pub computed: f64,
    /// The accepted distance.
    pub tolerance: Tolerance,
    /// The error measured as the tolerance measures it (absolute or relative).
    pub error: f64,
    /// Whether `error` is within the tolerance (false for NaN).
    pub passed: bool,
}

impl Check {
    /// A check with an absolute tolerance.
    pub fn abs(quantity: impl Into<String>, reference: f64, computed: f64, tol: f64) -> Self {
        Self::new(quantity.into(), reference, computed, Tolerance::Abs(tol))
    }

    /// A check with a tolerance relative to |reference|.
    pub fn rel(quantity: impl Into<String>, reference: f64, computed: f64, tol: f64) -> Self {
        Self::new(quantity.into(), reference, computed, Tolerance::Rel(tol))
    }

    fn new(quantity: String, reference: f64, computed: f64, tolerance: Tolerance) -> Self {
        let diff = (computed - reference).abs();
        let (error, tol) = match tolerance {
            Tolerance::Abs(tol) => (diff, tol),
            // An exact match of a zero reference is a pass, not 0/0.
            Tolerance::Rel(tol) if diff == 0.0 => (0.0, tol),
            Tolerance::Rel(tol) => (diff / reference.abs(), tol),
        };
        Self {
            quantity,
            reference,
            computed,
            tolerance,
            error,
            // Written so that a NaN anywhere fails.
            passed: error <= tol,
        }
    }

    /// A failed check standing for a case that panicked.
    fn panicked(message: &str) -> Self {
        Self {
            quantity: format!("case panicked: {message}"),
            reference: f64::NAN,
            computed: f64::NAN,
            tolerance: Tolerance::Abs(0.0),
            error: f64::NAN,
            passed: false,
        }
    }
}

/// Command-line options of `cargo xtask validate`.
#[derive(Debug, Default, Clone, PartialEq)]
pub struct Options {
    /// Run only the cases marked quick.
    pub quick: bool,
    /// Run only the cases whose name contains this.
    pub filter: Option<String>,
}

impl Options {
    /// Parses the arguments after `validate`.
    pub fn parse(args: &[String]) -> Result<Self, String> {
        let mut options = Self::default();
        let mut args = args.iter();
        while let Some(arg) = args.next() {
            match arg.as_str() {
                "--quick" => options.quick = true,
                "--filter" => match args.next() {
                    Some(value) => options.filter = Some(value.clone()),
                    None => return Err("`--filter` needs a value: --filter SUBSTR".to_owned()),
                },
                other => match other.strip_prefix("--filter=") {
                    Some(value) => options.filter = Some(value.to_owned()),
                    None => return Err(format!("unknown argument `{other}` to `validate`")),
                },
            }
        }
        Ok(options)
    }

    fn selects(&self, case: &Case) -> bool {
        (case.quick || !self.quick)
            && self
                .filter
                .as_ref()
                .is_none_or(|f| case.name.contains(f.as_str()))
    }
}

/// The outcome of one case.
#[derive(Debug, Clone)]
pub struct CaseResult {
    /// The case's name.
    pub name: &'static str,
    /// Its checks (one failed check if it panicked).
    pub checks: Vec<Check>,
    /// Markdown sections the case wrote with [`note`] (tables of results
    /// beside published ones), printed after its checks.
    pub notes: Vec<String>,
    /// The case asked [`quick_mode`]: its quick and full runs differ, so
    /// the page keeps the last result of each.
    pub mode_dependent: bool,
}

/// Whether this is a `--quick` run: a case marked quick may run a coarse
/// version of itself then (the paper's tables: coarse meshes in CI, the
/// shipped meshes in full mode) under the same name.
static QUICK: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Set when the running case asks [`quick_mode`] (cases run one at a
/// time; their own threads may ask too).
static CONSULTED: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// True while `cargo xtask validate --quick` runs.
pub fn quick_mode() -> bool {
    CONSULTED.store(true, std::sync::atomic::Ordering::Relaxed);
    QUICK.load(std::sync::atomic::Ordering::Relaxed)
}

thread_local! {
    static NOTES: RefCell<Vec<String>> = const { RefCell::new(Vec::new()) };
}

/// Adds a Markdown section to the report of the case running on this
/// thread: results that are reported rather than checked (a published
/// table beside drape's numbers). A case's checks still decide its status.
pub fn note(markdown: impl Into<String>) {
    NOTES.with(|n| n.borrow_mut().push(markdown.into()));
}

/// Runs one case, turning a panic into a failed check.
pub fn run_case(case: &Case) -> CaseResult {
    NOTES.with(|n| n.borrow_mut().clear());
    CONSULTED.store(false, std::sync::atomic::Ordering::Relaxed);
    let checks = match panic::catch_unwind(AssertUnwindSafe(case.run)) {
        Ok(checks) => checks,
        Err(payload) => {
            let message = payload
                .downcast_ref::<&str>()
                .map(|s| (*s).to_owned())
                .or_else(|| payload.downcast_ref::<String>().cloned())
                .unwrap_or_else(|| "(non-string panic payload)".to_owned());
            vec![Check::panicked(&message)]
        }
    };
    CaseResult {
        name: case.name,
        checks,
        notes: NOTES.with(|n| std::mem::take(&mut *n.borrow_mut())),
        mode_dependent: CONSULTED.load(std::sync::atomic::Ordering::Relaxed),
    }
}

/// `cargo xtask validate`: runs the selected cases, prints and writes the
/// report.
pub fn main(options: &Options, workspace_root: &Path) -> ExitCode {
    QUICK.store(options.quick, std::sync::atomic::Ordering::Relaxed);
    let selected: Vec<Case> = registry()
        .into_iter()
        .filter(|c| options.selects(c))
        .collect();
    if selected.is_empty() {
        eprintln!(
            "error: no validation case matches{}{}",
            if options.quick { " --quick" } else { "" },
            options
                .filter
                .as_ref()
                .map(|f| format!(" --filter {f}"))
                .unwrap_or_default()
        );
        return ExitCode::FAILURE;
    }
    let mut results = Vec::with_capacity(selected.len());
    for case in &selected {
        let result = run_case(case);
        print!("{}", text_table(&result));
        results.push(result);
    }
    let (passed, failed) = tally(&results);
    let summary = format!("{passed} passed, {failed} failed");
    println!("{summary}");

    let report = markdown_report(&results, options, &summary);
    let path = target_dir(workspace_root)
        .join("validation")
        .join("report.md");
    match write_atomically(&path, &report) {
        Ok(()) => eprintln!("report: {}", path.display()),
        Err(err) => {
            eprintln!("error: could not write {}: {err}", path.display());
            return ExitCode::FAILURE;
        }
    }
    let page = workspace_root.join("docs").join("validation.md");
    match page::update(&page, &results, options.quick) {
        Ok(()) => eprintln!("page: {}", page.display()),
        Err(err) => {
            eprintln!("error: could not write {err}");
            return ExitCode::FAILURE;
        }
    }
    if failed == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    }
}

/// (passed, failed) over all checks.
pub fn tally(results: &[CaseResult]) -> (usize, usize) {
    let checks = results.iter().flat_map(|r| &r.checks);
    let passed = checks.clone().filter(|c| c.passed).count();
    (passed, checks.count() - passed)
}

/// Cargo's target directory: `CARGO_TARGET_DIR` when set (relative to the
/// current directory, as cargo reads it), else `<workspace>/target`.
pub(super) fn target_dir(workspace_root: &Path) -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(dir) if !dir.is_empty() => PathBuf::from(dir),
        _ => workspace_root.join("target"),
    }
}

/// Writes through a temporary file in the same directory and a rename, so a
/// reader never sees half a report.
fn write_atomically(path: &Path, contents: &str) -> std::io::Result<()> {
    let dir = path.parent().expect("report path has a directory");
    std::fs::create_dir_all(dir)?;
    let tmp = dir.join(format!(".report.md.{}.tmp", std::process::id()));
    std::fs::write(&tmp, contents)?;
    std::fs::rename(&tmp, path).inspect_err(|_| {
        let _ = std::fs::remove_file(&tmp);
    })
}

pub(super) const HEADER: [&str; 6] = [
    "quantity",
    "reference",
    "computed",
    "tolerance",
    "error",
    "status",
];

/// A value of the table: a whole number (a count of steps, increments,
/// elements, or an exact zero) as an integer, "52794" rather than
/// "5.2794000000e4"; anything else with eleven significant digits.
fn value(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        format!("{v:.10e}")
    }
}

pub(super) fn cells(check: &Check) -> [String; 6] {
    let tolerance = match check.tolerance {
        Tolerance::Abs(t) => format!("abs {t:.1e}"),
        Tolerance::Rel(t) => format!("rel {t:.1e}"),
    };
    [
        check.quantity.clone(),
        value(check.reference),
        value(check.computed),
        tolerance,
        format!("{:.2e}", check.error),
        if check.passed { "PASS" } else { "FAIL" }.to_owned(),
    ]
}

/// Display width of a cell: combining marks (the bar of τ̄, ε̄) take none.
fn width(s: &str) -> usize {
    s.chars()
        .filter(|c| !('\u{300}'..='\u{36f}').contains(c))
        .count()
}

fn text_table(result: &CaseResult) -> String {
    let rows: Vec<[String; 6]> = result.checks.iter().map(cells).collect();
    let mut widths = HEADER.map(width);
    for row in &rows {
        for (w, cell) in widths.iter_mut().zip(row) {
            *w = (*w).max(width(cell));
        }
    }
    let line = |cells: &[String; 6]| {
        let mut out = String::from("  ");
        for (i, (cell, w)) in cells.iter().zip(widths).enumerate() {
            let pad = " ".repeat(w - width(cell));
            // Text left-aligned, numbers right-aligned.
            if i == 0 {
                out.push_str(cell);
                out.push_str(&pad);
            } else if i == 5 {
                out.push_str(cell);
            } else {
                out.push_str(&pad);
                out.push_str(cell);
            }
            if i < 5 {
                out.push_str("  ");
            }
        }
        out.push('\n');
        out
    };
    let mut out = format!("{}\n", result.name);
    out.push_str(&line(&HEADER.map(str::to_owned)));
    for row in &rows {
        out.push_str(&line(row));
    }
    out.push('\n');
    for note in &result.notes {
        out.push_str(note);
        out.push_str("\n\n");
    }
    out
}

fn markdown_report(results: &[CaseResult], options: &Options, summary: &str) -> String {
    let mut out = String::from("# drape validation report\n\n");
    let _ = writeln!(
        out,
        "Selection: {}{}.\n",
        if options.quick {
            "quick cases"
        } else {
            "all cases"
        },
        options
            .filter
            .as_ref()
            .map(|f| format!(" whose name contains `{f}`"))
            .unwrap_or_default()
    );
    let _ = writeln!(out, "**{summary}**\n");
    for result in results {
        let _ = writeln!(out, "## {}\n", result.name);
        let _ = writeln!(out, "| {} |", HEADER.join(" | "));
        let _ = writeln!(out, "|---|--:|--:|--:|--:|---|");
        for check in &result.checks {
            let row = cells(check).map(|c| c.replace('|', "\\|"));
            let _ = writeln!(out, "| {} |", row.join(" | "));
        }
        out.push('\n');
        for note in &result.notes {
            let _ = writeln!(out, "{note}\n");
        }
    }
    out
}

/// A small deterministic generator (SplitMix64) for the random samples of
/// the cases: the same seed gives the same report on every machine.
pub struct Rng(u64);

impl Rng {
    /// A generator from a seed.
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [lo, hi).
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        // The top 53 bits make a uniform double in [0, 1).
        let unit = (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * unit
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_print_as_integers_and_measures_in_full() {
        assert_eq!(value(52794.0), "52794");
        assert_eq!(value(0.0), "0");
        assert_eq!(value(-3.0), "-3");
        assert_eq!(value(0.25), "2.5000000000e-1");
        assert_eq!(value(1e20), "1.0000000000e20");
        assert_eq!(value(f64::NAN), "NaN");
    }

    /// The per-point cases run in `cargo test` too; the simulation cases
    /// (explicit, contact: tens of seconds) run in `cargo xtask validate
    /// --quick`, which CI runs right after the tests.
    #[test]
    fn the_quick_kinematics_and_constitutive_cases_pass() {
        let failures: Vec<String> = registry()
            .iter()
            .filter(|c| {
                c.quick
                    && (c.name.starts_with("kinematics/") || c.name.starts_with("constitutive/"))
            })
            .map(run_case)
            .flat_map(|r| {
                r.checks
                    .into_iter()
                    .filter(|c| !c.passed)
                    .map(move |c| format!("{}: {:?}", r.name, c))
            })
            .collect();
        assert!(
            failures.is_empty(),
            "failed checks:\n{}",
            failures.join("\n")
        );
    }

    #[test]
    fn case_names_are_unique_and_prefixed_by_their_crate() {
        let cases = registry();
        for (i, case) in cases.iter().enumerate() {
            assert!(case.name.contains('/'), "{}", case.name);
            assert!(
                cases[..i].iter().all(|c| c.name != case.name),
                "duplicate case {}",
                case.name
            );
        }
    }

    #[test]
    fn checks_fail_on_nan_and_outside_tolerance() {
        assert!(Check::abs("x", 1.0, 1.0 + 1e-9, 1e-8).passed);
        assert!(!Check::abs("x", 1.0, 1.0 + 1e-7, 1e-8).passed);
        assert!(Check::rel("x", 100.0, 100.5, 1e-2).passed);
        assert!(!Check::rel("x", 100.0, 102.0, 1e-2).passed);
        assert!(Check::rel("x", 0.0, 0.0, 1e-2).passed);
        assert!(!Check::rel("x", 0.0, 1e-300, 1e-2).passed);
        assert!(!Check::abs("x", 1.0, f64::NAN, 1.0).passed);
        assert!(!Check::rel("x", f64::NAN, 1.0, 1.0).passed);
    }

    #[test]
    fn notes_belong_to_the_case_that_wrote_them() {
        fn writes() -> Vec<Check> {
            note("| a | b |");
            vec![Check::abs("x", 1.0, 1.0, 0.0)]
        }
        fn silent() -> Vec<Check> {
            Vec::new()
        }
        let case = |name, run| Case {
            name,
            quick: true,
            run,
        };
        let first = run_case(&case("test/notes", writes));
        let second = run_case(&case("test/silent", silent));
        assert_eq!(first.notes, vec!["| a | b |".to_owned()]);
        assert!(second.notes.is_empty());
        let report = markdown_report(&[first], &Options::default(), "1 passed");
        assert!(report.contains("| a | b |"), "{report}");
    }

    #[test]
    fn a_panicking_case_is_one_failure_with_its_message() {
        fn boom() -> Vec<Check> {
            panic!("boom {}", 42)
        }
        let r = run_case(&Case {
            name: "test/boom",
            quick: true,
            run: boom,
        });
        assert_eq!(tally(std::slice::from_ref(&r)), (0, 1));
        assert!(r.checks[0].quantity.contains("boom 42"));
    }

    #[test]
    fn options_parse_and_reject_unknown_flags() {
        let args = |s: &[&str]| s.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        assert_eq!(
            Options::parse(&args(&["--quick", "--filter", "prony"])).unwrap(),
            Options {
                quick: true,
                filter: Some("prony".into())
            }
        );
        assert_eq!(
            Options::parse(&args(&["--filter=fibre"]))
                .unwrap()
                .filter
                .as_deref(),
            Some("fibre")
        );
        assert!(
            Options::parse(&args(&["--fast"]))
                .unwrap_err()
                .contains("--fast")
        );
        assert!(Options::parse(&args(&["--filter"])).is_err());
    }

    #[test]
    fn table_columns_align_with_combining_marks() {
        let r = CaseResult {
            name: "test/table",
            notes: Vec::new(),
            mode_dependent: false,
            checks: vec![
                Check::abs("τ̄₁₂", 1.0, 1.0, 0.0),
                Check::abs("a longer quantity", -2.5e-7, -2.5e-7, 1e-3),
            ],
        };
        let text = text_table(&r);
        // The status column starts at the same display column on every row.
        let starts: Vec<usize> = text
            .lines()
            .skip(1)
            .filter(|l| !l.is_empty())
            .map(|l| width(l) - width(l.split_whitespace().last().unwrap_or("")))
            .collect();
        assert_eq!(starts.len(), 3, "{text}");
        assert!(starts.windows(2).all(|w| w[0] == w[1]), "{text}");
    }
}
