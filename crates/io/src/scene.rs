//! Scene files: a forming simulation in TOML, read into a [`Model`] and the
//! run's settings.
//!
//! Every table rejects unknown keys, and every invalid value is a
//! [`SceneError`] that names the file, the line and the field and says what
//! is allowed. The format is documented with examples in
//! `docs/scene-reference.md`.
//!
//! ```
//! let text = r#"
//! [simulation]
//! end_time = 0.01
//!
//! [fabric]
//! material = "glass-serge-4x3"
//! orientation_deg = 0
//! fibres = "trusses"
//! blank = { width = 100, height = 100, cells = [10, 10] }
//!
//! [[boundary]]
//! nodes = "left"
//! motion = { kind = "fixed" }
//! "#;
//! let scene = drape_io::scene::Scene::parse(text, "example.toml".as_ref(), &[]).unwrap();
//! assert_eq!(scene.model.node_count(), 121);
//! ```

use std::path::{Path, PathBuf};

mod kinematic;
pub use kinematic::{KinematicSetup, KinematicSpec};

use drape_constitutive::Material;
use drape_contact::{Amplitude, ProfileSegment, Surface, Tool, ToolMotion};
use drape_elements::{ForceTable, SpringBatch};
use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
use drape_model::{BoundaryCondition, Model, ModelError, Motion, NodalLoad};
use drape_time::tangent::MembraneTangentChoice;
use drape_time::{ExplicitSettings, GuardSettings, ImplicitSettings};
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

mod bending;
mod locate;
mod open_mesh;
mod placement;

use bending::yarn_bending;
use locate::{Locator, Override, field_at, line_at, plain};
pub use placement::LengthUnit;
use placement::Placement;

/// A scene that cannot be used: where and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{}: {field}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct SceneError {
    /// The scene file.
    pub file: PathBuf,
    /// The line of the offending field, when known.
    pub line: Option<usize>,
    /// Dotted path of the field (`tools[0].friction`), or what failed.
    pub field: String,
    /// What is wrong and what is allowed.
    pub message: String,
}

/// Which integrator.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    /// Central differences with lumped mass.
    #[default]
    Explicit,
    /// Newton increments (Bossak–Newmark) with a sparse tangent and the
    /// condensed contact solve.
    Implicit,
}

/// Implicit: the resin membranes' tangent in the factorised K̂ (the
/// residual is exact either way; see [`MembraneTangentChoice`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MembraneTangentSpec {
    /// The exact derivative: indefinite where the resin is compressed.
    #[default]
    Exact,
    /// The compressive principal stresses dropped from the stress terms:
    /// positive semi-definite, exact where the resin is in tension.
    TensionField,
    /// The exact tangent, the tension field when that is indefinite.
    TensionFieldWhenIndefinite,
}

impl From<MembraneTangentSpec> for MembraneTangentChoice {
    fn from(spec: MembraneTangentSpec) -> Self {
        match spec {
            MembraneTangentSpec::Exact => MembraneTangentChoice::Exact,
            MembraneTangentSpec::TensionField => MembraneTangentChoice::TensionField,
            MembraneTangentSpec::TensionFieldWhenIndefinite => {
                MembraneTangentChoice::TensionFieldWhenIndefinite
            }
        }
    }
}

/// The most output frames a run may ask for: each is a file of the whole
/// blank, and a frame is written at most once per step anyway.
pub const MAX_FRAMES: usize = 100_000;

fn default_frames() -> usize {
    20
}
fn default_safety() -> f64 {
    0.9
}
fn default_margin() -> f64 {
    5.0
}
fn default_true() -> bool {
    true
}

/// `[simulation]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    /// Integrator.
    #[serde(default)]
    pub solver: Solver,
    /// Time to reach (s).
    pub end_time: f64,
    /// Output frames after the initial one.
    #[serde(default = "default_frames")]
    pub frames: usize,
    /// Fraction of the stable step used.
    #[serde(default = "default_safety")]
    pub safety_factor: f64,
    /// A fixed time step instead of the stable estimate (s).
    #[serde(default)]
    pub time_step: Option<f64>,
    /// Target time step of selective mass scaling (s).
    #[serde(default)]
    pub mass_scaling_dt: Option<f64>,
    /// Mass-proportional damping α (1/s).
    #[serde(default)]
    pub damping: f64,
    /// Stop when the energy balance error exceeds this fraction (default
    /// [`drape_time::GuardSettings`]' 1 %).
    #[serde(default)]
    pub max_energy_error: Option<f64>,
    /// The scene is quasi-static: stop when the kinetic energy exceeds the
    /// internal work.
    #[serde(default)]
    pub quasi_static: bool,
    /// The instability guard (speed, reach, energy balance); off leaves
    /// only a `max_energy_error` given explicitly.
    #[serde(default = "default_true")]
    pub instability_guard: bool,
    /// Broad-phase margin of the contact search (mm).
    #[serde(default = "default_margin")]
    pub contact_margin: f64,
    /// Implicit: first increment (s), default end_time/100.
    #[serde(default)]
    pub initial_increment: Option<f64>,
    /// Implicit: largest increment (s), default end_time/20.
    #[serde(default)]
    pub max_increment: Option<f64>,
    /// Implicit: smallest increment before giving up (s), default
    /// 1e-9·end_time.
    #[serde(default)]
    pub min_increment: Option<f64>,
    /// Implicit: spectral radius ρ∞ ∈ [0, 1] of the Bossak scheme.
    #[serde(default)]
    pub spectral_radius: f64,
    /// Implicit: residual tolerance, a fraction of the force scale.
    #[serde(default = "default_force_tolerance")]
    pub force_tolerance: f64,
    /// Implicit: correction tolerance, a fraction of the increment's
    /// displacement.
    #[serde(default = "default_displacement_tolerance")]
    pub displacement_tolerance: f64,
    /// Implicit: penetration and stick slip left (mm).
    #[serde(default = "default_gap_tolerance")]
    pub gap_tolerance: f64,
    /// Implicit: Newton iterations per attempt.
    #[serde(default = "default_newton_iterations")]
    pub max_iterations: usize,
    /// Implicit: the resin membranes' tangent.
    #[serde(default)]
    pub membrane_tangent: MembraneTangentSpec,
}

fn default_force_tolerance() -> f64 {
    ImplicitSettings::default().force_tolerance
}
fn default_displacement_tolerance() -> f64 {
    ImplicitSettings::default().displacement_tolerance
}
fn default_gap_tolerance() -> f64 {
    ImplicitSettings::default().gap_tolerance
}
fn default_newton_iterations() -> usize {
    ImplicitSettings::default().max_iterations
}

/// A material: a preset's name or a full table.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum MaterialSpec {
    /// A preset (`carbon-prepreg-2x2`, `glass-serge-4x3`).
    Preset(String),
    /// Every value given.
    Inline(Material),
}

/// Read by the form of the value rather than by trying each variant (as
/// `untagged` would), so that a table's own error (a missing or unknown
/// key) reaches the user instead of "did not match any variant".
impl<'de> Deserialize<'de> for MaterialSpec {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Form;
        impl<'de> serde::de::Visitor<'de> for Form {
            type Value = MaterialSpec;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(
                    f,
                    "a preset name ({}) or a table of material values",
                    drape_constitutive::PRESET_NAMES.join(", ")
                )
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<MaterialSpec, E> {
                Ok(MaterialSpec::Preset(v.to_owned()))
            }
            fn visit_map<A: serde::de::MapAccess<'de>>(
                self,
                map: A,
            ) -> Result<MaterialSpec, A::Error> {
                Material::deserialize(serde::de::value::MapAccessDeserializer::new(map))
                    .map(MaterialSpec::Inline)
            }
        }
        d.deserialize_any(Form)
    }
}

