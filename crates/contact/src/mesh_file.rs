//! Reading tool meshes from STL (binary through `stl_io`, ASCII by a small
//! reader of its own) and Wavefront OBJ (a small reader of its own) files,
//! as vertices and counter-clockwise triangles for
//! [`Surface::triangle_mesh`](crate::Surface::triangle_mesh).
//!
//! The text formats are read here rather than by `stl_io` and `tobj`
//! because a user needs the line of an error: `stl_io` gives none (and
//! reads ASCII coordinates as `f32`), `tobj` gives none either and finds an
//! out-of-range face index only at the end of an object. Both formats are
//! a few line types; everything a tool does not need (normals, texture
//! coordinates, materials, groups) is skipped.
//!
//! These readers belong in a later io crate; they live here until it exists.
//! They check the file, not the geometry: the mesh checks (degenerate
//! triangles, winding) are [`MeshSurface::new`](crate::MeshSurface::new)'s.
//! Every error names the file, and the text formats' errors their line.
//!
//! ```no_run
//! use drape_contact::{Surface, read_stl};
//!
//! let (vertices, triangles) = read_stl("tools/punch.stl")?;
//! let punch = Surface::triangle_mesh(vertices, triangles)?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use std::io::Cursor;
use std::path::{Path, PathBuf};

use nalgebra::Vector3;

/// A mesh file that cannot be read; every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum MeshFileError {
    /// The file cannot be opened or read (not found, no permission…).
    #[error("{}: cannot read the file: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The system's error.
        source: std::io::Error,
    },
    /// Not an STL file, or a damaged one.
    #[error("{}: not a valid STL file: {why}", path.display())]
    NotStl {
        /// The file.
        path: PathBuf,
        /// What is wrong.
        why: String,
    },
    /// A text file (ASCII STL, OBJ) broken at a line.
    #[error("{}:{line}: not a valid {format} file: {why}", path.display())]
    Syntax {
        /// The file.
        path: PathBuf,
        /// The 1-based line.
        line: usize,
        /// "ASCII STL" or "OBJ".
        format: &'static str,
        /// What is wrong there.
        why: String,
    },
    /// A readable file without a single triangle.
    #[error("{}: the file has no triangles", path.display())]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// More vertices than a `u32` index can address.
    #[error("{}: more than 2³² vertices", path.display())]
    TooLarge {
        /// The file.
        path: PathBuf,
    },
}

/// A mesh as read: vertices, and triangles as indices into them.
pub type MeshBuffers = (Vec<Vector3<f64>>, Vec<[u32; 3]>);

/// Size of a binary STL's header: 80 bytes of free text and the triangle
/// count.
const STL_HEADER: usize = 84;
/// Size of one binary STL triangle: normal, three vertices (12 × f32) and a
/// two-byte attribute count.
const STL_TRIANGLE: usize = 50;

