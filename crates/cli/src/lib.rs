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

pub mod bias_sim;
mod compare;
pub mod eta;
pub mod fit;
pub mod fit_bias;
pub mod fit_inverse;
mod kinematic;
pub mod limits;
pub mod lm;
pub mod memory;
mod orientations;
pub mod reserve;
mod setup;
pub mod sweep_check;
pub use compare::{CompareError, MeasureRow, RunComparison, RunComparisonSummary, compare_runs};
pub use kinematic::{
    Comparison, ComparisonReport, ComparisonSummary, KinematicError, KinematicReport,
    ProfileDifference, compare, compare_scene, kinematic_scene,
};
pub use orientations::{MappedReport, MeshUnits, map_orientations};
pub use setup::run_setup;

use drape_io::results::{
    CutbackRow, DrawInMm, EnergyRow, EnergySummary, FrameData, ImplicitRunInfo, Peaks, ResultsDir,
    ResultsError, RunInfo, Summary, ToolForceRow, ToolMeshes, ToolSummary, max_yarn_tension,
};
use drape_io::scene::{Device, Scene, SceneFile, Solver};
use drape_model::{Measures, State};
use drape_time::{
    Control, CutbackReport, DriverState, Energies, Explicit, Frame, Implicit, Observer, Progress,
    RunError, RunSummary,
};
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
///
/// It carries the scene as it ran (every value after `--set`, the files it
/// reads as absolute paths, see [`Scene::resolved_spec`]), not a path to
/// the scene file: a run resumes from any directory, and always with the
/// scene it started with, whatever became of the file since. The files
/// the scene reads beside itself (meshes) are fingerprinted: a resume
/// refuses to continue with a changed one.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Checkpoint {
    /// The scene file the run started from, for messages.
    pub scene_file: PathBuf,
    /// The `--set` overrides it started with (their values are in `scene`).
    pub overrides: Vec<(String, String)>,
    /// The scene as it runs.
    pub scene: SceneFile,
    /// The files the scene reads, as they were when the run started.
    pub inputs: Vec<InputFile>,
    /// Steps between checkpoints, kept by a resumed run.
    #[serde(default)]
    pub checkpoint_every: Option<u64>,
    /// The state, each membrane batch's history element after element
    /// ([`drape_model::Model::history_to_element_major`]): the order every
    /// drape has written, whatever order its kernels keep the history in.
    pub state: State,
    /// The driver's carried state.
    pub driver: DriverState,
    /// The energy history so far.
    pub rows: Vec<EnergyRow>,
    /// The implicit attempts cut back so far (`cutbacks.csv`).
    #[serde(default)]
    pub cutbacks: Vec<CutbackRow>,
    /// The tools at the frames so far (`tool_forces.csv`).
    #[serde(default)]
    pub tool_rows: Vec<ToolForceRow>,
    /// The frames written so far: (index, time).
    pub frames: Vec<(usize, f64)>,
    /// The peaks over the frames so far.
    #[serde(default)]
    pub peaks: Peaks,
}

/// A file a scene reads (a mesh), with its size and a fingerprint of its
/// bytes.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct InputFile {
    /// The file (absolute).
    pub path: PathBuf,
    /// Its size in bytes.
    pub bytes: u64,
    /// FNV-1a of its bytes (a change detector, not a security measure).
    pub fingerprint: u64,
}

impl InputFile {
    /// Reads and fingerprints `path`.
    pub fn of(path: &Path) -> std::io::Result<Self> {
        let bytes = std::fs::read(path)?;
        Ok(Self {
            path: path.to_owned(),
            bytes: bytes.len() as u64,
            fingerprint: fnv1a(&bytes),
        })
    }
}

/// 64-bit FNV-1a: stable across Rust releases and platforms (std's
/// `DefaultHasher` promises neither), a few lines rather than a dependency.
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// What a checkpoint records of the run's scene: written into each one.
#[derive(Debug, Clone)]
struct SceneRecord {
    scene_file: PathBuf,
    overrides: Vec<(String, String)>,
    scene: SceneFile,
    inputs: Vec<InputFile>,
    checkpoint_every: Option<u64>,
}

impl Checkpoint {
    /// The checkpoint file of an output directory.
    pub fn path(out: &Path) -> PathBuf {
        out.join("checkpoint.json")
    }

