//! The Abaqus `.inp` reader: a small keyword reader of its own (no crate
//! reads the format), for three uses that share it: a blank
//! ([`read_abaqus`], membrane and shell elements), a rigid tool's surface
//! ([`read_abaqus_surface`], rigid, surface, shell and membrane elements,
//! quads split into triangles) and the structural mesh of `drape export
//! --onto` (a blank's reader). It reads the mesh only: nodes, elements,
//! node and element sets, parts, the assembly and its instances; every
//! other keyword (materials, sections, surfaces, rigid bodies, steps…) is
//! skipped with its data.
//!
//! # Parts, assembly, instances
//!
//! A file written by Abaqus/CAE defines each mesh inside `*PART, NAME=…` …
//! `*END PART` and places it by `*INSTANCE, NAME=…, PART=…` … `*END
//! INSTANCE` inside `*ASSEMBLY`. Each instance is a copy of its part's
//! nodes and elements, moved by its data lines: the first is a
//! translation (x, y, z), the second a rotation (point a, point b, angle
//! in degrees about the axis a→b, right-handed). Abaqus applies the
//! translation first and then the rotation about the axis a→b given in
//! global coordinates (its keywords reference says so for every keyword
//! with these two lines, e.g. `*EVENT SERIES`: "if both translation and
//! rotation are specified, translation is applied before rotation"; and
//! Abaqus/CAE writes point a at the translated origin):
//! x ↦ a + R(a→b, θ)·(x + t − a). Nodes and elements given inside an
//! `*INSTANCE` block belong to that instance, moved the same way. Node
//! and element labels are the part's (or the instance's) own, so two
//! parts may both have a node 1; nodes written at the assembly level
//! (reference points) are a scope of their own. A file with parts and no
//! instance at all places each part once where it is; a file without
//! parts is one mesh, as before Abaqus had parts.
//!
//! Sets keep their names when the file has one instance (or none); with
//! several, a part's set `S` of instance `I` is `I.S`, as Abaqus itself
//! names it at the assembly level. An assembly-level set with
//! `INSTANCE=I` takes its labels from instance I.
//!
//! # Keywords and data
//!
//! `*NODE` (`NSET=`), `*ELEMENT, TYPE=…` (`ELSET=`), `*NSET, NSET=…` and
//! `*ELSET, ELSET=…` (labels, names of earlier sets, `GENERATE`,
//! `INSTANCE=`; `*NSET, ELSET=…` takes an element set's nodes),
//! `*INCLUDE, INPUT=…` (relative to the including file), `*PART`,
//! `*END PART`, `*ASSEMBLY`, `*INSTANCE`, `*END INSTANCE`. Keywords and set
//! names are case-insensitive, `**` starts a comment, a keyword line or an
//! element's data ending in a comma continues on the next line, numbers
//! may use Fortran's `D` exponent. Node labels are any integers.

use std::path::{Path, PathBuf};

use nalgebra::{Rotation3, Unit, Vector3};

mod assemble;

use super::{
    ImportError, ImportErrorKind, ImportedMesh, RawElement, RawMesh, error, finish, read_bytes,
};

/// Reads an Abaqus `.inp` file as a blank (its mesh: nodes, membrane and
/// shell elements, node and element sets).
pub fn read_abaqus(path: impl AsRef<Path>) -> Result<ImportedMesh, ImportError> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    // Lossy: keywords and numbers are ASCII, and a comment or heading in
    // Latin-1 should not stop the read.
    parse_abaqus(&String::from_utf8_lossy(&bytes), path)
}

/// Reads the text of an Abaqus `.inp` file as a blank; `path` names it in
/// errors and anchors `*INCLUDE` files.
pub fn parse_abaqus(text: &str, path: &Path) -> Result<ImportedMesh, ImportError> {
    let (raw, hint) = parse_abaqus_raw(text, path)?;
    finish(raw, hint, false).map(|(mesh, _)| mesh)
}

/// The blank mesh of an Abaqus file as read, before the checks, and the
/// hint for an empty one.
pub(super) fn parse_abaqus_raw(
    text: &str,
    path: &Path,
) -> Result<(RawMesh, &'static str), ImportError> {
    let raw = read_raw(text, path, Use::Blank, None)?;
    Ok((
        raw,
        ": drape reads the element types M3D3, M3D4, M3D4R, S3, S3R, S4, S4R, CPS3, CPS4 and \
         CPS4R",
    ))
}

