//! Resource limits from estimates: before an explicit run starts, the
//! steps it will take and the masses it will integrate with, refused as
//! bad input (naming the key that decides them) when the run would take no
//! step at all, would not finish in any sensible time, or would integrate
//! with masses that are not numbers. After a run, the one completion
//! check: "completed" only where the work the summary claims was done. And
//! a resumed run that fails before its first step: an error of its own,
//! not a summary over the stopped run's.
//!
//! Not here: the scene's own value checks (drape-io), the stable step and
//! the mass scaling themselves (drape-time's explicit driver), the
//! implicit solver's increments.

use drape_io::results::ResultsError;
use drape_io::scene::Scene;
use drape_model::State;
use drape_time::{Energies, Explicit};

/// The most node·steps (nodes × steps) a run may need: 10¹⁵. The fastest
/// explicit step measured (README, 100 × 100 blank with trusses, 2 threads)
/// does 8.6 M node·steps/s, so this is 3.7 years there, and still two weeks
/// on a machine a hundred times as fast: a run past it would not finish.
pub const MAX_NODE_STEPS: f64 = 1e15;

/// The most steps a run may need whatever its size: 10¹⁰. A step has a
/// fixed cost of some microseconds (the frame, guard and progress
/// bookkeeping, waking the threads), so even a four-node model needs hours.
pub const MAX_STEPS: f64 = 1e10;

/// The fastest explicit rate measured (node·steps per second, README's
/// step table: 100 × 100 blank with trusses on 2 threads), for the time a
/// refused run would take.
const MEASURED_NODE_STEPS_PER_S: f64 = 8.56e6;

/// The scene key that decides a run's step and what it is set to, for
/// messages.
fn step_key(scene: &Scene) -> String {
    let sim = &scene.spec.simulation;
    match (sim.time_step, sim.mass_scaling_dt) {
        (Some(dt), _) => format!("simulation.time_step = {} s", num(dt)),
        (None, Some(dt)) => format!(
            "simulation.mass_scaling_dt = {} s (with simulation.safety_factor = {})",
            num(dt),
            num(sim.safety_factor)
        ),
        (None, None) => format!(
            "the material's stable step times simulation.safety_factor = {}",
            num(sim.safety_factor)
        ),
    }
}

/// A scene value as a user writes it: plain where that is short,
/// with an exponent otherwise (1e-300, not three hundred zeros).
fn num(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-4..1e6).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// A duration in the largest unit that keeps it above 1.
fn duration(seconds: f64) -> String {
    const YEAR: f64 = 365.25 * 86_400.0;
    if seconds >= YEAR {
        format!("{:.1e} years", seconds / YEAR)
    } else if seconds >= 86_400.0 {
        format!("{:.1} days", seconds / 86_400.0)
    } else if seconds >= 3600.0 {
        format!("{:.1} hours", seconds / 3600.0)
    } else {
        format!("{seconds:.0} s")
    }
}

/// Checks an explicit run of `scene` by `driver` (built from its settings)
/// before it starts: masses that are numbers, at least one step, and at
/// most [`MAX_STEPS`] steps and [`MAX_NODE_STEPS`] node·steps. The error
/// names the key and gives the estimate.
pub fn check_explicit(scene: &Scene, driver: &Explicit<'_>) -> Result<(), String> {
    let model = &scene.model;
    let sim = &scene.spec.simulation;
    let end = scene.settings.end_time;
    let mass: f64 = model.mass.iter().sum();
    let scaled: f64 = driver.mass().iter().sum();
    if !scaled.is_finite() || driver.mass().iter().any(|m| !(m.is_finite() && *m > 0.0)) {
        return Err(format!(
            "simulation.mass_scaling_dt = {} s at simulation.safety_factor = {}: mass scaling \
             would make the blank's mass {scaled:e} t (it is {mass:.4e} t): not a number a run \
             can integrate with. Lower mass_scaling_dt, or raise safety_factor",
            sim.mass_scaling_dt.map_or_else(|| "none".to_owned(), num),
            num(sim.safety_factor)
        ));
    }
    let dt = driver.stable_time_step(&model.x0);
    let steps = end / dt;
    if !(dt > 0.0 && dt.is_finite() && steps >= 1.0) {
        return Err(format!(
            "{}: a step of {dt:.4e} s is not shorter than simulation.end_time = {} s, so the \
             run would end after {} steps without simulating anything{}. Lower the step (or \
             lengthen end_time)",
            step_key(scene),
            num(end),
            if steps >= 1e-6 { "at most one" } else { "0" },
            if scaled > 1.001 * mass {
                format!(", with the blank {:.3e}× as heavy", scaled / mass)
            } else {
                String::new()
            }
        ));
    }
    let nodes = model.node_count() as f64;
    let node_steps = steps * nodes;
    if steps > MAX_STEPS || node_steps > MAX_NODE_STEPS {
        return Err(format!(
            "{} over simulation.end_time = {} s: an estimated {steps:.3e} steps of {dt:.3e} s \
             on {nodes} nodes ({node_steps:.3e} node·steps, about {} at the fastest rate measured, \
             {:.1} M node·steps/s), more than a run may take (at most {MAX_STEPS:e} steps and \
             {MAX_NODE_STEPS:e} node·steps). Raise the step (remove time_step, or mass-scale with \
             mass_scaling_dt) or shorten end_time",
            step_key(scene),
            num(end),
            duration(node_steps / MEASURED_NODE_STEPS_PER_S),
            MEASURED_NODE_STEPS_PER_S / 1e6
        ));
    }
    Ok(())
}

