//! The stress row of the step settings at the edges of f64 (issue 29):
//! `time_step`, `mass_scaling_dt`, `safety_factor` and `end_time` set,
//! one or two at a time, to values from the smallest subnormal to the
//! largest f64. Each run must be refused naming a key it sets, or
//! run with the masses and the steps it claims: a completed run took steps
//! and reached its end time with numbers in its outputs, a run stopped at
//! the step budget would have finished (its step estimate within
//! `drape::limits`). What it caught: runs "completed" after 0 steps with
//! NaN energies, a 1e-300 s step announcing 2⁶⁴ − 1 steps and running for
//! ever, mass scaling computed from a forced step.

use std::time::{Duration, Instant};

use super::{Context, Expect, Outcome, Row, Run, execute};

/// Steps a run may take before it is stopped: enough to see it move.
const STEP_BUDGET: u64 = 300;

/// The values tried, smallest subnormal to the largest f64.
const EDGES: [f64; 9] = [
    5e-324,
    1e-300,
    1e-12,
    1e-6,
    1e-3,
    0.5,
    1e10,
    1e300,
    f64::MAX,
];

/// A 20 × 10 mm strip of two quads, pulled 0.1 mm, with `set` lines in
/// its `[simulation]` table.
fn strip(set: &[(&str, f64)]) -> String {
    let mut simulation = String::new();
    let mut end = 1e-3;
    for (key, value) in set {
        if *key == "end_time" {
            end = *value;
        } else {
            simulation.push_str(&format!("{key} = {value:e}\n"));
        }
    }
    format!(
        r#"[simulation]
end_time = {end:e}
frames = 2
{simulation}
[fabric]
material = "glass-serge-4x3"
fibres = "trusses"
blank = {{ width = 20, height = 10, cells = [2, 1] }}

[[boundary]]
nodes = "left"
motion = {{ kind = "fixed" }}

[[boundary]]
nodes = "right"
motion = {{ kind = "displacement", value = [0.1, 0, 0], amplitude = {{ kind = "smooth_step", duration = 1e-3 }} }}

[output]
vtu = false
pictures = false
"#
    )
}

/// What is wrong with `outcome` of a run of `end` s with the keys `set`,
/// or None.
fn judge(outcome: &Outcome, end: f64, set: &[(&str, f64)]) -> Option<String> {
    if !outcome.passes(Expect::Robust) {
        return Some(outcome.describe());
    }
    match outcome {
        Outcome::Refused(reason) if !set.iter().any(|(key, _)| reason.contains(key)) => {
            Some(format!("refused without naming the key: {reason}"))
        }
        Outcome::Ran { summary, .. } => {
            let estimate = summary.setup.as_ref().map_or(0, |s| s.expected_steps);
            match summary.status.as_str() {
                "completed" if summary.run.steps == 0 || summary.time < end * (1.0 - 1e-6) => {
                    Some(format!(
                        "completed after {} steps at t = {:e} s of {end:e} s",
                        summary.run.steps, summary.time
                    ))
                }
                "stopped" if estimate as f64 > drape::limits::MAX_STEPS => {
                    Some(format!("not refused although it needs {estimate} steps"))
                }
                _ => None,
            }
        }
        _ => None,
    }
}

/// The row: every key alone at every edge value, and the forced step
/// below the mass-scaling target.
pub fn step_edges(ctx: &Context) -> Row {
    let started = Instant::now();
    let mut cases: Vec<Vec<(&str, f64)>> = Vec::new();
    for key in ["time_step", "mass_scaling_dt", "safety_factor", "end_time"] {
        for v in EDGES {
            cases.push(vec![(key, v)]);
        }
    }
    for v in EDGES {
        cases.push(vec![("mass_scaling_dt", 2e-6), ("time_step", v)]);
        cases.push(vec![("mass_scaling_dt", 2e-6), ("safety_factor", v)]);
    }
    let (mut refused, mut ran) = (0, 0);
    let mut bad = Vec::new();
    for (k, set) in cases.iter().enumerate() {
        let end = set
            .iter()
            .find(|(key, _)| *key == "end_time")
            .map_or(1e-3, |(_, v)| *v);
        let outcome = execute(
            &ctx.dir.join(format!("case-{k:02}")),
            Run {
                step_budget: Some(STEP_BUDGET),
                limit: Duration::from_secs(60),
                ..Run::scene(strip(set))
            },
        );
        match &outcome {
            Outcome::Refused(_) => refused += 1,
            _ => ran += 1,
        }
        if let Some(why) = judge(&outcome, end, set) {
            let set: Vec<String> = set.iter().map(|(k, v)| format!("{k}={v:e}")).collect();
            bad.push(format!("{}: {why}", set.join(" ")));
        }
    }
    let mut happened = format!(
        "{} settings: {refused} refused naming the key, {ran} ran as they claim",
        cases.len()
    );
    if !bad.is_empty() {
        happened = format!(
            "{} settings, {} WRONG: {}",
            cases.len(),
            bad.len(),
            bad[..bad.len().min(3)].join("; ")
        );
    }
    Row {
        case: ctx.name.to_owned(),
        expect: Expect::Robust,
        happened,
        pass: bad.is_empty(),
        seconds: started.elapsed().as_secs_f64(),
    }
}