/// A rigid tool's surface from an Abaqus file: its vertices (the file's
/// coordinates, instances placed) and triangles, for
/// `drape_contact::Surface::triangle_mesh`.
///
/// Rigid (R3D3, R3D4), surface (SFM3D3, SFM3D4, SFM3D4R), shell and
/// membrane elements are read; each quad becomes two triangles split
/// along its shorter diagonal, which gives the better-shaped pair (no
/// sliver in a skewed quad, whose normal — the contact normal — would
/// turn with every rounding) and, for a warped quad, the fold along the
/// diagonal whose ends are closer together. Both triangles keep the
/// quad's node order, so the side its normal points to (Abaqus's positive
/// side of a rigid element) is the side the fabric belongs to, as for
/// an STL. Nodes no triangle uses (reference points) are dropped. The
/// geometry (degenerate triangles, winding) is checked by the surface,
/// not here.
///
/// With `instance`, only that instance is read (in a file without
/// instances, that part): one file may hold a mould and a punch.
pub fn read_abaqus_surface(
    path: impl AsRef<Path>,
    instance: Option<&str>,
) -> Result<SurfaceMesh, ImportError> {
    let path = path.as_ref();
    let bytes = read_bytes(path)?;
    parse_abaqus_surface(&String::from_utf8_lossy(&bytes), path, instance)
}

/// [`read_abaqus_surface`] from the file's text; `path` names it in errors
/// and anchors `*INCLUDE` files.
pub fn parse_abaqus_surface(
    text: &str,
    path: &Path,
    instance: Option<&str>,
) -> Result<SurfaceMesh, ImportError> {
    let raw = read_raw(text, path, Use::Surface, instance)?;
    if raw.elements.is_empty() {
        return Err(error(
            path,
            None,
            ImportErrorKind::Empty,
            format!(
                "the file has no surface elements: a tool is read from {}",
                Use::Surface.accepted()
            ),
        ));
    }
    let mut index = vec![u32::MAX; raw.x0.len()];
    let mut vertices = Vec::new();
    let elements: Vec<Vec<u32>> = raw
        .elements
        .iter()
        .map(|e| {
            e.nodes()
                .iter()
                .map(|&n| {
                    let slot = &mut index[n as usize];
                    if *slot == u32::MAX {
                        *slot = vertices.len() as u32;
                        vertices.push(raw.x0[n as usize]);
                    }
                    *slot
                })
                .collect()
        })
        .collect();
    let mut triangles = Vec::with_capacity(2 * elements.len());
    for n in &elements {
        match *n.as_slice() {
            [a, b, c] => triangles.push([a, b, c]),
            [a, b, c, d] => triangles.extend(split_quad(&vertices, [a, b, c, d])),
            _ => {}
        }
    }
    Ok(SurfaceMesh {
        vertices,
        triangles,
        instances: raw.instances,
    })
}

/// A tool surface read from an Abaqus file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SurfaceMesh {
    /// Vertices (the file's coordinates and units, instances placed).
    pub vertices: Vec<Vector3<f64>>,
    /// Triangles, counter-clockwise about the elements' normals.
    pub triangles: Vec<[u32; 3]>,
    /// The instances the surface was assembled from (empty for a file
    /// without them).
    pub instances: Vec<String>,
}

/// The two triangles of quad `q` (nodes in order round it), split along
/// its shorter diagonal (0–2 on a tie), in the quad's orientation.
pub fn split_quad(x: &[Vector3<f64>], q: [u32; 4]) -> [[u32; 3]; 2] {
    let p = |i: usize| x[q[i] as usize];
    if (p(2) - p(0)).norm_squared() <= (p(3) - p(1)).norm_squared() {
        [[q[0], q[1], q[2]], [q[0], q[2], q[3]]]
    } else {
        [[q[0], q[1], q[3]], [q[1], q[2], q[3]]]
    }
}

/// What the mesh is read for: which element types are taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Use {
    /// A blank or a structural mesh: membranes and shells.
    Blank,
    /// A rigid tool: rigid, surface, shell and membrane elements.
    Surface,
}