    /// Reads the checkpoint of the output directory `out`.
    pub fn read(out: &Path) -> Result<Self, String> {
        let path = Self::path(out);
        let text = std::fs::read_to_string(&path).map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                format!(
                    "{}: no checkpoint to resume from (a run writes one with \
                     --checkpoint-every N)",
                    path.display()
                )
            } else {
                format!("{}: {e}", path.display())
            }
        })?;
        serde_json::from_str(&text).map_err(|e| {
            format!(
                "{}: not a checkpoint this drape can read ({e})",
                path.display()
            )
        })
    }

    /// The scene to continue with: the checkpoint's own copy, after
    /// checking that the files it reads are those the run started with and
    /// that the state fits its model.
    pub fn scene(&self) -> Result<Scene, String> {
        for input in &self.inputs {
            match InputFile::of(&input.path) {
                Ok(now) if now == *input => {}
                Ok(_) => {
                    return Err(format!(
                        "{} has changed since the run started: the run cannot continue with a \
                         different mesh (restore the file, or start a new run)",
                        input.path.display()
                    ));
                }
                Err(e) => {
                    return Err(format!(
                        "{}: {e}: the run needs the files it started with",
                        input.path.display()
                    ));
                }
            }
        }
        let scene = Scene::from_spec(self.scene.clone(), &self.scene_file)
            .map_err(|e| format!("the checkpoint's scene: {e}"))?;
        if self.state.x.len() != scene.model.node_count() {
            return Err(format!(
                "the checkpoint's state has {} nodes, its scene's model {}: a damaged checkpoint",
                self.state.x.len(),
                scene.model.node_count()
            ));
        }
        if !scene.model.history_fits(&self.state.history) {
            return Err(
                "the checkpoint's element history does not fit its scene's model: a damaged \
                 checkpoint"
                    .to_owned(),
            );
        }
        Ok(scene)
    }

    /// Continues the run on `device` (`drape run --resume DIR --device
    /// D`): the scene's `simulation.device`, kept among the overrides too,
    /// so that the scene file still reads as the run's scene. Both drivers
    /// carry the same [`DriverState`]: a run resumed on the other device
    /// goes on from the same state (its last bits then differ as the two
    /// devices' math functions do).
    pub fn switch_device(&mut self, device: Device) {
        self.scene.simulation.device = device;
        self.overrides.retain(|(k, _)| k != "simulation.device");
        let name = match device {
            Device::Cpu => "cpu",
            Device::Gpu => "gpu",
        };
        self.overrides
            .push(("simulation.device".to_owned(), name.to_owned()));
    }

    /// Whether the scene file now says something else than the scene the
    /// run started with (read with the same overrides); `None` when it
    /// cannot be read or parsed any more, which also means it changed.
    pub fn scene_file_matches(&self) -> Option<bool> {
        let now = Scene::from_file(&self.scene_file, &self.overrides).ok()?;
        Some(now.resolved_spec() == self.scene)
    }
}

/// How to run beyond the scene itself.
#[derive(Debug, Clone, Default)]
pub struct RunOptions {
    /// Write a checkpoint every this many steps (a resumed run keeps its
    /// checkpoint's interval unless this is given).
    pub checkpoint_every: Option<u64>,
    /// The `--set` overrides, recorded in checkpoints.
    pub overrides: Vec<(String, String)>,
    /// Continue from this checkpoint (its output directory is `out`).
    pub resume: Option<Checkpoint>,
}

struct Recorder<'a> {
    /// The model run (its batches say how they keep their history).
    model: &'a drape_model::Model,
    results: ResultsDir,
    record: SceneRecord,
    /// The step of the last checkpoint written (or resumed from).
    last_checkpoint: Option<(u64, f64)>,
    write_frames: bool,
    rows: Vec<EnergyRow>,
    cutbacks: Vec<CutbackRow>,
    tool_rows: Vec<ToolForceRow>,
    max_shear_deg: f64,
    error: Option<ResultsError>,
    last_energy: Energies,
    callback: &'a mut dyn FnMut(&RunProgress) -> Control,
    /// The largest values over the frames.
    peaks: Peaks,
    /// The tools, tessellated once for the `tools.pvd` series.
    tools: ToolMeshes,
    /// The tools' displacements at the last frame (where a failed run's
    /// results are: the driver falls back to that frame).
    frame_tools: Vec<f64>,
    /// Which tools the blank came near (`reach`) at some frame.
    reached: ToolReach,
    /// A laminate's plies at the last frame.
    plies: Vec<drape_io::results::PlySummary>,
}

/// Which tools the blank has come near: within the contact margin plus
/// the fabric's half thickness, or in contact, at some output frame. A
/// mould the blank never nears is most often one in another unit or
/// placed elsewhere, and the run would end "completed" without a word.
#[derive(Debug, Clone)]
struct ToolReach {
    /// The distance (mm) within which a node counts as near.
    reach: f64,
    near: Vec<bool>,
}

impl ToolReach {
    /// `unknown`: every tool counts as near (a resumed run, whose frames
    /// before the checkpoint are not seen).
    fn new(tools: usize, reach: f64, unknown: bool) -> Self {
        Self {
            reach,
            near: vec![unknown; tools],
        }
    }