/// The vertices and triangles of an STL file, ASCII or binary. Vertices
/// that repeat exactly are shared (STL stores each triangle's corners
/// separately); the facet normals in the file are ignored, the winding
/// (counter-clockwise seen from outside, as STL requires) gives the side.
pub fn read_stl(path: impl AsRef<Path>) -> Result<MeshBuffers, MeshFileError> {
    let path = path.as_ref();
    let mut bytes = std::fs::read(path).map_err(|source| MeshFileError::Io {
        path: path.into(),
        source,
    })?;
    let not_stl = |why: String| MeshFileError::NotStl {
        path: path.into(),
        why,
    };
    if bytes.is_empty() {
        return Err(not_stl("the file is empty".into()));
    }
    // stl_io takes anything starting with "solid " for ASCII and anything
    // else for binary, without checking the binary's length. Decide here:
    // a binary STL is exactly 84 + 50·n bytes for the n of its header.
    let binary_size = (bytes.len() >= STL_HEADER).then(|| {
        let n = u32::from_le_bytes([bytes[80], bytes[81], bytes[82], bytes[83]]) as usize;
        STL_HEADER + STL_TRIANGLE * n
    });
    let is_binary = binary_size == Some(bytes.len());
    let looks_ascii = bytes.starts_with(b"solid ");
    let mesh = if looks_ascii {
        match read_ascii_stl(&bytes, path) {
            Ok(buffers) => return finish(buffers, path),
            // Some exporters start a binary header with "solid " too: blank
            // the header (free text) so that stl_io reads it as binary.
            Err(_) if is_binary => {
                bytes[..5].fill(b' ');
                stl_io::read_stl(&mut Cursor::new(&bytes)).map_err(|e| not_stl(e.to_string()))?
            }
            Err(e) => return Err(e),
        }
    } else if is_binary {
        stl_io::read_stl(&mut Cursor::new(&bytes)).map_err(|e| not_stl(e.to_string()))?
    } else {
        return Err(not_stl(match binary_size {
            Some(expected) => format!(
                "it does not start with \"solid \" (ASCII) and its {} bytes are not the {expected} \
                 of a binary STL with the {} triangles its header announces",
                bytes.len(),
                (expected - STL_HEADER) / STL_TRIANGLE
            ),
            None => format!(
                "it does not start with \"solid \" (ASCII) and its {} bytes are shorter than a \
                 binary STL's 84-byte header",
                bytes.len()
            ),
        }));
    };
    if mesh.faces.is_empty() {
        return Err(MeshFileError::Empty { path: path.into() });
    }
    let vertices = mesh
        .vertices
        .iter()
        .map(|v| Vector3::new(v[0], v[1], v[2]).cast::<f64>())
        .collect();
    let index =
        |i: usize| u32::try_from(i).map_err(|_| MeshFileError::TooLarge { path: path.into() });
    let triangles = mesh
        .faces
        .iter()
        .map(|f| {
            Ok([
                index(f.vertices[0])?,
                index(f.vertices[1])?,
                index(f.vertices[2])?,
            ])
        })
        .collect::<Result<_, MeshFileError>>()?;
    Ok((vertices, triangles))
}

/// A mesh with at least one triangle, or the error that it has none.
fn finish(buffers: MeshBuffers, path: &Path) -> Result<MeshBuffers, MeshFileError> {
    if buffers.1.is_empty() {
        return Err(MeshFileError::Empty { path: path.into() });
    }
    Ok(buffers)
}

/// Vertices shared by exact value (STL repeats each triangle's corners).
#[derive(Default)]
struct SharedVertices {
    vertices: Vec<Vector3<f64>>,
    index: std::collections::HashMap<[u64; 3], u32>,
}

impl SharedVertices {
    fn add(&mut self, v: Vector3<f64>) -> Option<u32> {
        // + 0.0 turns −0 into +0: the same point.
        let key = [v.x + 0.0, v.y + 0.0, v.z + 0.0].map(f64::to_bits);
        if let Some(&i) = self.index.get(&key) {
            return Some(i);
        }
        let i = u32::try_from(self.vertices.len()).ok()?;
        self.vertices.push(v);
        self.index.insert(key, i);
        Some(i)
    }
}

/// The text of a file's lines, 1-based, without comments (`#` in OBJ) and
/// trailing blanks; lines ending in `\` (OBJ) are joined with the next.
fn numbered_lines(bytes: &[u8], comment: Option<char>) -> Vec<(usize, String)> {
    let text = String::from_utf8_lossy(bytes);
    let mut out: Vec<(usize, String)> = Vec::new();
    let mut pending: Option<(usize, String)> = None;
    for (i, raw) in text.lines().enumerate() {
        let mut line = match comment.and_then(|c| raw.find(c)) {
            Some(at) => &raw[..at],
            None => raw,
        }
        .trim_end()
        .to_owned();
        let continues = comment.is_some() && line.ends_with('\\');
        if continues {
            line.pop();
        }
        let (first, mut joined) = pending.take().unwrap_or((i + 1, String::new()));
        joined.push(' ');
        joined.push_str(&line);
        if continues {
            pending = Some((first, joined));
        } else if !joined.trim().is_empty() {
            out.push((first, joined.trim().to_owned()));
        }
    }
    if let Some((first, joined)) = pending {
        out.push((first, joined.trim().to_owned()));
    }
    out
}

