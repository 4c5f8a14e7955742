//! The scene file's tables as serde reads them (`[simulation]`, `[fabric]`,
//! `[[tools]]`...), with their defaults: what a file may say, not whether
//! it makes sense (that is [`super::build`]'s work).

use drape_constitutive::Material;
use drape_contact::{Amplitude, ProfileSegment};
use drape_model::blank::{ElementKind, FibreRepresentation};
use drape_time::ImplicitSettings;
use drape_time::tangent::MembraneTangentChoice;
use serde::{Deserialize, Serialize};

use super::{KinematicSpec, LengthUnit};

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

/// Where the explicit driver's steps run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Device {
    /// On the CPU's cores.
    #[default]
    Cpu,
    /// On an NVIDIA GPU (drape-gpu): the scene must use only what it does.
    Gpu,
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

/// Implicit: how each Newton iteration solves the contact (see
/// [`drape_time::ContactSolver`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ContactSolverSpec {
    /// The paper's condensed multiplier solve (the reference).
    Condensed,
    /// Semi-smooth Newton: one active set and one saddle-point
    /// factorisation per Newton iteration (the default: see
    /// [`drape_time::ContactSolver`]).
    #[default]
    ActiveSet,
}

impl From<ContactSolverSpec> for drape_time::ContactSolver {
    fn from(spec: ContactSolverSpec) -> Self {
        match spec {
            ContactSolverSpec::Condensed => drape_time::ContactSolver::Condensed,
            ContactSolverSpec::ActiveSet => drape_time::ContactSolver::ActiveSet,
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
    /// Where the explicit steps run.
    #[serde(default)]
    pub device: Device,
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
    /// Implicit: how each Newton iteration solves the contact.
    #[serde(default)]
    pub contact_solver: ContactSolverSpec,
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

/// Whether a material named in a scene is a card beside it (a `.toml`
/// file) rather than a preset.
pub(crate) fn is_card(name: &str) -> bool {
    name.ends_with(".toml")
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
    /// The yarns' buckling law (beyond the paper): unset or `true`, the
    /// material's `fibre.buckling_stress` (every preset has one); `false`
    /// runs the paper's yarn, which buckles at no cost.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yarn_buckling: Option<bool>,
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
    /// edge rounded into an inner wall (see [`drape_contact::Surface::ring`]).
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
    /// `[stack]`: a laminate of plies instead of `[fabric]`'s one.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stack: Option<super::StackSpec>,
}
