//! What a run starts with, for the user before it runs and for its
//! summary: the model's size, the fibres, the stable and the mass-scaled
//! time step, the added mass and the steps to expect. An implicit run
//! integrates with the same (scaled) masses and its own increments: its
//! set-up has the first increment as its step.

use drape_io::results::RunSetup;
use drape_io::scene::{Scene, Solver};
use drape_time::{Explicit, ExplicitSettings};

/// The set-up of `scene`'s explicit run, or None when its driver cannot be
/// built (the run itself then reports why).
///
/// The steps are those at the reference shape: the run re-estimates its
/// step as the part deforms, so `expected_steps` is an estimate.
pub fn run_setup(scene: &Scene) -> Option<RunSetup> {
    let model = &scene.model;
    let settings = &scene.settings;
    let explicit = Explicit::new(model, settings.clone()).ok()?;
    let time_step = explicit.stable_time_step(&model.x0);
    // The physical step: a driver without mass scaling or a fixed step.
    let stable = if settings.mass_scaling.is_some() || settings.time_step.is_some() {
        Explicit::new(
            model,
            ExplicitSettings {
                mass_scaling: None,
                time_step: None,
                ..settings.clone()
            },
        )
        .ok()?
        .stable_time_step(&model.x0)
    } else {
        time_step
    };
    let mass: f64 = model.mass.iter().sum();
    let added = explicit.added_mass();
    let trusses: usize = model.trusses.iter().map(|b| b.len()).sum();
    let embedded = model.features().embedded_fibres;
    let mut setup = RunSetup {
        nodes: model.node_count(),
        membrane_elements: model.membrane_count(),
        trusses,
        fibres: if embedded { "embedded" } else { "trusses" }.to_owned(),
        stable_time_step_s: stable,
        time_step_s: time_step,
        mass_scaling_dt_s: settings.mass_scaling,
        added_mass_t: added,
        added_mass_fraction: if mass > 0.0 { added / mass } else { 0.0 },
        expected_steps: if time_step > 0.0 {
            (settings.end_time / time_step).ceil() as u64
        } else {
            0
        },
    };
    if scene.spec.simulation.solver == Solver::Implicit {
        let end = scene.implicit.end_time;
        let first = scene.implicit.initial_increment.unwrap_or(end / 100.0);
        setup.time_step_s = first;
        // The increments grow and shrink as Newton converges.
        setup.expected_steps = (end / first).ceil() as u64;
    }
    Some(setup)
}
