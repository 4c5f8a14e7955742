//! Blank meshes from files: Gmsh `.msh` (format 4.1, ASCII or binary, read
//! with `mshio`) and Abaqus `.inp` (a small keyword reader of its own, as no
//! crate reads it), into an [`ImportedMesh`]: reference nodes, 0-based
//! triangles and quads, and named node sets for springs and boundary
//! conditions.
//!
//! ```
//! use std::path::Path;
//! use drape_io::mesh_import::parse_abaqus;
//!
//! let text = "\
//! ** two triangles and a quad
//! *NODE, NSET=ALL_NODES
//! 10, 0, 0
//! 11, 1, 0
//! 12, 1, 1
//! 13, 0, 1
//! 14, 2, 0
//! 15, 2, 1
//! *ELEMENT, TYPE=M3D3, ELSET=LEFT_HALF
//! 1, 10, 11, 12
//! 2, 10, 12, 13
//! *ELEMENT, TYPE=S4R
//! 3, 11, 14, 15, 12
//! *NSET, NSET=clamp
//! 10, 13
//! ";
//! let mesh = parse_abaqus(text, Path::new("plate.inp")).unwrap();
//! assert_eq!((mesh.x0.len(), mesh.triangles.len(), mesh.quads.len()), (6, 2, 1));
//! assert_eq!(mesh.triangles[0], [0, 1, 2]);
//! assert_eq!(mesh.node_sets["clamp"], [0, 3]);
//! assert_eq!(mesh.node_sets["elset:LEFT_HALF"], [0, 1, 2, 3]);
//! assert_eq!(mesh.node_sets["boundary"].len(), 6);
//! ```
//!
//! # What is read
//!
//! - **Gmsh 4.1**: nodes; 3-node triangles (type 2) and 4-node quads (type
//!   3) become membranes; 2-node lines (1) and points (15) only feed node
//!   sets; any other type is an error naming it. Each physical group
//!   becomes a node set of its elements' nodes, named by `$PhysicalNames`
//!   (unnamed groups: `physical:<dim>:<tag>`). Other formats (2.2, 4.0) are
//!   refused with the command that converts them.
//! - **Abaqus** (module `abaqus`, which also reads rigid tool surfaces):
//!   `*NODE`, `*ELEMENT`, `*NSET`, `*ELSET`, `*INCLUDE`, and the
//!   Abaqus/CAE structure — `*PART`s placed by the `*INSTANCE`s of the
//!   `*ASSEMBLY`, translated and rotated, each instance a copy of its part.
//!   Every other keyword (materials, surfaces, rigid bodies, steps…) is
//!   skipped with its data. Element types: triangles M3D3, S3, S3R, S3RS,
//!   CPS3, STRI3; quads M3D4, M3D4R, S4, S4R, S4RS, S4R5, CPS4, CPS4R; the
//!   2-node lines T3D2, T2D2, B31, B21 and the points MASS, ROTARYI only
//!   feed element sets; any other type (rigid R3D4, second-order M3D8,
//!   solids…) is an error naming it and its line. Node labels are any
//!   integers, numbered 0, 1, … in the order the file defines them
//!   (instance by instance). An element set `NAME` becomes the node set
//!   `elset:NAME` (its elements' nodes), a node set keeps its name as
//!   first written (`INSTANCE.NAME` when the file has several instances).
//!
//! # Checks
//!
//! Every error names the file, the line where known (for Gmsh: the line
//! mshio's error points at, and each element's line in ASCII files) and
//! what is wrong: unknown element types, undefined node or element labels,
//! bad numbers, a duplicate label, an empty mesh, a broken file. Then the
//! geometry: an element that repeats a node, has no area (its normal —
//! the cross product of the diagonals of a quad, of two edges of a
//! triangle — vanishes) or is a quad folded at a corner (non-convex or a
//! bow-tie) is reported by its label and line.
//!
//! **Flipped elements are reported, not fixed.** Within each connected
//! piece, neighbours must run through their shared edge in opposite
//! directions (consistent node order); the elements whose order disagrees
//! with the piece's majority (by area) are inverted — for a flat or gently
//! curved blank, a clockwise element among counter-clockwise ones. A piece
//! whose summed normal points against the whole mesh's is inverted as a
//! whole (this catches an element whose neighbours do not share its nodes).
//! drape could flip them silently, but a flipped element usually means a
//! broken mesh (a bad import, duplicated nodes, a mirrored part), so the
//! error names the first one and how many there are.
//!
//! # Choices
//!
//! - Nodes used by no triangle or quad (an Abaqus reference node, Gmsh's
//!   unsaved geometry points) are dropped: they would carry no mass. A node
//!   set left empty by this is dropped too.
//! - Two node sets are added unless the file defines them: `all` and
//!   `boundary` (the nodes on edges that only one element uses).
//! - Node sets are sorted and free of repeats.
//! - A dense Gmsh node numbering is taken in file order from mshio, which
//!   does not keep the tags then; in ASCII files the tags are read from the
//!   text, so a dense numbering out of order is still mapped correctly.

use std::collections::{BTreeMap, HashMap, HashSet};
use std::path::{Path, PathBuf};

use drape_model::blank::BlankMesh;
use nalgebra::Vector3;

mod abaqus;

use abaqus::parse_abaqus_raw;
pub use abaqus::{
    SurfaceMesh, parse_abaqus, parse_abaqus_surface, read_abaqus, read_abaqus_surface, split_quad,
};