impl Use {
    fn shape(self, name: &str) -> Option<InpShape> {
        let blank = match name {
            "M3D3" | "S3" | "S3R" | "S3RS" | "CPS3" | "STRI3" => Some(InpShape::Triangle),
            "M3D4" | "M3D4R" | "S4" | "S4R" | "S4RS" | "S4R5" | "CPS4" | "CPS4R" => {
                Some(InpShape::Quad)
            }
            "T3D2" | "T2D2" | "B31" | "B21" => Some(InpShape::Line),
            // The point elements of a rigid body's reference node.
            "MASS" | "ROTARYI" => Some(InpShape::Point),
            _ => None,
        };
        match (self, name) {
            (Self::Surface, "R3D3" | "SFM3D3") => Some(InpShape::Triangle),
            (Self::Surface, "R3D4" | "SFM3D4" | "SFM3D4R") => Some(InpShape::Quad),
            _ => blank,
        }
    }

    /// The element types read, for messages.
    fn accepted(self) -> &'static str {
        match self {
            Self::Blank => {
                "the triangles M3D3, S3, S3R, S3RS, CPS3, STRI3, the quads M3D4, M3D4R, S4, S4R, \
                 S4RS, S4R5, CPS4, CPS4R, and takes the lines T3D2, T2D2, B31, B21 and the points \
                 MASS, ROTARYI for element sets only"
            }
            Self::Surface => {
                "the triangles R3D3, SFM3D3, M3D3, S3, S3R, S3RS, CPS3, STRI3 and the quads R3D4, \
                 SFM3D4, SFM3D4R, M3D4, M3D4R, S4, S4R, S4RS, S4R5, CPS4, CPS4R (split in two \
                 triangles), and skips the lines T3D2, T2D2, B31, B21 and the points MASS, \
                 ROTARYI"
            }
        }
    }
}

/// Reads a whole file (and its includes) into a raw mesh: instances
/// placed (only `only`, if given), labels resolved, sets named.
fn read_raw(
    text: &str,
    path: &Path,
    use_: Use,
    only: Option<&str>,
) -> Result<RawMesh, ImportError> {
    let mut reader = InpReader {
        use_,
        scopes: vec![Scope::default()],
        ..InpReader::default()
    };
    reader.files.push(path.to_owned());
    reader.read(text, 0, 0)?;
    reader.end_block()?;
    reader.resolve(only)
}

/// How many `*INCLUDE` levels are followed (a cycle would never end).
const MAX_INCLUDE_DEPTH: usize = 16;

/// What an Abaqus element type is to drape.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum InpShape {
    Triangle,
    Quad,
    Line,
    Point,
}

impl InpShape {
    fn nodes(self) -> usize {
        match self {
            Self::Triangle => 3,
            Self::Quad => 4,
            Self::Line => 2,
            Self::Point => 1,
        }
    }
}

/// Where something was written: file index and 1-based line.
#[derive(Debug, Clone, Copy, Default)]
struct At {
    file: usize,
    line: usize,
}

/// A member of a set as written.
#[derive(Debug, Clone)]
enum Member {
    Label(i64),
    /// first, last, step (GENERATE).
    Range(i64, i64, i64),
    /// An earlier set of the same kind.
    Set(String),
    /// The nodes of an element set (`*NSET, ELSET=`).
    ElementSet(String),
    /// Nothing: the set's keyword, which makes it exist even if empty.
    Created,
}

/// A member added to a set, in file order: a set's contents are what the
/// lines before a reference to it gave it (as in Abaqus), and a set
/// defined in several places is one set.
#[derive(Debug, Clone)]
struct SetMember {
    elements: bool,
    /// The set's upper-case name.
    key: String,
    member: Member,
    /// The instance whose labels the member names (`INSTANCE=` of an
    /// assembly-level set), as written.
    instance: Option<String>,
    at: At,
}

#[derive(Debug, Clone)]
struct InpElement {
    label: i64,
    shape: InpShape,
    node_labels: Vec<i64>,
    at: At,
}

/// An instance's placement: x ↦ a + R·(x + translation − a).
#[derive(Debug, Clone, Default)]
struct Position {
    translation: Vector3<f64>,
    /// Point a and the rotation about a→b.
    rotation: Option<(Vector3<f64>, Rotation3<f64>)>,
}

impl Position {
    fn apply(&self, x: &Vector3<f64>) -> Vector3<f64> {
        let moved = x + self.translation;
        match &self.rotation {
            Some((a, r)) => a + r * (moved - a),
            None => moved,
        }
    }
}

/// What a scope is.
#[derive(Debug, Clone, Default)]
enum ScopeKind {
    /// The model (and assembly) level: a file without parts, or the
    /// assembly's reference points.
    #[default]
    Model,
    Part,
    Instance {
        /// The part's name as written.
        part: String,
        position: Position,
    },
}