    /// Marks the tools some node of `x` is near, each displaced as
    /// `displacement` says (an empty list for tools at rest); `tool_of` is
    /// the contact pass's touching tool per node (none: empty).
    fn observe(
        &mut self,
        tools: &[drape_contact::Tool],
        x: &[nalgebra::Vector3<f64>],
        displacement: &[f64],
        tool_of: &[u32],
    ) {
        for (t, tool) in tools.iter().enumerate() {
            if self.near.get(t).copied().unwrap_or(true) {
                continue;
            }
            let d = displacement.get(t).copied().unwrap_or(0.0);
            self.near[t] = tool_of.iter().any(|&o| o as usize == t)
                || x.iter().any(|p| tool.project(p, d).gap <= self.reach);
        }
    }

    /// The warning for each tool no node came near.
    fn warnings(&self, tools: &[drape_contact::Tool], margin: f64) -> Vec<String> {
        tools
            .iter()
            .enumerate()
            .filter(|&(t, _)| !self.near.get(t).copied().unwrap_or(true))
            .map(|(t, tool)| {
                format!(
                    "tool `{}` (tools[{t}]) never came near the blank: at no output frame was a \
                     node within the contact margin ({} mm) of it, so it did nothing in this run; \
                     if it should have, check its place and its units (a mesh in metres needs \
                     `units = \"m\"` in [tools[{t}].geometry])",
                    tool.name, margin
                )
            })
            .collect()
    }
}

/// Each tool's displacement along its axis where `contact` left it
/// (zeros without tools).
fn tool_displacements(contact: Option<drape_contact::ContactView<'_>>) -> Vec<f64> {
    contact.map_or_else(Vec::new, |c| {
        c.tool_state.iter().map(|s| s.displacement).collect()
    })
}

impl Observer for Recorder<'_> {
    fn frame(&mut self, frame: &Frame<'_>) {
        self.rows.push(EnergyRow {
            time: frame.state.time,
            step: frame.state.step,
            energy: *frame.energy,
        });
        self.last_energy = *frame.energy;
        if let Some(c) = frame.contact {
            self.tool_rows.push(ToolForceRow {
                time: frame.state.time,
                step: frame.state.step,
                state: c.tool_state.to_vec(),
                force: c.tool_force.to_vec(),
            });
        }
        let Ok(fields) = frame.model.element_fields(frame.state) else {
            return;
        };
        self.max_shear_deg = fields
            .shear
            .iter()
            .fold(0.0f64, |m, g| m.max(g.abs()))
            .to_degrees();
        self.peaks.observe(frame.model, frame.state, &fields);
        if frame.model.plies.len() > 1 {
            self.plies = drape_io::results::PlySummary::of(
                frame.model,
                &frame.state.x,
                &fields,
                frame.contact.and_then(|c| c.plies),
            );
        }
        if self.write_frames && self.error.is_none() {
            let data = FrameData {
                model: frame.model,
                state: frame.state,
                fields: &fields,
                contact_force: frame.contact.map(|c| c.force),
                contact_status: frame.contact.map(|c| c.status),
                plies: frame.contact.and_then(|c| c.plies),
            };
            let (index, time) = (frame.index, frame.state.time);
            let moved = tool_displacements(frame.contact);
            if let Err(e) = self
                .results
                .write_frame(index, time, &data)
                .and_then(|()| self.results.write_tools(index, time, &self.tools, &moved))
            {
                self.error = Some(e);
            }
        }
        self.frame_tools = tool_displacements(frame.contact);
        if let Some(c) = frame.contact {
            self.reached
                .observe(c.tools, &frame.state.x, &self.frame_tools, c.tool_of);
        }
    }

    fn checkpoint(&mut self, state: &State, driver: &DriverState) {
        if self.error.is_some() {
            return;
        }
        let r = &self.record;
        let checkpoint = Checkpoint {
            scene_file: r.scene_file.clone(),
            overrides: r.overrides.clone(),
            scene: r.scene.clone(),
            inputs: r.inputs.clone(),
            checkpoint_every: r.checkpoint_every,
            state: State {
                history: self.model.history_to_element_major(&state.history),
                x: state.x.clone(),
                v: state.v.clone(),
                ..*state
            },
            driver: driver.clone(),
            rows: self.rows.clone(),
            cutbacks: self.cutbacks.clone(),
            tool_rows: self.tool_rows.clone(),
            frames: self.results.frames(),
            peaks: self.peaks,
        };
        let path = Checkpoint::path(self.results.path());
        let written = serde_json::to_vec(&checkpoint)
            .map_err(std::io::Error::other)
            .and_then(|bytes| drape_io::atomic::write(&path, &bytes));
        match written {
            Ok(()) => self.last_checkpoint = Some((state.step, state.time)),
            Err(source) => self.error = Some(ResultsError { path, source }),
        }
    }

    fn cutback(&mut self, c: &CutbackReport<'_>) {
        self.cutbacks.push(CutbackRow {
            step: c.step,
            time: c.time,
            increment: c.increment,
            reason: c.reason.to_owned(),
            message: c.message.to_owned(),
        });
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
    if scene.spec.simulation.device == Device::Gpu {
        check_gpu(scene)?;
    }
    let checked = match scene.spec.simulation.solver {
        Solver::Explicit => Explicit::new(&scene.model, scene.settings.clone()).and_then(|d| {
            limits::check_explicit(scene, &d).map_err(drape_time::RunError::Setup)?;
            Ok(d.warnings().to_vec())
        }),
        Solver::Implicit => {
            Implicit::new(&scene.model, scene.implicit.clone()).map(|d| d.warnings().to_vec())
        }
    };
    match checked {
        Ok(warnings) => Ok(warnings),
        Err(drape_time::RunError::Setup(reason)) => Err(reason),
        Err(e) => Err(e.to_string()),
    }
}