/// A blank mesh read from a file.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct ImportedMesh {
    /// Reference node positions (mm).
    pub x0: Vec<Vector3<f64>>,
    /// Quads, 0-based node indices in the file's order.
    pub quads: Vec<[u32; 4]>,
    /// Triangles, 0-based node indices in the file's order.
    pub triangles: Vec<[u32; 3]>,
    /// Named node sets (sorted node indices).
    pub node_sets: BTreeMap<String, Vec<u32>>,
    /// The file's label of each quad, for messages.
    pub quad_labels: Vec<i64>,
    /// The file's label of each triangle, for messages.
    pub triangle_labels: Vec<i64>,
    /// The Abaqus instances the mesh was assembled from, in file order
    /// (empty for a file without them): element labels repeat between
    /// instances.
    pub instances: Vec<String>,
}

impl ImportedMesh {
    /// The blank mesh for a model with embedded fibres whose warp is at
    /// `orientation_deg` from x: the warp (cos θ, sin θ, 0) is the same for
    /// every element, and each membrane integration point projects it on
    /// its own tangent plane (so a curved blank gets the warp's projection).
    pub fn blank_mesh(&self, orientation_deg: f64) -> BlankMesh {
        let (s, c) = orientation_deg.to_radians().sin_cos();
        BlankMesh {
            x0: self.x0.clone(),
            quads: self.quads.clone(),
            triangles: self.triangles.clone(),
            warp: Vector3::new(c, s, 0.0),
            trusses: Vec::new(),
            node_sets: self.node_sets.clone(),
        }
    }

    /// Number of membrane elements.
    pub fn element_count(&self) -> usize {
        self.quads.len() + self.triangles.len()
    }
}

/// What kind of problem a mesh file has.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ImportErrorKind {
    /// The file cannot be read.
    Read,
    /// The file is broken: not the format, a missing or extra field.
    Syntax,
    /// A format feature drape does not read (a Gmsh 2.2 file, an imported
    /// Abaqus instance, an unknown file extension).
    Unsupported,
    /// An element type drape cannot use.
    UnsupportedElement,
    /// An element or set names a node that does not exist.
    UndefinedNode,
    /// A set names an element that does not exist.
    UndefinedElement,
    /// A set refers to a set that is not defined before it.
    UndefinedSet,
    /// A number that cannot be read, or is not finite.
    BadNumber,
    /// A label defined twice.
    Duplicate,
    /// No triangle or quad.
    Empty,
    /// An element with a repeated node, without area, or folded.
    Degenerate,
    /// An element whose node order runs against its neighbours'.
    Inverted,
}

/// A mesh file that cannot be used: where and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{}{}: {message}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct ImportError {
    /// The file (an included file, for an error inside it).
    pub file: PathBuf,
    /// The 1-based line, when known.
    pub line: Option<usize>,
    /// What kind of problem.
    pub kind: ImportErrorKind,
    /// What is wrong, naming the element, node or set.
    pub message: String,
}

fn error(
    file: &Path,
    line: Option<usize>,
    kind: ImportErrorKind,
    message: impl Into<String>,
) -> ImportError {
    ImportError {
        file: file.to_owned(),
        line,
        kind,
        message: message.into(),
    }
}

/// Reads a Gmsh `.msh` (4.1) or an Abaqus `.inp` file, by its extension.
pub fn read_mesh(path: impl AsRef<Path>) -> Result<ImportedMesh, ImportError> {
    let path = path.as_ref();
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .as_deref()
    {
        Some("msh") => read_gmsh(path),
        Some("inp") => read_abaqus(path),
        _ => Err(error(
            path,
            None,
            ImportErrorKind::Unsupported,
            "expected a Gmsh .msh (format 4.1) or an Abaqus .inp file",
        )),
    }
}

/// [`read_mesh`], turning inverted elements over instead of refusing
/// them: each element whose node order runs against its neighbours' (by
/// the majority rule of the module's "Checks") gets the order of the rest.
/// Returns the mesh and how many elements were turned.
pub fn read_mesh_reoriented(path: impl AsRef<Path>) -> Result<(ImportedMesh, usize), ImportError> {
    let path = path.as_ref();
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let (raw, hint) = match extension.as_deref() {
        Some("msh") => parse_gmsh_raw(&read_bytes(path)?, path)?,
        Some("inp") => parse_abaqus_raw(&String::from_utf8_lossy(&read_bytes(path)?), path)?,
        _ => return read_mesh(path).map(|m| (m, 0)),
    };
    finish(raw, hint, true)
}

fn read_bytes(path: &Path) -> Result<Vec<u8>, ImportError> {
    std::fs::read(path).map_err(|e| {
        error(
            path,
            None,
            ImportErrorKind::Read,
            format!("cannot read the mesh: {e}"),
        )
    })
}

/// The 1-based line of byte `offset`.
fn line_at(bytes: &[u8], offset: usize) -> usize {
    bytes[..offset.min(bytes.len())]
        .iter()
        .filter(|&&b| b == b'\n')
        .count()
        + 1
}

// ---------------------------------------------------------------------------
// Shared: checks and the final mesh.
// ---------------------------------------------------------------------------

/// An element as read, before the checks.
#[derive(Debug, Clone)]
struct RawElement {
    label: i64,
    /// 0-based nodes; the 4th is unused for a triangle.
    nodes: [u32; 4],
    /// 3 or 4.
    len: usize,
    /// Index into [`RawMesh::files`].
    file: usize,
    line: Option<usize>,
}

impl RawElement {
    fn nodes(&self) -> &[u32] {
        &self.nodes[..self.len]
    }
}

