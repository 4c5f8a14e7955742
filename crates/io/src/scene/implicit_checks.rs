//! Checks of the implicit solver's settings against each other and against
//! the model, before a run: values each fine alone that cannot work
//! together (an increment below the smallest one allowed) or that would
//! let the solver accept what the run's end check refuses (a gap tolerance
//! deeper than the physical one). Each error names the key at fault and
//! the values it was compared with.
//!
//! Not here: the range of each value alone (`build` in the parent module).

use drape_model::Model;
use drape_time::ImplicitSettings;

use super::{Locator, SceneError};

/// The increments as the driver resolves them (its defaults: the first a
/// hundredth, the largest a twentieth, the smallest 1e-9 of the end time),
/// checked against each other; the gap tolerance against the run's end
/// check ([`drape_time::completion::penetration_tolerance`]); the Newton
/// tolerances as fractions.
pub(super) fn check(
    at: &Locator<'_>,
    s: &ImplicitSettings,
    model: &Model,
) -> Result<(), SceneError> {
    let end = s.end_time;
    let resolved = |set: Option<f64>, default: f64, what: &str| match set {
        Some(v) => (v, format!("{v:e} s")),
        None => (default, format!("{default:e} s (the default, {what})")),
    };
    let (min, min_text) = resolved(s.min_increment, 1e-9 * end, "1e-9 of end_time");
    for (key, set, default, what) in [
        (
            "simulation.initial_increment",
            s.initial_increment,
            end / 100.0,
            "end_time/100",
        ),
        (
            "simulation.max_increment",
            s.max_increment,
            end / 20.0,
            "end_time/20",
        ),
    ] {
        let (value, text) = resolved(set, default, what);
        if value < min {
            // Blame a key the user set: the smallest increment if given,
            // else this one.
            let blamed = if s.min_increment.is_some() {
                "simulation.min_increment"
            } else {
                key
            };
            return Err(at.error(
                blamed,
                format!(
                    "`{key}` {text} is below `simulation.min_increment` {min_text}: the run would \
                     stop at its first cutback; make `simulation.min_increment` smaller than both \
                     `simulation.initial_increment` and `simulation.max_increment`"
                ),
            ));
        }
    }
    // Fractions of the force scale and of the increment's displacement: a
    // residual as large as the largest force is no equilibrium.
    for (key, value) in [
        ("simulation.force_tolerance", s.force_tolerance),
        (
            "simulation.displacement_tolerance",
            s.displacement_tolerance,
        ),
    ] {
        if value >= 1.0 {
            return Err(at.error(
                key,
                format!(
                    "{value:e} is not allowed: it is a fraction (of the force scale or of the \
                     increment's largest displacement), expected below 1 (default 1e-6)"
                ),
            ));
        }
    }
    let physical = drape_time::completion::penetration_tolerance(model);
    if !model.tools.is_empty() && s.gap_tolerance > physical {
        return Err(at.error(
            "simulation.gap_tolerance",
            format!(
                "{:e} mm is not allowed: Newton would accept nodes that deep inside a tool, and a run \
                 ends as failed with any node deeper than {physical:.3e} mm (the lesser of a tenth of \
                 the fabric's thickness, {:e} mm, and a hundredth of the shortest element edge); \
                 expected at most that (default 1e-9)",
                s.gap_tolerance,
                2.0 * model.contact_offset
            ),
        ));
    }
    Ok(())
}
