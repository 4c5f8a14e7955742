//! Results of a run in an output directory.
//!
//! A [`ResultsDir`] holds the results of one run:
//!
//! | file | what | written by |
//! |---|---|---|
//! | `frames/frame_NNNNN.vtu` | VTK unstructured grid of frame `NNNNN` | [`ResultsDir::write_frame`] |
//! | `series.pvd` | VTK collection of the frames with their times (open this in ParaView) | [`ResultsDir::write_frame`] |
//! | `energy.csv` | energy history | [`ResultsDir::write_energy`] |
//! | `cutbacks.csv` | implicit runs: every increment cut back, when and why | [`ResultsDir::write_cutbacks`] |
//! | `tool_forces.csv` | each tool's displacement, velocity and force on the fabric per frame | [`ResultsDir::write_tool_forces`] |
//! | `profiles.csv` | shear along the blank's diagonal and median (a laminate: each ply's, a `ply` column first) | [`ResultsDir::write_profiles`] |
//! | `summary.json` | derived measures and run statistics ([`Summary`]) | [`ResultsDir::write_summary`] |
//! | `shear_map.png`, `waviness_map.png`, `profiles.png` | pictures | [`ResultsDir::write_pictures`] |
//! | `shear_map_<ply>.png`, `waviness_map_<ply>.png`, `profiles_<ply>.png` | a laminate's pictures per ply (the last two in place of `waviness_map.png` and `profiles.png`) | [`ResultsDir::write_pictures`] |
//! | `shear_3d.png` (a laminate: `shear_3d_<ply>.png` per ply instead) | the formed part seen obliquely, with the tools' outline | [`ResultsDir::write_view`] |
//! | `frames/trusses_NNNNN.vtu`, `trusses.pvd` | the fibre trusses as lines (models with trusses) | [`ResultsDir::write_frame`] |
//! | `frames/tools_NNNNN.vtu`, `tools.pvd` | the tools' surfaces where they are at each frame | [`ResultsDir::write_tools`] |
//! | `orientations.inp`, `orientations.csv` | draped fibre orientations for structural analysis | [`ResultsDir::write_orientations`] |
//!
//! Every file is written whole or not at all ([`crate::atomic::write`]), and
//! `series.pvd` is rewritten after each frame, so a run that fails part way
//! leaves a valid series of the frames written so far.
//!
//! A [`ResultsDir`] holds the folder's [`OutputLock`] while it lives: a
//! second run into the same folder is refused rather than mixed with the
//! first. Having the lock, it clears the hidden temporaries a killed run
//! left (`.<name>.tmp<pid>`, see [`crate::atomic`]).
//!
//! # VTU contents
//! Points are the current positions; cells are the membrane elements in
//! batch order (VTK triangles and quads), so cell `i` is entry `i` of
//! [`ElementFields`]. Point data: `displacement` (x − x₀, mm), `velocity`
//! (mm/s), `contact_force` (N), `contact_status` (0 open, 1 stick, 2 slip:
//! 1 and 2 are in contact, a node resting on a tool at zero gap included;
//! zeros without tools). Cell data: `shear_angle_deg`,
//! `fibre_stretch_warp`, `fibre_stretch_weft`, `fibre_direction_warp`,
//! `fibre_direction_weft` (unit vectors), `fibre_tension_warp`,
//! `fibre_tension_weft` (N/mm), `resin_stress` (3 components: 11, 22, 12 in
//! fibre axes, MPa), `thickness` (mm), `waviness` (degrees, the wrinkle
//! indicator of `drape_model::measures::waviness`). The encoding (inline base64 binary
//! with a `UInt64` header) and why are in the `vtk` submodule's docs.
//!
//! # Numbers in text files
//! CSV and PVD numbers are the shortest decimal text that reads back as the
//! same `f64`, in plain notation for magnitudes in [1e-5, 1e16) and in
//! exponent notation (`1.5e-7`) otherwise, so no value is rounded and no
//! small energy prints as a long run of zeros.
//!
//! ```no_run
//! use drape_io::results::{ResultsDir, Summary};
//! # fn main() -> Result<(), drape_io::results::ResultsError> {
//! let out = ResultsDir::create(std::path::Path::new("out/run1"))?;
//! out.write_summary(&Summary { status: "completed".into(), ..Summary::default() })?;
//! # Ok(()) }
//! ```

pub mod export;
mod lock;
pub mod mapping;
mod pictures;
mod profiles;

pub(crate) use pictures::boundary_edges;
pub mod read;
mod summary;
mod tool_forces;
mod tools;
mod vtk;

pub use lock::{LOCK_FILE, OutputLock};
pub use pictures::maps::MapPanel;
pub use pictures::sweep::{SweepAxis, SweepRun};
pub use pictures::work_precision::{WorkPrecisionPanel, WorkPrecisionPoint, pareto_front};
pub use summary::{Peaks, RunSetup, max_yarn_tension};
pub use tool_forces::{TOOL_FORCES_HEADER, ToolForceRow, ToolSummary, tool_forces_csv};
pub use tools::{ToolMesh, ToolMeshes};

use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use drape_contact::ContactStatus;
use drape_model::{ElementFields, Measures, Model, State};
use drape_time::Energies;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// What can go wrong while writing results.
#[derive(Debug, thiserror::Error)]
#[error("{path}: {source}")]
pub struct ResultsError {
    /// The file or directory.
    pub path: PathBuf,
    /// The cause.
    pub source: std::io::Error,
}