/// A mesh as read, before the checks.
#[derive(Debug, Default)]
struct RawMesh {
    files: Vec<PathBuf>,
    x0: Vec<Vector3<f64>>,
    /// The file's label of each node, for messages.
    node_labels: Vec<i64>,
    elements: Vec<RawElement>,
    node_sets: BTreeMap<String, Vec<u32>>,
    /// The Abaqus instances placed.
    instances: Vec<String>,
}

impl RawMesh {
    fn element_error(&self, e: &RawElement, kind: ImportErrorKind, message: String) -> ImportError {
        let file = self.files.get(e.file).or(self.files.first());
        error(
            file.map_or(Path::new(""), PathBuf::as_path),
            e.line,
            kind,
            message,
        )
    }
}

/// Twice the area vector of an element: the cross product of the diagonals
/// of a quad (exact for a planar one, the mean plane of a warped one), of
/// two edges of a triangle.
fn normal(x: &[Vector3<f64>], nodes: &[u32]) -> Vector3<f64> {
    let p = |i: usize| x[nodes[i] as usize];
    if nodes.len() == 4 {
        (p(2) - p(0)).cross(&(p(3) - p(1)))
    } else {
        (p(1) - p(0)).cross(&(p(2) - p(0)))
    }
}

/// Checks the elements and builds the mesh: geometry, orientation, unused
/// nodes dropped, `all` and `boundary` added. With `reorient`, inverted
/// elements are turned over (and counted) instead of refused.
fn finish(
    raw: RawMesh,
    empty_hint: &str,
    reorient: bool,
) -> Result<(ImportedMesh, usize), ImportError> {
    let main = raw.files.first().cloned().unwrap_or_default();
    if raw.elements.is_empty() {
        return Err(error(
            &main,
            None,
            ImportErrorKind::Empty,
            format!("the mesh has no triangles or quads{empty_hint}"),
        ));
    }
    let normals = check_geometry(&raw)?;

    // Drop unused nodes (they would have no mass), keeping the file's order.
    let mut new_index = vec![u32::MAX; raw.x0.len()];
    for e in &raw.elements {
        for &n in e.nodes() {
            new_index[n as usize] = 0;
        }
    }
    let mut x0 = Vec::new();
    for (i, slot) in new_index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = x0.len() as u32;
            x0.push(raw.x0[i]);
        }
    }
    let mut elements: Vec<Vec<u32>> = raw
        .elements
        .iter()
        .map(|e| e.nodes().iter().map(|&n| new_index[n as usize]).collect())
        .collect();

    let (boundary, inverted) = check_orientation(&raw, &elements, &normals, reorient)?;
    // Turned over: the same first node, the others in reverse order.
    for (nodes, _) in elements.iter_mut().zip(&inverted).filter(|(_, i)| **i) {
        nodes[1..].reverse();
    }
    let turned = inverted.iter().filter(|&&i| i).count();

    let mut node_sets = BTreeMap::new();
    for (name, set) in &raw.node_sets {
        let mut kept: Vec<u32> = set
            .iter()
            .map(|&n| new_index[n as usize])
            .filter(|&n| n != u32::MAX)
            .collect();
        kept.sort_unstable();
        kept.dedup();
        if !kept.is_empty() {
            node_sets.insert(name.clone(), kept);
        }
    }
    node_sets
        .entry("all".to_owned())
        .or_insert_with(|| (0..x0.len() as u32).collect());
    node_sets.entry("boundary".to_owned()).or_insert(boundary);

    let mut mesh = ImportedMesh {
        x0,
        node_sets,
        instances: raw.instances.clone(),
        ..ImportedMesh::default()
    };
    for (e, nodes) in raw.elements.iter().zip(&elements) {
        match *nodes.as_slice() {
            [a, b, c] => {
                mesh.triangles.push([a, b, c]);
                mesh.triangle_labels.push(e.label);
            }
            [a, b, c, d] => {
                mesh.quads.push([a, b, c, d]);
                mesh.quad_labels.push(e.label);
            }
            _ => {}
        }
    }
    Ok((mesh, turned))
}

/// Each element's normal (twice its area vector), or the first element
/// that repeats a node, has no area or is folded.
fn check_geometry(raw: &RawMesh) -> Result<Vec<Vector3<f64>>, ImportError> {
    let x = &raw.x0;
    let mut normals = Vec::with_capacity(raw.elements.len());
    for e in &raw.elements {
        let nodes = e.nodes();
        let label = |n: u32| raw.node_labels[n as usize];
        let degenerate = |why: String| {
            raw.element_error(
                e,
                ImportErrorKind::Degenerate,
                format!("element {} is degenerate: {why}", e.label),
            )
        };
        for (i, &a) in nodes.iter().enumerate() {
            if nodes[i + 1..].contains(&a) {
                return Err(degenerate(format!(
                    "it repeats node {} (a collapsed quad should be a triangle)",
                    label(a)
                )));
            }
        }
        let n = normal(x, nodes);
        // Zero area relative to the element's size: exact zeros and
        // rounding-level areas (collinear nodes) alike.
        let longest = (0..nodes.len())
            .map(|i| (x[nodes[(i + 1) % nodes.len()] as usize] - x[nodes[i] as usize]).norm())
            .fold(0.0, f64::max);
        if !n.norm().is_finite() {
            return Err(degenerate(
                "its size overflows (coordinates near 1e308?)".into(),
            ));
        }
        if n.norm() <= 1e-10 * longest * longest {
            return Err(degenerate(
                "it has no area (its nodes are collinear or coincide)".into(),
            ));
        }
        if nodes.len() == 4 {
            // A convex quad turns the same way at every corner; a corner
            // turning the other way (or not at all) folds the element, and
            // its Jacobian vanishes or changes sign inside it.
            for k in 0..4 {
                let here = x[nodes[k] as usize];
                let next = x[nodes[(k + 1) % 4] as usize];
                let prev = x[nodes[(k + 3) % 4] as usize];
                if (next - here).cross(&(prev - here)).dot(&n) <= 0.0 {
                    return Err(degenerate(format!(
                        "it is folded at node {} (not convex, or its nodes are not in order round \
                         the element)",
                        label(nodes[k])
                    )));
                }
            }
        }
        normals.push(n);
    }
    Ok(normals)
}