/// Whether `scene` can run on this machine's GPU: the explicit driver, only
/// what the GPU step does, a GPU and NVRTC to compile its kernels.
fn check_gpu(scene: &Scene) -> Result<(), String> {
    if scene.spec.simulation.solver == Solver::Implicit {
        return Err(
            "simulation.device = \"gpu\" steps the explicit driver; this scene's solver is \
             implicit"
                .into(),
        );
    }
    let missing = drape_gpu::unsupported(&scene.model);
    if !missing.is_empty() {
        return Err(format!(
            "simulation.device = \"gpu\": the GPU step does not do {} yet; run the scene on \
             the CPU (without --device gpu)",
            missing.join(", ")
        ));
    }
    drape_gpu::probe()
        .map(|_| ())
        .map_err(|e| format!("simulation.device = \"gpu\": {e}"))
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
    let results = open_output(out, options.resume.as_ref())?;
    run_in(scene, results, options, progress)
}

/// Claims the output directory `out` for a run (see [`ResultsDir`]): locks
/// it (another run writing there is an error of kind `ResourceBusy`),
/// clears what a killed run left, and then, for a new run, removes the
/// results and checkpoint of an earlier one, or, to continue from
/// `resume`, keeps the frames it lists. Nothing is run: a caller can tell
/// an unusable folder from a failed run.
pub fn open_output(out: &Path, resume: Option<&Checkpoint>) -> Result<ResultsDir, ResultsError> {
    match resume {
        Some(c) => ResultsDir::reopen(out, &c.frames),
        None => {
            let results = ResultsDir::create(out)?;
            remove_checkpoint(out)?;
            Ok(results)
        }
    }
}

/// Removes the checkpoint of `out`, if any.
fn remove_checkpoint(out: &Path) -> Result<(), ResultsError> {
    let path = Checkpoint::path(out);
    match std::fs::remove_file(&path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(ResultsError { path, source: e }),
        _ => Ok(()),
    }
}

