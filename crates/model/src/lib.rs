//! # drape-model
//!
//! The discretised forming problem, ready for a time integrator: reference
//! nodes and lumped masses, element batches (fibre trusses, resin membranes,
//! holding springs), node sets, boundary conditions with amplitudes,
//! gravity, the node→slot adjacency for a lock-free deterministic force
//! gather, the record of [`Features`] a scene uses, the [`State`]
//! (positions, velocities, histories) and the derived measures of SPEC §8
//! (maximum shear and where, shear profiles, draw-in, area above a locking
//! angle, maximum fibre tension).
//!
//! What it is not: no time stepping (`drape-time`), no file formats
//! (`drape-io`).
//!
//! ```
//! use drape_constitutive::Material;
//! use drape_model::{Amplitude, BoundaryCondition, Model, Motion};
//! use drape_model::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};
//! use nalgebra::Vector3;
//!
//! let blank = RectangleBlank {
//!     width: 100.0,
//!     height: 50.0,
//!     center: Vector3::zeros(),
//!     orientation_deg: 0.0,
//!     element: ElementKind::Quad,
//!     meshing: Meshing::Cells([10, 5]),
//!     fibres: FibreRepresentation::Trusses,
//! };
//! let glass = Material::preset("glass-serge-4x3").unwrap();
//! let mut model = Model::from_blank(&blank, &glass).unwrap();
//! let left = model.node_set("left").unwrap().to_vec();
//! model.boundary.push(BoundaryCondition::fixed(left));
//! assert_eq!(model.node_count(), 66);
//! assert!(model.features().trusses && !model.features().viscoelastic);
//! ```

pub mod blank;
pub mod folds;
pub mod measures;
pub mod pressure;
pub mod stack;

use std::collections::BTreeMap;
use std::fmt;
use std::sync::Arc;

use drape_constitutive::{Material, MaterialError};
use drape_elements::{
    BendingBatch, ElementError, FabricSection, MembraneBatch, SpringBatch, TrussBatch,
    yarn_triplets,
};
use nalgebra::Vector3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use blank::{BlankFrame, BlankMesh, FibreRepresentation, MeshError, RectangleBlank};
use measures::{DrawIn, ProfileLine, ProfilePoint};
pub use pressure::PressureLoad;

/// What can go wrong while building a model.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// The blank cannot be meshed.
    #[error(transparent)]
    Mesh(#[from] MeshError),
    /// The material is invalid.
    #[error(transparent)]
    Material(#[from] MaterialError),
    /// An element is degenerate in the reference configuration.
    #[error("{kind}: {error}")]
    Element {
        /// Which batch kind.
        kind: &'static str,
        /// What is wrong.
        error: ElementError,
    },
    /// A node set does not exist.
    #[error("unknown node set `{0}`")]
    UnknownNodeSet(String),
    /// A tool is invalid.
    #[error("{0}")]
    Tool(String),
    /// Bending was asked for a mesh without lines along the yarns.
    #[error(
        "yarn bending needs mesh lines along the yarns (a rectangle blank with trusses, or \
         embedded fibres at 0° or 90° on a grid); this mesh has no edge along the warp or weft \
         that continues through a node"
    )]
    NoYarnLines,
    /// A node index is out of range.
    #[error("node {node} does not exist (the model has {count} nodes)")]
    NoSuchNode {
        /// The index.
        node: u32,
        /// Number of nodes.
        count: usize,
    },
}

pub use drape_contact::{Amplitude, Tool, ToolMotion};

/// A prescribed displacement u(x₀, t) of a node from its reference position
/// x₀, for motions no amplitude describes (a picture frame's arms).
pub type Trajectory = Arc<dyn Fn(&Vector3<f64>, f64) -> Vector3<f64> + Send + Sync>;

/// How constrained components move.
#[derive(Clone)]
pub enum Motion {
    /// Held at the reference position.
    Fixed,
    /// u(t) = value·a(t).
    Displacement {
        /// Displacement at a = 1 (mm).
        value: Vector3<f64>,
        /// a(t).
        amplitude: Amplitude,
    },
    /// v(t) = value·a(t).
    Velocity {
        /// Velocity at a = 1 (mm/s).
        value: Vector3<f64>,
        /// a(t).
        amplitude: Amplitude,
    },
    /// u = f(x₀, t), per node.
    Trajectory(Trajectory),
}

impl fmt::Debug for Motion {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Self::Fixed => write!(f, "Fixed"),
            Self::Displacement { value, amplitude } => {
                write!(f, "Displacement({value:?}, {amplitude:?})")
            }
            Self::Velocity { value, amplitude } => write!(f, "Velocity({value:?}, {amplitude:?})"),
            Self::Trajectory(_) => write!(f, "Trajectory(..)"),
        }
    }
}