/// One use of an edge by an element.
#[derive(Debug, Clone, Copy)]
struct EdgeUse {
    element: u32,
    /// Whether the element runs from the lower node to the higher.
    forward: bool,
}

/// Checks that every element's node order agrees with its neighbours' and
/// each piece's with the whole mesh; returns the boundary nodes (on edges
/// that only one element uses) and, with `reorient`, which elements are
/// inverted (none without: an inverted element is an error then).
fn check_orientation(
    raw: &RawMesh,
    elements: &[Vec<u32>],
    normals: &[Vector3<f64>],
    reorient: bool,
) -> Result<(Vec<u32>, Vec<bool>), ImportError> {
    let mut edges: HashMap<(u32, u32), Vec<EdgeUse>> = HashMap::new();
    for (i, nodes) in elements.iter().enumerate() {
        for k in 0..nodes.len() {
            let (a, b) = (nodes[k], nodes[(k + 1) % nodes.len()]);
            edges
                .entry((a.min(b), a.max(b)))
                .or_default()
                .push(EdgeUse {
                    element: i as u32,
                    forward: a < b,
                });
        }
    }
    let mut boundary: Vec<u32> = edges
        .iter()
        .filter(|(_, uses)| uses.len() == 1)
        .flat_map(|(&(a, b), _)| [a, b])
        .collect();
    boundary.sort_unstable();
    boundary.dedup();

    // Neighbours across manifold edges, and whether they must run the same
    // edge the same way (never, for a consistent order). Edges shared by
    // more than two elements (a T-junction) carry no orientation.
    let count = elements.len();
    let mut neighbours: Vec<Vec<(u32, bool)>> = vec![Vec::new(); count];
    for uses in edges.values() {
        if let [u, v] = uses.as_slice() {
            let same_direction = u.forward == v.forward;
            neighbours[u.element as usize].push((v.element, same_direction));
            neighbours[v.element as usize].push((u.element, same_direction));
        }
    }
    // Each element's order relative to its piece's first element (true =
    // opposite), by a search in file order so that the result does not
    // depend on hashing.
    for list in &mut neighbours {
        list.sort_unstable();
    }
    let mut flipped: Vec<Option<bool>> = vec![None; count];
    let mut piece = vec![0usize; count];
    let mut pieces = 0;
    let mut stack = Vec::new();
    for seed in 0..count {
        if flipped[seed].is_some() {
            continue;
        }
        flipped[seed] = Some(false);
        piece[seed] = pieces;
        stack.push(seed);
        while let Some(e) = stack.pop() {
            let fe = flipped[e].unwrap_or(false);
            for &(nb, same_direction) in &neighbours[e] {
                let nb = nb as usize;
                if flipped[nb].is_none() {
                    flipped[nb] = Some(fe ^ same_direction);
                    piece[nb] = pieces;
                    stack.push(nb);
                }
            }
        }
        pieces += 1;
    }
    let flipped: Vec<bool> = flipped.into_iter().map(|f| f.unwrap_or(false)).collect();

    // The majority order of each piece, by area (a tie keeps the first
    // element's).
    let mut area = vec![[0.0f64; 2]; pieces];
    for e in 0..count {
        area[piece[e]][flipped[e] as usize] += normals[e].norm();
    }
    let majority: Vec<bool> = area.iter().map(|a| a[1] > a[0]).collect();
    let mut inverted: Vec<bool> = (0..count)
        .map(|e| flipped[e] != majority[piece[e]])
        .collect();

    // Pieces against the whole: each piece's normal with its majority order,
    // compared with their sum; a piece whose normals cancel (closed, or
    // strongly curved) says nothing.
    let mut piece_normal = vec![Vector3::zeros(); pieces];
    for e in 0..count {
        let sign = if inverted[e] { -1.0 } else { 1.0 };
        piece_normal[piece[e]] += sign * normals[e];
    }
    let total: Vector3<f64> = piece_normal.iter().sum();
    let total_area: f64 = area.iter().map(|a| a[0] + a[1]).sum();
    if pieces > 1 && total.norm() > 1e-3 * total_area {
        let against: Vec<bool> = piece_normal
            .iter()
            .zip(&area)
            .map(|(n, a)| n.norm() > 1e-3 * (a[0] + a[1]) && n.dot(&total) < 0.0)
            .collect();
        for e in 0..count {
            if against[piece[e]] {
                inverted[e] = !inverted[e];
            }
        }
    }

    if reorient {
        return Ok((boundary, inverted));
    }
    let how_many = inverted.iter().filter(|&&i| i).count();
    if let Some(first) = inverted.iter().position(|&i| i) {
        let e = &raw.elements[first];
        let others = match how_many {
            1 => String::new(),
            n => format!(" ({n} elements are, in all)"),
        };
        return Err(raw.element_error(
            e,
            ImportErrorKind::Inverted,
            format!(
                "element {} is inverted{others}: its nodes run round it the other way from the \
                 rest of the blank's (its normal points against theirs, a clockwise element \
                 among counter-clockwise ones); flipped elements are reported rather than fixed \
                 because they usually mean a broken mesh — reverse their node order in the \
                 mesher, or give `reorient = true` in [fabric.blank] to have drape turn them",
                e.label
            ),
        ));
    }
    Ok((boundary, inverted))
}