/// `[fabric.blank]`: a rectangle meshed by drape (`width`, `height`,
/// `cells` or `element_size`, `center`, `element`) or a mesh file (`mesh`),
/// never both. The rectangle's keys are options so that mixing the two
/// forms is reported rather than silently ignored.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlankSpec {
    /// Extent along x (mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<f64>,
    /// Extent along y (mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<f64>,
    /// Centre (mm), default the origin.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub center: Option<[f64; 3]>,
    /// `quad` (default) or `triangle`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub element: Option<ElementKind>,
    /// Cells along x and y.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cells: Option<[usize; 2]>,
    /// Or a target element size (mm).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub element_size: Option<f64>,
    /// Or a mesh file, Gmsh `.msh` (4.1) or Abaqus `.inp`, relative to the
    /// scene file (see [`crate::mesh_import`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<String>,
    /// With `mesh`: the unit of the file's coordinates.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub units: Option<LengthUnit>,
    /// With `mesh`: a factor on the file's coordinates (or `units`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scale: Option<f64>,
    /// With `mesh`: rotations about x, then y, then z (degrees), after
    /// the scale.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotate: Option<[f64; 3]>,
    /// With `mesh`: a translation (mm), applied last.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub offset: Option<[f64; 3]>,
    /// With `mesh`: turn elements whose node order runs against their
    /// neighbours' instead of refusing the mesh.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reorient: Option<bool>,
}

/// `[fabric]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FabricSpec {
    /// The material.
    pub material: MaterialSpec,
    /// θ, warp angle from x (degrees).
    #[serde(default)]
    pub orientation_deg: f64,
    /// `trusses` or `embedded`.
    pub fibres: FibreRepresentation,
    /// The blank.
    pub blank: BlankSpec,
    /// Yarn bending (beyond the paper): a discrete elastica along the
    /// mesh's yarn lines with the material's `bending_rigidity`. Unset, it
    /// is on wherever it can be (the material has a rigidity and the mesh
    /// lines follow the yarns), with a note where it cannot; `true` insists
    /// (an error where it cannot), `false` turns it off.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bending: Option<bool>,
}

/// A tool's shape.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum GeometrySpec {
    /// An infinite plane; the fabric on the normal's side.
    Plane {
        /// A point of it.
        point: [f64; 3],
        /// Normal towards the fabric.
        normal: [f64; 3],
    },
    /// A sphere; the fabric outside.
    Sphere {
        /// Centre.
        center: [f64; 3],
        /// Radius.
        radius: f64,
    },
    /// A hemisphere on a cylindrical shank, pole up (or down).
    HemisphericalPunch {
        /// The pole.
        pole: [f64; 3],
        /// Radius.
        radius: f64,
        /// Shank length behind the equator.
        shank: f64,
        /// Which way the pole points.
        #[serde(default)]
        pointing: Pointing,
    },
    /// A flat die face at height `z` with a round opening and a fillet,
    /// the fabric above it and in the opening.
    Die {
        /// Axis position (x, y) and face height z.
        center: [f64; 3],
        /// Radius of the opening.
        opening_radius: f64,
        /// Radius of the fillet between face and opening.
        fillet_radius: f64,
        /// Depth of the opening's wall below the fillet.
        depth: f64,
        /// Outer radius of the face.
        outer_radius: f64,
    },
    /// A blank holder: a ring facing down, the fabric below, its inner
    /// edge rounded into an inner wall (see [`Surface::ring`]).
    Ring {
        /// Axis position (x, y) and face height z.
        center: [f64; 3],
        /// Inner radius (of the inner wall; the flat face starts at
        /// `inner_radius + edge_radius`).
        inner_radius: f64,
        /// Outer radius.
        outer_radius: f64,
        /// Radius of the rounded inner edge (0: sharp).
        #[serde(default)]
        edge_radius: f64,
        /// Height of the ring (default: the larger of 10 mm and twice the
        /// edge radius).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        thickness: Option<f64>,
    },
    /// A surface of revolution about the vertical axis through `origin`.
    Revolution {
        /// A point of the axis.
        origin: [f64; 3],
        /// Profile segments in (r, z), fabric on the left of travel.
        profile: Vec<ProfileSegment>,
    },
    /// A triangle mesh from an STL or OBJ file (relative to the scene
    /// file), moved by `offset`; the fabric on the side its counter-clockwise
    /// normals point to (outside a closed mesh).
    Mesh {
        /// The file.
        file: String,
        /// Translation applied to the mesh (mm), last.
        #[serde(default)]
        offset: [f64; 3],
        /// The unit of the file's coordinates.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        units: Option<LengthUnit>,
        /// A factor on the file's coordinates (or `units`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        scale: Option<f64>,
        /// Rotations about x, then y, then z (degrees), after the scale.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rotate: Option<[f64; 3]>,
        /// Wind the triangles consistently (a warning counts those turned).
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        reorient: bool,
        /// Drop degenerate triangles (a warning counts them).
        #[serde(default, skip_serializing_if = "std::ops::Not::not")]
        drop_degenerate: bool,
        /// With an Abaqus file: only this instance (or part, in a file
        /// without instances), when the file holds several tools.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        instance: Option<String>,
        /// For an open mesh: whether the fabric is behind the file's
        /// normals (true) or in front (false); detected from the blank's
        /// start position when absent.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        flip_normals: Option<bool>,
        /// For an open mesh: how far its open rims are extended
        /// tangentially (mm; 0: not at all; default in `open_mesh`).
        #[serde(default, skip_serializing_if = "Option::is_none")]
        rim_extension: Option<f64>,
    },
}

/// Which way a punch points.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pointing {
    /// Pole at the top (+z), pushed up into the fabric.
    #[default]
    Up,
    /// Pole at the bottom (−z), pushed down into the fabric.
    Down,
}

/// A tool's motion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum MotionSpec {
    /// Fixed.
    Fixed,
    /// Travel `distance·a(t)` along `direction`.
    Displacement {
        /// Axis (normalised).
        direction: [f64; 3],
        /// Travel (mm).
        distance: f64,
        /// a(t).
        amplitude: Amplitude,
    },
    /// A rigid body free along `direction`, pushed by `force·a(t)`.
    Force {
        /// Axis (normalised).
        direction: [f64; 3],
        /// Force (N).
        force: f64,
        /// a(t).
        #[serde(default = "constant")]
        amplitude: Amplitude,
        /// Mass of the tool (t).
        mass: f64,
    },
}

fn constant() -> Amplitude {
    Amplitude::Constant
}

fn fixed() -> MotionSpec {
    MotionSpec::Fixed
}

/// `[[tools]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ToolSpec {
    /// Name.
    pub name: String,
    /// Coulomb friction with the fabric.
    #[serde(default)]
    pub friction: f64,
    /// Shape.
    pub geometry: GeometrySpec,
    /// Motion.
    #[serde(default = "fixed")]
    pub motion: MotionSpec,
}

/// Nodes by set name or by index.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum NodeSelection {
    /// A named set (`left`, `corners`, `edge_midpoints`, `all`, …).
    Set(String),
    /// Node indices.
    List(Vec<u32>),
    /// The union of named sets.
    Sets(Vec<String>),
}

/// One entry of a node list: a node number or a set name.
enum NodeItem {
    Node(u32),
    Name(String),
}

impl<'de> Deserialize<'de> for NodeItem {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Form;
        impl serde::de::Visitor<'_> for Form {
            type Value = NodeItem;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("a node number (a whole number ≥ 0) or a set name in quotes")
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<NodeItem, E> {
                u32::try_from(v)
                    .map(NodeItem::Node)
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Signed(v), &self))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<NodeItem, E> {
                u32::try_from(v)
                    .map(NodeItem::Node)
                    .map_err(|_| E::invalid_value(serde::de::Unexpected::Unsigned(v), &self))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<NodeItem, E> {
                Ok(NodeItem::Name(v.to_owned()))
            }
        }
        d.deserialize_any(Form)
    }
}