/// Constrained components of a set of nodes and their motion. Where
/// conditions overlap, the later one wins for the components it names.
#[derive(Debug, Clone)]
pub struct BoundaryCondition {
    /// The nodes.
    pub nodes: Vec<u32>,
    /// Which of x, y, z are constrained.
    pub components: [bool; 3],
    /// How they move.
    pub motion: Motion,
}

impl BoundaryCondition {
    /// All components of `nodes` held fixed.
    pub fn fixed(nodes: Vec<u32>) -> Self {
        Self {
            nodes,
            components: [true; 3],
            motion: Motion::Fixed,
        }
    }

    /// The prescribed displacement of a node at reference `x0` at time `t`,
    /// or None for a velocity condition.
    pub fn displacement(&self, x0: &Vector3<f64>, t: f64) -> Option<Vector3<f64>> {
        match &self.motion {
            Motion::Fixed => Some(Vector3::zeros()),
            Motion::Displacement { value, amplitude } => Some(value * amplitude.value(t)),
            Motion::Velocity { .. } => None,
            Motion::Trajectory(f) => Some(f(x0, t)),
        }
    }
}

/// A force on each of a set of nodes, scaled by an amplitude.
#[derive(Debug, Clone, PartialEq)]
pub struct NodalLoad {
    /// The nodes.
    pub nodes: Vec<u32>,
    /// Force on each node at a = 1 (N).
    pub force: Vector3<f64>,
    /// a(t).
    pub amplitude: Amplitude,
}

impl NodalLoad {
    /// The force on each of its nodes at time `t` (N).
    pub fn force_at(&self, t: f64) -> Vector3<f64> {
        self.force * self.amplitude.value(t)
    }
}

/// The features a model uses, so that a driver runs only their passes
/// (SPEC §7, "skip what a scene doesn't need").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize)]
pub struct Features {
    /// Fibre trusses.
    pub trusses: bool,
    /// Fibres embedded in membranes.
    pub embedded_fibres: bool,
    /// A resin with Prony relaxation.
    pub viscoelastic: bool,
    /// Holding springs.
    pub springs: bool,
    /// Gravity.
    pub gravity: bool,
    /// Concentrated loads.
    pub loads: bool,
    /// Prescribed motions other than fixed.
    pub prescribed_motion: bool,
    /// Rigid tools.
    pub contact: bool,
    /// A tool with friction.
    pub friction: bool,
    /// A force-driven tool (couples the contact constraints).
    pub force_driven_tools: bool,
    /// Yarn bending (beyond the paper).
    pub bending: bool,
    /// A follower pressure on the blank's surface.
    pub pressure: bool,
}

/// How far a mesh's lines follow the yarns ([`Model::yarn_coverage`]):
/// yarn bending acts on a node only where a line of each family runs
/// straight through it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct YarnCoverage {
    /// Nodes of the membranes that are not on the blank's outline.
    pub interior_nodes: usize,
    /// Of those, the nodes a warp line and a weft line both run through.
    pub covered_nodes: usize,
    /// Bending triplets there would be (both families, outline included).
    pub triplets: usize,
}

impl YarnCoverage {
    /// Whether the lines run through every interior node in both
    /// families: the mesh follows the yarns everywhere, so bending holds
    /// the whole blank.
    pub fn is_complete(&self) -> bool {
        self.triplets > 0 && self.covered_nodes == self.interior_nodes
    }
}

/// Where each element batch writes its nodal forces in the global slot
/// array, and which slots each node gathers, in a fixed order (CSR).
#[derive(Debug, Clone, Default)]
pub struct SlotLayout {
    /// First slot of each truss batch.
    pub truss_offsets: Vec<usize>,
    /// First slot of each membrane batch.
    pub membrane_offsets: Vec<usize>,
    /// First slot of each spring batch.
    pub spring_offsets: Vec<usize>,
    /// First slot of each bending batch (after every other kind's, so a
    /// model without bending has the slots it had before bending existed).
    pub bending_offsets: Vec<usize>,
    /// Total number of slots.
    pub len: usize,
    node_ptr: Vec<usize>,
    node_slots: Vec<u32>,
}

