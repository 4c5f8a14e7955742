//! Reading tool meshes from STL (ASCII or binary, through `stl_io`) and
//! Wavefront OBJ (through `tobj`) files, as vertices and counter-clockwise
//! triangles for [`Surface::triangle_mesh`](crate::Surface::triangle_mesh).
//!
//! These readers belong in a later io crate; they live here until it exists.
//! They check the file, not the geometry: the mesh checks (degenerate
//! triangles, winding) are [`MeshSurface::new`](crate::MeshSurface::new)'s.
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
    /// An OBJ file that `tobj` rejects.
    #[error("{}: not a valid OBJ file: {source}", path.display())]
    Obj {
        /// The file.
        path: PathBuf,
        /// The parser's error.
        source: tobj::LoadError,
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
        match stl_io::read_stl(&mut Cursor::new(&bytes)) {
            Ok(mesh) => mesh,
            // Some exporters start a binary header with "solid " too: blank
            // the header (free text) so that stl_io reads it as binary.
            Err(_) if is_binary => {
                bytes[..5].fill(b' ');
                stl_io::read_stl(&mut Cursor::new(&bytes)).map_err(|e| not_stl(e.to_string()))?
            }
            Err(e) => return Err(not_stl(format!("ASCII STL: {e}"))),
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

/// The vertices and triangles of a Wavefront OBJ file: the faces of all its
/// objects and groups, polygons split into triangle fans by tobj (convex
/// polygons only), points and lines ignored, materials not read. Faces keep
/// their winding (counter-clockwise seen from outside by OBJ convention).
pub fn read_obj(path: impl AsRef<Path>) -> Result<MeshBuffers, MeshFileError> {
    let path = path.as_ref();
    // Opened here rather than by `tobj::load_obj`, which replaces the
    // system's error (not found, permission) by a bare "open file failed".
    let file = std::fs::File::open(path).map_err(|source| MeshFileError::Io {
        path: path.into(),
        source,
    })?;
    // The struct update covers the options of tobj's optional features
    // (`merging`, `reordering`), should another crate turn them on.
    #[allow(clippy::needless_update)]
    let options = tobj::LoadOptions {
        triangulate: true,
        // One index per corner into the positions; normals and texture
        // coordinates are not needed, so no per-corner vertex splitting.
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
        ..Default::default()
    };
    // A tool needs no materials: a `mtllib` line is not followed.
    let (models, _materials) =
        tobj::load_obj_buf(&mut std::io::BufReader::new(file), &options, |_| {
            Err(tobj::LoadError::OpenFileFailed)
        })
        .map_err(|source| MeshFileError::Obj {
            path: path.into(),
            source,
        })?;
    let mut vertices = Vec::new();
    let mut triangles = Vec::new();
    for model in &models {
        let m = &model.mesh;
        // Each object indexes its own positions: shift to the joint list.
        let offset = u32::try_from(vertices.len())
            .map_err(|_| MeshFileError::TooLarge { path: path.into() })?;
        vertices.extend(
            m.positions
                .chunks_exact(3)
                // f64 positions: tobj's `use_f64` feature.
                .map(|p| Vector3::new(p[0], p[1], p[2])),
        );
        triangles.extend(
            m.indices
                .chunks_exact(3)
                .map(|t| [t[0] + offset, t[1] + offset, t[2] + offset]),
        );
    }
    if triangles.is_empty() {
        return Err(MeshFileError::Empty { path: path.into() });
    }
    Ok((vertices, triangles))
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
        // Each object brings the positions it uses (all eight corners for
        // both here); the mesh merges them.
        assert_eq!(v.len(), 16);
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

        let out_of_range = TempFile::new("bad-index.obj", b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
        let e = read_obj(&out_of_range.0).unwrap_err();
        assert!(matches!(e, MeshFileError::Obj { .. }), "{e}");
        assert!(e.to_string().contains("bad-index.obj"), "{e}");

        let garbled = TempFile::new("garbled.obj", b"v 0 zero 0\nf 1 2 3\n");
        let e = read_obj(&garbled.0).unwrap_err();
        assert!(matches!(e, MeshFileError::Obj { .. }), "{e}");
    }
}