/// [`run_scene_with`] into an output directory already claimed by
/// [`open_output`] (with the same `options.resume`).
///
/// A run that completes removes its checkpoint (there is nothing left to
/// resume); one that stops early (on request) writes a last frame of where
/// it stopped, and its summary says `stopped` and from which checkpoint it
/// can continue.
pub fn run_in(
    scene: &Scene,
    results: ResultsDir,
    options: RunOptions,
    progress: &mut dyn FnMut(&RunProgress) -> Control,
) -> Result<RunReport, FacadeError> {
    let model = &scene.model;
    let mut results = results;
    // The summary's room, before anything else is written.
    let reserve = reserve::SummaryReserve::claim(results.path())?;
    results.set_shear_range(scene.spec.output.shear_range_deg);
    let peaks = options
        .resume
        .as_ref()
        .map_or_else(Peaks::default, |c| c.peaks);
    let (record, mut state, rows, cutbacks, tool_rows, driver, last_checkpoint) =
        match options.resume {
            Some(c) => (
                SceneRecord {
                    scene_file: c.scene_file,
                    overrides: c.overrides,
                    scene: c.scene,
                    inputs: c.inputs,
                    checkpoint_every: options.checkpoint_every.or(c.checkpoint_every),
                },
                // (A history that does not fit is left for the driver's state
                // check to report.)
                State {
                    history: model
                        .history_from_element_major(&c.state.history)
                        .unwrap_or(c.state.history),
                    ..c.state
                },
                c.rows,
                c.cutbacks,
                c.tool_rows,
                Some(c.driver),
                None,
            ),
            None => {
                let mut inputs = Vec::new();
                for path in scene.input_files() {
                    let input = InputFile::of(&path).map_err(|source| ResultsError {
                        path: path.clone(),
                        source,
                    })?;
                    inputs.push(input);
                }
                (
                    SceneRecord {
                        // Absolute: a resume may start from anywhere.
                        scene_file: std::path::absolute(&scene.file).unwrap_or(scene.file.clone()),
                        overrides: options.overrides,
                        scene: scene.resolved_spec(),
                        inputs,
                        checkpoint_every: options.checkpoint_every,
                    },
                    model.initial_state(),
                    Vec::new(),
                    Vec::new(),
                    Vec::new(),
                    None,
                    None,
                )
            }
        };
    let last_checkpoint =
        last_checkpoint.or_else(|| driver.as_ref().map(|_| (state.step, state.time)));
    // Where a resumed run picks up: one that fails before its first step
    // leaves the stopped run's summary as it was.
    let resumed_at = driver.as_ref().map(|_| state.step);
    let mut settings = scene.settings.clone();
    settings.checkpoint_every = record.checkpoint_every;
    let mut recorder = Recorder {
        model,
        results,
        record,
        last_checkpoint,
        write_frames: scene.spec.output.vtu,
        rows,
        cutbacks,
        tool_rows,
        max_shear_deg: 0.0,
        error: None,
        last_energy: Energies::default(),
        callback: progress,
        peaks,
        tools: ToolMeshes::new(&model.tools, &model.x0),
        frame_tools: Vec::new(),
        reached: ToolReach::new(
            model.tools.len(),
            scene.spec.simulation.contact_margin + model.contact_offset,
            // What came near before a checkpoint is not kept: a resumed
            // run makes no claim about it.
            driver.is_some(),
        ),
        plies: Vec::new(),
    };
    let started = std::time::Instant::now();
    let solver = scene.spec.simulation.solver;
    // Where the tools are at the end, for the oblique picture.
    let mut end_tools = Vec::new();
    // The implicit driver's totals, a failed run's included.
    let mut implicit_totals = None;
    // The GPU the steps ran on, if they did.
    let mut gpu_name = None;
    // The scene's own (an imported file's units, repairs) first.
    let mut warnings = scene.warnings.clone();
    let outcome: Result<RunSummary, RunError> = match solver {
        Solver::Explicit => Explicit::new(model, settings).and_then(|mut explicit| {
            if let Some(d) = driver {
                explicit.resume_from(d);
            }
            // On the GPU, the contact at the end is the GPU run's (the
            // CPU driver's stays at its start).
            let mut gpu_contact = None;
            let outcome = if scene.spec.simulation.device == Device::Gpu {
                // The CPU driver's set-up (masses, dashpots, contact
                // settings), the steps on the GPU.
                match drape_gpu::CudaStep::new(&explicit) {
                    Ok(mut engine) => {
                        gpu_name = Some(engine.device.clone());
                        drape_gpu::run(&explicit, &mut engine, &mut state, &mut recorder).map(
                            |(summary, contact)| {
                                gpu_contact = Some(contact);
                                summary
                            },
                        )
                    }
                    Err(e) => Err(drape_time::RunError::Setup(e.to_string())),
                }
            } else {
                explicit.run(&mut state, &mut recorder)
            };
            let contact = match &gpu_contact {
                Some(c) => c.view(&model.tools),
                None => explicit.contact().map(drape_contact::ExplicitContact::view),
            };
            // A failed run's state is its last frame's; the tools are there too.
            end_tools = if outcome.is_err() {
                recorder.frame_tools.clone()
            } else {
                tool_displacements(contact)
            };
            if let Ok(s) = &outcome {
                if s.stopped {
                    recorder.stop_frame(model, &state, &s.energy, contact);
                }
            }
            warnings.extend_from_slice(explicit.warnings());
            outcome
        }),
        Solver::Implicit => {
            let mut settings = scene.implicit.clone();
            settings.checkpoint_every = recorder.record.checkpoint_every;
            Implicit::new(model, settings).and_then(|mut implicit| {
                if let Some(d) = driver {
                    implicit.resume_from(d);
                }
                let outcome = implicit.run(&mut state, &mut recorder);
                end_tools = if outcome.is_err() {
                    recorder.frame_tools.clone()
                } else {
                    tool_displacements(implicit.contact())
                };
                if let Ok(s) = &outcome {
                    if s.stopped {
                        recorder.stop_frame(model, &state, &s.energy, implicit.contact());
                    }
                }
                warnings.extend_from_slice(implicit.warnings());
                implicit_totals = Some(implicit.totals());
                outcome
            })
        }
    };
    let wall_s = started.elapsed().as_secs_f64();
    // A frame or checkpoint that could not be written stopped the run: it
    // still gets a summary, which says so.
    let mut write_error = recorder.error.take();
    if let (Some(step), Err(e), None) = (resumed_at, &outcome, &write_error) {
        if e.step_and_time().is_none_or(|(s, _)| s <= step) {
            reserve.release();
            return Err(limits::resume_refused(recorder.results.path(), e));
        }
    }
    let (status, reason, energy) = match &outcome {
        Ok(s) if s.stopped => {
            let mut reason = format!(
                "stopped on request at t = {:.6e} s of {:.6e} s (step {})",
                state.time, scene.settings.end_time, state.step
            );
            match recorder.last_checkpoint {
                Some((step, time)) => reason.push_str(&format!(
                    "; it can be resumed from the checkpoint at step {step} (t = {time:.6e} s)"
                )),
                None => reason.push_str("; no checkpoint was written, so it cannot be resumed"),
            }
            ("stopped", Some(reason), s.energy)
        }
        Ok(s) => ("completed", None, s.energy),
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
            ("failed", Some(reason), recorder.last_energy)
        }
    };
    // The one completion check: "completed" only with the work done.
    let (status, reason) = match status {
        "completed" => match limits::incomplete(&state, scene.settings.end_time, &energy) {
            Some(why) => ("failed", Some(why)),
            None => (status, reason),
        },
        _ => (status, reason),
    };
    let locking = scene.spec.output.locking_angle_deg;
    let measured = model.measures(&state, locking);
    let draw_in_note = draw_in_note(model.blank.is_some(), measured.as_ref().err());
    let measures = measured.unwrap_or_default();
    let fields = model.element_fields(&state).ok();
    if let Some(f) = &fields {
        // The end state, when it was not a frame (a failed run's last good step).
        recorder.peaks.observe(model, &state, f);
    }
    // Draw-in needs a rectangular blank's edges: NaN (null in the JSON)
    // for an imported mesh, `draw_in_note` saying why.
    let draw_in = measures.draw_in.unwrap_or(drape_model::measures::DrawIn {
        dx: f64::NAN,
        dy: f64::NAN,
        dd: f64::NAN,
    });
    let setup = run_setup(scene);
    let floor = drape_time::guard::energy_floor(model);
    let internal = energy.internal_work.abs();
    // Every run's end state, a failed one's last good frame included: a
    // ply folded over itself must not read as a formed one.
    let fold = fields.as_ref().map(|f| model.fold_check(&state, f));
    warnings.extend(
        fold.as_ref()
            .and_then(|f| f.warning(model.features().bending)),
    );
    if status == "completed" {
        recorder
            .reached
            .observe(&model.tools, &state.x, &end_tools, &[]);
        warnings.extend(
            recorder
                .reached
                .warnings(&model.tools, scene.spec.simulation.contact_margin),
        );
        warnings.extend(inertia_warning(
            energy.kinetic,
            internal,
            floor,
            setup.as_ref().map_or(0.0, |s| s.added_mass_fraction),
        ));
    }
    let mut summary = Summary {
        status: status.to_owned(),
        reason,
        scene: recorder.record.scene_file.display().to_string(),
        time: state.time,
        max_shear_deg: measures.max_shear_deg,
        max_shear_at: measures.max_shear_at,
        draw_in_mm: DrawInMm {
            dx: draw_in.dx,
            dy: draw_in.dy,
            dd: draw_in.dd,
        },
        draw_in_note,
        // A truss force means nothing without trusses: null, not 0 N.
        max_fibre_tension_n: if model.features().trusses {
            measures.max_fibre_tension_n
        } else {
            f64::NAN
        },
        max_fibre_tension_n_per_mm: fields
            .as_ref()
            .and_then(|f| max_yarn_tension(model, &state.x, f))
            .map_or(f64::NAN, |(t, _)| t),
        area_above_locking_mm2: measures.area_above_locking,
        peak: recorder.peaks,
        max_waviness_deg: measures.max_waviness_deg,
        wrinkle_area_mm2: measures.wrinkle_area,
        fold,
        energy: EnergySummary {
            balance_error: drape_time::guard::relative_balance_error(&energy, floor),
            kinetic_to_internal: kinetic_share(energy.kinetic, internal, floor).unwrap_or(f64::NAN),
            kinetic_mj: Some(energy.kinetic),
            internal_mj: Some(internal),
            newton_residual_work: (solver == Solver::Implicit)
                .then(|| drape_time::guard::relative_residual_work(&energy, floor)),
        },
        setup,
        run: RunInfo {
            device: gpu_name,
            wall_s,
            // Every step from the start, a resumed run's included.
            steps: state.step,
            threads: rayon::current_num_threads(),
            solver: match solver {
                Solver::Explicit => "explicit",
                Solver::Implicit => "implicit",
            }
            .to_owned(),
            mould: None,
            mould_reason: None,
            ply: None,
            implicit: implicit_totals.map(|t: drape_time::ImplicitTotals| ImplicitRunInfo {
                newton_iterations: t.newton_iterations,
                wasted_iterations: t.wasted_iterations,
                contact_iterations: t.contact_iterations,
                contact_solver: if t.contact_solver == "active_set" {
                    drape_io::results::ContactSolverName::ActiveSet
                } else {
                    drape_io::results::ContactSolverName::Condensed
                },
                active_set_changes: t.active_set_changes,
                factorisations: t.factorisations,
                indefinite: t.indefinite,
                compression_scaled: t.compression_scaled,
                cutbacks: t.cutbacks,
                cutback_reasons: t.cutback_reasons.into(),
                factor_s: t.factor_seconds,
                assembly_s: t.assembly_seconds,
                contact_s: t.contact_seconds,
                factor_share: if wall_s > 0.0 {
                    t.factor_seconds / wall_s
                } else {
                    0.0
                },
            }),
        },
        warnings,
        plies: Vec::new(),
        tools: Vec::new(),
    };
    summary.plies = std::mem::take(&mut recorder.plies);
    let tool_names: Vec<&str> = model.tools.iter().map(|t| t.name.as_str()).collect();
    summary.tools = ToolSummary::of(&tool_names, &recorder.tool_rows);
    let results = &recorder.results;
    // Every file is tried, the first failure kept: the summary comes last
    // and says what is missing.
    let mut keep = |written: Result<(), ResultsError>| {
        if let Err(e) = written {
            write_error.get_or_insert(e);
        }
    };
    keep(results.write_energy(&recorder.rows));
    keep(results.write_tool_forces(&tool_names, &recorder.tool_rows));
    if solver == Solver::Implicit {
        keep(results.write_cutbacks(&recorder.cutbacks));
    }
    keep(results.write_profiles(&measures));
    if let Some(fields) = &fields {
        let title = format!("{} at t = {} s", summary.scene, state.time);
        keep(results.write_orientations(model, &state, fields, &title));
        if scene.spec.output.pictures {
            keep(results.write_pictures(model, &state, fields, &measures));
            keep(results.write_view(model, &state, fields, &recorder.tools, &end_tools));
        }
    }
    if let Some(e) = &write_error {
        summary.status = "failed".to_owned();
        summary.reason = Some(match summary.reason.take() {
            // What the run itself found first, then the write.
            Some(r) if status == "failed" => format!("{r}; then {}", reserve::write_failure(e)),
            _ => reserve::write_failure(e),
        });
    }
    reserve.release();
    results.write_summary(&summary)?;
    if let Some(e) = write_error {
        return Err(e);
    }
    if status == "completed" {
        remove_checkpoint(results.path())?;
    }
    Ok(RunReport {
        summary,
        measures,
        state,
    })
}

