//! # drape
//!
//! The one-call facade over drape's crates: a scene in, results and a
//! summary out. The `drape` command is built on it, and so are `xtask`,
//! the end-to-end tests and the benches, so none of them wires io and time
//! again.
//!
//! ```no_run
//! use drape::{run_scene, RunControl};
//! use drape_io::scene::Scene;
//!
//! let scene = Scene::from_file("scenes/hemisphere-0-90.toml".as_ref(), &[]).unwrap();
//! let report = run_scene(&scene, "results/hemisphere".as_ref(), &mut |_| RunControl::Continue).unwrap();
//! println!("max shear {:.1}°", report.summary.max_shear_deg);
//! ```

use std::path::Path;

use drape_io::results::{
    DrawInMm, EnergyRow, EnergySummary, FrameData, ResultsDir, ResultsError, RunInfo, Summary,
};
use drape_io::scene::Scene;
use drape_model::{Measures, State};
use drape_time::{Control, Energies, Explicit, Frame, Observer, Progress};

pub use drape_time::Control as RunControl;

/// Progress of a run as the facade reports it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunProgress {
    /// The driver's progress.
    pub progress: Progress,
    /// Largest |shear angle| at the last frame (degrees).
    pub max_shear_deg: f64,
}

/// What a finished (or failed) run leaves.
#[derive(Debug, Clone)]
pub struct RunReport {
    /// The summary written to `summary.json`.
    pub summary: Summary,
    /// The derived measures at the end.
    pub measures: Measures,
    /// The final state.
    pub state: State,
}

/// The facade's error: only writing results can fail outright; a run that
/// diverges is reported in the summary (`status = "failed"`).
pub type FacadeError = ResultsError;

struct Recorder<'a> {
    results: ResultsDir,
    write_frames: bool,
    rows: Vec<EnergyRow>,
    max_shear_deg: f64,
    error: Option<ResultsError>,
    last_energy: Energies,
    callback: &'a mut dyn FnMut(&RunProgress) -> Control,
}

impl Observer for Recorder<'_> {
    fn frame(&mut self, frame: &Frame<'_>) {
        self.rows.push(EnergyRow {
            time: frame.state.time,
            step: frame.state.step,
            energy: *frame.energy,
        });
        self.last_energy = *frame.energy;
        let Ok(fields) = frame.model.element_fields(frame.state) else {
            return;
        };
        self.max_shear_deg = fields
            .shear
            .iter()
            .fold(0.0f64, |m, g| m.max(g.abs()))
            .to_degrees();
        if self.write_frames && self.error.is_none() {
            let data = FrameData {
                model: frame.model,
                state: frame.state,
                fields: &fields,
                contact_force: frame.contact.map(|c| c.force.as_slice()),
                contact_status: frame.contact.map(|c| c.status.as_slice()),
            };
            if let Err(e) = self
                .results
                .write_frame(frame.index, frame.state.time, &data)
            {
                self.error = Some(e);
            }
        }
    }

    fn progress(&mut self, progress: &Progress) -> Control {
        if self.error.is_some() {
            return Control::Stop;
        }
        (self.callback)(&RunProgress {
            progress: *progress,
            max_shear_deg: self.max_shear_deg,
        })
    }
}

/// Runs `scene`, writing its results into `out` (created if needed), and
/// calling `progress` every few steps (return [`Control::Stop`] to stop).
///
/// A run that diverges still writes every frame it reached, the energy
/// history and a summary with `status = "failed"` and the reason.
pub fn run_scene(
    scene: &Scene,
    out: &Path,
    progress: &mut dyn FnMut(&RunProgress) -> Control,
) -> Result<RunReport, FacadeError> {
    let results = ResultsDir::create(out)?;
    let model = &scene.model;
    let mut state = model.initial_state();
    let mut recorder = Recorder {
        results,
        write_frames: scene.spec.output.vtu,
        rows: Vec::new(),
        max_shear_deg: 0.0,
        error: None,
        last_energy: Energies::default(),
        callback: progress,
    };
    let started = std::time::Instant::now();
    let outcome = Explicit::new(model, scene.settings.clone())
        .and_then(|mut driver| driver.run(&mut state, &mut recorder));
    let wall_s = started.elapsed().as_secs_f64();
    if let Some(e) = recorder.error.take() {
        return Err(e);
    }
    let (status, reason, steps, energy) = match &outcome {
        Ok(s) if s.stopped => (
            "stopped",
            Some("stopped on request".to_owned()),
            s.steps,
            s.energy,
        ),
        Ok(s) => ("completed", None, s.steps, s.energy),
        Err(e) => (
            "failed",
            Some(e.to_string()),
            state.step,
            recorder.last_energy,
        ),
    };
    let locking = scene.spec.output.locking_angle_deg;
    let measures = model.measures(&state, locking).unwrap_or_default();
    let draw_in = measures.draw_in.unwrap_or_default();
    let summary = Summary {
        status: status.to_owned(),
        reason,
        scene: scene.file.display().to_string(),
        time: state.time,
        max_shear_deg: measures.max_shear_deg,
        max_shear_at: measures.max_shear_at,
        draw_in_mm: DrawInMm {
            dx: draw_in.dx,
            dy: draw_in.dy,
            dd: draw_in.dd,
        },
        max_fibre_tension_n: measures.max_fibre_tension_n,
        area_above_locking_mm2: measures.area_above_locking,
        energy: EnergySummary {
            balance_error: energy.relative_error(),
            kinetic_to_internal: energy.kinetic_to_internal(),
        },
        run: RunInfo {
            wall_s,
            steps,
            threads: rayon::current_num_threads(),
            solver: "explicit".to_owned(),
        },
    };
    let results = &recorder.results;
    results.write_energy(&recorder.rows)?;
    results.write_profiles(&measures)?;
    if scene.spec.output.pictures {
        if let Ok(fields) = model.element_fields(&state) {
            results.write_pictures(model, &state, &fields, &measures)?;
        }
    }
    results.write_summary(&summary)?;
    Ok(RunReport {
        summary,
        measures,
        state,
    })
}