/// Read by the form of the value (see [`MaterialSpec`]'s), so that a bad
/// entry is named rather than "did not match any variant".
impl<'de> Deserialize<'de> for NodeSelection {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Form;
        impl<'de> serde::de::Visitor<'de> for Form {
            type Value = NodeSelection;
            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str(
                    "a node set name (\"left\"), a list of node numbers ([0, 5]) or a list of \
                     set names ([\"corners\", \"left\"])",
                )
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<NodeSelection, E> {
                Ok(NodeSelection::Set(v.to_owned()))
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<NodeSelection, A::Error> {
                let (mut numbers, mut names) = (Vec::new(), Vec::new());
                while let Some(item) = seq.next_element::<NodeItem>()? {
                    match item {
                        NodeItem::Node(n) => numbers.push(n),
                        NodeItem::Name(s) => names.push(s),
                    }
                }
                match (numbers.is_empty(), names.is_empty()) {
                    (_, true) => Ok(NodeSelection::List(numbers)),
                    (true, false) => Ok(NodeSelection::Sets(names)),
                    (false, false) => Err(serde::de::Error::custom(
                        "the list mixes node numbers and set names: give one or the other",
                    )),
                }
            }
        }
        d.deserialize_any(Form)
    }
}

/// `[[springs]]`: holding springs from nodes to anchors.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpringSpec {
    /// The held nodes.
    pub nodes: NodeSelection,
    /// Linear stiffness (N/mm), with `preload`.
    #[serde(default)]
    pub stiffness: Option<f64>,
    /// Force at zero extension (N).
    #[serde(default)]
    pub preload: f64,
    /// Or a force–extension table [[δ, F], …].
    #[serde(default)]
    pub table: Option<Vec<[f64; 2]>>,
    /// Anchor = the node's initial position + this offset (mm).
    #[serde(default)]
    pub anchor_offset: [f64; 3],
    /// Rest length (mm).
    #[serde(default)]
    pub rest_length: f64,
    /// The forces (`stiffness`, `preload`, the table's forces) are per mm
    /// of the blank's edge: each node gets them times its share of the
    /// outline's length (half of each outline edge it ends). A frame of
    /// springs along the edge, the same for every mesh.
    #[serde(default)]
    pub per_length: bool,
}

/// A boundary condition's motion.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case", tag = "kind", deny_unknown_fields)]
pub enum BcMotionSpec {
    /// Held.
    Fixed,
    /// u = value·a(t).
    Displacement {
        /// Displacement (mm).
        value: [f64; 3],
        /// a(t).
        amplitude: Amplitude,
    },
    /// v = value·a(t).
    Velocity {
        /// Velocity (mm/s).
        value: [f64; 3],
        /// a(t).
        amplitude: Amplitude,
    },
    /// A pin-jointed picture frame sheared to `shear_deg·a(t)` about the
    /// pin at `pin` (default: the blank's bottom-left corner): both arms
    /// turn by half the shear, so a point at s·x̂ + t·ŷ from the pin goes to
    /// s·(cos γ/2, sin γ/2) + t·(sin γ/2, cos γ/2).
    PictureFrame {
        /// Final shear angle (degrees).
        shear_deg: f64,
        /// a(t).
        amplitude: Amplitude,
        /// The pinned corner.
        #[serde(default)]
        pin: Option<[f64; 3]>,
    },
}

fn xyz() -> String {
    "xyz".to_owned()
}

/// `[[boundary]]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// The nodes.
    pub nodes: NodeSelection,
    /// Constrained components, some of "xyz".
    #[serde(default = "xyz")]
    pub components: String,
    /// How they move.
    pub motion: BcMotionSpec,
}

/// `[[loads]]`: a force on each node of a set.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    /// The nodes.
    pub nodes: NodeSelection,
    /// Force per node (N), or per mm of the blank's edge with `per_length`.
    pub force: [f64; 3],
    /// a(t).
    #[serde(default = "constant")]
    pub amplitude: Amplitude,
    /// `force` is per mm of the blank's edge (N/mm): each node gets it
    /// times its share of the outline's length, as for springs.
    #[serde(default)]
    pub per_length: bool,
}

/// `[[pressure]]`: a uniform follower pressure on the blank's surface (a
/// vacuum bag, a diaphragm), along each element's current normal.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureSpec {
    /// Pressure (MPa; 0.1 is one bar, a full vacuum).
    pub value: f64,
    /// Push the blank towards the tool of this name (the side it lies on
    /// at the start). Exactly one of `towards` and `side`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub towards: Option<String>,
    /// Push along the blank's normal at the start ("+": +z for a rectangle,
    /// a mesh's by its elements' node order) or against it ("-").
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub side: Option<String>,
    /// a(t).
    #[serde(default = "constant")]
    pub amplitude: Amplitude,
    /// Only the elements whose nodes all belong to these (default: the
    /// whole blank).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub nodes: Option<NodeSelection>,
}

fn default_locking() -> f64 {
    50.0
}
fn yes() -> bool {
    true
}

/// `[output]`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputSpec {
    /// Locking angle for the area at risk of wrinkling (degrees).
    #[serde(default = "default_locking")]
    pub locking_angle_deg: f64,
    /// Write VTU frames.
    #[serde(default = "yes")]
    pub vtu: bool,
    /// Write PNG pictures.
    #[serde(default = "yes")]
    pub pictures: bool,
    /// A fixed |γ| range of the shear pictures' colours (degrees), so
    /// that runs compare picture to picture; None: 0 to each run's largest.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shear_range_deg: Option<[f64; 2]>,
}

impl Default for OutputSpec {
    fn default() -> Self {
        Self {
            locking_angle_deg: default_locking(),
            vtu: true,
            pictures: true,
            shear_range_deg: None,
        }
    }
}

/// A whole scene file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// `[simulation]`.
    pub simulation: SimulationSpec,
    /// `[fabric]`.
    pub fabric: FabricSpec,
    /// `[[tools]]`.
    #[serde(default)]
    pub tools: Vec<ToolSpec>,
    /// `[[springs]]`.
    #[serde(default)]
    pub springs: Vec<SpringSpec>,
    /// `[[boundary]]`.
    #[serde(default)]
    pub boundary: Vec<BoundarySpec>,
    /// `[[loads]]`.
    #[serde(default)]
    pub loads: Vec<LoadSpec>,
    /// `[[pressure]]`.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub pressure: Vec<PressureSpec>,
    /// Gravity (mm/s²).
    #[serde(default)]
    pub gravity: Option<[f64; 3]>,
    /// `[output]`.
    #[serde(default)]
    pub output: OutputSpec,
    /// `[kinematic]`: the pin-jointed net of `drape kinematic`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kinematic: Option<KinematicSpec>,
}

/// A scene ready to run.
#[derive(Debug, Clone)]
pub struct Scene {
    /// The file it came from.
    pub file: PathBuf,
    /// What the file said (after `--set` overrides).
    pub spec: SceneFile,
    /// The model.
    pub model: Model,
    /// The explicit driver's settings.
    pub settings: ExplicitSettings,
    /// The implicit driver's settings (`[simulation] solver = "implicit"`).
    pub implicit: ImplicitSettings,
    /// The kinematic drape (`drape kinematic`), or why the scene has none:
    /// without a `[kinematic]` table a default that cannot be found is not
    /// an error for the other commands.
    pub kinematic: Result<KinematicSetup, SceneError>,
    /// What may not be what was meant, located like errors (a blank mesh
    /// whose size suggests metres, degenerate triangles dropped from a tool
    /// mesh, elements turned over): the command prints them.
    pub warnings: Vec<String>,
}

fn vector(v: [f64; 3]) -> Vector3<f64> {
    Vector3::from(v)
}