/// Each node's slots from the (node, slot) pairs `owners` of a force pass
/// that writes every element's share into slots of its own: `ptr` (one
/// more than `node_count`) indexes `slots`, which lists node i's slots in
/// `slots[ptr[i]..ptr[i + 1]]`. A counting sort by node keeps each node's
/// slots in the order of `owners`, so a gather that sums them in that
/// order does not depend on how the slots were filled.
pub fn node_slots(
    node_count: usize,
    owners: impl Iterator<Item = (u32, u32)> + Clone,
) -> (Vec<usize>, Vec<u32>) {
    let mut ptr = vec![0usize; node_count + 1];
    for (node, _) in owners.clone() {
        ptr[node as usize + 1] += 1;
    }
    for i in 0..node_count {
        ptr[i + 1] += ptr[i];
    }
    let mut fill = ptr.clone();
    let mut slots = vec![0u32; ptr[node_count]];
    for (node, slot) in owners {
        slots[fill[node as usize]] = slot;
        fill[node as usize] += 1;
    }
    (ptr, slots)
}

impl SlotLayout {
    /// Each node's slots in the order [`Self::gather`] sums them: node i's
    /// are `slots[ptr[i]..ptr[i + 1]]` of (`ptr`, `slots`).
    pub fn node_slot_lists(&self) -> (&[usize], &[u32]) {
        (&self.node_ptr, &self.node_slots)
    }

    /// fₙ = Σ of node n's slots, in ascending slot order: the same sums in
    /// the same order whatever the number of threads.
    pub fn gather(&self, slots: &[Vector3<f64>], forces: &mut [Vector3<f64>]) {
        // Tasks of 1 024 nodes, each a plain loop: a per-node parallel
        // iterator called a closure at every node and doubled the pass's
        // instructions.
        const PIECE: usize = 1024;
        forces
            .par_chunks_mut(PIECE)
            .enumerate()
            .for_each(|(c, out)| {
                let first = c * PIECE;
                let ptr = &self.node_ptr[first..=first + out.len()];
                for (f, range) in out.iter_mut().zip(ptr.windows(2)) {
                    let mut sum = Vector3::zeros();
                    for &s in &self.node_slots[range[0]..range[1]] {
                        sum += slots[s as usize];
                    }
                    *f = sum;
                }
            });
    }
}

/// What a blank-based model knows about its blank, for derived measures.
#[derive(Debug, Clone)]
pub struct BlankInfo {
    /// The blank's reference frame.
    pub frame: BlankFrame,
    /// Edge midpoint nodes [left, right, bottom, top].
    pub midpoints: [u32; 4],
    /// Corner nodes [bottom-left, bottom-right, top-right, top-left].
    pub corners: [u32; 4],
    /// Typical element size (for profile bands).
    pub cell_size: f64,
}

/// The discretised problem.
#[derive(Debug, Clone, Default)]
pub struct Model {
    /// Reference node positions.
    pub x0: Vec<Vector3<f64>>,
    /// Lumped nodal masses (t).
    pub mass: Vec<f64>,
    /// Fibre truss batches.
    pub trusses: Vec<TrussBatch>,
    /// Membrane batches.
    pub membranes: Vec<MembraneBatch>,
    /// Holding spring batches.
    pub springs: Vec<SpringBatch>,
    /// Yarn bending batches (empty unless a scene asks for bending).
    pub bending: Vec<BendingBatch>,
    /// Boundary conditions, applied in order.
    pub boundary: Vec<BoundaryCondition>,
    /// Gravity acceleration (mm/s²), zero for none.
    pub gravity: Vector3<f64>,
    /// Concentrated nodal forces.
    pub loads: Vec<NodalLoad>,
    /// Follower pressures on membrane elements.
    pub pressure: Vec<PressureLoad>,
    /// Named node sets.
    pub node_sets: BTreeMap<String, Vec<u32>>,
    /// The blank, when the model was meshed from one.
    pub blank: Option<BlankInfo>,
    /// Rigid tools.
    pub tools: Vec<Tool>,
    /// Distance of the fabric's mid-surface from a tool at contact: half
    /// its thickness (mm).
    pub contact_offset: f64,
    /// The plies of a laminate, bottom to top (empty for one ply, see
    /// [`stack`]).
    pub plies: Vec<stack::Ply>,
}

/// The evolving state of a model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct State {
    /// Time (s).
    pub time: f64,
    /// Completed steps.
    pub step: u64,
    /// Current positions.
    pub x: Vec<Vector3<f64>>,
    /// Velocities (mid-step for an explicit run).
    pub v: Vec<Vector3<f64>>,
    /// Committed history of each membrane batch.
    pub history: Vec<Vec<f64>>,
}