/// One frame of a run, borrowed from it.
pub struct FrameData<'a> {
    /// The model.
    pub model: &'a Model,
    /// The state at the frame.
    pub state: &'a State,
    /// Element output fields at the frame (membrane elements in batch order).
    pub fields: &'a ElementFields,
    /// Contact force per node (N), when the model has tools.
    pub contact_force: Option<&'a [Vector3<f64>]>,
    /// Contact status per node, when the model has tools.
    pub contact_status: Option<&'a [ContactStatus]>,
    /// The contact between the plies of a laminate (its slip and
    /// pressure are point fields), when the model is one.
    pub plies: Option<&'a drape_contact::PlyContact>,
}

/// One row of the energy history.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct EnergyRow {
    /// Time (s).
    pub time: f64,
    /// Completed steps.
    pub step: u64,
    /// The energies.
    pub energy: Energies,
}

/// One implicit attempt cut back (a row of `cutbacks.csv`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CutbackRow {
    /// The increment being attempted (completed increments + 1).
    pub step: u64,
    /// Time at its start (s).
    pub time: f64,
    /// The increment that failed (s).
    pub increment: f64,
    /// Why, as counted in the summary's `cutback_reasons`.
    pub reason: String,
    /// The driver's diagnosis of the failed attempt.
    pub message: String,
}

/// Draw-in, mm. NaN (written as `null`) where it cannot be measured; the
/// summary's `draw_in_note` says why.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct DrawInMm {
    /// DX.
    #[serde(deserialize_with = "nan_if_null")]
    pub dx: f64,
    /// DY.
    #[serde(deserialize_with = "nan_if_null")]
    pub dy: f64,
    /// DD.
    #[serde(deserialize_with = "nan_if_null")]
    pub dd: f64,
}

/// JSON has no NaN: serde_json writes it as `null`; read `null` back as NaN.
fn nan_if_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// The energy part of the summary.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct EnergySummary {
    /// |balance error| / largest energy.
    pub balance_error: f64,
    /// E_kin / E_int at the end; NaN (`null`) when the internal energy is
    /// too small for a ratio to mean anything (an unstrained blank): then
    /// `kinetic_mj` and `internal_mj` say what there is.
    #[serde(deserialize_with = "nan_if_null")]
    pub kinetic_to_internal: f64,
    /// The kinetic energy at the end (mJ, N·mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kinetic_mj: Option<f64>,
    /// The internal energy at the end (mJ, N·mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub internal_mj: Option<f64>,
    /// The implicit driver's Newton residual work over the same scale as
    /// `balance_error`, with its sign: the out-of-balance force each
    /// increment was accepted with (within the Newton tolerance) times the
    /// increment's motion, summed. The balance error is this to round-off
    /// when every force's work is accounted for. Absent for explicit runs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub newton_residual_work: Option<f64>,
}

/// Run statistics.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct RunInfo {
    /// Wall-clock seconds.
    pub wall_s: f64,
    /// Steps taken.
    pub steps: u64,
    /// Threads.
    pub threads: usize,
    /// "explicit" or "implicit".
    pub solver: String,
    /// The GPU the explicit steps ran on (absent: the CPU's threads).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub device: Option<String>,
    /// What the implicit driver did (absent for explicit runs).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub implicit: Option<ImplicitRunInfo>,
    /// The tool a kinematic drape was draped on (absent for a forming
    /// run).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub mould: Option<String>,
    /// Why that tool: named by `kinematic.mould`, or the default's rule.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub mould_reason: Option<String>,
    /// The ply of a laminate a kinematic drape is of (`kinematic.ply`;
    /// absent for one ply and for a forming run).
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub ply: Option<String>,
}

/// The implicit driver's contact solver in `summary.json`
/// (`simulation.contact_solver`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactSolverName {
    /// The condensed multiplier solve (also: a summary written before the
    /// choice existed).
    #[default]
    Condensed,
    /// The active-set saddle-point solve.
    ActiveSet,
}

impl std::fmt::Display for ContactSolverName {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            ContactSolverName::Condensed => "condensed",
            ContactSolverName::ActiveSet => "active_set",
        })
    }
}

/// The implicit driver's totals in `summary.json`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct ImplicitRunInfo {
    /// Newton iterations of the converged increments.
    pub newton_iterations: u64,
    /// Newton iterations of attempts that were cut back.
    pub wasted_iterations: u64,
    /// Solves with the factors of the contact solves (the condensed
    /// solver's products, the active-set solver's solves and refinements).
    pub contact_iterations: u64,
    /// Which contact solver.
    #[serde(default)]
    pub contact_solver: ContactSolverName,
    /// Normal contact rows that entered or left the active set.
    #[serde(default)]
    pub active_set_changes: u64,
    /// Numeric factorisations of the tangent.
    pub factorisations: u64,
    /// Of which were not positive definite (LDLᵀ).
    pub indefinite: u64,
    /// Of which had the resin's compressive stress terms scaled down
    /// because the exact tangent was indefinite.
    #[serde(default)]
    pub compression_scaled: u64,
    /// Increments cut back.
    pub cutbacks: u64,
    /// The cutbacks by why the attempt failed.
    #[serde(default)]
    pub cutback_reasons: CutbackReasonsInfo,
    /// Seconds in numeric factorisations.
    pub factor_s: f64,
    /// Seconds in tangent assembly.
    pub assembly_s: f64,
    /// Seconds in the condensed contact solves.
    pub contact_s: f64,
    /// factor_s / wall_s.
    pub factor_share: f64,
}