impl Scene {
    /// Reads the scene at `path`, with `--set key.path=value` overrides.
    pub fn from_file(path: &Path, overrides: &[(String, String)]) -> Result<Self, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| SceneError {
            file: path.to_owned(),
            line: None,
            field: "file".into(),
            message: format!("cannot read the scene: {e}"),
        })?;
        Self::parse(&text, path, overrides)
    }

    /// Reads a scene from its text; `path` names it in errors and anchors
    /// relative file names.
    ///
    /// An error names the field and its line, or, when the value came from
    /// an override, the `--set key=value` that gave it.
    pub fn parse(
        text: &str,
        path: &Path,
        overrides: &[(String, String)],
    ) -> Result<Self, SceneError> {
        let given: Vec<Override> = overrides.iter().map(|(k, v)| Override::new(k, v)).collect();
        let at = Locator {
            file: path,
            text: Some(text),
            overrides: &given,
            warnings: Default::default(),
        };
        let syntax = |e: toml::de::Error| SceneError {
            file: path.to_owned(),
            line: e.span().map(|s| line_at(text, s.start)),
            field: e
                .span()
                .and_then(|s| field_at(text, s.start))
                .unwrap_or_else(|| "scene".into()),
            message: plain(e.message()),
        };
        // The document that is read: the file's text, or with overrides the
        // file's table with them applied, written out again so that the
        // reader's error spans still lead to a field.
        let document = if overrides.is_empty() {
            text.to_owned()
        } else {
            let mut table: toml::Table = toml::from_str(text).map_err(syntax)?;
            for ((key, value), o) in overrides.iter().zip(&given) {
                set_path(&mut table, key, value).map_err(|message| SceneError {
                    file: path.to_owned(),
                    line: None,
                    field: o.field.clone(),
                    message: format!("--set {}: {message}", o.given),
                })?;
            }
            toml::to_string(&table).map_err(|e| SceneError {
                file: path.to_owned(),
                line: None,
                field: "--set".into(),
                message: format!("the overrides do not make a valid scene: {e}"),
            })?
        };
        let spec: SceneFile = toml::from_str(&document).map_err(|e| {
            let start = e.span().map(|s| s.start);
            let message = plain(e.message());
            match start.and_then(|s| field_at(&document, s)) {
                Some(field) if overrides.is_empty() => {
                    at.error_with_line(&field, start.map(|s| line_at(text, s)), message)
                }
                Some(field) => at.error(&field, message),
                None if overrides.is_empty() => syntax(e),
                None => at.error("scene", message),
            }
        })?;
        Self::assemble(spec, path, &at)
    }

    /// Builds a scene from its values alone (a checkpoint's copy of
    /// [`Self::resolved_spec`]); `file` names it in errors and anchors any
    /// relative file name. Errors have no line: there is no text.
    pub fn from_spec(spec: SceneFile, file: &Path) -> Result<Self, SceneError> {
        let at = Locator {
            file,
            text: None,
            overrides: &[],
            warnings: Default::default(),
        };
        Self::assemble(spec, file, &at)
    }

    /// The model, the run settings and the kinematic set-up of `spec`; a
    /// `[kinematic]` table the scene gives must be valid, an absent one is
    /// only needed by `drape kinematic`.
    fn assemble(spec: SceneFile, file: &Path, at: &Locator<'_>) -> Result<Self, SceneError> {
        let (model, settings, implicit) = build(&spec, at)?;
        let kinematic = kinematic::setup(&spec, &model, at);
        if spec.kinematic.is_some() {
            kinematic.clone()?;
        }
        Ok(Self {
            file: file.to_owned(),
            spec,
            model,
            settings,
            implicit,
            kinematic,
            warnings: at.warnings.take(),
        })
    }

    /// The scene as it runs, self-contained: every value after the
    /// overrides, and the files it reads (the blank's mesh, tools' meshes)
    /// as absolute paths, so that [`Self::from_spec`] builds the same scene
    /// from any directory.
    pub fn resolved_spec(&self) -> SceneFile {
        let base = self.file.parent().unwrap_or(Path::new("."));
        let absolute = |file: &str| -> String {
            let joined = base.join(file);
            std::path::absolute(&joined)
                .unwrap_or(joined)
                .to_string_lossy()
                .into_owned()
        };
        let mut spec = self.spec.clone();
        if let Some(mesh) = &mut spec.fabric.blank.mesh {
            *mesh = absolute(mesh);
        }
        for tool in &mut spec.tools {
            if let GeometrySpec::Mesh { file, .. } = &mut tool.geometry {
                *file = absolute(file);
            }
        }
        spec
    }

    /// The files the scene reads beside itself (the blank's mesh, tools'
    /// meshes), as absolute paths.
    pub fn input_files(&self) -> Vec<PathBuf> {
        let spec = self.resolved_spec();
        spec.fabric
            .blank
            .mesh
            .iter()
            .chain(spec.tools.iter().filter_map(|t| match &t.geometry {
                GeometrySpec::Mesh { file, .. } => Some(file),
                _ => None,
            }))
            .map(PathBuf::from)
            .collect()
    }
}

/// Sets `key` (dotted, numeric parts index lists; `tools[0].friction` is
/// read as `tools.0.friction`) to the TOML `value` (a bare word that is not
/// TOML is taken as text). A missing table on the way is created, a
/// missing list entry is an error.
pub fn set_path(table: &mut toml::Table, key: &str, value: &str) -> Result<(), String> {
    let parsed: toml::Value = match toml::from_str::<toml::Table>(&format!("v = {value}"))
        .ok()
        .and_then(|mut t| t.remove("v"))
    {
        Some(v) => v,
        None => {
            let v = value.trim();
            let digits = v.trim_start_matches(['+', '-']);
            if !digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit()) {
                return Err(format!(
                    "{v} is too large: whole numbers go up to {}",
                    i64::MAX
                ));
            }
            toml::Value::String(value.to_owned())
        }
    };
    let parts = locate::key_parts(key);
    if parts.iter().any(String::is_empty) {
        return Err("expected a key such as simulation.end_time or tools.0.friction".into());
    }
    let index_of = |here: &str, part: &str, len: usize| -> Result<usize, String> {
        let index: usize = part
            .parse()
            .map_err(|_| format!("`{here}` is a list: index it with a number, not `{part}`"))?;
        if index < len {
            Ok(index)
        } else if len == 0 {
            Err(format!(
                "`{here}` is an empty list: there is no entry {index}"
            ))
        } else {
            Err(format!(
                "`{here}` has {len} entries (0 to {}): there is no entry {index}",
                len - 1
            ))
        }
    };
    let mut current: Option<&mut toml::Value> = None;
    for (i, part) in parts.iter().enumerate() {
        let here = parts[..i].join(".");
        let next_is_index = parts
            .get(i + 1)
            .is_some_and(|p| p.bytes().all(|b| b.is_ascii_digit()));
        let missing = |t: &toml::Table| !t.contains_key(part.as_str());
        let slot = match current {
            None => {
                if next_is_index && missing(table) {
                    return Err(format!(
                        "the scene has no `{part}` list, so there is no entry {}",
                        parts[i + 1]
                    ));
                }
                table
                    .entry(part.as_str())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            Some(toml::Value::Table(t)) => {
                if next_is_index && missing(t) {
                    return Err(format!(
                        "`{here}` has no `{part}` list, so there is no entry {}",
                        parts[i + 1]
                    ));
                }
                t.entry(part.as_str())
                    .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            }
            Some(toml::Value::Array(a)) => {
                let index = index_of(&here, part, a.len())?;
                &mut a[index]
            }
            Some(_) => return Err(format!("`{here}` is a value, not a table")),
        };
        current = Some(slot);
    }
    if let Some(slot) = current {
        *slot = parsed;
    }
    Ok(())
}

fn positive(at: &Locator<'_>, field: &str, v: f64) -> Result<f64, SceneError> {
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(at.error(
            field,
            format!("{v} is not allowed: expected a positive number"),
        ))
    }
}

fn finite3(at: &Locator<'_>, field: &str, v: [f64; 3]) -> Result<Vector3<f64>, SceneError> {
    if v.iter().all(|x| x.is_finite()) {
        Ok(vector(v))
    } else {
        Err(at.error(field, "every component must be a finite number"))
    }
}