// ---------------------------------------------------------------------------
// Gmsh.
// ---------------------------------------------------------------------------

/// Reads a Gmsh `.msh` file of format 4.1 (ASCII or binary).
pub fn read_gmsh(path: impl AsRef<Path>) -> Result<ImportedMesh, ImportError> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    parse_gmsh(&bytes, path)
}

/// Reads the bytes of a Gmsh `.msh` file of format 4.1; `path` names it in
/// errors.
pub fn parse_gmsh(bytes: &[u8], path: &Path) -> Result<ImportedMesh, ImportError> {
    let (raw, hint) = parse_gmsh_raw(bytes, path)?;
    finish(raw, hint, false).map(|(mesh, _)| mesh)
}

/// The mesh of a Gmsh file as read, before the checks, and the hint for
/// an empty one.
fn parse_gmsh_raw(bytes: &[u8], path: &Path) -> Result<(RawMesh, &'static str), ImportError> {
    let syntax =
        |line: Option<usize>, message: String| error(path, line, ImportErrorKind::Syntax, message);
    let binary = check_gmsh_header(bytes, path)?;
    check_gmsh_sections(bytes, path, binary)?;
    if !binary {
        check_ascii_element_types(bytes, path)?;
    }
    // mshio 0.4 still has a few `unwrap`s on malformed input; a panic there
    // is this file's fault and becomes its error.
    let parsed = std::panic::catch_unwind(|| {
        mshio::parse_msh_bytes(bytes).map_err(|e| describe_mshio_error(&e, bytes, binary))
    });
    let msh = match parsed {
        Ok(Ok(msh)) => msh,
        Ok(Err((line, message))) => return Err(syntax(line, message)),
        Err(_) => {
            return Err(syntax(
                None,
                "not a valid Gmsh 4.1 file (the reader gave up on it)".into(),
            ));
        }
    };
    let names = physical_names(bytes, path)?;
    let text_tags = if binary { None } else { ascii_node_tags(bytes) };

    let mut raw = RawMesh {
        files: vec![path.to_owned()],
        ..RawMesh::default()
    };
    let mut index: HashMap<u64, u32> = HashMap::new();
    if let Some(nodes) = &msh.data.nodes {
        let mut global = 0u64;
        for block in &nodes.node_blocks {
            // The tag of each node of the block: mshio keeps them for a
            // sparse numbering; a dense one is min_tag + position in the
            // file, unless the ASCII text says otherwise.
            let mut tags = vec![0u64; block.nodes.len()];
            match &block.node_tags {
                Some(map) => {
                    for (&tag, &i) in map {
                        if let Some(slot) = tags.get_mut(i) {
                            *slot = tag;
                        }
                    }
                }
                None => {
                    for (i, slot) in tags.iter_mut().enumerate() {
                        let g = global + i as u64;
                        *slot = text_tags
                            .as_ref()
                            .filter(|t| t.len() as u64 == nodes.num_nodes)
                            .and_then(|t| t.get(g as usize).copied())
                            .unwrap_or_else(|| nodes.min_node_tag.saturating_add(g));
                    }
                }
            }
            global += block.nodes.len() as u64;
            for (node, &tag) in block.nodes.iter().zip(&tags) {
                let label = i64::try_from(tag).map_err(|_| {
                    error(
                        path,
                        None,
                        ImportErrorKind::BadNumber,
                        format!("node tag {tag} is too large"),
                    )
                })?;
                let x = Vector3::new(node.x, node.y, node.z);
                if !x.iter().all(|c| c.is_finite()) {
                    return Err(error(
                        path,
                        None,
                        ImportErrorKind::BadNumber,
                        format!("node {tag} has a coordinate that is not a finite number"),
                    ));
                }
                let i = u32::try_from(raw.x0.len()).map_err(|_| {
                    error(
                        path,
                        None,
                        ImportErrorKind::Unsupported,
                        "more than 2³² nodes",
                    )
                })?;
                if index.insert(tag, i).is_some() {
                    return Err(error(
                        path,
                        None,
                        ImportErrorKind::Duplicate,
                        format!("node {tag} is defined twice"),
                    ));
                }
                raw.x0.push(x);
                raw.node_labels.push(label);
            }
        }
    }

    // Physical tags of each entity (dim, tag).
    let mut physical: HashMap<(i32, i32), Vec<i32>> = HashMap::new();
    if let Some(entities) = &msh.data.entities {
        for p in &entities.points {
            physical.insert((0, p.tag), p.physical_tags.clone());
        }
        for c in &entities.curves {
            physical.insert((1, c.tag), c.physical_tags.clone());
        }
        for s in &entities.surfaces {
            physical.insert((2, s.tag), s.physical_tags.clone());
        }
        for v in &entities.volumes {
            physical.insert((3, v.tag), v.physical_tags.clone());
        }
    }

    let lines = if binary {
        None
    } else {
        ElementLines::new(bytes)
    };
    let mut group_nodes: BTreeMap<(i32, i32), Vec<u32>> = BTreeMap::new();
    let mut seen_elements: HashSet<u64> = HashSet::new();
    if let Some(elements) = &msh.data.elements {
        for (b, block) in elements.element_blocks.iter().enumerate() {
            let type_code = block.element_type as i32;
            let membrane = match type_code {
                2 | 3 => true,
                1 | 15 => false,
                _ => {
                    let hint = element_type_hint(type_code.into());
                    return Err(error(
                        path,
                        lines.as_ref().and_then(|l| l.block_header(b)),
                        ImportErrorKind::UnsupportedElement,
                        format!(
                            "element type {type_code} ({:?}) of entity ({}, {}) is not \
                             supported{hint}: drape reads 3-node triangles (2) and 4-node quads \
                             (3) and takes lines (1) and points (15) for node sets only",
                            block.element_type, block.entity_dim, block.entity_tag
                        ),
                    ));
                }
            };
            let groups = physical
                .get(&(block.entity_dim, block.entity_tag))
                .cloned()
                .unwrap_or_default();
            for (k, element) in block.elements.iter().enumerate() {
                let line = || {
                    lines
                        .as_ref()
                        .and_then(|l| l.element(b, k, element.element_tag))
                };
                let tag = element.element_tag;
                if !seen_elements.insert(tag) {
                    return Err(error(
                        path,
                        line(),
                        ImportErrorKind::Duplicate,
                        format!("element {tag} is defined twice"),
                    ));
                }
                let mut nodes = [0u32; 4];
                for (slot, &n) in nodes.iter_mut().zip(&element.nodes) {
                    *slot = *index.get(&n).ok_or_else(|| {
                        error(
                            path,
                            line(),
                            ImportErrorKind::UndefinedNode,
                            format!("element {tag} uses node {n}, which the file does not define"),
                        )
                    })?;
                }
                let len = element.nodes.len().min(4);
                for &g in &groups {
                    group_nodes
                        .entry((block.entity_dim, g))
                        .or_default()
                        .extend_from_slice(&nodes[..len]);
                }
                if membrane {
                    raw.elements.push(RawElement {
                        label: i64::try_from(tag).map_err(|_| {
                            error(
                                path,
                                line(),
                                ImportErrorKind::BadNumber,
                                format!("element tag {tag} is too large"),
                            )
                        })?,
                        nodes,
                        len,
                        file: 0,
                        line: line(),
                    });
                }
            }
        }
    }
    for ((dim, tag), nodes) in group_nodes {
        let name = names
            .get(&(dim, tag))
            .cloned()
            .unwrap_or_else(|| format!("physical:{dim}:{tag}"));
        raw.node_sets.entry(name).or_default().extend(nodes);
    }
    Ok((
        raw,
        ": with physical groups, Gmsh saves only their elements — add the surface to a \
         physical group, or set Mesh.SaveAll = 1",
    ))
}