/// Output fields of every membrane element (all batches, in batch order).
#[derive(Debug, Clone, Default)]
pub struct ElementFields {
    /// Shear angle (rad).
    pub shear: Vec<f64>,
    /// Warp and weft stretch.
    pub fibre_stretch: Vec<[f64; 2]>,
    /// Current unit directions of [warp, weft].
    pub fibre_direction: Vec<[Vector3<f64>; 2]>,
    /// Fibre stress τ of the embedded families (MPa); zero when trusses
    /// carry the fibres (their tension is a truss output).
    pub fibre_stress: Vec<[f64; 2]>,
    /// Yarn tension per unit width of fabric, t_f·τ(ln λ)/λ, of each family
    /// from the element's fibre stretch (N/mm): the same measure for trusses
    /// (N/strip width) and embedded fibres.
    pub fibre_tension: Vec<[f64; 2]>,
    /// Rotated resin stress [11, 22, 12] in fibre axes (MPa).
    pub resin_stress: Vec<[f64; 3]>,
    /// Thickness (mm).
    pub thickness: Vec<f64>,
    /// Reference centroid.
    pub centroid0: Vec<Vector3<f64>>,
    /// Current centroid.
    pub centroid: Vec<Vector3<f64>>,
    /// Reference area.
    pub area: Vec<f64>,
    /// Out-of-plane waviness at the scale of the mesh (degrees), see
    /// [`measures::waviness`].
    pub waviness: Vec<f64>,
}

/// The derived measures of a state (SPEC §8).
#[derive(Debug, Clone, Default, Serialize)]
pub struct Measures {
    /// Largest |shear angle| (degrees).
    pub max_shear_deg: f64,
    /// Current centroid of the element where it occurs.
    pub max_shear_at: [f64; 3],
    /// Draw-in (mm), for a rectangular blank.
    pub draw_in: Option<DrawIn>,
    /// Shear along the diagonal (of a laminate: of its bottom ply, whose
    /// blank the model's is; every ply's in `ply_profiles`).
    pub profile_diagonal: Vec<ProfilePoint>,
    /// Shear along the median parallel to x (of a laminate, as above).
    pub profile_median: Vec<ProfilePoint>,
    /// A laminate's profiles ply by ply, bottom to top (empty for one
    /// ply), see [`Model::ply_profiles`].
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub ply_profiles: Vec<stack::PlyProfiles>,
    /// Reference area above the locking angle (mm²).
    pub area_above_locking: f64,
    /// Largest truss tension (N), 0 without trusses.
    pub max_fibre_tension_n: f64,
    /// Largest element waviness (degrees), see [`measures::waviness`].
    pub max_waviness_deg: f64,
    /// Reference area of the elements whose waviness exceeds
    /// [`measures::WRINKLE_THRESHOLD_DEG`] (mm²).
    pub wrinkle_area: f64,
}

impl Model {
    /// A model of a meshed rectangular blank of `material`: membranes
    /// (with embedded fibres or not), trusses from the mesh, lumped masses
    /// from the areal density, node sets.
    pub fn from_blank(blank: &RectangleBlank, material: &Material) -> Result<Self, ModelError> {
        material.validate()?;
        let mesh = blank.mesh()?;
        let mut model = Self::from_mesh(&mesh, material, blank.fibres)?;
        let set = |name: &str| -> [u32; 4] {
            let s = &mesh.node_sets[name];
            [s[0], s[1], s[2], s[3]]
        };
        let cells = (mesh.quads.len() + mesh.triangles.len()).max(1) as f64;
        model.blank = Some(BlankInfo {
            frame: blank.frame(),
            midpoints: set("edge_midpoints"),
            corners: set("corners"),
            cell_size: (blank.width * blank.height / cells).sqrt(),
        });
        Ok(model)
    }

    /// A model of any blank mesh.
    pub fn from_mesh(
        mesh: &BlankMesh,
        material: &Material,
        fibres: FibreRepresentation,
    ) -> Result<Self, ModelError> {
        material.validate()?;
        let embedded = fibres == FibreRepresentation::Embedded;
        let section = FabricSection::new(material.clone(), embedded);
        let element = |kind| move |error| ModelError::Element { kind, error };
        let mut membranes = Vec::new();
        if !mesh.quads.is_empty() {
            let warp = vec![mesh.warp; mesh.quads.len()];
            membranes.push(
                MembraneBatch::quads(section.clone(), &mesh.x0, mesh.quads.clone(), &warp)
                    .map_err(element("quad"))?,
            );
        }
        if !mesh.triangles.is_empty() {
            let warp = vec![mesh.warp; mesh.triangles.len()];
            membranes.push(
                MembraneBatch::triangles(section, &mesh.x0, mesh.triangles.clone(), &warp)
                    .map_err(element("triangle"))?,
            );
        }
        let trusses = Self::truss_batches(&mesh.trusses, &mesh.x0, &mesh.x0, material)?;
        let mass = Self::lumped_mass(mesh.x0.len(), &membranes);
        Ok(Self {
            x0: mesh.x0.clone(),
            mass,
            trusses,
            membranes,
            springs: Vec::new(),
            bending: Vec::new(),
            boundary: Vec::new(),
            gravity: Vector3::zeros(),
            loads: Vec::new(),
            pressure: Vec::new(),
            node_sets: mesh.node_sets.clone(),
            blank: None,
            tools: Vec::new(),
            contact_offset: 0.5 * material.thickness,
            plies: Vec::new(),
        })
    }