/// Why the implicit driver cut increments back, in `summary.json` (see
/// `drape_time::CutbackReasons`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct CutbackReasonsInfo {
    /// Newton iteration limit with friction states still changing.
    pub friction_chatter: u64,
    /// Newton iteration limit with the friction states settled.
    pub newton_limit: u64,
    /// An element's law failed (inverted element) at every step length.
    pub element_failure: u64,
    /// The residual was not finite.
    pub not_finite: u64,
    /// The tangent failed to assemble or had a zero pivot.
    pub tangent_failure: u64,
    /// The condensed contact solve met non-positive curvature.
    pub contact_indefinite: u64,
    /// The condensed contact solve ran out of iterations.
    pub contact_not_converged: u64,
    /// Newton diverged (a correction longer than the model and growing);
    /// absent from summaries written before it was counted.
    #[serde(default)]
    pub diverged: u64,
}

impl From<drape_time::CutbackReasons> for CutbackReasonsInfo {
    fn from(r: drape_time::CutbackReasons) -> Self {
        Self {
            friction_chatter: r.friction_chatter,
            newton_limit: r.newton_limit,
            element_failure: r.element_failure,
            not_finite: r.not_finite,
            tangent_failure: r.tangent_failure,
            contact_indefinite: r.contact_indefinite,
            contact_not_converged: r.contact_not_converged,
            diverged: r.diverged,
        }
    }
}

impl CutbackReasonsInfo {
    /// The non-zero counts, "name count" joined by commas (empty when none).
    pub fn describe(&self) -> String {
        [
            ("friction chatter", self.friction_chatter),
            ("Newton limit", self.newton_limit),
            ("element failure", self.element_failure),
            ("residual not finite", self.not_finite),
            ("tangent failure", self.tangent_failure),
            ("contact indefinite", self.contact_indefinite),
            ("contact not converged", self.contact_not_converged),
            ("diverged", self.diverged),
        ]
        .iter()
        .filter(|(_, n)| *n > 0)
        .map(|(name, n)| format!("{name} {n}"))
        .collect::<Vec<_>>()
        .join(", ")
    }
}

/// One ply of a laminate in `summary.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PlySummary {
    /// Its name.
    pub name: String,
    /// Largest |shear angle| of its elements (degrees).
    pub max_shear_deg: f64,
    /// Its wrinkle indicator: largest waviness (degrees)...
    pub max_waviness_deg: f64,
    /// ...and the area above the threshold (mm²).
    pub wrinkle_area_mm2: f64,
    /// Its draw-in (null for a blank from a mesh file).
    pub draw_in_mm: DrawInMm,
    /// Largest accumulated slip of its nodes on the ply below (mm; 0 for
    /// the bottom ply).
    pub max_slip_mm: f64,
    /// Largest contact pressure of the ply below on its nodes (MPa; 0 for
    /// the bottom ply).
    pub max_pressure_mpa: f64,
    /// Largest depth of a node of it or of the ply below inside the other
    /// (mm; 0 for the bottom ply), over the run's checks so far (every
    /// frame and at least 20 a run): a run stops when it passes a tenth
    /// of the thinnest ply's thickness, so what is left is the margin.
    #[serde(default)]
    pub max_overlap_mm: f64,
}

impl PlySummary {
    /// Each ply of `model` at the frame of `x`, `fields` and the ply
    /// contact `plies` (slip and pressure zero without).
    pub fn of(
        model: &Model,
        x: &[Vector3<f64>],
        fields: &ElementFields,
        plies: Option<&drape_contact::PlyContact>,
    ) -> Vec<Self> {
        model
            .ply_measures(x, fields)
            .into_iter()
            .zip(&model.plies)
            .enumerate()
            .map(|(p, (m, ply))| {
                let nodes = ply.nodes.start as usize..ply.nodes.end as usize;
                let peak = |v: &[f64]| v[nodes.clone()].iter().fold(0.0f64, |a, &b| a.max(b));
                let d = m.draw_in.unwrap_or(drape_model::measures::DrawIn {
                    dx: f64::NAN,
                    dy: f64::NAN,
                    dd: f64::NAN,
                });
                Self {
                    name: m.name,
                    max_shear_deg: m.max_shear_deg,
                    max_waviness_deg: m.max_waviness_deg,
                    wrinkle_area_mm2: m.wrinkle_area_mm2,
                    draw_in_mm: DrawInMm {
                        dx: d.dx,
                        dy: d.dy,
                        dd: d.dd,
                    },
                    max_slip_mm: plies.map_or(0.0, |p| peak(&p.slip)),
                    max_pressure_mpa: plies.map_or(0.0, |p| peak(&p.pressure)),
                    // The interface with the ply below is the one before.
                    max_overlap_mm: plies
                        .and_then(|c| c.overlap_peaks().get(p.checked_sub(1)?).copied())
                        .unwrap_or(0.0),
                }
            })
            .collect()
    }
}