/// Checks the `$MeshFormat` header before mshio sees it (it panics on some
/// malformed headers and says little about old versions); returns whether
/// the file is binary.
fn check_gmsh_header(bytes: &[u8], path: &Path) -> Result<bool, ImportError> {
    let head = &bytes[..bytes.len().min(4096)];
    let text = String::from_utf8_lossy(head);
    let mut lines = text
        .lines()
        .enumerate()
        .skip_while(|(_, l)| l.trim().is_empty());
    let bad = |line: Option<usize>, m: &str| {
        error(
            path,
            line,
            ImportErrorKind::Syntax,
            format!("not a Gmsh mesh: {m}"),
        )
    };
    match lines.next() {
        Some((_, l)) if l.trim() == "$MeshFormat" => {}
        Some((i, _)) => return Err(bad(Some(i + 1), "expected `$MeshFormat` on the first line")),
        None => return Err(bad(None, "the file is empty")),
    }
    let Some((i, l)) = lines.next() else {
        return Err(bad(None, "the `$MeshFormat` header is cut short"));
    };
    let line = Some(i + 1);
    let fields: Vec<&str> = l.split_whitespace().collect();
    let [version, file_type, size] = fields[..] else {
        return Err(bad(
            line,
            "expected `4.1 0 8` (version, file type, data size)",
        ));
    };
    if version != "4.1" {
        return Err(error(
            path,
            line,
            ImportErrorKind::Unsupported,
            format!(
                "Gmsh format {version}: drape reads format 4.1 — convert it with \
                 `gmsh FILE -save -format msh41 -o NEW.msh` (or Mesh.MshFileVersion = 4.1)"
            ),
        ));
    }
    if !matches!(size, "4" | "8") {
        return Err(bad(line, &format!("data size `{size}`: expected 4 or 8")));
    }
    match file_type {
        "0" => Ok(false),
        "1" => Ok(true),
        _ => Err(bad(
            line,
            &format!("file type `{file_type}`: expected 0 (ASCII) or 1 (binary)"),
        )),
    }
}

/// The sections Gmsh 4.1 writes: each `$Name` is closed by `$EndName`.
const GMSH_SECTIONS: [&str; 13] = [
    "MeshFormat",
    "PhysicalNames",
    "Entities",
    "PartitionedEntities",
    "Nodes",
    "Elements",
    "Periodic",
    "GhostElements",
    "Parametrizations",
    "NodeData",
    "ElementData",
    "ElementNodeData",
    "InterpolationScheme",
];