/// Bytes a frame takes at least per blank node (`frame_NNNNN.vtu`: the
/// 221-node draped test scene's is 80.9 kB, 366 B a node) and per truss
/// (`trusses_NNNNN.vtu`: 88 B a truss there). Tools' frames come on top:
/// the estimate is a lower bound, so a run it refuses would not fit.
const FRAME_BYTES_PER_NODE: f64 = 300.0;
const FRAME_BYTES_PER_TRUSS: f64 = 80.0;

/// The frames a run of `scene` writes and their bytes at least: none
/// without `output.vtu`; otherwise the initial frame and `frames` more,
/// at most one a step.
pub fn frame_bytes(scene: &Scene) -> (f64, f64) {
    if !scene.spec.output.vtu {
        return (0.0, 0.0);
    }
    let model = &scene.model;
    let steps = Explicit::new(model, scene.settings.clone())
        .map(|d| scene.settings.end_time / d.stable_time_step(&model.x0))
        .unwrap_or(f64::INFINITY);
    let frames = 1.0 + (scene.spec.simulation.frames as f64).min(steps.ceil());
    let trusses: usize = model.trusses.iter().map(|b| b.len()).sum();
    let per_frame =
        FRAME_BYTES_PER_NODE * model.node_count() as f64 + FRAME_BYTES_PER_TRUSS * trusses as f64;
    (frames, frames * per_frame)
}

/// The bytes free to an unprivileged writer on the file system of `path`
/// (or of its nearest existing ancestor: the folder may not exist yet);
/// None where that cannot be asked.
pub fn free_bytes(path: &std::path::Path) -> Option<f64> {
    // (A relative path's last ancestor is "", the current folder.)
    let existing = path
        .ancestors()
        .map(|a| {
            if a.as_os_str().is_empty() {
                std::path::Path::new(".")
            } else {
                a
            }
        })
        .find(|a| a.exists())?;
    #[cfg(unix)]
    {
        let s = rustix::fs::statvfs(existing).ok()?;
        Some(s.f_bavail as f64 * s.f_frsize as f64)
    }
    #[cfg(not(unix))]
    {
        let _ = existing;
        None
    }
}

/// Checks that the frames of `runs` (scenes writing into `out`) fit the
/// free space there, from [`frame_bytes`]'s lower bound; the error names
/// `simulation.frames` and `output.vtu`.
pub fn check_output(runs: &[&Scene], out: &std::path::Path) -> Result<(), String> {
    let (frames, bytes) = runs.iter().fold((0.0, 0.0), |(f, b), scene| {
        let (fs, bs) = frame_bytes(scene);
        (f + fs, b + bs)
    });
    let Some(free) = free_bytes(out) else {
        return Ok(());
    };
    if bytes > free {
        let first = &runs[0].spec.simulation;
        return Err(format!(
            "simulation.frames = {}: {frames:.0} frames of the blank need at least {} and {} has \
             {} free; lower simulation.frames, set output.vtu = false, or free space",
            first.frames,
            megabytes(bytes),
            out.display(),
            megabytes(free)
        ));
    }
    Ok(())
}