fn unit(at: &Locator<'_>, field: &str, v: [f64; 3]) -> Result<Vector3<f64>, SceneError> {
    let d = finite3(at, field, v)?;
    let n = d.norm();
    if n > 0.0 {
        Ok(d / n)
    } else {
        Err(at.error(field, "a direction must not be zero"))
    }
}

fn amplitude(at: &Locator<'_>, field: &str, a: &Amplitude) -> Result<Amplitude, SceneError> {
    a.validate().map_err(|m| at.error(field, m))?;
    Ok(a.clone())
}

/// A `[[pressure]]` on `model` (its tools already in): the elements
/// selected, oriented to the side asked for.
fn pressure(
    at: &Locator<'_>,
    here: &str,
    model: &Model,
    p: &PressureSpec,
) -> Result<drape_model::PressureLoad, SceneError> {
    if !(p.value.is_finite() && p.value >= 0.0) {
        return Err(at.error(
            &format!("{here}.value"),
            format!(
                "{} is not allowed: expected a pressure ≥ 0 in MPa (0.1 is one bar); \
                 `towards` or `side` says which way it pushes",
                p.value
            ),
        ));
    }
    let amplitude = amplitude(at, &format!("{here}.amplitude"), &p.amplitude)?;
    let selected = match &p.nodes {
        Some(sel) => Some(nodes(at, &format!("{here}.nodes"), model, sel)?),
        None => None,
    };
    let load = |flip| {
        drape_model::PressureLoad::on_membranes(
            model,
            selected.as_deref(),
            flip,
            p.value,
            amplitude.clone(),
        )
    };
    let plus = load(false);
    if plus.is_empty() {
        return Err(at.error(
            &format!("{here}.nodes"),
            "no element of the blank has all its nodes in this selection: the pressure would act on nothing",
        ));
    }
    let flip = match (&p.towards, p.side.as_deref()) {
        (Some(_), Some(_)) | (None, None) => {
            return Err(at.error(
                here,
                "give exactly one of `towards = \"<tool name>\"` and `side = \"+\"` or `\"-\"`",
            ));
        }
        (None, Some("+")) => false,
        (None, Some("-")) => true,
        (None, Some(other)) => {
            return Err(at.error(
                &format!("{here}.side"),
                format!("`{other}` is not allowed: expected \"+\" (along the blank's normal, +z for a rectangle) or \"-\""),
            ));
        }
        (Some(name), None) => {
            let field = format!("{here}.towards");
            let Some(tool) = model.tools.iter().find(|t| &t.name == name) else {
                let known: Vec<&str> = model.tools.iter().map(|t| t.name.as_str()).collect();
                return Err(at.error(
                    &field,
                    if known.is_empty() {
                        format!("unknown tool `{name}`: the scene has no tools; use `side` instead")
                    } else {
                        format!("unknown tool `{name}`; the tools are: {}", known.join(", "))
                    },
                ));
            };
            // Which way the elements' normals (node order) face the tool,
            // weighted by area: the tool's side of the blank at the start.
            let (mut facing, mut total) = (0.0, 0.0);
            for e in 0..plus.len() {
                let nodes = plus.element(e);
                let area = drape_model::pressure::vector_area(nodes, &model.x0);
                let centroid = nodes
                    .iter()
                    .map(|&n| model.x0[n as usize])
                    .sum::<Vector3<f64>>()
                    / nodes.len() as f64;
                let to = tool.surface.project(&centroid).point - centroid;
                let d = to.norm();
                if d > 0.0 {
                    facing += area.dot(&to) / d;
                }
                total += area.norm();
            }
            if facing.is_nan() || facing.abs() <= 0.05 * total {
                return Err(at.error(
                    &field,
                    format!(
                        "cannot tell which side of the blank tool `{name}` is on (it lies \
                         edgewise to the blank or on both sides of it): give `side = \"+\"` \
                         (along +z for a rectangle) or `side = \"-\"` instead"
                    ),
                ));
            }
            facing < 0.0
        }
    };
    Ok(if flip { load(true) } else { plus })
}

/// The nodes `held`, grouped by their share of the blank's outline (mm):
/// half the reference length of each outline edge (an edge of one element
/// only) they end. Groups in order of first appearance, nodes in the given
/// order, so the model does not depend on anything but the scene. A node
/// off the outline has no share: that is an error naming it, since a
/// force "per mm of edge" means nothing there.
fn edge_shares(
    at: &Locator<'_>,
    field: &str,
    model: &Model,
    held: &[u32],
) -> Result<Vec<(f64, Vec<u32>)>, SceneError> {
    let mut share = vec![0.0; model.x0.len()];
    for [a, b] in crate::results::boundary_edges(model) {
        let half = 0.5 * (model.x0[a as usize] - model.x0[b as usize]).norm();
        share[a as usize] += half;
        share[b as usize] += half;
    }
    let mut groups: Vec<(f64, Vec<u32>)> = Vec::new();
    for &n in held {
        let s = share[n as usize];
        if s == 0.0 {
            return Err(at.error(
                field,
                format!(
                    "node {n} is not on the blank's edge, so `per_length` gives it no share of a \
                     force per mm of edge: hold only edge nodes (the set `boundary`, an edge set)"
                ),
            ));
        }
        // Equal shares to the last bit (a uniform grid) share a batch.
        match groups.iter_mut().find(|(g, _)| g.to_bits() == s.to_bits()) {
            Some((_, nodes)) => nodes.push(n),
            None => groups.push((s, vec![n])),
        }
    }
    Ok(groups)
}

fn nodes(
    at: &Locator<'_>,
    field: &str,
    model: &Model,
    sel: &NodeSelection,
) -> Result<Vec<u32>, SceneError> {
    match sel {
        NodeSelection::Set(name) => {
            if let Ok(set) = model.node_set(name) {
                return Ok(set.to_vec());
            }
            // Set names are matched regardless of case when that is not
            // ambiguous: Abaqus's are case-insensitive (`*NSET, NSET=Clamp`
            // is `clamp`), and a rectangle's `LEFT` can only mean `left`.
            let same: Vec<&String> = model
                .node_sets
                .keys()
                .filter(|k| k.eq_ignore_ascii_case(name))
                .collect();
            if let [only] = same[..] {
                return Ok(model.node_sets[only].clone());
            }
            let known: Vec<&str> = model.node_sets.keys().map(String::as_str).collect();
            Err(at.error(
                field,
                if same.is_empty() {
                    format!(
                        "unknown node set `{name}`; known sets: {}",
                        known.join(", ")
                    )
                } else {
                    let names: Vec<&str> = same.iter().map(|s| s.as_str()).collect();
                    format!(
                        "`{name}` matches the sets {} when case is ignored: write the name \
                         exactly as one of them",
                        names.join(", ")
                    )
                },
            ))
        }
        NodeSelection::Sets(names) => {
            let mut all = Vec::new();
            for name in names {
                all.extend(nodes(at, field, model, &NodeSelection::Set(name.clone()))?);
            }
            all.sort_unstable();
            all.dedup();
            Ok(all)
        }
        NodeSelection::List(list) => {
            let count = model.node_count();
            match list.iter().find(|&&n| n as usize >= count) {
                Some(n) => Err(at.error(
                    field,
                    format!("node {n} does not exist (the blank has {count} nodes)"),
                )),
                None => Ok(list.clone()),
            }
        }
    }
}