    /// One truss batch per yarn family for the mesh's `specs`, on the
    /// reference positions `x0`. A truss's section A₀ = t_f·(strip area /
    /// its length in `flat`, the flat blank the strips were measured on);
    /// `flat` and `x0` differ only for a blank bent before the run.
    ///
    /// One batch per family, so that a node's mass is shared among the
    /// trusses of one family (the stable step of a truss chain).
    pub fn truss_batches(
        specs: &[blank::TrussSpec],
        flat: &[Vector3<f64>],
        x0: &[Vector3<f64>],
        material: &Material,
    ) -> Result<Vec<TrussBatch>, ModelError> {
        let mut batches = Vec::new();
        for family in 0..2u8 {
            let specs: Vec<_> = specs.iter().filter(|t| t.family == family).collect();
            if specs.is_empty() {
                continue;
            }
            let nodes: Vec<[u32; 2]> = specs.iter().map(|t| t.nodes).collect();
            let section = specs
                .iter()
                .map(|t| {
                    let [i, j] = t.nodes;
                    let length = (flat[j as usize] - flat[i as usize]).norm();
                    material.family_thickness() * t.strip_area / length
                })
                .collect();
            batches.push(
                TrussBatch::new(material.fibre, x0, nodes, section).map_err(|error| {
                    ModelError::Element {
                        kind: "truss",
                        error,
                    }
                })?,
            );
        }
        Ok(batches)
    }

    /// The lumped nodal masses of `membranes` over `node_count` nodes: each
    /// node gets ρh·∫Nₐ dA of every element it belongs to.
    pub fn lumped_mass(node_count: usize, membranes: &[MembraneBatch]) -> Vec<f64> {
        let mut mass = vec![0.0; node_count];
        for b in membranes {
            let rho_h = b.section.material.areal_density();
            for e in 0..b.len() {
                for (&n, a) in b.element_nodes(e).iter().zip(b.nodal_areas(e)) {
                    mass[n as usize] += rho_h * a;
                }
            }
        }
        mass
    }

    /// Adds yarn bending with rigidities `rigidity` = [warp, weft] (N·mm)
    /// on the lines of the membranes' edges that run along the yarns: the
    /// warp `warp` and the weft `normal × warp` of a blank whose plane has
    /// the normal `normal` (see `drape_elements::BendingBatch`).
    ///
    /// Lines are clamped at the nodes the boundary conditions fix in place
    /// already ([`Motion::Fixed`], all three components; see
    /// `BendingBatch::clamp`): add bending after them.
    ///
    /// Fails when the mesh has no such line.
    pub fn add_yarn_bending(
        &mut self,
        warp: Vector3<f64>,
        normal: Vector3<f64>,
        rigidity: [f64; 2],
    ) -> Result<(), ModelError> {
        self.add_yarn_bending_of(0..self.membranes.len(), warp, normal, rigidity)
    }

    /// [`Self::add_yarn_bending`] on the lines of the membrane batches
    /// `membranes` only (one ply of a stack: its own yarns, its own
    /// rigidity).
    pub fn add_yarn_bending_of(
        &mut self,
        membranes: std::ops::Range<usize>,
        warp: Vector3<f64>,
        normal: Vector3<f64>,
        rigidity: [f64; 2],
    ) -> Result<(), ModelError> {
        let n = self.node_count();
        let mut area = vec![0.0; n];
        for b in &self.membranes[membranes.clone()] {
            for e in 0..b.len() {
                for (&node, a) in b.element_nodes(e).iter().zip(b.nodal_areas(e)) {
                    area[node as usize] += a;
                }
            }
        }
        let (triplets, _) = self.yarn_lines(membranes, warp, normal);
        if triplets.is_empty() {
            return Err(ModelError::NoYarnLines);
        }
        let mut batch =
            BendingBatch::new(&self.x0, &triplets, &area, rigidity).map_err(|error| {
                ModelError::Element {
                    kind: "bending",
                    error,
                }
            })?;
        let mut held = vec![false; n];
        for bc in &self.boundary {
            if matches!(bc.motion, Motion::Fixed) && bc.components == [true; 3] {
                for &node in &bc.nodes {
                    held[node as usize] = true;
                }
            }
        }
        batch.clamp(&held);
        self.bending.push(batch);
        Ok(())
    }