/// `summary.json`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Summary {
    /// "completed", "failed" or "stopped".
    pub status: String,
    /// Why it failed or stopped.
    #[serde(skip_serializing_if = "Option::is_none", default)]
    pub reason: Option<String>,
    /// The scene file.
    pub scene: String,
    /// Simulated time reached (s).
    pub time: f64,
    /// Largest |shear angle| (degrees).
    pub max_shear_deg: f64,
    /// Where (current position of the element's centroid, mm).
    pub max_shear_at: [f64; 3],
    /// Draw-in.
    pub draw_in_mm: DrawInMm,
    /// Why a draw-in value is missing (`null`), when one is.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub draw_in_note: Option<String>,
    /// Largest truss force (N) at the end; NaN (`null`) when the fibres
    /// are embedded (there is no truss).
    #[serde(deserialize_with = "nan_if_null")]
    pub max_fibre_tension_n: f64,
    /// Largest yarn tension per unit width at the end (N/mm), for trusses
    /// and embedded fibres alike ([`max_yarn_tension`]).
    #[serde(default)]
    pub max_fibre_tension_n_per_mm: f64,
    /// Reference area above the locking angle (mm²).
    pub area_above_locking_mm2: f64,
    /// The largest values over the run's frames, and when.
    #[serde(default)]
    pub peak: Peaks,
    /// Largest element waviness (degrees): the wrinkle indicator.
    #[serde(default)]
    pub max_waviness_deg: f64,
    /// Reference area of the elements wavier than 5° (mm²).
    #[serde(default)]
    pub wrinkle_area_mm2: f64,
    /// The fold check of the end state (`drape_model::folds`); when it
    /// finds a fold, `warnings` says where and what to change. Absent for
    /// a kinematic drape, whose net reports its undraped cells instead.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fold: Option<drape_model::folds::FoldCheck>,
    /// Energy.
    pub energy: EnergySummary,
    /// What the run started with (absent for a kinematic drape).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub setup: Option<RunSetup>,
    /// Run statistics.
    pub run: RunInfo,
    /// What the scene and the run found doubtful but not wrong enough to
    /// stop it (an imported mesh's size or repairs, the driver's start-up
    /// warnings).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// Each ply of a laminate at the last frame (none for one ply).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub plies: Vec<PlySummary>,
    /// Each tool's travel and force on the fabric (`tool_forces.csv`'s
    /// means between frames); none without tools, or for a kinematic drape.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub tools: Vec<ToolSummary>,
}

/// An output directory being filled by a run.
pub struct ResultsDir {
    dir: PathBuf,
    /// Frames written so far: index → (time, file relative to `dir`).
    frames: BTreeMap<usize, (f64, String)>,
    /// The trusses' frames (`trusses.pvd`), the same way.
    truss_frames: BTreeMap<usize, (f64, String)>,
    /// The tools' frames (`tools.pvd`), the same way.
    tool_frames: BTreeMap<usize, (f64, String)>,
    /// The fixed colour range of the shear pictures (degrees of |γ|),
    /// `[output] shear_range_deg`; None: 0 to the largest.
    shear_range: Option<[f64; 2]>,
    /// The folder's lock, held while the run writes.
    _lock: OutputLock,
}

/// The files a [`ResultsDir`] writes at its top level.
const OUTPUT_FILES: [&str; 14] = [
    "series.pvd",
    "trusses.pvd",
    "tools.pvd",
    "energy.csv",
    "cutbacks.csv",
    "tool_forces.csv",
    "profiles.csv",
    "summary.json",
    "shear_map.png",
    "shear_3d.png",
    "waviness_map.png",
    "profiles.png",
    "orientations.inp",
    "orientations.csv",
];

/// The shear map of one ply of a laminate, `shear_map_<ply>.png` (a
/// ply's name holds no path separator: the scene refuses one).
pub fn ply_picture(ply: &str) -> String {
    ply_picture_of(PlyPicture::ShearMap, ply)
}

/// The pictures a laminate has one of per ply.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PlyPicture {
    /// `shear_map_<ply>.png`, beside the plies overlaid in `shear_map.png`.
    ShearMap,
    /// `shear_3d_<ply>.png`, in place of `shear_3d.png`.
    Shear3d,
    /// `waviness_map_<ply>.png`, in place of `waviness_map.png`.
    WavinessMap,
    /// `profiles_<ply>.png`, in place of `profiles.png`.
    Profiles,
}

impl PlyPicture {
    const ALL: [Self; 4] = [
        Self::ShearMap,
        Self::Shear3d,
        Self::WavinessMap,
        Self::Profiles,
    ];

    /// The one-ply file's name without `.png`.
    fn stem(self) -> &'static str {
        match self {
            Self::ShearMap => "shear_map",
            Self::Shear3d => "shear_3d",
            Self::WavinessMap => "waviness_map",
            Self::Profiles => "profiles",
        }
    }
}

/// The file of `picture` for the ply named `ply`: `<stem>_<ply>.png`.
pub fn ply_picture_of(picture: PlyPicture, ply: &str) -> String {
    format!("{}_{ply}.png", picture.stem())
}

/// Whether `name` is a ply's picture ([`ply_picture_of`]) of an earlier run.
fn is_ply_picture(name: &str) -> bool {
    PlyPicture::ALL.iter().any(|p| {
        name.strip_prefix(p.stem())
            .and_then(|rest| rest.strip_prefix('_'))
            .and_then(|rest| rest.strip_suffix(".png"))
            .is_some_and(|ply| !ply.is_empty())
    })
}

/// The plies a laminate pictures one by one: none for one ply (a stack of
/// one is pictured as `[fabric]` is, byte for byte).
fn pictured_plies(model: &Model) -> &[drape_model::stack::Ply] {
    if model.plies.len() > 1 {
        &model.plies
    } else {
        &[]
    }
}

/// The series a results folder holds: the `.pvd` file and the prefix of
/// its frame files in `frames/`.
const SERIES: [(&str, &str); 3] = [
    ("series.pvd", "frame_"),
    ("trusses.pvd", "trusses_"),
    ("tools.pvd", "tools_"),
];

/// The `energy.csv` header.
const ENERGY_HEADER: &str = "time,step,kinetic,strain,internal_work,viscous,damping,external_work,\
boundary_work,contact_work,friction_dissipation,numerical_dissipation,confinement_work,balance_error";

/// Maps an I/O error on `path` into a [`ResultsError`].
fn at(path: &Path) -> impl FnOnce(std::io::Error) -> ResultsError + '_ {
    move |source| ResultsError {
        path: path.to_owned(),
        source,
    }
}

/// `f64` as the shortest text that reads back as the same value: plain
/// notation for magnitudes in [1e-5, 1e16), exponent notation otherwise
/// (`Display` alone would print 1e-12 as fourteen digits of zeros).
pub(crate) fn fmt_f64(v: f64) -> String {
    let a = v.abs();
    if v == 0.0 || !v.is_finite() || (1e-5..1e16).contains(&a) {
        format!("{v}")
    } else {
        format!("{v:e}")
    }
}