/// Kinetic over internal energy at the end of a run above which its
/// answer is said to carry inertia: the guideline of explicit forming
/// codes for a quasi-static process (the kinetic energy a few per cent of
/// the internal at most). The shipped hemisphere ends at 1.4e-3, the deep
/// drawing below 1e-3.
pub const QUASI_STATIC_KINETIC_SHARE: f64 = 0.05;

/// An internal energy within this many times the energy floor
/// ([`drape_time::guard::energy_floor`]: a microstrain of the blank) is
/// too small to divide by: the instability guard's own threshold for its
/// quasi-static check. An unstrained blank's internal energy is round-off,
/// and a kinetic energy over it reads as 10²¹ %.
pub const RATIO_FLOOR: f64 = 100.0;

/// E_kin/E_int, or None when the internal energy is within
/// [`RATIO_FLOOR`] times `floor` (or either is not a number).
pub fn kinetic_share(kinetic: f64, internal: f64, floor: f64) -> Option<f64> {
    let internal = internal.abs();
    (kinetic.is_finite() && internal.is_finite() && internal > RATIO_FLOOR * floor)
        .then(|| kinetic / internal)
}

/// Why a run's summary has no draw-in: a blank from a mesh file has no
/// rectangle's edge midpoints and corners; a rectangle's end state whose
/// elements cannot be evaluated (`failed`) has no measures at all. None
/// when the draw-in is there.
pub fn draw_in_note(rectangular: bool, failed: Option<&impl std::fmt::Display>) -> Option<String> {
    match (rectangular, failed) {
        (false, _) => Some(
            "the blank is a mesh file: draw-in is measured at a rectangular blank's edge \
             midpoints and corners"
                .to_owned(),
        ),
        (true, Some(e)) => Some(format!("the end state cannot be measured: {e}")),
        (true, None) => None,
    }
}