fn megabytes(bytes: f64) -> String {
    if bytes >= 1e9 {
        format!("{:.1} GB", bytes / 1e9)
    } else {
        format!("{:.1} MB", bytes / 1e6)
    }
}

/// The completion check of a run that ended without an error: why it is
/// not "completed" (no step taken, the end time not reached, energies that
/// are not numbers), or None when it is. `end_time` is the run's.
pub fn incomplete(state: &State, end_time: f64, energy: &Energies) -> Option<String> {
    if state.step == 0 {
        return Some(format!(
            "the run ended after 0 steps at t = {:e} s of {end_time:e} s: nothing was simulated",
            state.time
        ));
    }
    // The drivers stop within a millionth of a step of the end time, and
    // a step is never longer than the run (`check_explicit`).
    let left = end_time - state.time;
    if left.is_nan() || left > 1e-6 * end_time {
        return Some(format!(
            "the run ended at t = {:.6e} s, short of the end time {end_time:.6e} s (step {})",
            state.time, state.step
        ));
    }
    let values = [
        ("kinetic", energy.kinetic),
        ("strain", energy.strain),
        ("internal work", energy.internal_work),
        ("external work", energy.external_work),
    ];
    let bad: Vec<&str> = values
        .iter()
        .filter(|(_, v)| !v.is_finite())
        .map(|(name, _)| *name)
        .collect();
    if !bad.is_empty() {
        return Some(format!(
            "the {} energy at the end (t = {:.6e} s, step {}) is not a number",
            bad.join(", "),
            state.time,
            state.step
        ));
    }
    None
}

/// The error of a resumed run that failed before its first step
/// (`error`): the stopped run's summary and checkpoint in `out` stay as
/// they were, and it can still be resumed once the cause is fixed.
pub fn resume_refused(out: &std::path::Path, error: &drape_time::RunError) -> ResultsError {
    ResultsError {
        path: out.join("checkpoint.json"),
        source: std::io::Error::other(format!(
            "the run cannot continue from this checkpoint ({error}): the stopped run's \
             summary.json and checkpoint are kept as they were"
        )),
    }
}

/// `value` with `decimals` decimals and its unit, or "n/a" when it is
/// not a number: the console never prints NaN.
pub fn or_na(value: f64, decimals: usize, unit: &str) -> String {
    if value.is_finite() {
        format!("{value:.decimals$} {unit}")
    } else {
        "n/a".to_owned()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn free_space_is_asked_of_the_nearest_existing_folder() {
        // A relative folder that does not exist yet: the current one's disk.
        let free = free_bytes(std::path::Path::new("no-such-folder/below/it"));
        if cfg!(unix) {
            assert!(free.is_some_and(|b| b >= 0.0), "{free:?}");
        }
    }

    #[test]
    fn values_read_as_written() {
        assert_eq!(num(1e-300), "1e-300");
        assert_eq!(num(0.004), "0.004");
        assert_eq!(num(2e-5), "2e-5");
        assert_eq!(num(1e300), "1e300");
    }

    #[test]
    fn durations_read_in_their_unit() {
        assert_eq!(duration(59.0), "59 s");
        assert_eq!(duration(7200.0), "2.0 hours");
        assert_eq!(duration(3.0 * 86_400.0), "3.0 days");
        assert_eq!(duration(2.0 * 365.25 * 86_400.0), "2.0e0 years");
    }

    #[test]
    fn completion_needs_a_step_the_end_time_and_finite_energies() {
        let mut state = State {
            x: Vec::new(),
            v: Vec::new(),
            history: Vec::new(),
            time: 0.0,
            step: 0,
        };
        let energy = Energies::default();
        let why = incomplete(&state, 0.1, &energy).unwrap();
        assert!(why.contains("after 0 steps"), "{why}");
        state.step = 10;
        state.time = 0.05;
        let why = incomplete(&state, 0.1, &energy).unwrap();
        assert!(why.contains("short of the end time"), "{why}");
        state.time = 0.1 * (1.0 - 1e-9);
        assert_eq!(incomplete(&state, 0.1, &energy), None);
        let nan = Energies {
            kinetic: f64::NAN,
            ..Energies::default()
        };
        let why = incomplete(&state, 0.1, &nan).unwrap();
        assert!(why.contains("kinetic energy"), "{why}");
    }
}