    /// How far the membranes' mesh lines follow the yarns (see
    /// [`YarnCoverage`]), for a warp `warp` in a blank of normal `normal`:
    /// what [`Self::add_yarn_bending`] would bend.
    pub fn yarn_coverage(&self, warp: Vector3<f64>, normal: Vector3<f64>) -> YarnCoverage {
        self.yarn_coverage_of(0..self.membranes.len(), warp, normal)
    }

    /// [`Self::yarn_coverage`] of the membrane batches `membranes` only
    /// (one ply of a stack): what [`Self::add_yarn_bending_of`] would bend.
    pub fn yarn_coverage_of(
        &self,
        membranes: std::ops::Range<usize>,
        warp: Vector3<f64>,
        normal: Vector3<f64>,
    ) -> YarnCoverage {
        let (triplets, edges) = self.yarn_lines(membranes.clone(), warp, normal);
        let n = self.node_count();
        // A node on an edge that only one element owns is on the blank's
        // outline, where a line ends and no triplet can sit.
        let mut on_outline = vec![false; n];
        for (k, &[a, b]) in edges.iter().enumerate() {
            let shared = (k > 0 && edges[k - 1] == [a, b])
                || edges.get(k + 1).is_some_and(|&next| next == [a, b]);
            if !shared {
                on_outline[a as usize] = true;
                on_outline[b as usize] = true;
            }
        }
        let mut family = vec![[false; 2]; n];
        for t in &triplets {
            family[t.nodes[1] as usize][t.family as usize] = true;
        }
        let used = self.node_use(membranes);
        let inner = (0..n).filter(|&j| used[j] && !on_outline[j]);
        YarnCoverage {
            interior_nodes: inner.clone().count(),
            covered_nodes: inner.filter(|&j| family[j] == [true; 2]).count(),
            triplets: triplets.len(),
        }
    }

    /// Which nodes some membrane of the batches `membranes` uses.
    fn node_use(&self, membranes: std::ops::Range<usize>) -> Vec<bool> {
        let mut used = vec![false; self.node_count()];
        for b in &self.membranes[membranes] {
            for e in 0..b.len() {
                for &node in b.element_nodes(e) {
                    used[node as usize] = true;
                }
            }
        }
        used
    }

    /// The yarn-line triplets of the edges of the membrane batches
    /// `membranes` (see `drape_elements::yarn_triplets`), and those edges,
    /// each as its sorted node pair once per element that has it, sorted.
    fn yarn_lines(
        &self,
        membranes: std::ops::Range<usize>,
        warp: Vector3<f64>,
        normal: Vector3<f64>,
    ) -> (Vec<drape_elements::YarnTriplet>, Vec<[u32; 2]>) {
        let mut edges = Vec::new();
        for b in &self.membranes[membranes] {
            for e in 0..b.len() {
                let nodes = b.element_nodes(e);
                for (k, &a) in nodes.iter().enumerate() {
                    let mut edge = [a, nodes[(k + 1) % nodes.len()]];
                    edge.sort_unstable();
                    edges.push(edge);
                }
            }
        }
        edges.sort_unstable();
        // An edge between two elements appears twice; once is enough for
        // the lines.
        let mut unique = edges.clone();
        unique.dedup();
        let warp = warp.normalize();
        let weft = normal.cross(&warp).normalize();
        (yarn_triplets(&self.x0, &unique, [warp, weft]), edges)
    }