/// Three finite coordinates from `words`, or what is wrong with them.
fn coordinates<'a>(words: impl Iterator<Item = &'a str>) -> Result<Vector3<f64>, String> {
    let mut v = Vector3::zeros();
    let mut words = words;
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        let Some(word) = words.next() else {
            return Err(format!("the {axis} coordinate is missing"));
        };
        match word.parse::<f64>() {
            Ok(c) if c.is_finite() => v[k] = c,
            _ => return Err(format!("`{word}` is not a finite number ({axis})")),
        }
    }
    Ok(v)
}

/// An ASCII STL file: `solid` … `facet normal` n n n, `outer loop`, three
/// `vertex` x y z, `endloop`, `endfacet` … `endsolid`, keywords in any
/// case, several solids one after the other. Coordinates are read as f64.
fn read_ascii_stl(bytes: &[u8], path: &Path) -> Result<MeshBuffers, MeshFileError> {
    #[derive(Clone, Copy, PartialEq)]
    enum Expect {
        Solid,
        FacetOrEnd,
        OuterLoop,
        Vertex(usize),
        EndLoop,
        EndFacet,
    }
    let fail = |line: usize, why: String| MeshFileError::Syntax {
        path: path.into(),
        line,
        format: "ASCII STL",
        why,
    };
    let mut shared = SharedVertices::default();
    let mut triangles = Vec::new();
    let mut corners = [0u32; 3];
    let mut expect = Expect::Solid;
    let mut last_line = 0;
    for (line, text) in numbered_lines(bytes, None) {
        last_line = line;
        let mut words = text.split_whitespace();
        let keyword = words.next().unwrap_or("").to_ascii_lowercase();
        let found = || format!("found `{text}`");
        expect = match (expect, keyword.as_str()) {
            (Expect::Solid, "solid") => Expect::FacetOrEnd,
            (Expect::Solid, _) => {
                return Err(fail(line, format!("expected `solid name`, {}", found())));
            }
            (Expect::FacetOrEnd, "endsolid") => Expect::Solid,
            (Expect::FacetOrEnd, "facet") => {
                let normal = words.next().map(str::to_ascii_lowercase);
                if normal.as_deref() != Some("normal") {
                    return Err(fail(
                        line,
                        format!("expected `facet normal nx ny nz`, {}", found()),
                    ));
                }
                // The normal is not used (the winding gives the side), but
                // a garbled one means a broken file.
                coordinates(words).map_err(|why| fail(line, format!("facet normal: {why}")))?;
                Expect::OuterLoop
            }
            (Expect::FacetOrEnd, _) => {
                return Err(fail(
                    line,
                    format!("expected `facet normal …` or `endsolid`, {}", found()),
                ));
            }
            (Expect::OuterLoop, "outer")
                if words.next().is_some_and(|w| w.eq_ignore_ascii_case("loop")) =>
            {
                Expect::Vertex(0)
            }
            (Expect::OuterLoop, _) => {
                return Err(fail(line, format!("expected `outer loop`, {}", found())));
            }
            (Expect::Vertex(k), "vertex") => {
                let v = coordinates(words).map_err(|why| fail(line, format!("vertex: {why}")))?;
                corners[k] = shared
                    .add(v)
                    .ok_or_else(|| MeshFileError::TooLarge { path: path.into() })?;
                if k == 2 {
                    Expect::EndLoop
                } else {
                    Expect::Vertex(k + 1)
                }
            }
            (Expect::Vertex(k), _) => {
                return Err(fail(
                    line,
                    format!(
                        "expected `vertex x y z` (corner {} of 3), {}",
                        k + 1,
                        found()
                    ),
                ));
            }
            (Expect::EndLoop, "endloop") => {
                triangles.push(corners);
                Expect::EndFacet
            }
            (Expect::EndLoop, _) => {
                return Err(fail(
                    line,
                    format!("expected `endloop` after three vertices, {}", found()),
                ));
            }
            (Expect::EndFacet, "endfacet") => Expect::FacetOrEnd,
            (Expect::EndFacet, _) => {
                return Err(fail(line, format!("expected `endfacet`, {}", found())));
            }
        };
    }
    if expect != Expect::Solid {
        let what = match expect {
            Expect::FacetOrEnd => "`endsolid`",
            Expect::OuterLoop => "`outer loop`",
            Expect::Vertex(_) => "`vertex x y z`",
            Expect::EndLoop => "`endloop`",
            _ => "`endfacet`",
        };
        return Err(fail(
            last_line.max(1),
            format!("the file ends where {what} was expected (cut short?)"),
        ));
    }
    Ok((shared.vertices, triangles))
}