/// Labels live in a scope: the model level, a part or an instance.
#[derive(Debug, Clone, Default)]
struct Scope {
    kind: ScopeKind,
    /// The name as written ("" for the model).
    name: String,
    /// Where the scope's keyword is.
    at: At,
    /// (label, position, where).
    nodes: Vec<(i64, Vector3<f64>, At)>,
    elements: Vec<InpElement>,
    /// (upper-case key, name as first written), in order of first
    /// definition.
    nsets: Vec<(String, String)>,
    elsets: Vec<(String, String)>,
    /// Every set member, in file order.
    set_members: Vec<SetMember>,
}

/// The keyword block being read.
#[derive(Debug, Clone, Default)]
enum Block {
    /// Data skipped (an unknown keyword, or none yet).
    #[default]
    Skip,
    Node {
        /// The key of the `NSET=` set.
        nset: Option<String>,
    },
    Element {
        type_name: String,
        shape: InpShape,
        /// The key of the `ELSET=` set.
        elset: Option<String>,
    },
    Nset {
        key: String,
        generate: bool,
        instance: Option<String>,
    },
    Elset {
        key: String,
        generate: bool,
        instance: Option<String>,
    },
    Instance {
        lines: usize,
    },
}

#[derive(Debug)]
struct InpReader {
    use_: Use,
    files: Vec<PathBuf>,
    block: Block,
    /// A keyword line ending in a comma, waiting for its continuation.
    keyword: Option<(String, At)>,
    /// An element whose data continues on the next line.
    element: Option<(Vec<String>, At)>,
    /// Scope 0 is the model level.
    scopes: Vec<Scope>,
    /// The scope being read.
    current: usize,
}

impl Default for InpReader {
    fn default() -> Self {
        Self {
            use_: Use::Blank,
            files: Vec::new(),
            block: Block::Skip,
            keyword: None,
            element: None,
            scopes: vec![Scope::default()],
            current: 0,
        }
    }
}

/// A keyword line: upper-case name and parameters (upper-case keys, values
/// as written without quotes).
struct Keyword {
    name: String,
    params: Vec<(String, Option<String>)>,
}

impl Keyword {
    fn parse(text: &str) -> Self {
        let mut parts = text.trim_start_matches('*').split(',');
        let name = parts
            .next()
            .unwrap_or("")
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ")
            .to_ascii_uppercase();
        let params = parts
            .map(str::trim)
            .filter(|p| !p.is_empty())
            .map(|p| match p.split_once('=') {
                Some((k, v)) => (
                    k.trim().to_ascii_uppercase(),
                    Some(v.trim().trim_matches('"').to_owned()),
                ),
                None => (p.to_ascii_uppercase(), None),
            })
            .collect();
        Self { name, params }
    }

    fn get(&self, key: &str) -> Option<&str> {
        self.params
            .iter()
            .find(|(k, _)| k == key)
            .and_then(|(_, v)| v.as_deref())
    }

    fn has(&self, key: &str) -> bool {
        self.params.iter().any(|(k, _)| k == key)
    }
}

impl InpReader {
    fn err(&self, at: At, kind: ImportErrorKind, message: impl Into<String>) -> ImportError {
        let file = self.files.get(at.file).or(self.files.first());
        error(
            file.map_or(Path::new(""), PathBuf::as_path),
            (at.line > 0).then_some(at.line),
            kind,
            message,
        )
    }

    fn scope(&mut self) -> &mut Scope {
        &mut self.scopes[self.current]
    }

    /// Reads the lines of one file (the main one or an included one).
    fn read(&mut self, text: &str, file: usize, depth: usize) -> Result<(), ImportError> {
        for (i, raw_line) in text.lines().enumerate() {
            let at = At { file, line: i + 1 };
            let line = raw_line.trim();
            if line.starts_with("**") {
                continue;
            }
            if let Some((mut pending, first)) = self.keyword.take() {
                // A continued keyword line: this line is more of it.
                pending.push_str(line);
                if pending.ends_with(',') {
                    self.keyword = Some((pending, first));
                } else {
                    self.keyword_line(&pending, first, depth)?;
                }
                continue;
            }
            if line.is_empty() {
                continue;
            }
            if line.starts_with('*') {
                if line.ends_with(',') {
                    self.keyword = Some((line.to_owned(), at));
                } else {
                    self.keyword_line(line, at, depth)?;
                }
            } else {
                self.data_line(line, at)?;
            }
        }
        if let Some((_, at)) = self.keyword.take() {
            return Err(self.err(
                at,
                ImportErrorKind::Syntax,
                "the keyword line ends with a comma but nothing follows",
            ));
        }
        Ok(())
    }