    /// Total yarn bending energy at positions `x`.
    pub fn bending_energy(&self, x: &[Vector3<f64>]) -> Result<f64, ElementError> {
        self.bending.iter().map(|b| b.energy(x)).sum()
    }

    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.x0.len()
    }

    /// Number of membrane elements over all batches.
    pub fn membrane_count(&self) -> usize {
        self.membranes.iter().map(|b| b.len()).sum()
    }

    /// A named node set.
    pub fn node_set(&self, name: &str) -> Result<&[u32], ModelError> {
        self.node_sets
            .get(name)
            .map(Vec::as_slice)
            .ok_or_else(|| ModelError::UnknownNodeSet(name.to_owned()))
    }

    /// Checks that every node index used exists.
    pub fn check(&self) -> Result<(), ModelError> {
        let count = self.node_count();
        let bad = |node: u32| ModelError::NoSuchNode { node, count };
        for bc in &self.boundary {
            if let Some(&n) = bc.nodes.iter().find(|&&n| n as usize >= count) {
                return Err(bad(n));
            }
        }
        for s in &self.springs {
            if let Some(&n) = s.nodes.iter().find(|&&n| n as usize >= count) {
                return Err(bad(n));
            }
        }
        for t in &self.tools {
            t.validate().map_err(ModelError::Tool)?;
        }
        for l in &self.loads {
            if let Some(&n) = l.nodes.iter().find(|&&n| n as usize >= count) {
                return Err(bad(n));
            }
        }
        for p in &self.pressure {
            let mut nodes = p.quads.iter().flatten().chain(p.triangles.iter().flatten());
            if let Some(&n) = nodes.find(|&&n| n as usize >= count) {
                return Err(bad(n));
            }
        }
        Ok(())
    }

    /// The features in use.
    pub fn features(&self) -> Features {
        Features {
            trusses: self.trusses.iter().any(|b| !b.is_empty()),
            embedded_fibres: self
                .membranes
                .iter()
                .any(|b| b.section.embedded_fibres && !b.is_empty()),
            viscoelastic: self
                .membranes
                .iter()
                .any(|b| b.section.material.resin.is_viscoelastic()),
            springs: self.springs.iter().any(|b| !b.is_empty()),
            gravity: self.gravity != Vector3::zeros(),
            loads: !self.loads.is_empty(),
            prescribed_motion: self
                .boundary
                .iter()
                .any(|b| !matches!(b.motion, Motion::Fixed)),
            contact: !self.tools.is_empty(),
            friction: self.tools.iter().any(|t| t.friction > 0.0),
            force_driven_tools: self.tools.iter().any(|t| t.is_force_driven()),
            bending: self.bending.iter().any(|b| !b.is_empty()),
            pressure: self.pressure.iter().any(|p| !p.is_empty()),
        }
    }

    /// The slot layout of the current batches and its node adjacency.
    pub fn slot_layout(&self) -> SlotLayout {
        let mut layout = SlotLayout::default();
        let mut owners: Vec<u32> = Vec::new();
        for b in &self.trusses {
            layout.truss_offsets.push(owners.len());
            owners.extend(b.nodes.iter().flatten());
        }
        for b in &self.membranes {
            layout.membrane_offsets.push(owners.len());
            for e in 0..b.len() {
                owners.extend(b.element_nodes(e));
            }
        }
        for b in &self.springs {
            layout.spring_offsets.push(owners.len());
            owners.extend(&b.nodes);
        }
        for b in &self.bending {
            layout.bending_offsets.push(owners.len());
            owners.extend(b.nodes.iter().flatten());
        }
        layout.len = owners.len();
        (layout.node_ptr, layout.node_slots) = node_slots(
            self.node_count(),
            owners.iter().enumerate().map(|(s, &o)| (o, s as u32)),
        );
        layout
    }

    /// Whether `history` has one array of the right length per membrane
    /// batch.
    pub fn history_fits(&self, history: &[Vec<f64>]) -> bool {
        history.len() == self.membranes.len()
            && self
                .membranes
                .iter()
                .zip(history)
                .all(|(b, h)| h.len() == b.len() * b.element_history_len())
    }

    /// Each membrane batch's history element after element (as
    /// [`MembraneBatch::element_history`] gives an element's), whatever order
    /// the batch keeps it in: the order of a file that must read back into
    /// any build (checkpoints).
    ///
    /// # Panics
    /// If `history` does not fit the model ([`Self::history_fits`]).
    pub fn history_to_element_major(&self, history: &[Vec<f64>]) -> Vec<Vec<f64>> {
        assert!(self.history_fits(history), "a history of this model");
        self.membranes
            .iter()
            .zip(history)
            .map(|(b, h)| b.history_to_element_major(h))
            .collect()
    }

    /// The inverse of [`Self::history_to_element_major`]; `None` if
    /// `history` does not fit the model.
    pub fn history_from_element_major(&self, history: &[Vec<f64>]) -> Option<Vec<Vec<f64>>> {
        self.history_fits(history).then(|| {
            self.membranes
                .iter()
                .zip(history)
                .map(|(b, h)| b.history_from_element_major(h))
                .collect()
        })
    }

    /// The undeformed state at rest at t = 0.
    pub fn initial_state(&self) -> State {
        State {
            time: 0.0,
            step: 0,
            x: self.x0.clone(),
            v: vec![Vector3::zeros(); self.node_count()],
            history: self.membranes.iter().map(|b| b.initial_history()).collect(),
        }
    }

    /// Output fields of every membrane element at `state`.
    pub fn element_fields(&self, state: &State) -> Result<ElementFields, ElementError> {
        let mut out = ElementFields::default();
        for (b, h) in self.membranes.iter().zip(&state.history) {
            for e in 0..b.len() {
                let o = b.element_output(e, &state.x, &b.element_history(h, e))?;
                out.shear.push(o.shear_angle);
                out.fibre_stretch.push(o.fibre_stretch);
                out.fibre_direction.push(o.fibre_direction);
                out.fibre_stress.push(o.fibre_stress);
                let m = &b.section.material;
                out.fibre_tension.push(
                    o.fibre_stretch
                        .map(|l| m.family_thickness() * m.fibre.stress(l.ln()) / l),
                );
                out.resin_stress.push(o.resin_stress);
                out.thickness.push(o.thickness);
                let nodes = b.element_nodes(e);
                let k = nodes.len() as f64;
                out.centroid0.push(
                    nodes
                        .iter()
                        .map(|&n| self.x0[n as usize])
                        .sum::<Vector3<f64>>()
                        / k,
                );
                out.centroid.push(
                    nodes
                        .iter()
                        .map(|&n| state.x[n as usize])
                        .sum::<Vector3<f64>>()
                        / k,
                );
                out.area.push(b.element_area(e));
            }
        }
        out.waviness = self.waviness(&state.x);
        Ok(out)
    }

    /// The waviness of every membrane element at positions `x` (degrees),
    /// see [`measures::waviness`].
    pub fn waviness(&self, x: &[Vector3<f64>]) -> Vec<f64> {
        let elements: Vec<&[u32]> = self
            .membranes
            .iter()
            .flat_map(|b| (0..b.len()).map(move |e| b.element_nodes(e)))
            .collect();
        measures::waviness(&elements, x)
    }

    /// The fold check of `state` (see [`folds::fold_check`]), from its
    /// element fields.
    pub fn fold_check(&self, state: &State, fields: &ElementFields) -> folds::FoldCheck {
        let elements: Vec<&[u32]> = self
            .membranes
            .iter()
            .flat_map(|b| (0..b.len()).map(move |e| b.element_nodes(e)))
            .collect();
        let yarns = self.trusses.iter().flat_map(|b| {
            (0..b.len()).filter_map(move |e| {
                let [i, j] = b.nodes[e].map(|n| state.x[n as usize]);
                let out = b.element_output(e, &state.x).ok()?;
                Some((out.stretch, b.length[e], 0.5 * (i + j)))
            })
        });
        folds::fold_check(
            &elements,
            &state.x,
            &fields.waviness,
            &fields.area,
            &fields.centroid,
        )
        .with_gathering(folds::Gathering::of(yarns))
    }

    /// The largest truss tension (N) at positions `x`.
    pub fn max_truss_tension(&self, x: &[Vector3<f64>]) -> Result<f64, ElementError> {
        let mut max = 0.0f64;
        for b in &self.trusses {
            for e in 0..b.len() {
                max = max.max(b.element_output(e, x)?.tension);
            }
        }
        Ok(max)
    }

    /// The derived measures of `state`, with `locking_deg` the locking
    /// angle for the area at risk of wrinkling.
    pub fn measures(&self, state: &State, locking_deg: f64) -> Result<Measures, ElementError> {
        let fields = self.element_fields(state)?;
        let mut m = Measures::default();
        if let Some((i, g)) = fields
            .shear
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        {
            m.max_shear_deg = g.abs().to_degrees();
            m.max_shear_at = fields.centroid[i].into();
        }
        m.area_above_locking =
            measures::area_above(&fields.shear, &fields.area, locking_deg.to_radians());
        m.max_fibre_tension_n = self.max_truss_tension(&state.x)?;
        (m.max_waviness_deg, m.wrinkle_area) =
            measures::wrinkle_indicator(&fields.waviness, &fields.area);
        if let Some(info) = &self.blank {
            m.draw_in = Some(measures::draw_in(
                &info.frame,
                &self.x0,
                &state.x,
                info.midpoints,
                info.corners,
            ));
            let band = 0.5 * info.cell_size;
            let profile = |line| {
                measures::shear_profile(&info.frame, &fields.centroid0, &fields.shear, line, band)
            };
            m.profile_diagonal = profile(ProfileLine::Diagonal);
            m.profile_median = profile(ProfileLine::MedianX);
        }
        m.ply_profiles = self.ply_profiles(&fields);
        if let Some(bottom) = m.ply_profiles.first() {
            // The model's lines cross every ply: the bottom ply's own.
            m.profile_diagonal = bottom.diagonal.clone();
            m.profile_median = bottom.median.clone();
        }
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn amplitudes_are_the_contact_crates() {
        assert_eq!(Amplitude::Ramp { duration: 2.0 }.value(1.0), 0.5);
    }
}
