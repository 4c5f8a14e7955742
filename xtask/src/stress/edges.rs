//! The stress suite's edge-number generator: every numeric key of the
//! shipped scenes (their TOML trees, with the documented optional keys
//! added) set to numbers at the edges of f64 and of the integers (0, ±0,
//! subnormals, ±1e-300, ±1e300, ±f64::MAX, ±inf, NaN, i64 and u32 edges),
//! and every list to a wrong length, in the file and through `--set`.
//!
//! A case must either be refused with a message that names the key it
//! changed (`drape run` exits 2), or run (within a step budget and a wall
//! clock) to a summary without a NaN: completed or stopped with a sane
//! balance, or failed with a reason. What breaks that is listed in the
//! row and, whole, in `findings.txt` beside the cases.
//!
//! Not for plausible scenes (`generate::random_scene`) nor damaged files.

use std::fmt::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};

use toml::{Table, Value};

use super::{Context, Expect, Outcome, Row, Run, execute};
use crate::validate::Rng;

/// Steps an accepted case may run: it is the reading and the first steps
/// that are tested, and a finite budget keeps the suite's time bounded.
const STEP_BUDGET: u64 = 30;
/// Wall clock after which a case counts as hung.
const LIMIT: Duration = Duration::from_secs(60);

/// Numbers at the edges of f64, as TOML writes them.
const FLOATS: [&str; 14] = [
    "0.0",
    "-0.0",
    "5e-324",
    "-5e-324",
    "2.2250738585072014e-308",
    "1e-300",
    "-1e-300",
    "1e300",
    "-1e300",
    "1.7976931348623157e308",
    "-1.7976931348623157e308",
    "inf",
    "-inf",
    "nan",
];

/// Whole numbers at the edges of the integer types a scene reads (counts
/// are usize, node numbers u32; TOML's own are i64), and a number past
/// i64 that TOML cannot hold.
const INTEGERS: [&str; 9] = [
    "0",
    "-1",
    "4294967295",
    "4294967296",
    "9223372036854775807",
    "-9223372036854775808",
    "18446744073709551615",
    "1e300",
    "nan",
];

/// The scenes whose keys are varied, and the optional keys each is given
/// (with ordinary values) so that those are varied too.
const BASES: [(&str, &str); 5] = [
    (
        "hemisphere-0-90.toml",
        r#"
[simulation]
safety_factor = 0.9
damping = 0.0
contact_margin = 5.0
max_energy_error = 0.05

[fabric.blank]
center = [0, 0, 0]

[[springs]]
nodes = [0]
stiffness = 1.0
preload = 0.5
rest_length = 1.0
anchor_offset = [0, 0, 1]

[[loads]]
nodes = [1, 2]
force = [0, 0, -1]

[output]
shear_range_deg = [0, 50]

[kinematic]
seed = [0, 0]
spacing = 10.0
direction = [0, 0, 1]
"#,
    ),
    (
        "imported-plate.toml",
        r#"
[fabric.blank]
scale = 1.0
offset = [0, 0, 0]
rotate = [0, 0, 0]
"#,
    ),
    (
        "hemisphere-ring.toml",
        r#"
[simulation]
initial_increment = 1e-3
max_increment = 1e-2
min_increment = 1e-6
spectral_radius = 0.8
force_tolerance = 1e-3
displacement_tolerance = 1e-6
gap_tolerance = 1e-3
max_iterations = 20
"#,
    ),
    ("tray.toml", ""),
    ("picture-frame.toml", ""),
];