    /// Closes the current block: an element still waiting for nodes is an
    /// error.
    fn end_block(&mut self) -> Result<(), ImportError> {
        if let Some((fields, at)) = self.element.take() {
            let Block::Element {
                type_name, shape, ..
            } = &self.block
            else {
                return Ok(());
            };
            return Err(self.err(
                at,
                ImportErrorKind::Syntax,
                format!(
                    "element {} ({type_name}) has {} nodes, expected {}",
                    fields.first().map_or("?", String::as_str),
                    fields.len().saturating_sub(1),
                    shape.nodes()
                ),
            ));
        }
        Ok(())
    }

    fn keyword_line(&mut self, text: &str, at: At, depth: usize) -> Result<(), ImportError> {
        let k = Keyword::parse(text);
        if k.name == "INCLUDE" {
            // The included text stands in for this line: it may carry the
            // data of the keyword before it, so the block goes on.
            return self.include(&k, at, depth);
        }
        self.end_block()?;
        let required = |me: &Self, key: &str| -> Result<String, ImportError> {
            match k.get(key) {
                Some(v) if !v.is_empty() => Ok(v.to_owned()),
                _ => Err(me.err(
                    at,
                    ImportErrorKind::Syntax,
                    format!("*{} needs {key}=…", k.name),
                )),
            }
        };
        let unsupported =
            |me: &Self, what: String| Err(me.err(at, ImportErrorKind::Unsupported, what));
        self.block = Block::Skip;
        match k.name.as_str() {
            "NODE" => {
                if k.has("INPUT") {
                    return unsupported(
                        self,
                        "*NODE, INPUT=… is not supported: use *INCLUDE".into(),
                    );
                }
                if let Some(system) = k.get("SYSTEM")
                    && !system.eq_ignore_ascii_case("R")
                {
                    return unsupported(
                        self,
                        format!(
                            "*NODE, SYSTEM={system} is not supported: give Cartesian coordinates"
                        ),
                    );
                }
                let nset = k.get("NSET").map(|name| self.set_entry(false, name, at));
                self.block = Block::Node { nset };
            }
            "ELEMENT" => {
                if k.has("INPUT") {
                    return unsupported(
                        self,
                        "*ELEMENT, INPUT=… is not supported: use *INCLUDE".into(),
                    );
                }
                let type_name = required(self, "TYPE")?.to_ascii_uppercase();
                let Some(shape) = self.use_.shape(&type_name) else {
                    let hint = if type_name.starts_with('R') && self.use_ == Use::Blank {
                        " (rigid elements describe tools: give the file as a tool's mesh)"
                    } else if [
                        "M3D6", "M3D8", "M3D8R", "M3D9", "M3D9R", "S8R", "S8R5", "S9R5", "STRI65",
                        "CPS6", "CPS8", "CPS8R", "R3D6", "R3D9", "SFM3D6", "SFM3D8", "SFM3D8R",
                    ]
                    .contains(&type_name.as_str())
                    {
                        " (second-order elements are not supported: export a linear mesh)"
                    } else {
                        ""
                    };
                    return Err(self.err(
                        at,
                        ImportErrorKind::UnsupportedElement,
                        format!(
                            "element type {type_name} is not supported{hint}: drape reads {}",
                            self.use_.accepted()
                        ),
                    ));
                };
                let elset = k.get("ELSET").map(|name| self.set_entry(true, name, at));
                self.block = Block::Element {
                    type_name,
                    shape,
                    elset,
                };
            }
            "NSET" | "ELSET" => {
                let elements = k.name == "ELSET";
                let name = required(self, if elements { "ELSET" } else { "NSET" })?;
                let instance = k.get("INSTANCE").map(str::to_owned);
                let key = self.set_entry(elements, &name, at);
                if !elements && let Some(elset) = k.get("ELSET") {
                    self.add_member(
                        false,
                        &key,
                        Member::ElementSet(elset.to_owned()),
                        instance.clone(),
                        at,
                    );
                }
                let generate = k.has("GENERATE");
                self.block = if elements {
                    Block::Elset {
                        key,
                        generate,
                        instance,
                    }
                } else {
                    Block::Nset {
                        key,
                        generate,
                        instance,
                    }
                };
            }
            "PART" => {
                let name = required(self, "NAME")?;
                self.open_scope(ScopeKind::Part, name, at)?;
            }
            "INSTANCE" => {
                if k.has("INSTANCE") || k.has("LIBRARY") {
                    return unsupported(
                        self,
                        "an instance imported from a previous analysis (*INSTANCE, INSTANCE=…) \
                         carries no mesh in this file"
                            .into(),
                    );
                }
                let name = required(self, "NAME")?;
                let part = required(self, "PART")?;
                self.open_scope(
                    ScopeKind::Instance {
                        part,
                        position: Position::default(),
                    },
                    name,
                    at,
                )?;
                self.block = Block::Instance { lines: 0 };
            }
            "END PART" | "END INSTANCE" => self.current = 0,
            "ASSEMBLY" if self.current != 0 => {
                let open = &self.scopes[self.current];
                return Err(self.err(
                    at,
                    ImportErrorKind::Syntax,
                    format!(
                        "*ASSEMBLY starts inside {} (line {}): its *END is missing",
                        open.name, open.at.line
                    ),
                ));
            }
            // Everything else (headings, materials, sections, surfaces,
            // rigid bodies, steps…) is not the mesh's: skipped with its data.
            _ => {}
        }
        Ok(())
    }