/// The frame index of `name` when it is a frame file this module writes:
/// `frame_`, `trusses_` or `tools_`, then digits, then `.vtu`.
fn frame_index(name: &str) -> Option<usize> {
    SERIES
        .iter()
        .find_map(|(_, prefix)| name.strip_prefix(prefix))
        .and_then(|rest| rest.strip_suffix(".vtu"))
        .filter(|digits| !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()))
        .and_then(|digits| digits.parse().ok())
}

/// Whether `name` is a frame file this module writes.
fn is_frame_file(name: &str) -> bool {
    frame_index(name).is_some()
}

impl ResultsDir {
    /// Creates (or reuses) `dir` and its `frames/` folder.
    ///
    /// A directory holds the results of one run: when `dir` is reused, the
    /// files this module writes (`series.pvd`, `frames/frame_*.vtu`, the
    /// CSV, JSON and PNG files above) are removed first, so a run that
    /// fails early cannot leave a previous run's summary or frames looking
    /// like its own. Other files are left alone.
    ///
    /// The folder is locked first ([`OutputLock`]): another run writing
    /// into it is an error of kind `ResourceBusy`, and nothing is touched.
    pub fn create(dir: &Path) -> Result<Self, ResultsError> {
        let lock = claim(dir)?;
        let frames = dir.join("frames");
        for name in OUTPUT_FILES {
            remove_if_present(&dir.join(name))?;
        }
        for entry in std::fs::read_dir(dir).map_err(at(dir))? {
            let entry = entry.map_err(at(dir))?;
            if entry.file_name().to_str().is_some_and(is_ply_picture) {
                remove_if_present(&entry.path())?;
            }
        }
        for entry in std::fs::read_dir(&frames).map_err(at(&frames))? {
            let entry = entry.map_err(at(&frames))?;
            if entry.file_name().to_str().is_some_and(is_frame_file) {
                remove_if_present(&entry.path())?;
            }
        }
        Ok(Self {
            dir: dir.to_owned(),
            frames: BTreeMap::new(),
            truss_frames: BTreeMap::new(),
            tool_frames: BTreeMap::new(),
            shear_range: None,
            _lock: lock,
        })
    }

    /// Reopens the directory of a stopped run to continue it: the frames
    /// listed in `frames` (index, time: those its checkpoint had written)
    /// are kept and stay in the series, any later frame is removed.
    /// The folder is locked as by [`Self::create`].
    pub fn reopen(dir: &Path, frames: &[(usize, f64)]) -> Result<Self, ResultsError> {
        let lock = claim(dir)?;
        let folder = dir.join("frames");
        let kept: BTreeMap<usize, f64> = frames.iter().copied().collect();
        let mut series: [BTreeMap<usize, (f64, String)>; 3] = Default::default();
        for entry in std::fs::read_dir(&folder).map_err(at(&folder))? {
            let entry = entry.map_err(at(&folder))?;
            let name = entry.file_name();
            let Some((name, index)) = name.to_str().and_then(|n| Some((n, frame_index(n)?))) else {
                continue;
            };
            match kept.get(&index) {
                Some(&time) => {
                    let k = SERIES
                        .iter()
                        .position(|(_, prefix)| name.starts_with(prefix))
                        .unwrap_or(0);
                    series[k].insert(index, (time, format!("frames/{name}")));
                }
                None => remove_if_present(&entry.path())?,
            }
        }
        let [frames, truss_frames, tool_frames] = series;
        let reopened = Self {
            dir: dir.to_owned(),
            frames,
            truss_frames,
            tool_frames,
            shear_range: None,
            _lock: lock,
        };
        for (k, (pvd, _)) in SERIES.iter().enumerate() {
            let listed = reopened.series(k);
            if k == 0 || !listed.is_empty() {
                let path = dir.join(pvd);
                crate::atomic::write(&path, vtk::series_pvd(listed).as_bytes())
                    .map_err(at(&path))?;
            }
        }
        Ok(reopened)
    }

    /// The frames of series `k` of [`SERIES`].
    fn series(&self, k: usize) -> &BTreeMap<usize, (f64, String)> {
        match k {
            0 => &self.frames,
            1 => &self.truss_frames,
            _ => &self.tool_frames,
        }
    }

    /// The frames written so far: (index, time).
    pub fn frames(&self) -> Vec<(usize, f64)> {
        self.frames.iter().map(|(&i, &(t, _))| (i, t)).collect()
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.dir
    }

    /// Writes frame `index` at `time` as `frames/frame_NNNNN.vtu` and
    /// rewrites `series.pvd` to list every frame written so far.
    ///
    /// Writing an index again replaces that frame. A frame whose arrays do
    /// not match the model's node or element count is an error of kind
    /// `InvalidInput` naming the frame file (nothing is written).
    pub fn write_frame(
        &mut self,
        index: usize,
        time: f64,
        frame: &FrameData<'_>,
    ) -> Result<(), ResultsError> {
        let relative = format!("frames/frame_{index:05}.vtu");
        let path = self.dir.join(&relative);
        let xml = vtk::frame_vtu(time, frame).map_err(|mismatch| ResultsError {
            path: path.clone(),
            source: std::io::Error::new(std::io::ErrorKind::InvalidInput, mismatch.to_string()),
        })?;
        crate::atomic::write(&path, xml.as_bytes()).map_err(at(&path))?;
        if let Some(xml) = vtk::trusses_vtu(time, frame.model, &frame.state.x) {
            let relative = format!("frames/trusses_{index:05}.vtu");
            let path = self.dir.join(&relative);
            crate::atomic::write(&path, xml.as_bytes()).map_err(at(&path))?;
            self.truss_frames.insert(index, (time, relative));
            let pvd = self.dir.join("trusses.pvd");
            crate::atomic::write(&pvd, vtk::series_pvd(&self.truss_frames).as_bytes())
                .map_err(at(&pvd))?;
        }
        self.frames.insert(index, (time, relative));
        // The series only ever names frames already on disk: a crash
        // between the two writes loses at most the newest entry.
        let pvd = self.dir.join("series.pvd");
        crate::atomic::write(&pvd, vtk::series_pvd(&self.frames).as_bytes()).map_err(at(&pvd))
    }