/// The vertices and triangles of a Wavefront OBJ file: the faces of all its
/// objects and groups (`f` lines; `v`, `v/vt`, `v//vn`, `v/vt/vn` corners,
/// negative indices counting back from the last vertex), polygons split
/// into triangle fans (convex polygons only), points, lines, normals,
/// texture coordinates and materials skipped, a `w` or vertex colour after
/// the coordinates ignored. Faces keep their winding (counter-clockwise
/// seen from outside by OBJ convention).
pub fn read_obj(path: impl AsRef<Path>) -> Result<MeshBuffers, MeshFileError> {
    let path = path.as_ref();
    let bytes = std::fs::read(path).map_err(|source| MeshFileError::Io {
        path: path.into(),
        source,
    })?;
    let fail = |line: usize, why: String| MeshFileError::Syntax {
        path: path.into(),
        line,
        format: "OBJ",
        why,
    };
    let mut vertices: Vec<Vector3<f64>> = Vec::new();
    // Triangles with their line, checked against the vertex count at the
    // end (a file may name a vertex before defining it).
    let mut faces: Vec<([i64; 3], usize)> = Vec::new();
    for (line, text) in numbered_lines(&bytes, Some('#')) {
        let mut words = text.split_whitespace();
        match words.next() {
            Some("v") => {
                vertices.push(coordinates(words).map_err(|why| fail(line, format!("v: {why}")))?)
            }
            Some("f") => {
                let mut corners = Vec::new();
                for word in words {
                    let first = word.split('/').next().unwrap_or("");
                    let index: i64 = first.parse().map_err(|_| {
                        fail(
                            line,
                            format!("face corner `{word}`: `{first}` is not a vertex number"),
                        )
                    })?;
                    // Negative: counted back from the last vertex so far.
                    let absolute = match index {
                        0 => {
                            return Err(fail(
                                line,
                                "face corner 0: OBJ numbers vertices from 1".into(),
                            ));
                        }
                        i if i < 0 => vertices.len() as i64 + 1 + i,
                        i => i,
                    };
                    if absolute < 1 {
                        return Err(fail(
                            line,
                            format!(
                                "face corner {index} counts back past the first vertex ({} defined \
                                 so far)",
                                vertices.len()
                            ),
                        ));
                    }
                    corners.push(absolute - 1);
                }
                if corners.len() < 3 {
                    return Err(fail(
                        line,
                        format!(
                            "a face needs at least 3 corners, this one has {}",
                            corners.len()
                        ),
                    ));
                }
                for k in 1..corners.len() - 1 {
                    faces.push(([corners[0], corners[k], corners[k + 1]], line));
                }
            }
            // Everything else a tool does not need: vt, vn, l, p, o, g, s,
            // usemtl, mtllib, curves…
            _ => {}
        }
    }
    let count = vertices.len();
    let mut triangles = Vec::with_capacity(faces.len());
    for (corners, line) in faces {
        let mut t = [0u32; 3];
        for (slot, &c) in t.iter_mut().zip(&corners) {
            if c as usize >= count {
                return Err(fail(
                    line,
                    format!(
                        "face corner {} does not exist: the file has {count} vertices",
                        c + 1
                    ),
                ));
            }
            *slot = u32::try_from(c).map_err(|_| MeshFileError::TooLarge { path: path.into() })?;
        }
        triangles.push(t);
    }
    finish((vertices, triangles), path)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Surface;

    /// A fresh path in the temporary directory (process id and a counter:
    /// tests run in parallel, and in parallel processes).
    fn temp_path(name: &str) -> PathBuf {
        use std::sync::atomic::{AtomicUsize, Ordering};
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        std::env::temp_dir().join(format!("drape-contact-{}-{n}-{name}", std::process::id()))
    }

    /// Writes `contents` to a fresh temporary file, removed on drop.
    struct TempFile(PathBuf);

    impl TempFile {
        fn new(name: &str, contents: &[u8]) -> Self {
            let path = temp_path(name);
            std::fs::write(&path, contents).unwrap();
            Self(path)
        }
    }

    impl Drop for TempFile {
        fn drop(&mut self) {
            let _ = std::fs::remove_file(&self.0);
        }
    }

    /// A tetrahedron, wound outwards.
    fn tetrahedron() -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
        (
            vec![
                Vector3::new(0.0, 0.0, 0.0),
                Vector3::new(10.0, 0.0, 0.0),
                Vector3::new(0.0, 10.0, 0.0),
                Vector3::new(0.0, 0.0, 10.0),
            ],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
    }

    /// The triangles as corner coordinates, to compare meshes whatever
    /// their vertex numbering.
    fn corners(v: &[Vector3<f64>], f: &[[u32; 3]]) -> Vec<[Vector3<f64>; 3]> {
        f.iter().map(|t| t.map(|i| v[i as usize])).collect()
    }

    #[test]
    fn binary_stl_written_with_stl_io_reads_back_the_same_triangles() {
        let (v, f) = tetrahedron();
        let triangles: Vec<stl_io::Triangle> = corners(&v, &f)
            .iter()
            .map(|c| {
                let n = (c[1] - c[0])
                    .cross(&(c[2] - c[0]))
                    .normalize()
                    .cast::<f32>();
                stl_io::Triangle {
                    normal: stl_io::Normal::new([n.x, n.y, n.z]),
                    vertices: c.map(|p| {
                        let p = p.cast::<f32>();
                        stl_io::Vertex::new([p.x, p.y, p.z])
                    }),
                }
            })
            .collect();
        let mut bytes = Vec::new();
        stl_io::write_stl(&mut bytes, triangles.iter()).unwrap();
        let file = TempFile::new("tet.stl", &bytes);
        let (rv, rf) = read_stl(&file.0).unwrap();
        // Corners shared again: four vertices, not twelve.
        assert_eq!(rv.len(), 4);
        assert_eq!(corners(&rv, &rf), corners(&v, &f));
        let s = Surface::triangle_mesh(rv, rf).unwrap();
        assert!((s.project(&Vector3::new(1.0, 1.0, -2.0)).gap - 2.0).abs() < 1e-12);

        // The same bytes with a header that starts like an ASCII file.
        bytes[..6].copy_from_slice(b"solid ");
        let file = TempFile::new("solid-header.stl", &bytes);
        let (rv, rf) = read_stl(&file.0).unwrap();
        assert_eq!(corners(&rv, &rf), corners(&v, &f));
    }

    #[test]
    fn ascii_stl_is_read() {
        let text = "solid plate\n\
            facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 1 1 0\n endloop\nendfacet\n\
            facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 1 0\n  vertex 0 1 0\n endloop\nendfacet\n\
            endsolid plate\n";
        let file = TempFile::new("plate.stl", text.as_bytes());
        let (v, f) = read_stl(&file.0).unwrap();
        assert_eq!(v.len(), 4);
        assert_eq!(f, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(v[2], Vector3::new(1.0, 1.0, 0.0));
    }

    #[test]
    fn bad_stl_files_are_named_and_explained() {
        let missing = temp_path("missing.stl");
        let e = read_stl(&missing).unwrap_err();
        assert!(
            matches!(&e, MeshFileError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound)
        );
        assert!(e.to_string().contains(&*missing.to_string_lossy()), "{e}");

        let empty = TempFile::new("empty.stl", b"");
        let e = read_stl(&empty.0).unwrap_err();
        assert!(matches!(e, MeshFileError::NotStl { .. }), "{e}");
        assert!(e.to_string().contains("empty"), "{e}");

        let text = TempFile::new(
            "notes.stl",
            b"these are not the triangles you are looking for",
        );
        let e = read_stl(&text.0).unwrap_err();
        assert!(matches!(e, MeshFileError::NotStl { .. }), "{e}");
        assert!(e.to_string().contains(&*text.0.to_string_lossy()), "{e}");

        // A binary file whose header announces 3 triangles but holds 1.
        let mut bytes = vec![0u8; STL_HEADER + STL_TRIANGLE];
        bytes[80] = 3;
        let short = TempFile::new("short.stl", &bytes);
        let e = read_stl(&short.0).unwrap_err();
        assert!(e.to_string().contains("3 triangles"), "{e}");

        let garbled = TempFile::new(
            "garbled.stl",
            b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n",
        );
        let e = read_stl(&garbled.0).unwrap_err();
        assert!(e.to_string().contains("ASCII STL"), "{e}");

        // A valid binary STL with no triangles.
        let none = TempFile::new("none.stl", &[0u8; STL_HEADER]);
        let e = read_stl(&none.0).unwrap_err();
        assert!(matches!(e, MeshFileError::Empty { .. }), "{e}");
        let none = TempFile::new("none-ascii.stl", b"solid x\nendsolid x\n");
        assert!(matches!(
            read_stl(&none.0),
            Err(MeshFileError::Empty { .. })
        ));
    }

    #[test]
    fn obj_polygons_are_triangulated_and_objects_joined() {
        // A unit cube as six quads (counter-clockwise from outside) in two
        // objects, with a comment, normals and a material that is not read.
        let text = "# cube\nmtllib cube.mtl\n\
            v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n\
            vn 0 0 1\n\
            o bottom_and_top\nusemtl steel\nf 1 4 3 2\nf 5 6 7 8\n\
            o sides\nf 1 2 6 5\nf 2 3 7 6\nf 3//1 4//1 8//1 7//1\nf 4 1 5 8\n\
            l 1 2\n";
        let file = TempFile::new("cube.obj", text.as_bytes());
        let (v, f) = read_obj(&file.0).unwrap();
        assert_eq!(f.len(), 12);
        // One vertex list for all objects.
        assert_eq!(v.len(), 8);
        let cube = Surface::triangle_mesh(v, f).unwrap();
        let Surface::Mesh(m) = &cube else {
            unreachable!()
        };
        assert!(m.is_closed());
        assert_eq!(m.vertices().len(), 8);
        assert!((cube.project(&Vector3::new(0.5, 0.5, 0.75)).gap + 0.25).abs() < 1e-15);
        assert!((cube.project(&Vector3::new(0.5, 2.0, 0.5)).gap - 1.0).abs() < 1e-15);
    }

    #[test]
    fn bad_obj_files_are_named_and_explained() {
        let missing = temp_path("missing.obj");
        let e = read_obj(&missing).unwrap_err();
        assert!(
            matches!(&e, MeshFileError::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound)
        );
        assert!(e.to_string().contains(&*missing.to_string_lossy()), "{e}");

        let no_faces = TempFile::new("points.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\n");
        let e = read_obj(&no_faces.0).unwrap_err();
        assert!(matches!(e, MeshFileError::Empty { .. }), "{e}");
        assert!(e.to_string().contains("no triangles"), "{e}");

        // Each error names the file and the line.
        let syntax = |name: &str, text: &str, line: usize, what: &str| {
            let file = TempFile::new(name, text.as_bytes());
            let e = read_obj(&file.0).unwrap_err();
            assert!(
                matches!(&e, MeshFileError::Syntax { line: l, .. } if *l == line),
                "{name}: {e}"
            );
            let shown = e.to_string();
            assert!(
                shown.starts_with(&format!(
                    "{}:{line}: not a valid OBJ file",
                    file.0.display()
                )),
                "{shown}"
            );
            assert!(shown.contains(what), "{shown}");
        };
        syntax(
            "bad-index.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n",
            4,
            "corner 4 does not exist: the file has 3 vertices",
        );
        syntax(
            "garbled.obj",
            "# a comment\nv 0 zero 0\nf 1 2 3\n",
            2,
            "`zero`",
        );
        syntax(
            "short.obj",
            "v 0 0 0\nv 1 0\n",
            2,
            "z coordinate is missing",
        );
        syntax(
            "zero.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n",
            4,
            "from 1",
        );
        syntax(
            "back.obj",
            "v 0 0 0\nv 1 0 0\nf -1 -2 -3\n",
            3,
            "counts back",
        );
        syntax(
            "two.obj",
            "v 0 0 0\nv 1 0 0\nf 1 2\n",
            3,
            "at least 3 corners",
        );
        syntax(
            "word.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x/1\n",
            4,
            "`x`",
        );
        // A continued line is reported at its first line.
        syntax(
            "cont.obj",
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n 9\n",
            4,
            "corner 9",
        );
    }

    #[test]
    fn obj_negative_indices_and_continuations_are_read() {
        let text =
            "v 0 0 0\nv 1 0 0\nv 1 1 0 1.0\nv 0 1 0 0.5 0.5 0.5\nf -4/1/1 -3//1 \\\n -2 -1\n";
        let file = TempFile::new("neg.obj", text.as_bytes());
        let (v, f) = read_obj(&file.0).unwrap();
        assert_eq!(v.len(), 4);
        assert_eq!(f, vec![[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn ascii_stl_errors_name_file_and_line() {
        let good = "solid plate\n\
            facet normal 0 0 1\n outer loop\n  vertex 0 0 0\n  vertex 1 0 0\n  vertex 1 1 0\n endloop\nendfacet\n\
            endsolid plate\n";
        let (v, f) = {
            let file = TempFile::new("good.stl", good.as_bytes());
            read_stl(&file.0).unwrap()
        };
        assert_eq!((v.len(), f.len()), (3, 1));
        for (name, text, line, what) in [
            (
                "vertex.stl",
                good.replace("vertex 1 0 0", "vertex 1 0"),
                5,
                "z coordinate",
            ),
            (
                "number.stl",
                good.replace("vertex 1 1 0", "vertex 1 1 O"),
                6,
                "`O`",
            ),
            (
                "loop.stl",
                good.replace(" outer loop\n", ""),
                3,
                "expected `outer loop`",
            ),
            (
                "four.stl",
                good.replace("  vertex 1 1 0\n", "  vertex 1 1 0\n  vertex 2 2 0\n"),
                7,
                "expected `endloop`",
            ),
            (
                "cut.stl",
                good[..good.find(" endloop").unwrap()].to_owned(),
                6,
                "cut short",
            ),
            (
                "normal.stl",
                good.replace("facet normal 0 0 1", "facet 0 0 1"),
                2,
                "facet normal",
            ),
        ] {
            let file = TempFile::new(name, text.as_bytes());
            let e = read_stl(&file.0).unwrap_err();
            let shown = e.to_string();
            assert!(
                shown.starts_with(&format!(
                    "{}:{line}: not a valid ASCII STL file",
                    file.0.display()
                )),
                "{name}: {shown}"
            );
            assert!(shown.contains(what), "{name}: {shown}");
        }
        // Coordinates keep their f64 digits.
        let precise = good.replace("vertex 1 0 0", "vertex 0.1000000000000000055511 0 0");
        let file = TempFile::new("precise.stl", precise.as_bytes());
        let (v, _) = read_stl(&file.0).unwrap();
        assert_eq!(v[1].x, 0.1);
    }
}