    /// Starts a part or an instance; its name must be new among its kind.
    fn open_scope(&mut self, kind: ScopeKind, name: String, at: At) -> Result<(), ImportError> {
        let part = matches!(kind, ScopeKind::Part);
        let what = if part { "part" } else { "instance" };
        if self.current != 0 {
            let open = &self.scopes[self.current];
            let (open_what, end) = match open.kind {
                ScopeKind::Instance { .. } => ("instance", "*END INSTANCE"),
                _ => ("part", "*END PART"),
            };
            return Err(self.err(
                at,
                ImportErrorKind::Syntax,
                format!(
                    "*{} {name} starts inside {open_what} {} (line {}): {end} is missing",
                    what.to_ascii_uppercase(),
                    open.name,
                    open.at.line
                ),
            ));
        }
        if let Some(before) = self.scopes.iter().find(|s| {
            matches!(s.kind, ScopeKind::Part) == part
                && !matches!(s.kind, ScopeKind::Model)
                && s.name.eq_ignore_ascii_case(&name)
        }) {
            return Err(self.err(
                at,
                ImportErrorKind::Duplicate,
                format!(
                    "{what} {name} is defined twice (first at {}:{})",
                    self.files[before.at.file].display(),
                    before.at.line
                ),
            ));
        }
        self.scopes.push(Scope {
            kind,
            name,
            at,
            ..Scope::default()
        });
        self.current = self.scopes.len() - 1;
        Ok(())
    }

    fn include(&mut self, k: &Keyword, at: At, depth: usize) -> Result<(), ImportError> {
        let input = match k.get("INPUT") {
            Some(v) if !v.is_empty() => v.to_owned(),
            _ => {
                return Err(self.err(at, ImportErrorKind::Syntax, "*INCLUDE needs INPUT=…"));
            }
        };
        if depth + 1 > MAX_INCLUDE_DEPTH {
            return Err(self.err(
                at,
                ImportErrorKind::Unsupported,
                format!("*INCLUDE nested more than {MAX_INCLUDE_DEPTH} deep (a cycle?)"),
            ));
        }
        let here = self.files.get(at.file).cloned().unwrap_or_default();
        let path = here.parent().unwrap_or(Path::new(".")).join(&input);
        let bytes = std::fs::read(&path).map_err(|e| {
            self.err(
                at,
                ImportErrorKind::Read,
                format!("cannot read the included file {}: {e}", path.display()),
            )
        })?;
        self.files.push(path);
        let file = self.files.len() - 1;
        self.read(&String::from_utf8_lossy(&bytes), file, depth + 1)
    }

    /// A set of the current scope by its case-insensitive name (created if
    /// new, keeping the name as first written); returns its upper-case key.
    fn set_entry(&mut self, elements: bool, name: &str, at: At) -> String {
        let key = name.to_ascii_uppercase();
        let scope = self.scope();
        let sets = if elements {
            &mut scope.elsets
        } else {
            &mut scope.nsets
        };
        if !sets.iter().any(|(k, _)| *k == key) {
            sets.push((key.clone(), name.to_owned()));
        }
        self.add_member(elements, &key, Member::Created, None, at);
        key
    }