/// What a completed run whose blank still moves at the end must say: its
/// shapes and angles include inertia, which mass scaling (`added_mass`,
/// the added over the physical mass) or a fast tool put there. None while
/// the `kinetic` energy is within [`QUASI_STATIC_KINETIC_SHARE`] of the
/// `internal` one, that one taken as at least [`RATIO_FLOOR`] times
/// `floor` (mJ all three): over the internal energy of a barely strained
/// blank a share means nothing, and the message gives both energies
/// instead.
pub fn inertia_warning(kinetic: f64, internal: f64, floor: f64, added_mass: f64) -> Option<String> {
    let internal = internal.abs();
    let scale = internal.max(RATIO_FLOOR * floor);
    if kinetic.is_nan() || internal.is_nan() || kinetic <= QUASI_STATIC_KINETIC_SHARE * scale {
        return None;
    }
    let cause = if added_mass > 0.0 {
        format!(
            "less mass scaling (this run adds {:.0} % of the blank's mass) or a slower tool",
            100.0 * added_mass
        )
    } else {
        "a slower tool or a longer end time".to_owned()
    };
    let amount = match kinetic_share(kinetic, internal, floor) {
        Some(share) => format!(
            "{:.1} % of the internal energy (more than {:.0} %)",
            100.0 * share,
            100.0 * QUASI_STATIC_KINETIC_SHARE
        ),
        None => format!(
            "{kinetic:.3e} mJ while the blank is barely strained (internal energy \
             {internal:.3e} mJ, too small for a ratio)"
        ),
    };
    Some(format!(
        "the kinetic energy at the end is {amount}: the blank is still moving, so its shape, \
         shear and draw-in include inertia; if the process is meant to be quasi-static, run it \
         with {cause}"
    ))
}