/// The model of a rectangular blank, and its bottom-left corner (the
/// default pin of a picture frame).
fn rectangle_blank(
    at: &Locator<'_>,
    fabric: &FabricSpec,
    material: &Material,
) -> Result<(Model, Vector3<f64>), SceneError> {
    let b = &fabric.blank;
    let mesh_keys = [
        ("units", b.units.is_some()),
        ("scale", b.scale.is_some()),
        ("rotate", b.rotate.is_some()),
        ("offset", b.offset.is_some()),
        ("reorient", b.reorient.is_some()),
    ];
    if let Some((key, _)) = mesh_keys.iter().find(|(_, given)| *given) {
        return Err(at.error(
            &format!("fabric.blank.{key}"),
            format!(
                "`{key}` places a blank read from a mesh file (`mesh = \"file.msh\"`); a \
                 rectangle is placed by `center`"
            ),
        ));
    }
    let (Some(width), Some(height)) = (b.width, b.height) else {
        let missing = if b.width.is_none() { "width" } else { "height" };
        return Err(at.error(
            "fabric.blank",
            format!(
                "`{missing}` is missing: give `width`, `height` and `cells` (or `element_size`) \
                 for a rectangle, or `mesh = \"file.msh\"` (or .inp) for a meshed blank"
            ),
        ));
    };
    let meshing = match (b.cells, b.element_size) {
        (Some(c), None) => Meshing::Cells(c),
        (None, Some(h)) => Meshing::Size(h),
        _ => {
            return Err(at.error(
                "fabric.blank",
                "give exactly one of `cells = [nx, ny]` and `element_size`",
            ));
        }
    };
    let blank = RectangleBlank {
        width,
        height,
        center: finite3(at, "fabric.blank.center", b.center.unwrap_or_default())?,
        orientation_deg: fabric.orientation_deg,
        element: b.element.unwrap_or(ElementKind::Quad),
        meshing,
        fibres: fabric.fibres,
    };
    let model = Model::from_blank(&blank, material).map_err(|e| match e {
        ModelError::Mesh(drape_model::blank::MeshError::Invalid {
            field,
            value,
            expected,
        }) => {
            let path = match field {
                "orientation_deg" => "fabric.orientation_deg".to_owned(),
                "meshing" => "fabric.blank.cells".to_owned(),
                f => format!("fabric.blank.{f}"),
            };
            at.error(&path, format!("{value} is not allowed: {expected}"))
        }
        other => at.error("fabric", other.to_string()),
    })?;
    let corner = blank.center - Vector3::new(0.5 * blank.width, 0.5 * blank.height, 0.0);
    Ok((model, corner))
}

/// The model of a blank meshed in a file (`fabric.blank.mesh`, relative to
/// the scene file), with embedded fibres along the warp (cos θ, sin θ, 0)
/// projected on each element; and its bounding box's low corner (the
/// default pin of a picture frame).
fn mesh_blank(
    at: &Locator<'_>,
    fabric: &FabricSpec,
    file: &str,
    material: &Material,
) -> Result<(Model, Vector3<f64>), SceneError> {
    let b = &fabric.blank;
    let rectangle_keys = [
        ("width", b.width.is_some()),
        ("height", b.height.is_some()),
        ("center", b.center.is_some()),
        ("element", b.element.is_some()),
        ("cells", b.cells.is_some()),
        ("element_size", b.element_size.is_some()),
    ];
    if let Some((key, _)) = rectangle_keys.iter().find(|(_, given)| *given) {
        return Err(at.error(
            &format!("fabric.blank.{key}"),
            format!(
                "`{key}` describes a rectangle and cannot be combined with `mesh`: a blank is \
                 either a rectangle (`width`, `height`, `cells` or `element_size`) or a mesh file"
            ),
        ));
    }
    if fabric.fibres != FibreRepresentation::Embedded {
        return Err(at.error(
            "fabric.fibres",
            "a blank from a mesh file needs `fibres = \"embedded\"`: trusses need the \
             fibre-aligned lattice that drape meshes itself",
        ));
    }
    if !fabric.orientation_deg.is_finite() {
        return Err(at.error("fabric.orientation_deg", "must be a finite angle"));
    }
    let placement = Placement::new(at, "fabric.blank", b.units, b.scale, b.rotate, b.offset)?;
    let path = at.file.parent().unwrap_or(Path::new(".")).join(file);
    let (mut mesh, turned) = if b.reorient == Some(true) {
        crate::mesh_import::read_mesh_reoriented(&path)
    } else {
        crate::mesh_import::read_mesh(&path).map(|m| (m, 0))
    }
    .map_err(|e| at.error("fabric.blank.mesh", e.to_string()))?;
    if turned > 0 {
        at.warn(
            "fabric.blank.reorient",
            format!(
                "{}: turned {turned} element{} over to the node order of their neighbours",
                path.display(),
                if turned == 1 { "" } else { "s" }
            ),
        );
    }
    for x in &mut mesh.x0 {
        *x = placement.apply(x);
    }
    // drape works in mm: a blank of less than a millimetre or more than ten
    // metres across is most likely a file in another unit.
    let (low, high) = mesh.x0.iter().fold(
        (
            Vector3::repeat(f64::INFINITY),
            Vector3::repeat(f64::NEG_INFINITY),
        ),
        |(l, h), x| (l.inf(x), h.sup(x)),
    );
    let size = (high - low).norm();
    if !(1.0..=10_000.0).contains(&size) {
        at.warn(
            "fabric.blank.mesh",
            format!(
                "{}: the blank is {size:.3e} mm across, after `units`/`scale`: drape's lengths \
                 are in mm; if the file is in another unit, give `units = \"m\"` (or \"cm\", \
                 \"in\") or `scale` in [fabric.blank]",
                path.display()
            ),
        );
    }
    let model = Model::from_mesh(
        &mesh.blank_mesh(fabric.orientation_deg),
        material,
        FibreRepresentation::Embedded,
    )
    .map_err(|e| {
        let message = match &e {
            // The batch's index back to the file's label.
            ModelError::Element { kind, error } => {
                let labels = if *kind == "quad" {
                    &mesh.quad_labels
                } else {
                    &mesh.triangle_labels
                };
                match labels.get(error.element) {
                    Some(label) => format!(
                        "{}: element {label} ({kind}): {} (at integration point {})",
                        path.display(),
                        error.cause,
                        error.point
                    ),
                    None => format!("{}: {e}", path.display()),
                }
            }
            _ => format!("{}: {e}", path.display()),
        };
        at.error("fabric.blank.mesh", message)
    })?;
    let low = mesh
        .x0
        .iter()
        .fold(Vector3::repeat(f64::INFINITY), |m, x| m.inf(x));
    Ok((model, low))
}