    fn add_member(
        &mut self,
        elements: bool,
        key: &str,
        member: Member,
        instance: Option<String>,
        at: At,
    ) {
        self.scope().set_members.push(SetMember {
            elements,
            key: key.to_owned(),
            member,
            instance,
            at,
        });
    }

    fn data_line(&mut self, line: &str, at: At) -> Result<(), ImportError> {
        // Taken out for the call (the readers need `&mut self`), put back
        // after: no copy of the block's strings per line.
        let block = std::mem::take(&mut self.block);
        let mut instance_lines = usize::MAX;
        let result = match &block {
            Block::Skip => Ok(()),
            Block::Node { nset } => self.node_line(line, at, nset.as_deref()),
            Block::Element {
                type_name,
                shape,
                elset,
            } => self.element_line(line, at, type_name, *shape, elset.as_deref()),
            Block::Nset {
                key,
                generate,
                instance,
            } => self.set_line(line, at, false, key, *generate, instance),
            Block::Elset {
                key,
                generate,
                instance,
            } => self.set_line(line, at, true, key, *generate, instance),
            Block::Instance { lines } => self.instance_line(line, at, *lines).map(|taken| {
                instance_lines = taken + 1;
            }),
        };
        self.block = match block {
            Block::Instance { .. } => Block::Instance {
                lines: instance_lines,
            },
            other => other,
        };
        result
    }