    /// Writes the tools of frame `index` at `time` as
    /// `frames/tools_NNNNN.vtu` (every tool's triangles, each moved by its
    /// entry of `displacements` along its axis, with the cell data `tool`:
    /// its index among the scene's tools) and rewrites `tools.pvd`.
    /// Nothing is written without tools.
    pub fn write_tools(
        &mut self,
        index: usize,
        time: f64,
        tools: &ToolMeshes,
        displacements: &[f64],
    ) -> Result<(), ResultsError> {
        if tools.is_empty() {
            return Ok(());
        }
        let (mut points, mut triangles, mut owner) = (Vec::new(), Vec::new(), Vec::new());
        for (k, tool) in tools.tools.iter().enumerate() {
            let first = points.len() as u32;
            points.extend(tool.vertices_at(displacements.get(k).copied().unwrap_or(0.0)));
            triangles.extend(tool.triangles.iter().map(|t| t.map(|i| i + first)));
            owner.extend(std::iter::repeat_n(k as u32, tool.triangles.len()));
        }
        let relative = format!("frames/tools_{index:05}.vtu");
        let path = self.dir.join(&relative);
        let xml = vtk::surfaces_vtu(time, &points, &triangles, &owner);
        crate::atomic::write(&path, xml.as_bytes()).map_err(at(&path))?;
        self.tool_frames.insert(index, (time, relative));
        let pvd = self.dir.join("tools.pvd");
        crate::atomic::write(&pvd, vtk::series_pvd(&self.tool_frames).as_bytes()).map_err(at(&pvd))
    }

    /// Writes `energy.csv`: one row per entry of `rows`, energies in mJ
    /// (N·mm), with the header
    /// `time,step,kinetic,strain,internal_work,viscous,damping,external_work,boundary_work,contact_work,friction_dissipation,numerical_dissipation,confinement_work,balance_error`
    /// (numerical dissipation: what the implicit integrator removed, zero
    /// for explicit runs; confinement work: what the tools put into yarns
    /// they confine, zero without). A value that is not finite is left empty.
    pub fn write_energy(&self, rows: &[EnergyRow]) -> Result<(), ResultsError> {
        let mut csv = String::with_capacity(64 + rows.len() * 200);
        csv.push_str(ENERGY_HEADER);
        csv.push('\n');
        for row in rows {
            let e = &row.energy;
            let _ = write!(csv, "{},{}", fmt_f64(row.time), row.step);
            for v in [
                e.kinetic,
                e.strain,
                e.internal_work,
                e.viscous,
                e.damping,
                e.external_work,
                e.boundary_work,
                e.contact_work,
                e.friction_dissipation,
                e.numerical_dissipation,
                e.confinement_work,
                e.balance_error,
            ] {
                csv.push(',');
                // A value that is not a number is missing, not "NaN": the
                // run's completion check says why (drape's `limits`).
                csv.push_str(&crate::finite::or_empty(v, fmt_f64));
            }
            csv.push('\n');
        }
        self.write_file("energy.csv", csv.as_bytes())
    }

    /// Writes `cutbacks.csv`: one row per implicit attempt that failed and
    /// was cut back, header `step,time,increment,reason,message` (the
    /// message quoted, `"` doubled, as RFC 4180 has it). Where and why an
    /// implicit run spends its wasted iterations: the summary only counts
    /// them.
    pub fn write_cutbacks(&self, rows: &[CutbackRow]) -> Result<(), ResultsError> {
        let mut csv = String::with_capacity(64 + rows.len() * 240);
        csv.push_str("step,time,increment,reason,message\n");
        for row in rows {
            let _ = writeln!(
                csv,
                "{},{},{},{},\"{}\"",
                row.step,
                fmt_f64(row.time),
                fmt_f64(row.increment),
                row.reason,
                row.message.replace('"', "\"\"")
            );
        }
        self.write_file("cutbacks.csv", csv.as_bytes())
    }

    /// Writes `profiles.csv` (diagonal and median shear profiles): header
    /// `line,distance_mm,shear_deg`, the rows of `diagonal` then of
    /// `median`, each sorted by signed initial distance from the centre.
    /// Without a rectangular blank both profiles are empty and the file
    /// holds only its header.
    ///
    /// A laminate (`measures.ply_profiles`) writes each ply's own profiles
    /// instead, with a first column naming the ply as `orientations.csv`
    /// does: header `ply,line,distance_mm,shear_deg`, ply by ply from the
    /// bottom, each ply's diagonal then its median.
    pub fn write_profiles(&self, measures: &Measures) -> Result<(), ResultsError> {
        if !measures.ply_profiles.is_empty() {
            return self.write_file(
                "profiles.csv",
                profiles::ply_csv(&measures.ply_profiles).as_bytes(),
            );
        }
        let mut csv = String::from("line,distance_mm,shear_deg\n");
        for (line, points) in [
            ("diagonal", &measures.profile_diagonal),
            ("median", &measures.profile_median),
        ] {
            for p in points {
                let _ = writeln!(
                    csv,
                    "{line},{},{}",
                    fmt_f64(p.distance),
                    fmt_f64(p.shear_deg)
                );
            }
        }
        self.write_file("profiles.csv", csv.as_bytes())
    }