fn build(
    spec: &SceneFile,
    at: &Locator<'_>,
) -> Result<(Model, ExplicitSettings, ImplicitSettings), SceneError> {
    let sim = &spec.simulation;
    positive(at, "simulation.end_time", sim.end_time)?;
    if sim.frames == 0 || sim.frames > MAX_FRAMES {
        return Err(at.error(
            "simulation.frames",
            format!(
                "{} is not allowed: expected from 1 to {MAX_FRAMES} frames (each frame is a \
                 VTU file of the whole blank)",
                sim.frames
            ),
        ));
    }
    if !(sim.safety_factor > 0.0 && sim.safety_factor <= 1.0) {
        return Err(at.error(
            "simulation.safety_factor",
            format!(
                "{} is not allowed: expected a number in (0, 1]",
                sim.safety_factor
            ),
        ));
    }
    if let Some(dt) = sim.time_step {
        positive(at, "simulation.time_step", dt)?;
    }
    if let Some(dt) = sim.mass_scaling_dt {
        positive(at, "simulation.mass_scaling_dt", dt)?;
    }
    if !(sim.damping.is_finite() && sim.damping >= 0.0) {
        return Err(at.error(
            "simulation.damping",
            format!("{} is not allowed: expected ≥ 0", sim.damping),
        ));
    }
    if let Some(e) = sim.max_energy_error {
        positive(at, "simulation.max_energy_error", e)?;
    }
    positive(at, "simulation.contact_margin", sim.contact_margin)?;
    for (field, value) in [
        ("simulation.initial_increment", sim.initial_increment),
        ("simulation.max_increment", sim.max_increment),
        ("simulation.min_increment", sim.min_increment),
    ] {
        if let Some(v) = value {
            positive(at, field, v)?;
        }
    }
    if !(0.0..=1.0).contains(&sim.spectral_radius) {
        return Err(at.error(
            "simulation.spectral_radius",
            format!(
                "{} is not allowed: expected a number in [0, 1]",
                sim.spectral_radius
            ),
        ));
    }
    positive(at, "simulation.force_tolerance", sim.force_tolerance)?;
    positive(
        at,
        "simulation.displacement_tolerance",
        sim.displacement_tolerance,
    )?;
    positive(at, "simulation.gap_tolerance", sim.gap_tolerance)?;
    if sim.max_iterations == 0 {
        return Err(at.error(
            "simulation.max_iterations",
            "0 is not allowed: expected at least 1 Newton iteration",
        ));
    }

    let fabric = &spec.fabric;
    let material = match &fabric.material {
        MaterialSpec::Preset(name) => Material::preset(name).ok_or_else(|| {
            at.error(
                "fabric.material",
                format!(
                    "unknown preset `{name}`: expected one of {} or a table of values",
                    drape_constitutive::PRESET_NAMES.join(", ")
                ),
            )
        })?,
        MaterialSpec::Inline(m) => m.clone(),
    };
    material.validate().map_err(|e| {
        at.error(
            &format!("fabric.material.{}", e.field),
            format!("{} is not allowed: expected {}", e.value, e.expected),
        )
    })?;
    let (mut model, default_pin) = match &fabric.blank.mesh {
        Some(file) => mesh_blank(at, fabric, file, &material)?,
        None => rectangle_blank(at, fabric, &material)?,
    };

    for (i, t) in spec.tools.iter().enumerate() {
        let here = format!("tools[{i}]");
        if !(t.friction.is_finite() && t.friction >= 0.0) {
            return Err(at.error(
                &format!("{here}.friction"),
                format!(
                    "{} is not allowed: expected a friction coefficient ≥ 0",
                    t.friction
                ),
            ));
        }
        let g = format!("{here}.geometry");
        let surface_err = |e: drape_contact::SurfaceError| at.error(&g, e.to_string());
        let surface = match &t.geometry {
            GeometrySpec::Plane { point, normal } => Surface::plane(
                finite3(at, &format!("{g}.point"), *point)?,
                unit(at, &format!("{g}.normal"), *normal)?,
            )
            .map_err(surface_err)?,
            GeometrySpec::Sphere { center, radius } => {
                positive(at, &format!("{g}.radius"), *radius)?;
                Surface::sphere(finite3(at, &format!("{g}.center"), *center)?, *radius)
                    .map_err(surface_err)?
            }
            GeometrySpec::HemisphericalPunch {
                pole,
                radius,
                shank,
                pointing,
            } => {
                positive(at, &format!("{g}.radius"), *radius)?;
                positive(at, &format!("{g}.shank"), *shank)?;
                let pole = finite3(at, &format!("{g}.pole"), *pole)?;
                match pointing {
                    Pointing::Up => Surface::hemispherical_punch(pole, *radius, *shank),
                    Pointing::Down => Surface::hemispherical_punch_down(pole, *radius, *shank),
                }
                .map_err(surface_err)?
            }
            GeometrySpec::Die {
                center,
                opening_radius,
                fillet_radius,
                depth,
                outer_radius,
            } => {
                let (a, f) = (
                    positive(at, &format!("{g}.opening_radius"), *opening_radius)?,
                    positive(at, &format!("{g}.fillet_radius"), *fillet_radius)?,
                );
                positive(at, &format!("{g}.depth"), *depth)?;
                if outer_radius.is_nan() || *outer_radius <= a + f {
                    return Err(at.error(
                        &format!("{g}.outer_radius"),
                        format!("{outer_radius} is not allowed: expected more than opening + fillet radius ({})", a + f),
                    ));
                }
                Surface::die(
                    finite3(at, &format!("{g}.center"), *center)?,
                    a,
                    f,
                    *depth,
                    *outer_radius,
                )
                .map_err(surface_err)?
            }
            GeometrySpec::Ring {
                center,
                inner_radius,
                outer_radius,
                edge_radius,
                thickness,
            } => {
                positive(at, &format!("{g}.inner_radius"), *inner_radius)?;
                if !(edge_radius.is_finite() && *edge_radius >= 0.0) {
                    return Err(at.error(
                        &format!("{g}.edge_radius"),
                        format!(
                            "{edge_radius} is not allowed: expected a radius ≥ 0 (0: a sharp edge)"
                        ),
                    ));
                }
                if outer_radius.is_nan() || *outer_radius <= inner_radius + edge_radius {
                    return Err(at.error(
                        &format!("{g}.outer_radius"),
                        format!(
                            "{outer_radius} is not allowed: expected more than the inner radius plus the edge radius ({})",
                            inner_radius + edge_radius
                        ),
                    ));
                }
                let thickness = match thickness {
                    Some(t) => {
                        if !(t.is_finite() && *t > 0.0 && t >= edge_radius) {
                            return Err(at.error(
                                &format!("{g}.thickness"),
                                format!("{t} is not allowed: expected a height > 0 and at least the edge radius ({edge_radius})"),
                            ));
                        }
                        *t
                    }
                    None => f64::max(10.0, 2.0 * edge_radius),
                };
                Surface::ring(
                    finite3(at, &format!("{g}.center"), *center)?,
                    *inner_radius,
                    *outer_radius,
                    *edge_radius,
                    thickness,
                )
                .map_err(surface_err)?
            }
            GeometrySpec::Revolution { origin, profile } => Surface::revolution(
                finite3(at, &format!("{g}.origin"), *origin)?,
                profile.clone(),
            )
            .map_err(surface_err)?,
            GeometrySpec::Mesh {
                file,
                offset,
                units,
                scale,
                rotate,
                reorient,
                drop_degenerate,
                instance,
                flip_normals,
                rim_extension,
            } => {
                let placement = Placement::new(at, &g, *units, *scale, *rotate, Some(*offset))?;
                let options = drape_contact::RepairOptions {
                    drop_degenerate: *drop_degenerate,
                    reorient: *reorient,
                };
                let surface =
                    placement::tool_mesh(at, &g, file, &placement, options, instance.as_deref())?;
                let open = open_mesh::OpenMesh {
                    flip_normals: *flip_normals,
                    rim_extension: *rim_extension,
                };
                open_mesh::place(at, &g, &t.name, surface, &open, &model, &material)?
            }
        };
        let m = format!("{here}.motion");
        let motion = match &t.motion {
            MotionSpec::Fixed => ToolMotion::Fixed,
            MotionSpec::Displacement {
                direction,
                distance,
                amplitude: a,
            } => ToolMotion::Displacement {
                direction: unit(at, &format!("{m}.direction"), *direction)?,
                distance: if distance.is_finite() {
                    *distance
                } else {
                    return Err(at.error(&format!("{m}.distance"), "must be a finite number"));
                },
                amplitude: amplitude(at, &format!("{m}.amplitude"), a)?,
            },
            MotionSpec::Force {
                direction,
                force,
                amplitude: a,
                mass,
            } => ToolMotion::Force {
                direction: unit(at, &format!("{m}.direction"), *direction)?,
                force: if force.is_finite() {
                    *force
                } else {
                    return Err(at.error(&format!("{m}.force"), "must be a finite number"));
                },
                amplitude: amplitude(at, &format!("{m}.amplitude"), a)?,
                mass: positive(at, &format!("{m}.mass"), *mass)?,
            },
        };
        model.tools.push(Tool {
            name: t.name.clone(),
            surface,
            motion,
            friction: t.friction,
        });
    }

    for (i, s) in spec.springs.iter().enumerate() {
        let here = format!("springs[{i}]");
        let held = nodes(at, &format!("{here}.nodes"), &model, &s.nodes)?;
        let table = match (&s.table, s.stiffness) {
            (Some(t), None) => {
                ForceTable::new(t).map_err(|e| at.error(&format!("{here}.table"), e.to_string()))?
            }
            (None, Some(k)) => {
                positive(at, &format!("{here}.stiffness"), k)?;
                if !(s.preload.is_finite() && s.preload >= 0.0) {
                    return Err(at.error(&format!("{here}.preload"), "expected a force ≥ 0"));
                }
                ForceTable::linear(k, s.preload)
            }
            _ => {
                return Err(at.error(
                    &here,
                    "give exactly one of `stiffness` (with an optional `preload`) and `table`",
                ));
            }
        };
        if !(s.rest_length.is_finite() && s.rest_length >= 0.0) {
            return Err(at.error(&format!("{here}.rest_length"), "expected a length ≥ 0"));
        }
        let offset = finite3(at, &format!("{here}.anchor_offset"), s.anchor_offset)?;
        // Anchored at its node, a spring starts at zero length: a force
        // there pulls in no direction, and near the anchor its transverse
        // stiffness F/l has no bound (no time step is stable).
        let (start, _) = table.force_and_stiffness(offset.norm() - s.rest_length);
        if offset == Vector3::zeros() && start != 0.0 {
            return Err(at.error(
                &here,
                format!(
                    "a spring anchored at its own node starts at zero length, where its force of {start} N \
                     has no direction: give an anchor_offset, or no force at the start (preload, rest_length)"
                ),
            ));
        }
        // Per length: one batch per distinct edge share, its forces scaled
        // by the share (a table's extensions stay as given).
        let groups = if s.per_length {
            edge_shares(at, &format!("{here}.nodes"), &model, &held)?
        } else {
            vec![(1.0, held)]
        };
        for (share, held) in groups {
            let table = match (&s.table, s.stiffness) {
                (Some(t), _) if share != 1.0 => {
                    ForceTable::new(&t.iter().map(|&[d, f]| [d, share * f]).collect::<Vec<_>>())
                        .map_err(|e| at.error(&format!("{here}.table"), e.to_string()))?
                }
                (None, Some(k)) if share != 1.0 => ForceTable::linear(share * k, share * s.preload),
                _ => table.clone(),
            };
            model.springs.push(SpringBatch {
                table,
                anchors: held
                    .iter()
                    .map(|&n| model.x0[n as usize] + offset)
                    .collect(),
                rest_length: vec![s.rest_length; held.len()],
                nodes: held,
            });
        }
    }

    for (i, bc) in spec.boundary.iter().enumerate() {
        let here = format!("boundary[{i}]");
        let held = nodes(at, &format!("{here}.nodes"), &model, &bc.nodes)?;
        let mut components = [false; 3];
        for ch in bc.components.chars() {
            match ch {
                'x' => components[0] = true,
                'y' => components[1] = true,
                'z' => components[2] = true,
                other => {
                    return Err(at.error(
                        &format!("{here}.components"),
                        format!("`{other}` is not allowed: expected some of the letters x, y, z"),
                    ));
                }
            }
        }
        let motion = match &bc.motion {
            BcMotionSpec::Fixed => Motion::Fixed,
            BcMotionSpec::Displacement {
                value,
                amplitude: a,
            } => Motion::Displacement {
                value: finite3(at, &format!("{here}.motion.value"), *value)?,
                amplitude: amplitude(at, &format!("{here}.motion.amplitude"), a)?,
            },
            BcMotionSpec::Velocity {
                value,
                amplitude: a,
            } => Motion::Velocity {
                value: finite3(at, &format!("{here}.motion.value"), *value)?,
                amplitude: amplitude(at, &format!("{here}.motion.amplitude"), a)?,
            },
            BcMotionSpec::PictureFrame {
                shear_deg,
                amplitude: a,
                pin,
            } => {
                if !(shear_deg.is_finite() && shear_deg.abs() < 90.0) {
                    return Err(at.error(
                        &format!("{here}.motion.shear_deg"),
                        format!("{shear_deg} is not allowed: expected a shear angle between −90° and 90°"),
                    ));
                }
                let pin = match pin {
                    Some(p) => finite3(at, &format!("{here}.motion.pin"), *p)?,
                    None => default_pin,
                };
                let a = amplitude(at, &format!("{here}.motion.amplitude"), a)?;
                let gamma = shear_deg.to_radians();
                Motion::Trajectory(std::sync::Arc::new(move |x0: &Vector3<f64>, t: f64| {
                    let (s, c) = (0.5 * gamma * a.value(t)).sin_cos();
                    let d = x0 - pin;
                    Vector3::new(c * d.x + s * d.y, s * d.x + c * d.y, d.z) - d
                }))
            }
        };
        model.boundary.push(BoundaryCondition {
            nodes: held,
            components,
            motion,
        });
    }

    for (i, l) in spec.loads.iter().enumerate() {
        let here = format!("loads[{i}]");
        let loaded = nodes(at, &format!("{here}.nodes"), &model, &l.nodes)?;
        let force = finite3(at, &format!("{here}.force"), l.force)?;
        let amplitude = amplitude(at, &format!("{here}.amplitude"), &l.amplitude)?;
        let groups = if l.per_length {
            edge_shares(at, &format!("{here}.nodes"), &model, &loaded)?
        } else {
            vec![(1.0, loaded)]
        };
        for (share, nodes) in groups {
            model.loads.push(NodalLoad {
                nodes,
                force: share * force,
                amplitude: amplitude.clone(),
            });
        }
    }
    if let Some(g) = spec.gravity {
        model.gravity = finite3(at, "gravity", g)?;
    }
    for (i, p) in spec.pressure.iter().enumerate() {
        let load = pressure(at, &format!("pressure[{i}]"), &model, p)?;
        model.pressure.push(load);
    }
    // After the boundary conditions: lines are clamped at the fixed nodes.
    if let Some(rigidity) = yarn_bending(fabric, &material, &model, at)? {
        let theta = fabric.orientation_deg.to_radians();
        let warp = Vector3::new(theta.cos(), theta.sin(), 0.0);
        model
            .add_yarn_bending(warp, Vector3::z(), rigidity)
            .map_err(|e| at.error("fabric.bending", e.to_string()))?;
    }
    if !(spec.output.locking_angle_deg.is_finite() && spec.output.locking_angle_deg > 0.0) {
        return Err(at.error("output.locking_angle_deg", "expected a positive angle"));
    }
    if let Some([lo, hi]) = spec.output.shear_range_deg
        && !(lo.is_finite() && hi.is_finite() && 0.0 <= lo && lo < hi)
    {
        return Err(at.error(
            "output.shear_range_deg",
            format!(
                "[{lo}, {hi}]: expected [min, max] in degrees of |γ|, finite, with 0 ≤ min < max"
            ),
        ));
    }
    let guard = GuardSettings {
        enabled: sim.instability_guard,
        max_energy_error: sim.max_energy_error.or(GuardSettings::default()
            .max_energy_error
            .filter(|_| sim.instability_guard)),
        max_kinetic_ratio: sim
            .quasi_static
            .then_some(drape_time::guard::QUASI_STATIC_KINETIC_RATIO),
        ..GuardSettings::default()
    };
    let settings = ExplicitSettings {
        end_time: sim.end_time,
        safety_factor: sim.safety_factor,
        time_step: sim.time_step,
        mass_scaling: sim.mass_scaling_dt,
        damping: sim.damping,
        frames: sim.frames,
        guard: guard.clone(),
        contact_margin: sim.contact_margin,
        ..ExplicitSettings::default()
    };
    let implicit = ImplicitSettings {
        end_time: sim.end_time,
        frames: sim.frames,
        initial_increment: sim.initial_increment,
        max_increment: sim.max_increment,
        min_increment: sim.min_increment,
        spectral_radius: sim.spectral_radius,
        force_tolerance: sim.force_tolerance,
        displacement_tolerance: sim.displacement_tolerance,
        gap_tolerance: sim.gap_tolerance,
        max_iterations: sim.max_iterations,
        damping: sim.damping,
        contact_margin: sim.contact_margin,
        mass_scaling: sim.mass_scaling_dt,
        safety_factor: sim.safety_factor,
        membrane_tangent: sim.membrane_tangent.into(),
        guard,
        ..ImplicitSettings::default()
    };
    Ok((model, settings, implicit))
}