    /// An `*INSTANCE` data line: the first is a translation, the second a
    /// rotation (point a, point b, angle in degrees about a→b).
    /// Returns which line it was taken as (0 translation, 1 rotation).
    fn instance_line(&mut self, line: &str, at: At, before: usize) -> Result<usize, ImportError> {
        let values = fields(line)
            .iter()
            .map(|f| self.float(f, at, "instance position"))
            .collect::<Result<Vec<_>, _>>()?;
        // Abaqus leaves the translation line blank for a pure rotation, and
        // blank lines are skipped here: seven values first are the rotation.
        let before = if before == 0 && values.len() == 7 {
            1
        } else {
            before
        };
        let v = |i: usize| values.get(i).copied().unwrap_or(0.0);
        let name = self.scopes[self.current].name.clone();
        let rotation = match before {
            0 if values.len() > 3 => {
                return Err(self.err(
                    at,
                    ImportErrorKind::Syntax,
                    format!(
                        "instance {name}: the translation line has {} values, expected 3",
                        values.len()
                    ),
                ));
            }
            0 => None,
            1 => {
                if values.len() != 7 {
                    return Err(self.err(
                        at,
                        ImportErrorKind::Syntax,
                        format!(
                            "instance {name}: the rotation line has {} values, expected 7 (point \
                             a, point b on the axis, the angle in degrees)",
                            values.len()
                        ),
                    ));
                }
                let a = Vector3::new(v(0), v(1), v(2));
                let axis = Vector3::new(v(3), v(4), v(5)) - a;
                let angle = v(6);
                if angle == 0.0 {
                    Some(None)
                } else if axis.norm() == 0.0 {
                    return Err(self.err(
                        at,
                        ImportErrorKind::Syntax,
                        format!(
                            "instance {name}: the rotation axis needs two different points a \
                             and b"
                        ),
                    ));
                } else {
                    let r =
                        Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle.to_radians());
                    Some(Some((a, r)))
                }
            }
            _ => {
                return Err(self.err(
                    at,
                    ImportErrorKind::Syntax,
                    format!(
                        "instance {name}: a third data line (an *INSTANCE takes a translation \
                         and a rotation line; is *END INSTANCE missing?)"
                    ),
                ));
            }
        };
        if let ScopeKind::Instance { position, .. } = &mut self.scopes[self.current].kind {
            match rotation {
                None => position.translation = Vector3::new(v(0), v(1), v(2)),
                Some(r) => position.rotation = r,
            }
        }
        Ok(before)
    }

    fn int(&self, field: &str, at: At, what: &str) -> Result<i64, ImportError> {
        field
            .trim()
            .trim_start_matches('+')
            .parse::<i64>()
            .map_err(|_| {
                self.err(
                    at,
                    ImportErrorKind::BadNumber,
                    format!("`{field}` is not a whole number ({what})"),
                )
            })
    }

    fn float(&self, field: &str, at: At, what: &str) -> Result<f64, ImportError> {
        let field = field.trim();
        if field.is_empty() {
            return Ok(0.0);
        }
        // Fortran's double-precision exponent: 1.5D-3.
        let value = field.replace(['d', 'D'], "e").parse::<f64>();
        match value {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.err(
                at,
                ImportErrorKind::BadNumber,
                format!("`{field}` is not a finite number ({what})"),
            )),
        }
    }

    fn node_line(&mut self, line: &str, at: At, nset: Option<&str>) -> Result<(), ImportError> {
        let f = fields(line);
        let label = self.int(&f[0], at, "node label")?;
        // Coordinates left out are 0, as in Abaqus (`5` or `5, 1.0` is a
        // node on an axis). A fifth field and beyond (a normal's direction
        // cosines) is not the position's.
        let mut x = Vector3::zeros();
        for (c, field) in f[1..].iter().take(3).enumerate() {
            x[c] = self.float(field, at, &format!("coordinate of node {label}"))?;
        }
        self.scope().nodes.push((label, x, at));
        if let Some(key) = nset {
            self.add_member(false, key, Member::Label(label), None, at);
        }
        Ok(())
    }

    fn element_line(
        &mut self,
        line: &str,
        at: At,
        type_name: &str,
        shape: InpShape,
        elset: Option<&str>,
    ) -> Result<(), ImportError> {
        let (mut all, first) = self.element.take().unwrap_or((Vec::new(), at));
        all.extend(fields(line).into_iter().filter(|f| !f.is_empty()));
        let needed = 1 + shape.nodes();
        if all.len() < needed && line.ends_with(',') {
            // The element's nodes continue on the next line.
            self.element = Some((all, first));
            return Ok(());
        }
        let label = self.int(
            all.first().map_or("", String::as_str),
            first,
            "element label",
        )?;
        if all.len() != needed {
            return Err(self.err(
                first,
                ImportErrorKind::Syntax,
                format!(
                    "element {label} ({type_name}) has {} nodes, expected {}",
                    all.len() - 1,
                    shape.nodes()
                ),
            ));
        }
        let node_labels = all[1..]
            .iter()
            .map(|f| self.int(f, first, &format!("node of element {label}")))
            .collect::<Result<Vec<_>, _>>()?;
        self.scope().elements.push(InpElement {
            label,
            shape,
            node_labels,
            at: first,
        });
        if let Some(key) = elset {
            self.add_member(true, key, Member::Label(label), None, first);
        }
        Ok(())
    }

    fn set_line(
        &mut self,
        line: &str,
        at: At,
        elements: bool,
        key: &str,
        generate: bool,
        instance: &Option<String>,
    ) -> Result<(), ImportError> {
        let f: Vec<String> = fields(line).into_iter().filter(|f| !f.is_empty()).collect();
        let what = if elements {
            "element label"
        } else {
            "node label"
        };
        let mut members = Vec::new();
        if generate {
            if !(2..=3).contains(&f.len()) {
                return Err(self.err(
                    at,
                    ImportErrorKind::Syntax,
                    "GENERATE expects `first, last[, step]`",
                ));
            }
            let first = self.int(&f[0], at, what)?;
            let last = self.int(&f[1], at, what)?;
            let step = match f.get(2) {
                Some(s) => self.int(s, at, "GENERATE step")?,
                None => 1,
            };
            if step <= 0 || last < first {
                return Err(self.err(
                    at,
                    ImportErrorKind::Syntax,
                    format!(
                        "GENERATE {first}, {last}, {step}: expected first ≤ last and a positive step"
                    ),
                ));
            }
            members.push(Member::Range(first, last, step));
        } else {
            for field in &f {
                // A name (it starts with a letter) is an earlier set.
                let member = if field.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
                    Member::Set(field.trim_matches('"').to_owned())
                } else {
                    Member::Label(self.int(field, at, what)?)
                };
                members.push(member);
            }
        }
        for member in members {
            self.add_member(elements, key, member, instance.clone(), at);
        }
        Ok(())
    }
}

/// The comma-separated fields of a data line, trimmed; a trailing comma
/// adds no field.
fn fields(line: &str) -> Vec<String> {
    let line = line.trim();
    let line = line.strip_suffix(',').unwrap_or(line);
    line.split(',').map(|f| f.trim().to_owned()).collect()
}