/// One numeric key of a scene: its path as `--set` takes it, and its form.
#[derive(Debug, Clone)]
struct Key {
    /// `tools.0.geometry.radius`.
    path: String,
    /// `tools[0].geometry.radius`, as errors name it.
    field: String,
    kind: Kind,
    /// A list's values as the scene gives them.
    items: Vec<String>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
enum Kind {
    Float,
    Integer,
    /// A list of this many numbers.
    List(usize),
}

/// One case: a base scene, a key and the value given to it, and whether
/// through `--set`.
#[derive(Debug, Clone)]
struct Case {
    base: usize,
    key: Key,
    value: String,
    set: bool,
}

/// The scene `name` of `root/scenes` with `extra` merged in, its outputs
/// cut to the summary and the tables, its files' paths absolute.
fn base_table(root: &Path, name: &str, extra: &str) -> Result<Table, String> {
    let dir = root.join("scenes");
    let text = std::fs::read_to_string(dir.join(name)).map_err(|e| format!("{name}: {e}"))?;
    let mut table: Table = toml::from_str(&text).map_err(|e| format!("{name}: {e}"))?;
    let extra: Table = toml::from_str(extra).map_err(|e| format!("{name} extra: {e}"))?;
    merge(&mut table, extra);
    let output = table
        .entry("output")
        .or_insert_with(|| Value::Table(Table::new()));
    if let Value::Table(o) = output {
        o.insert("vtu".into(), Value::Boolean(false));
        o.insert("pictures".into(), Value::Boolean(false));
    }
    absolute_files(&mut table, &dir);
    Ok(table)
}

/// `extra`'s keys into `table`: tables merged, lists of tables appended.
fn merge(table: &mut Table, extra: Table) {
    for (key, value) in extra {
        match (table.get_mut(&key), value) {
            (Some(Value::Table(t)), Value::Table(e)) => merge(t, e),
            (Some(Value::Array(a)), Value::Array(e)) if e.iter().all(Value::is_table) => {
                a.extend(e)
            }
            (_, value) => {
                table.insert(key, value);
            }
        }
    }
}

/// Mesh files (`mesh`, `file`) relative to `dir` made absolute, so that
/// the case's scene can be written anywhere.
fn absolute_files(table: &mut Table, dir: &Path) {
    for (key, value) in table.iter_mut() {
        match value {
            Value::String(s) if key == "mesh" || key == "file" => {
                *s = dir.join(&*s).to_string_lossy().into_owned();
            }
            Value::Table(t) => absolute_files(t, dir),
            Value::Array(a) => {
                for v in a {
                    if let Value::Table(t) = v {
                        absolute_files(t, dir);
                    }
                }
            }
            _ => {}
        }
    }
}

/// Every numeric key and list of numbers in `table`.
fn keys(table: &Table, path: &str, field: &str, out: &mut Vec<Key>) {
    for (k, v) in table {
        let (p, f) = if path.is_empty() {
            (k.clone(), k.clone())
        } else {
            (format!("{path}.{k}"), format!("{field}.{k}"))
        };
        value_keys(v, p, f, out);
    }
}

fn value_keys(value: &Value, path: String, field: String, out: &mut Vec<Key>) {
    let number = |v: &Value| matches!(v, Value::Integer(_) | Value::Float(_));
    match value {
        Value::Float(_) => out.push(Key {
            path,
            field,
            kind: Kind::Float,
            items: Vec::new(),
        }),
        Value::Integer(_) => out.push(Key {
            path,
            field,
            kind: Kind::Integer,
            items: Vec::new(),
        }),
        Value::Table(t) => keys(t, &path, &field, out),
        Value::Array(a) if !a.is_empty() && a.iter().all(number) => out.push(Key {
            path,
            field,
            kind: Kind::List(a.len()),
            items: a.iter().map(Value::to_string).collect(),
        }),
        Value::Array(a) => {
            for (i, v) in a.iter().enumerate() {
                value_keys(v, format!("{path}.{i}"), format!("{field}[{i}]"), out);
            }
        }
        _ => {}
    }
}

/// The values a key is given: the edges of its type; for a list, one
/// value short, one too many, and its last value at each edge of f64.
fn values(key: &Key) -> Vec<String> {
    match key.kind {
        Kind::Float => FLOATS.iter().map(|s| (*s).to_owned()).collect(),
        Kind::Integer => INTEGERS.iter().map(|s| (*s).to_owned()).collect(),
        Kind::List(n) => {
            let list = |items: &[String]| format!("[{}]", items.join(", "));
            let mut longer = key.items.clone();
            longer.push(key.items[n - 1].clone());
            let mut out = vec![list(&key.items[..n - 1]), list(&longer)];
            for edge in FLOATS {
                let mut items = key.items.clone();
                items[n - 1] = edge.to_owned();
                out.push(list(&items));
            }
            out
        }
    }
}

/// Sets the dotted `path` of `table` to `value` (a TOML value's text).
fn set(table: &mut Table, path: &str, value: &str) -> Result<(), String> {
    drape_io::scene::set_path(table, path, value)
}

/// Runs `case` in `dir`: the scene written there, the value in it or
/// through `--set`; `None` if it went as it must, else what happened.
fn check(dir: &Path, bases: &[(String, Table)], case: &Case) -> Option<String> {
    let (_, base) = &bases[case.base];
    let mut table = base.clone();
    let mut run = Run {
        step_budget: Some(STEP_BUDGET),
        limit: LIMIT,
        ..Run::scene(String::new())
    };
    if case.set {
        run.sets = vec![(case.key.path.clone(), case.value.clone())];
    } else {
        // The value as a user types it, even one TOML cannot hold (past
        // i64): a placeholder written out, then replaced by the text.
        if let Err(e) = set(&mut table, &case.key.path, "\"@EDGE@\"") {
            return Some(format!("could not place the value: {e}"));
        }
    }
    run.text = match toml::to_string(&table) {
        Ok(text) => text.replacen("\"@EDGE@\"", &case.value, 1),
        Err(e) => return Some(format!("could not write the scene: {e}")),
    };
    let outcome = execute(dir, run);
    match &outcome {
        Outcome::Refused(reason) => {
            // The key in the form errors use; for a tool's key, the tool
            // (its path or its name: where it starts, how far a force
            // moves it, are the tool's, from several of its keys).
            let (parent, leaf) = case
                .key
                .field
                .rsplit_once('.')
                .unwrap_or(("", &case.key.field));
            let named = reason.contains(&case.key.field)
                || (case.set && reason.contains(&format!("--set {}", case.key.path)))
                // The table, and the key among the keys it names
                // (`springs[1]: … give an anchor_offset`).
                || (!parent.is_empty()
                    && reason.contains(&format!("{parent}: "))
                    && reason.contains(leaf))
                || tool_of(base, &case.key.field).is_some_and(|(path, name)| {
                    reason.contains(&path) || reason.contains(&format!("`{name}`"))
                });
            (!named).then(|| format!("refused without naming the key: {}", outcome.describe()))
        }
        _ if outcome.passes(Expect::Robust) => None,
        _ => Some(outcome.describe()),
    }
}

/// For a key of a tool (`tools[2].motion.mass`), the tool's path
/// (`tools[2]`) and name.
fn tool_of(table: &Table, field: &str) -> Option<(String, String)> {
    let rest = field.strip_prefix("tools[")?;
    let index: usize = rest.split(']').next()?.parse().ok()?;
    let name = table
        .get("tools")?
        .as_array()?
        .get(index)?
        .get("name")?
        .as_str()?;
    Some((format!("tools[{index}]"), name.to_owned()))
}

/// The row: every case (or, quick, `sample` of them drawn by the seed).
pub fn edge_values(ctx: &Context, sample: Option<usize>) -> Row {
    let started = Instant::now();
    let mut bases = Vec::new();
    for (name, extra) in BASES {
        match base_table(&ctx.root, name, extra) {
            Ok(table) => bases.push((name.to_owned(), table)),
            Err(e) => return super::broken(ctx, Expect::Robust, e),
        }
    }
    let mut cases = Vec::new();
    for (b, (_, table)) in bases.iter().enumerate() {
        let mut found = Vec::new();
        keys(table, "", "", &mut found);
        for key in found {
            for value in values(&key) {
                for set in [false, true] {
                    cases.push(Case {
                        base: b,
                        key: key.clone(),
                        value: value.clone(),
                        set,
                    });
                }
            }
        }
    }
    let total = cases.len();
    if let Some(n) = sample {
        let mut rng = Rng::new(ctx.seed.wrapping_mul(0x9e37_79b9).wrapping_add(29));
        // A partial Fisher–Yates shuffle: the first n of a random order.
        for i in 0..n.min(total) {
            let j = i + (rng.next_u64() % (total - i) as u64) as usize;
            cases.swap(i, j);
        }
        cases.truncate(n);
    }
    let mut findings = Vec::new();
    for (k, case) in cases.iter().enumerate() {
        let dir = ctx.dir.join(format!("case-{k:04}"));
        if let Some(what) = check(&dir, &bases, case) {
            findings.push(format!(
                "{} {}{}={} : {what}",
                bases[case.base].0,
                if case.set { "--set " } else { "file " },
                case.key.path,
                case.value
            ));
        } else {
            // Passing cases leave nothing behind: only findings are read.
            let _ = std::fs::remove_dir_all(&dir);
        }
    }
    let _ = std::fs::create_dir_all(&ctx.dir);
    let _ = std::fs::write(ctx.dir.join("findings.txt"), findings.join("\n") + "\n");
    let mut happened = format!(
        "{} of {total} key=value cases (seed {}), {} not as they must be",
        cases.len(),
        ctx.seed,
        findings.len()
    );
    if !findings.is_empty() {
        let _ = write!(
            happened,
            ": {} (all in {})",
            findings[..findings.len().min(3)].join("; "),
            ctx.dir.join("findings.txt").display()
        );
    }
    Row {
        case: ctx.name.to_owned(),
        expect: Expect::Robust,
        happened,
        pass: findings.is_empty(),
        seconds: started.elapsed().as_secs_f64(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tools_key_knows_its_tool() {
        let table: Table =
            toml::from_str("[[tools]]\nname = \"a\"\n[[tools]]\nname = \"b\"").unwrap();
        assert_eq!(
            tool_of(&table, "tools[1].motion.mass"),
            Some(("tools[1]".into(), "b".into()))
        );
        assert_eq!(tool_of(&table, "gravity"), None);
    }

    #[test]
    fn keys_are_found_with_their_forms() {
        let table: Table =
            toml::from_str("g = [0, 0, -1]\n[[t]]\nf = 0.1\nn = 3\np = [[0, 1], [2, 3]]").unwrap();
        let mut found = Vec::new();
        keys(&table, "", "", &mut found);
        let forms: Vec<(&str, &str, Kind)> = found
            .iter()
            .map(|k| (k.path.as_str(), k.field.as_str(), k.kind))
            .collect();
        assert_eq!(
            forms,
            [
                ("g", "g", Kind::List(3)),
                ("t.0.f", "t[0].f", Kind::Float),
                ("t.0.n", "t[0].n", Kind::Integer),
                ("t.0.p.0", "t[0].p[0]", Kind::List(2)),
                ("t.0.p.1", "t[0].p[1]", Kind::List(2)),
            ]
        );
    }

    #[test]
    fn lists_get_wrong_lengths_and_edge_components() {
        let key = Key {
            path: "g".into(),
            field: "g".into(),
            kind: Kind::List(3),
            items: vec!["0".into(), "2".into(), "-9810".into()],
        };
        let v = values(&key);
        assert_eq!(v[0], "[0, 2]");
        assert_eq!(v[1], "[0, 2, -9810, -9810]");
        assert!(v.contains(&"[0, 2, nan]".to_owned()));
        assert_eq!(v.len(), 2 + FLOATS.len());
    }
}