    /// Writes `summary.json` (pretty-printed, with a final newline).
    ///
    /// JSON has no NaN or infinity: such a number is written as `null`.
    pub fn write_summary(&self, summary: &Summary) -> Result<(), ResultsError> {
        let path = self.dir.join("summary.json");
        let mut json = serde_json::to_vec_pretty(summary).map_err(|e| ResultsError {
            path: path.clone(),
            source: e.into(),
        })?;
        json.push(b'\n');
        crate::atomic::write(&path, &json).map_err(at(&path))
    }

    /// Colours the shear pictures ([`Self::write_pictures`],
    /// [`Self::write_view`]) over the fixed |γ| range `range` (degrees,
    /// `[output] shear_range_deg`, checked finite and increasing by the
    /// scene) instead of 0 to the run's largest, so that two runs' pictures
    /// compare colour for colour; values outside take the end colours.
    pub fn set_shear_range(&mut self, range: Option<[f64; 2]>) {
        self.shear_range = range;
    }

    /// Writes `shear_map.png` (the formed part seen from above, coloured by
    /// shear angle, with a colour bar), for a laminate one such map per
    /// ply ([`ply_picture`]), `waviness_map.png` (for a laminate, one per
    /// ply instead: `waviness_map_<ply>.png`) and `profiles.png` (for a
    /// laminate, one per ply instead: `profiles_<ply>.png`).
    ///
    /// The shear map projects the current positions on the x–y plane and
    /// paints each membrane element with the viridis colour of its
    /// |shear angle|, from 0 to the largest (or over the range of
    /// [`Self::set_shear_range`]), higher elements over lower
    /// ones; a grey line shows the blank's outline before forming and a
    /// marker the element of largest shear. The waviness map paints each
    /// element of the flat blank with its waviness (the wrinkle indicator,
    /// [`drape_model::measures::waviness`]), where a fold hidden under the
    /// formed part still shows. The profile plot shows the
    /// signed shear angle against the signed initial distance from the
    /// blank's centre, along the diagonal and the median.
    pub fn write_pictures(
        &self,
        model: &Model,
        state: &State,
        fields: &ElementFields,
        measures: &Measures,
    ) -> Result<(), ResultsError> {
        let path = self.dir.join("shear_map.png");
        write_png(
            &path,
            pictures::shear_map(model, state, fields, measures, self.shear_range, None),
        )?;
        // A laminate's plies overlap in the picture above: one each too.
        let plies = pictured_plies(model);
        for ply in plies {
            let path = self.dir.join(ply_picture(&ply.name));
            write_png(
                &path,
                pictures::shear_map(model, state, fields, measures, self.shear_range, Some(ply)),
            )?;
        }
        // A laminate's waviness one ply per picture only: on the flat
        // blank the plies lie on one another and the top one hides the rest.
        let wavy: Vec<(String, Option<&drape_model::stack::Ply>)> = if plies.is_empty() {
            vec![("waviness_map.png".to_owned(), None)]
        } else {
            plies
                .iter()
                .map(|p| (ply_picture_of(PlyPicture::WavinessMap, &p.name), Some(p)))
                .collect()
        };
        for (name, ply) in wavy {
            let path = self.dir.join(name);
            write_png(&path, pictures::waviness_map(model, fields, measures, ply))?;
        }
        if !measures.ply_profiles.is_empty() {
            // Each ply's profiles on a plot of its own, as its other pictures.
            return profiles::write_ply_pictures(&self.dir, &measures.ply_profiles, state.time);
        }
        let path = self.dir.join("profiles.png");
        write_png(&path, pictures::profiles(measures, state.time))
    }

    /// Writes `shear_3d.png`: the formed part seen obliquely (azimuth −60°,
    /// elevation 35°), coloured by |γ| with a colour bar, over the outline
    /// of the tools of `tools`, each displaced by its entry of
    /// `displacements` along its axis. For a laminate, one such view per
    /// ply instead, `shear_3d_<ply>.png` ([`ply_picture_of`]), each on the
    /// frame and colour scale of the whole laminate.
    pub fn write_view(
        &self,
        model: &Model,
        state: &State,
        fields: &ElementFields,
        tools: &ToolMeshes,
        displacements: &[f64],
    ) -> Result<(), ResultsError> {
        // A laminate one ply per picture only: its plies, a fraction of a
        // millimetre apart, speckle through each other in one view.
        let plies = pictured_plies(model);
        let views: Vec<(String, Option<&drape_model::stack::Ply>)> = if plies.is_empty() {
            vec![("shear_3d.png".to_owned(), None)]
        } else {
            plies
                .iter()
                .map(|p| (ply_picture_of(PlyPicture::Shear3d, &p.name), Some(p)))
                .collect()
        };
        for (name, ply) in views {
            let path = self.dir.join(name);
            write_png(
                &path,
                pictures::oblique::oblique_view(
                    model,
                    state,
                    fields,
                    tools,
                    displacements,
                    self.shear_range,
                    ply,
                ),
            )?;
        }
        Ok(())
    }

    /// Writes `orientations.inp` and `orientations.csv` (see
    /// [`export`]): the draped fibre orientation, shear angle and
    /// thickness of every element of `model` at `state`.
    pub fn write_orientations(
        &self,
        model: &Model,
        state: &State,
        fields: &ElementFields,
        title: &str,
    ) -> Result<(), ResultsError> {
        let o = export::Orientations::of_frame(model, state, fields, title);
        // No NaN reaches the files: what cannot be written is an error
        // naming the file (nothing written).
        o.check_finite().map_err(|e| ResultsError {
            path: self.dir.join("orientations.inp"),
            source: std::io::Error::new(std::io::ErrorKind::InvalidData, e),
        })?;
        self.write_file("orientations.inp", o.to_inp().as_bytes())?;
        self.write_file("orientations.csv", o.to_csv().as_bytes())
    }