/// Checks that every section is closed (mshio only says "not a valid
/// file" when an `$End…` line is missing). In an ASCII file the next
/// `$` line after a section's start must be its end; in a binary one
/// (whose data may hold any byte) the end must follow somewhere.
fn check_gmsh_sections(bytes: &[u8], path: &Path, binary: bool) -> Result<(), ImportError> {
    let mut from = 0;
    while let Some(i) = bytes[from..].iter().position(|&b| b == b'$') {
        let at = from + i;
        from = at + 1;
        if at > 0 && bytes[at - 1] != b'\n' {
            continue;
        }
        let name_end = bytes[at + 1..]
            .iter()
            .position(|b| !b.is_ascii_alphanumeric())
            .map_or(bytes.len(), |n| at + 1 + n);
        let name = String::from_utf8_lossy(&bytes[at + 1..name_end]).into_owned();
        if !GMSH_SECTIONS.contains(&name.as_str()) {
            continue;
        }
        let end_tag = format!("$End{name}");
        let line = line_at(bytes, at);
        let unclosed = |found: String| {
            error(
                path,
                Some(line),
                ImportErrorKind::Syntax,
                format!("the `${name}` section is not closed: expected `{end_tag}` {found}"),
            )
        };
        // At the end of the file: it is cut short, and its last line is
        // where the reader stopped.
        let cut_short = || {
            let last = line_at(bytes, bytes.len().saturating_sub(1));
            error(
                path,
                Some(last),
                ImportErrorKind::Syntax,
                format!(
                    "the file ends inside the `${name}` section of line {line}, without \
                     `{end_tag}` (cut short?)"
                ),
            )
        };
        if binary {
            match find_section(&bytes[name_end..], end_tag.as_bytes()) {
                Some(n) => from = name_end + n + end_tag.len(),
                None => return Err(cut_short()),
            }
            continue;
        }
        // The next line that starts with `$`.
        let mut next = name_end;
        let found = loop {
            match bytes[next..].iter().position(|&b| b == b'\n') {
                Some(n) if bytes.get(next + n + 1) == Some(&b'$') => break Some(next + n + 1),
                Some(n) => next += n + 1,
                None => break None,
            }
        };
        match found {
            Some(n) if bytes[n..].starts_with(end_tag.as_bytes()) => from = n + end_tag.len(),
            Some(n) => {
                let other: String = String::from_utf8_lossy(&bytes[n..])
                    .split_whitespace()
                    .next()
                    .unwrap_or("")
                    .to_owned();
                return Err(unclosed(format!(
                    "before `{other}` on line {}",
                    line_at(bytes, n)
                )));
            }
            None => return Err(cut_short()),
        }
    }
    Ok(())
}

/// Checks the element type of each block of an ASCII `$Elements` section
/// before mshio reads it: mshio refuses a type it does not know with "an
/// invalid element definition" and no type, and drape reads only a few
/// anyway. The error names the type and its block's line.
fn check_ascii_element_types(bytes: &[u8], path: &Path) -> Result<(), ImportError> {
    let Some(lines) = ElementLines::new(bytes) else {
        return Ok(());
    };
    for &line in &lines.headers {
        let Some(text) = lines.text(line) else {
            continue;
        };
        let fields: Vec<&str> = text.split_whitespace().collect();
        let Some(code) = fields.get(2).and_then(|t| t.parse::<i64>().ok()) else {
            continue;
        };
        if matches!(code, 1 | 2 | 3 | 15) {
            continue;
        }
        // Gmsh numbers its element types from 1 to 140 or so.
        let name = match code {
            4 => "Tet4",
            5 => "Hex8",
            6 => "Pri6",
            7 => "Pyr5",
            8 => "Lin3",
            9 => "Tri6",
            10 => "Qua9",
            11 => "Tet10",
            16 => "Qua8",
            1..=140 => "a Gmsh type",
            _ => "not a Gmsh element type",
        };
        return Err(error(
            path,
            Some(line),
            ImportErrorKind::UnsupportedElement,
            format!(
                "element type {code} ({name}) of entity ({}, {}) is not supported{}: drape \
                 reads 3-node triangles (2) and 4-node quads (3) and takes lines (1) and \
                 points (15) for node sets only",
                fields.first().unwrap_or(&"?"),
                fields.get(1).unwrap_or(&"?"),
                element_type_hint(code)
            ),
        ));
    }
    Ok(())
}

/// Why a Gmsh element type is refused, when a common case.
fn element_type_hint(code: i64) -> &'static str {
    match code {
        8 | 9 | 10 | 16 | 20..=28 => " (a higher-order element: mesh with Mesh.ElementOrder = 1)",
        4..=7 | 11..=14 | 17..=19 => " (a volume element: a blank is a surface mesh)",
        _ => "",
    }
}

/// mshio's error as (line, message): the innermost error, its line (ASCII)
/// or byte offset (binary), and the chain of what was being read.
fn describe_mshio_error(
    e: &mshio::MshParserError<&[u8]>,
    bytes: &[u8],
    binary: bool,
) -> (Option<usize>, String) {
    let trace = e.filtered_backtrace();
    let Some((input, kind)) = trace.first() else {
        return (None, "not a valid Gmsh 4.1 file".into());
    };
    let context: Vec<String> = trace[1..]
        .iter()
        .rev()
        .map(|(_, k)| k.context().map_or_else(|| k.to_string(), str::to_owned))
        .collect();
    let what = kind.to_string();
    let mut message = format!("not a valid Gmsh 4.1 file: {}", what.trim_end_matches('.'));
    if !context.is_empty() {
        message.push_str(&format!(" (reading {})", context.join(" › ")));
    }
    let start = bytes.as_ptr() as usize;
    let at = input.as_ptr() as usize;
    let offset = (at >= start && at <= start + bytes.len()).then(|| at - start);
    match offset {
        Some(o) if binary => {
            message.push_str(&format!(" at byte {o}"));
            (None, message)
        }
        Some(o) => (Some(line_at(bytes, o)), message),
        None => (None, message),
    }
}

