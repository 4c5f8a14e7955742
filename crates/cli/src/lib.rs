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

use std::path::{Path, PathBuf};

use drape_io::results::{
    DrawInMm, EnergyRow, EnergySummary, FrameData, ResultsDir, ResultsError, RunInfo, Summary,
};
use drape_io::scene::Scene;
use drape_model::{Measures, State};
use drape_time::{Control, DriverState, Energies, Explicit, Frame, Observer, Progress};
use serde::{Deserialize, Serialize};

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

/// Everything a stopped run needs to continue: written atomically to
/// `checkpoint.json` in its output directory.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The scene file.
    pub scene: PathBuf,
    /// The `--set` overrides it ran with.
    pub overrides: Vec<(String, String)>,
    /// The state.
    pub state: State,
    /// The driver's carried state.
    pub driver: DriverState,
    /// The energy history so far.
    pub rows: Vec<EnergyRow>,
    /// The frames written so far: (index, time).
    pub frames: Vec<(usize, f64)>,
}

impl Checkpoint {
    /// The checkpoint file of an output directory.
    pub fn path(out: &Path) -> PathBuf {
        out.join("checkpoint.json")
    }

    /// Reads the checkpoint of the output directory `out`.
    pub fn read(out: &Path) -> Result<Self, String> {
        let path = Self::path(out);
        let text =
            std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        serde_json::from_str(&text)
            .map_err(|e| format!("{}: not a drape checkpoint: {e}", path.display()))
    }
}

/// How to run beyond the scene itself.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Write a checkpoint every this many steps.
    pub checkpoint_every: Option<u64>,
    /// The `--set` overrides, recorded in checkpoints.
    pub overrides: Vec<(String, String)>,
    /// Continue from this checkpoint (its output directory is `out`).
    pub resume: Option<Checkpoint>,
}

struct Recorder<'a> {
    results: ResultsDir,
    scene: PathBuf,
    overrides: Vec<(String, String)>,
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

    fn checkpoint(&mut self, state: &State, driver: &DriverState) {
        if self.error.is_some() {
            return;
        }
        let checkpoint = Checkpoint {
            scene: self.scene.clone(),
            overrides: self.overrides.clone(),
            state: state.clone(),
            driver: driver.clone(),
            rows: self.rows.clone(),
            frames: self.results.frames(),
        };
        let path = Checkpoint::path(self.results.path());
        let written = serde_json::to_vec(&checkpoint)
            .map_err(std::io::Error::other)
            .and_then(|bytes| drape_io::atomic::write(&path, &bytes));
        if let Err(source) = written {
            self.error = Some(ResultsError { path, source });
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

/// Checks that `scene` can run, before anything is written: the settings,
/// a forced time step against the stable one, a blank that starts inside a
/// tool, a force-driven tool that would pass through the blank in one step
/// (see [`drape_time::guard::check_tools_at_start`]). The error is the
/// reason; the warnings are what the run will also report.
pub fn check_scene(scene: &Scene) -> Result<Vec<String>, String> {
    match Explicit::new(&scene.model, scene.settings.clone()) {
        Ok(explicit) => Ok(explicit.warnings().to_vec()),
        Err(drape_time::RunError::Setup(reason)) => Err(reason),
        Err(e) => Err(e.to_string()),
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
    run_scene_with(scene, out, RunOptions::default(), progress)
}

/// [`run_scene`] with checkpoints, or continuing from one: a resumed run
/// ends where an uninterrupted one would, bit for bit.
pub fn run_scene_with(
    scene: &Scene,
    out: &Path,
    options: RunOptions,
    progress: &mut dyn FnMut(&RunProgress) -> Control,
) -> Result<RunReport, FacadeError> {
    let model = &scene.model;
    let (results, mut state, rows, driver) = match options.resume {
        Some(c) => (
            ResultsDir::reopen(out, &c.frames)?,
            c.state,
            c.rows,
            Some(c.driver),
        ),
        None => (
            ResultsDir::create(out)?,
            model.initial_state(),
            Vec::new(),
            None,
        ),
    };
    let mut recorder = Recorder {
        results,
        scene: scene.file.clone(),
        overrides: options.overrides,
        write_frames: scene.spec.output.vtu,
        rows,
        max_shear_deg: 0.0,
        error: None,
        last_energy: Energies::default(),
        callback: progress,
    };
    let started = std::time::Instant::now();
    let mut settings = scene.settings.clone();
    settings.checkpoint_every = options.checkpoint_every;
    let mut warnings = Vec::new();
    let outcome = Explicit::new(model, settings).and_then(|mut explicit| {
        if let Some(d) = driver {
            explicit.resume_from(d);
        }
        let outcome = explicit.run(&mut state, &mut recorder);
        warnings = explicit.warnings().to_vec();
        outcome
    });
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
        Err(e) => {
            let mut reason = e.to_string();
            // The driver puts back the last output frame: say which one the
            // results are.
            if e.step_and_time().is_some() {
                reason.push_str(&format!(
                    "; the results are those of t = {:.6e} s (step {}), the last output frame",
                    state.time, state.step
                ));
            }
            ("failed", Some(reason), state.step, recorder.last_energy)
        }
    };
    let locking = scene.spec.output.locking_angle_deg;
    let measures = model.measures(&state, locking).unwrap_or_default();
    // Draw-in needs a rectangular blank's edges: NaN (null in the JSON)
    // for an imported mesh.
    let draw_in = measures.draw_in.unwrap_or(drape_model::measures::DrawIn {
        dx: f64::NAN,
        dy: f64::NAN,
        dd: f64::NAN,
    });
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
            balance_error: drape_time::guard::relative_balance_error(
                &energy,
                drape_time::guard::energy_floor(model),
            ),
            kinetic_to_internal: energy.kinetic_to_internal(),
        },
        run: RunInfo {
            wall_s,
            steps,
            threads: rayon::current_num_threads(),
            solver: "explicit".to_owned(),
        },
        warnings,
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