    /// Writes `bytes` whole to `name` in the directory.
    fn write_file(&self, name: &str, bytes: &[u8]) -> Result<(), ResultsError> {
        let path = self.dir.join(name);
        crate::atomic::write(&path, bytes).map_err(at(&path))
    }
}

/// Writes the PNG `path`: `panels` side by side, each a map of one value
/// per membrane element of `model` drawn on the flat blank (the reference
/// positions) with its colour bar: the picture of a comparison.
pub fn write_flat_maps(
    path: &Path,
    model: &Model,
    panels: &[MapPanel<'_>],
) -> Result<(), ResultsError> {
    write_png(path, pictures::maps::flat_maps(model, panels))
}

/// Writes the PNG `path` like [`write_flat_maps`], for elements `cells`
/// (node indices into `x0`) drawn at the (x, y) of `x0`: the picture of a
/// comparison of two results folders.
pub fn write_flat_maps_of(
    path: &Path,
    x0: &[Vector3<f64>],
    cells: &[Vec<u32>],
    panels: &[MapPanel<'_>],
) -> Result<(), ResultsError> {
    write_png(path, pictures::maps::flat_maps_of(x0, cells, panels))
}

/// Writes the PNG `path` with several shear profiles on one plot (for
/// comparing runs, like the paper's Figs. 7 and 12): `curves` are (legend,
/// profile) pairs, drawn as `profiles.png` draws one line.
pub fn write_profile_comparison(
    path: &Path,
    title: &str,
    curves: &[(String, &[drape_model::measures::ProfilePoint])],
) -> Result<(), ResultsError> {
    write_png(path, pictures::profile_comparison(title, curves))
}

/// Writes the PNG `path` of a fit (`drape fit`): the `measured` curves
/// (name, (x, y) points) as dots and the `fitted` law as a line, axes
/// described by `labels` (x, y).
pub fn write_fit_picture(
    path: &Path,
    title: &str,
    labels: (&str, &str),
    measured: &[(String, Vec<(f64, f64)>)],
    fitted: &[(f64, f64)],
) -> Result<(), ResultsError> {
    write_png(
        path,
        pictures::fit::fit_png(title, labels, measured, fitted),
    )
}

/// Writes the PNG `path` of a sweep: each measure of `runs` against each
/// swept key of `axes` (see `sweep.png` in the scene reference).
pub fn write_sweep_picture(
    path: &Path,
    axes: &[SweepAxis],
    runs: &[SweepRun],
) -> Result<(), ResultsError> {
    write_png(path, pictures::sweep::sweep_png(axes, runs))
}

/// Writes the PNG `path` of a work-precision study: run time against each
/// error of `panels` for every setting of `points` (time axis described by
/// `time_label`), with the Pareto front
/// (see `cargo xtask bench work-precision`).
pub fn write_work_precision_picture(
    path: &Path,
    title: &str,
    time_label: &str,
    panels: &[WorkPrecisionPanel],
    points: &[WorkPrecisionPoint],
) -> Result<(), ResultsError> {
    write_png(
        path,
        pictures::work_precision::work_precision_png(title, time_label, panels, points),
    )
}

/// Writes the PNG `png` renders to `path` (whole or not at all), or says
/// which picture could not be drawn.
fn write_png<E>(path: &Path, png: Result<Vec<u8>, E>) -> Result<(), ResultsError>
where
    E: Into<Box<dyn std::error::Error + Send + Sync>>,
{
    let png = png.map_err(|e| ResultsError {
        path: path.to_owned(),
        source: std::io::Error::other(e),
    })?;
    crate::atomic::write(path, &png).map_err(at(path))
}

/// Locks `dir` (created if needed), makes its `frames/` folder and clears
/// the temporaries a killed run left in both.
fn claim(dir: &Path) -> Result<OutputLock, ResultsError> {
    let lock = OutputLock::acquire(dir)?;
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).map_err(at(&frames))?;
    for folder in [dir, frames.as_path()] {
        crate::atomic::remove_temporaries(folder).map_err(at(folder))?;
    }
    Ok(lock)
}

/// Removes `path` unless it does not exist.
fn remove_if_present(path: &Path) -> Result<(), ResultsError> {
    match std::fs::remove_file(path) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(at(path)(e)),
        _ => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip_without_long_zero_runs() {
        for v in [
            0.0,
            1.0,
            -2.5,
            0.1,
            1e-12,
            123456.789,
            1e300,
            f64::MIN_POSITIVE,
            1e-5,
            9.99e-6,
        ] {
            let text = fmt_f64(v);
            assert_eq!(text.parse::<f64>().unwrap(), v, "{text}");
            assert!(text.len() <= 24, "{text}");
        }
        assert_eq!(fmt_f64(1e-12), "1e-12");
        assert_eq!(fmt_f64(0.25), "0.25");
        assert_eq!(fmt_f64(3.0), "3");
        assert_eq!(fmt_f64(f64::NAN), "NaN");
    }

    #[test]
    fn frame_file_names_are_recognised_exactly() {
        assert!(is_frame_file("frame_00000.vtu"));
        assert!(is_frame_file("frame_123456.vtu"));
        assert!(!is_frame_file("frame_.vtu"));
        assert!(!is_frame_file("frame_0001.vtu.bak"));
        assert!(!is_frame_file("my_frame_00001.vtu"));
        assert!(!is_frame_file("frame_00a01.vtu"));
    }
}