/// The `$PhysicalNames` section (mshio skips it): (dim, tag) → name. The
/// section is text in binary files too.
fn physical_names(bytes: &[u8], path: &Path) -> Result<HashMap<(i32, i32), String>, ImportError> {
    let mut names = HashMap::new();
    let Some(start) = find_section(bytes, b"$PhysicalNames") else {
        return Ok(names);
    };
    let first_line = line_at(bytes, start);
    let rest = &bytes[start..];
    let end = find_section(rest, b"$EndPhysicalNames").unwrap_or(rest.len());
    let text = String::from_utf8_lossy(&rest[..end]);
    let mut lines = text.lines().enumerate().skip(1);
    let bad = |i: usize, m: &str| {
        error(
            path,
            Some(first_line + i),
            ImportErrorKind::Syntax,
            format!("$PhysicalNames: {m}"),
        )
    };
    let count = match lines.next() {
        Some((i, l)) => l
            .trim()
            .parse::<usize>()
            .map_err(|_| bad(i, "expected the number of names"))?,
        None => return Ok(names),
    };
    let mut found = 0;
    for (i, l) in lines.by_ref().take(count) {
        found += 1;
        let entry = l
            .trim()
            .split_once(char::is_whitespace)
            .and_then(|(dim, rest)| {
                let (tag, name) = rest.trim_start().split_once(char::is_whitespace)?;
                let name = name.trim().trim_matches('"');
                Some((dim.parse::<i32>().ok()?, tag.parse::<i32>().ok()?, name))
            });
        match entry {
            Some((dim, tag, name)) if !name.is_empty() => {
                names.insert((dim, tag), name.to_owned());
            }
            _ => return Err(bad(i, "expected `dim tag \"name\"`")),
        }
    }
    if found < count {
        return Err(bad(0, &format!("{count} names announced, {found} given")));
    }
    Ok(names)
}

/// The byte offset of a line that starts with `tag`.
fn find_section(bytes: &[u8], tag: &[u8]) -> Option<usize> {
    let mut from = 0;
    while let Some(i) = bytes[from..].windows(tag.len()).position(|w| w == tag) {
        let at = from + i;
        if at == 0 || bytes[at - 1] == b'\n' || bytes[at - 1] == b'\r' {
            return Some(at);
        }
        from = at + 1;
    }
    None
}

/// The node tags of an ASCII `$Nodes` section in file order, read from the
/// text because mshio drops them for a dense numbering (and so would map an
/// out-of-order file wrongly). None if the section does not scan as
/// expected: mshio's reading then stands.
fn ascii_node_tags(bytes: &[u8]) -> Option<Vec<u64>> {
    let start = find_section(bytes, b"$Nodes")?;
    let mut tokens = bytes[start..]
        .split(u8::is_ascii_whitespace)
        .filter(|t| !t.is_empty())
        .skip(1);
    let mut number = || -> Option<u64> { std::str::from_utf8(tokens.next()?).ok()?.parse().ok() };
    let blocks = number()?;
    let total = number()?;
    let (_min, _max) = (number()?, number()?);
    // Only what the file can hold: no allocation from a broken count.
    let mut tags = Vec::with_capacity((total as usize).min(bytes.len() / 2));
    for _ in 0..blocks {
        let (_dim, _entity, parametric, count) = (number()?, number()?, number()?, number()?);
        if parametric != 0 || (tags.len() as u64).saturating_add(count) > total {
            return None;
        }
        for _ in 0..count {
            tags.push(number()?);
        }
        for _ in 0..count.saturating_mul(3) {
            // A coordinate: consumed (it need not parse as a tag).
            let _ = number();
        }
    }
    (tags.len() as u64 == total).then_some(tags)
}

/// The lines of the elements of an ASCII `$Elements` section: Gmsh writes
/// the section header, then per block a header line and one line per
/// element. A computed line is given only when it starts with the
/// element's tag, so a file laid out otherwise gets no line rather than a
/// wrong one.
struct ElementLines<'a> {
    bytes: &'a [u8],
    /// Byte offset of each line's start.
    starts: Vec<usize>,
    /// 1-based line of each block's header.
    headers: Vec<usize>,
}

impl<'a> ElementLines<'a> {
    fn new(bytes: &'a [u8]) -> Option<Self> {
        let section = find_section(bytes, b"$Elements")?;
        let starts: Vec<usize> = std::iter::once(0)
            .chain(
                bytes
                    .iter()
                    .enumerate()
                    .filter(|&(_, &b)| b == b'\n')
                    .map(|(i, _)| i + 1),
            )
            .collect();
        let mut lines = Self {
            bytes,
            starts,
            headers: Vec::new(),
        };
        let first = line_at(bytes, section);
        let blocks: u64 = lines.first_token(first + 1)?.parse().ok()?;
        // Walk the block headers: each says how many element lines follow.
        let mut line = first + 2;
        for _ in 0..blocks {
            let text = lines.text(line)?;
            let count: usize = text.split_whitespace().nth(3)?.parse().ok()?;
            lines.headers.push(line);
            line = line.checked_add(count)?.checked_add(1)?;
        }
        Some(lines)
    }

    fn text(&self, line: usize) -> Option<String> {
        let start = *self.starts.get(line.checked_sub(1)?)?;
        let end = self.starts.get(line).copied().unwrap_or(self.bytes.len());
        Some(String::from_utf8_lossy(&self.bytes[start..end]).into_owned())
    }

    fn first_token(&self, line: usize) -> Option<String> {
        self.text(line)?
            .split_whitespace()
            .next()
            .map(str::to_owned)
    }

    fn block_header(&self, block: usize) -> Option<usize> {
        self.headers.get(block).copied()
    }

    fn element(&self, block: usize, k: usize, tag: u64) -> Option<usize> {
        let line = self.headers.get(block)?.checked_add(1 + k)?;
        (self.first_token(line)? == tag.to_string()).then_some(line)
    }
}