impl Recorder<'_> {
    /// A last frame where a run stopped between frames, after the last one
    /// written, with its energy row.
    fn stop_frame(
        &mut self,
        model: &drape_model::Model,
        state: &State,
        energy: &Energies,
        contact: Option<drape_contact::ContactView<'_>>,
    ) {
        let frames = self.results.frames();
        if frames.last().is_some_and(|&(_, t)| t == state.time) {
            return;
        }
        let index = frames.last().map_or(0, |&(i, _)| i + 1);
        self.frame(&Frame {
            index,
            model,
            state,
            energy,
            reactions: &[],
            contact,
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_moving_blank_at_the_end_is_reported_with_its_cause() {
        // Internal energy 1000 mJ, far above the floor (1e-3 mJ).
        let share = |k: f64, added| inertia_warning(k * 1000.0, 1000.0, 1e-3, added);
        assert_eq!(share(1.4e-3, 38.6), None);
        assert_eq!(share(QUASI_STATIC_KINETIC_SHARE, 38.6), None);
        let w = share(8.77e-2, 496.6).unwrap();
        assert!(w.contains("8.8 % of the internal"), "{w}");
        assert!(w.contains("adds 49660 % of the blank's mass"), "{w}");
        let w = share(0.2, 0.0).unwrap();
        assert!(w.contains("a slower tool or a longer end time"), "{w}");
        // NaN energies are the balance check's business, not this one's.
        assert_eq!(inertia_warning(f64::NAN, 1000.0, 1e-3, 0.0), None);
    }

    /// The issue's case: an unstrained blank (internal energy round-off)
    /// still moving read "4641261081691772420096.0 %". Within 100 × the
    /// floor no share is printed, the energies are; and a kinetic energy
    /// small against that floor is no warning at all.
    #[test]
    fn a_barely_strained_blank_gets_energies_not_a_percentage() {
        let floor = 2e-3;
        let w = inertia_warning(12.5, 2.7e-21, floor, 0.0).unwrap();
        assert!(!w.contains('%'), "{w}");
        assert!(
            w.contains(
                "1.250e1 mJ while the blank is barely strained (internal energy 2.700e-21 mJ"
            ),
            "{w}"
        );
        // 5 % of 100 × the floor is 0.01 mJ: below it, nothing to say.
        assert_eq!(inertia_warning(0.0099, 2.7e-21, floor, 0.0), None);
        assert!(inertia_warning(0.0101, 2.7e-21, floor, 0.0).is_some());
        // Just above 100 × the floor the share is a share again.
        assert_eq!(kinetic_share(1.0, 0.2, floor), None);
        assert_eq!(kinetic_share(1.0, 0.25, floor), Some(4.0));
        let w = inertia_warning(1.0, 0.25, floor, 0.0).unwrap();
        assert!(w.contains("400.0 % of the internal energy"), "{w}");
        assert_eq!(kinetic_share(f64::NAN, 1.0, floor), None);
    }

    #[test]
    fn a_missing_draw_in_says_why() {
        let none: Option<&String> = None;
        assert_eq!(draw_in_note(true, none), None);
        assert!(draw_in_note(false, none).unwrap().contains("mesh file"));
        let e = "element 7 is inverted".to_owned();
        assert_eq!(
            draw_in_note(true, Some(&e)).unwrap(),
            "the end state cannot be measured: element 7 is inverted"
        );
    }
}
