//! Triangle-mesh tool surfaces (a punch or a die exported from CAD as STL or
//! OBJ), queried through parry3d-f64's [`TriMesh`].
//!
//! The sign convention and the normal are described on [`MeshSurface`].

use std::sync::Arc;

use nalgebra::Vector3;
use parry3d_f64::math::Vector as DVec3;
use parry3d_f64::query::PointQueryWithLocation;
use parry3d_f64::shape::{Polyline, TopologyError, TriMesh, TriMeshFlags, TrianglePointLocation};

use crate::mesh_near::{Closest, Near, rim_distance, rim_polyline};
use crate::surface::{Aabb, Projection};

/// Why a triangle mesh was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// No vertices.
    #[error("a triangle mesh needs vertices, none were given")]
    NoVertices,
    /// No triangles.
    #[error("a triangle mesh needs at least one triangle, none were given")]
    NoTriangles,
    /// A vertex with a NaN or infinite coordinate.
    #[error("vertex {vertex} has a coordinate that is not finite")]
    NotFinite {
        /// Index of the vertex.
        vertex: usize,
    },
    /// A triangle refers to a vertex that does not exist.
    #[error("triangle {triangle} refers to vertex {index}, but there are only {vertices} vertices")]
    IndexOutOfRange {
        /// Index of the triangle.
        triangle: usize,
        /// The bad vertex index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// A triangle without area.
    #[error(
        "triangle {triangle} is degenerate: a repeated vertex, two vertices at the same place, or three vertices on a line"
    )]
    Degenerate {
        /// Index of the triangle.
        triangle: usize,
    },
    /// Two triangles run along a shared edge in the same direction.
    #[error(
        "triangles {first} and {second} both run from vertex {from} to vertex {to}: \
         the winding is inconsistent (one of them is flipped) or more than two triangles share that edge"
    )]
    Winding {
        /// The earlier triangle.
        first: usize,
        /// The later triangle.
        second: usize,
        /// Start vertex of the shared edge (as given to the constructor).
        from: u32,
        /// End vertex of the shared edge (as given to the constructor).
        to: u32,
    },
}

/// A rigid triangle-mesh surface: parry's [`TriMesh`] with oriented
/// pseudo-normals and half-edge topology.
///
/// # Sign convention
///
/// A triangle's normal is the counter-clockwise one: for vertices `a, b, c`
/// it points along `(b − a) × (c − a)`. The fabric's side, where the gap is
/// positive, is the side that normal points to.
///
/// - A **closed** mesh (every edge shared by exactly two triangles) must be
///   wound with its normals pointing out of the solid: the gap is then
///   negative inside the solid and positive outside, like a sphere's.
/// - An **open** mesh (a die face, a sheet) has edges with one triangle
///   only, its rim. Behind a triangle is inside (negative gap), in front is
///   outside; a point whose closest surface point is on the rim (an open
///   edge or one of its vertices) is outside from every side: its gap is the
///   distance to the rim. As for the free end of a profile (see
///   [`Surface::revolution`](crate::Surface::revolution)) the gap then jumps
///   across the *cut* behind the rim, where "behind the last triangle" meets
///   "beside the rim"; elsewhere it is continuous and 1-Lipschitz. Close the
///   mesh if the fabric can come near the back of its rim.
///
/// The side of a point whose closest surface point is on an edge or a vertex
/// is decided with the angle-weighted pseudo-normals of Bærentzen & Aanæs
/// (parry's `ORIENTED` flag), which is exact for a consistently wound mesh.
/// The winding is checked when the mesh is built (parry's half-edge
/// topology): two triangles that run along a shared edge in the same
/// direction are an error.
///
/// # Normal
///
/// For a closest point inside a triangle the normal is that triangle's
/// normal. For a closest point on an edge or a vertex it is the direction
/// from the closest point to the query point (reversed inside), which is the
/// gradient of the signed distance. For a query point on the surface, where
/// that direction is undefined, it is the normal of the triangle parry
/// places the point in (a point exactly on an edge may land in either
/// neighbour's face) or, placed on an edge or a vertex, that feature's
/// normalised pseudo-normal.
///
/// ```
/// use drape_contact::Surface;
/// use nalgebra::Vector3;
///
/// // An open square plate z = 0, wound counter-clockwise seen from +z.
/// let plate = Surface::triangle_mesh(
///     vec![
///         Vector3::new(0.0, 0.0, 0.0),
///         Vector3::new(1.0, 0.0, 0.0),
///         Vector3::new(1.0, 1.0, 0.0),
///         Vector3::new(0.0, 1.0, 0.0),
///     ],
///     vec![[0, 1, 2], [0, 2, 3]],
/// )
/// .unwrap();
/// let p = plate.project(&Vector3::new(0.25, 0.5, -0.1));
/// assert!((p.gap + 0.1).abs() < 1e-15); // below: the back side
/// assert_eq!(p.normal, Vector3::z());
/// ```
#[derive(Clone)]
pub struct MeshSurface {
    /// Shared: a rigid tool's mesh never changes, and tools are cloned
    /// (scenes, sweeps); this also keeps [`Surface`](crate::Surface) small.
    pub(crate) mesh: Arc<TriMesh>,
    /// Every edge has two triangles.
    closed: bool,
    /// The rim of an open mesh: per triangle, whether its edges (in parry's
    /// numbering: ab, bc, ac) have no neighbour; per vertex, whether it is on
    /// such an edge. Empty for a closed mesh.
    pub(crate) rim: Arc<Rim>,
    /// Below this distance a query point is on the surface (relative to the
    /// mesh's size): the direction to it is then rounding noise.
    on_surface: f64,
    /// The triangles' neighbourhoods, for projections that start from the
    /// triangle a point found last ([`Self::project_from`]).
    pub(crate) near: Arc<Near>,
    /// The open edges (none for a closed mesh; a rim extension's outer
    /// edges when it has one), for [`Self::rim_distance`].
    rim_lines: Option<Arc<Polyline>>,
    /// The triangles that are the user's (the first ones); those after them
    /// extend the user's open rims (see [`MeshSurface::with_rim_extension`]).
    pub(crate) own_triangles: usize,
    /// The user's own open rim, as segments, kept through a rim extension
    /// (messages say how far from it a node is). Empty for a closed mesh.
    pub(crate) own_rim: Arc<Vec<[Vector3<f64>; 2]>>,
    /// The width of the rim extension (mm; 0 without).
    pub(crate) extension: f64,
}

/// The open edges and vertices of a mesh.
#[derive(Debug, Default)]
pub(crate) struct Rim {
    pub(crate) edges: Vec<[bool; 3]>,
    vertices: Vec<bool>,
}

impl Rim {
    /// The rim of the triangles `indices` over `vertex_count` vertices.
    fn of(indices: &[[u32; 3]], vertex_count: usize) -> Self {
        let key = |a: u32, b: u32| (a.min(b), a.max(b));
        let mut count = std::collections::HashMap::new();
        for t in indices {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
                *count.entry(key(a, b)).or_insert(0u32) += 1;
            }
        }
        let mut vertices = vec![false; vertex_count];
        let edges = indices
            .iter()
            .map(|t| {
                [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])].map(|(a, b)| {
                    let open = count[&key(a, b)] == 1;
                    if open {
                        vertices[a as usize] = true;
                        vertices[b as usize] = true;
                    }
                    open
                })
            })
            .collect();
        Self { edges, vertices }
    }

    /// The open edges of `mesh`, each once.
    fn segments(&self, mesh: &TriMesh) -> Vec<[Vector3<f64>; 2]> {
        let v = mesh.vertices();
        let mut out = Vec::new();
        for (t, open) in mesh.indices().iter().zip(&self.edges) {
            for (k, (a, b)) in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])]
                .into_iter()
                .enumerate()
            {
                if open[k] {
                    out.push([to_na(v[a as usize]), to_na(v[b as usize])]);
                }
            }
        }
        out
    }
}

/// Relative area below which a triangle counts as degenerate: the sine of
/// its smallest angle, roughly. Far below any meshing tolerance, far above
/// the rounding of a cross product.
pub(crate) const DEGENERATE_SINE: f64 = 1e-12;

/// Relative distance (to the mesh's size) below which a query point is on
/// the surface.
const ON_SURFACE: f64 = 1e-12;

fn to_glam(v: &Vector3<f64>) -> DVec3 {
    DVec3::new(v.x, v.y, v.z)
}

pub(crate) fn to_na(v: DVec3) -> Vector3<f64> {
    Vector3::new(v.x, v.y, v.z)
}

impl MeshSurface {
    /// A mesh from its vertices and its counter-clockwise triangles,
    /// checking that the input is usable: vertices and triangles present,
    /// coordinates finite, indices in range, no triangle without area and a
    /// consistent winding. Vertices at the same place are merged (an STL
    /// file repeats them for every triangle); unused vertices are dropped.
    pub fn new(vertices: Vec<Vector3<f64>>, triangles: Vec<[u32; 3]>) -> Result<Self, MeshError> {
        if vertices.is_empty() {
            return Err(MeshError::NoVertices);
        }
        if triangles.is_empty() {
            return Err(MeshError::NoTriangles);
        }
        if let Some(vertex) = vertices
            .iter()
            .position(|v| !v.iter().all(|c| c.is_finite()))
        {
            return Err(MeshError::NotFinite { vertex });
        }
        for (triangle, t) in triangles.iter().enumerate() {
            if let Some(&index) = t.iter().find(|&&i| i as usize >= vertices.len()) {
                return Err(MeshError::IndexOutOfRange {
                    triangle,
                    index,
                    vertices: vertices.len(),
                });
            }
            let [a, b, c] = t.map(|i| vertices[i as usize]);
            let (ab, ac, bc) = (b - a, c - a, c - b);
            let longest2 = ab
                .norm_squared()
                .max(ac.norm_squared())
                .max(bc.norm_squared());
            // |ab × ac| = |ab|·|ac|·sin α ≤ longest² · sin α: this also
            // catches repeated indices and coincident vertices (0 ≤ 0).
            if ab.cross(&ac).norm() <= DEGENERATE_SINE * longest2 {
                return Err(MeshError::Degenerate { triangle });
            }
        }

        // Built without flags first, then the flags set separately: parry's
        // `with_flags` discards the topology error, which is the only
        // report of an inconsistent winding.
        let original = triangles.clone();
        let mut mesh = TriMesh::new(vertices.iter().map(to_glam).collect(), triangles)
            .map_err(|_| MeshError::NoTriangles)?;
        let flags = TriMeshFlags::ORIENTED
            | TriMeshFlags::MERGE_DUPLICATE_VERTICES
            | TriMeshFlags::HALF_EDGE_TOPOLOGY;
        if let Err(e) = mesh.set_flags(flags) {
            return Err(match e {
                TopologyError::BadAdjacentTrianglesOrientation {
                    edge,
                    triangle1,
                    triangle2,
                } => {
                    // The edge is in merged vertex numbering: name it by the
                    // caller's indices, through the first triangle's corners
                    // (merging keeps the triangles and their order).
                    let merged = mesh.indices()[triangle1 as usize];
                    let given = original[triangle1 as usize];
                    let caller = |m: u32| given[merged.iter().position(|&k| k == m).unwrap_or(0)];
                    MeshError::Winding {
                        first: triangle1 as usize,
                        second: triangle2 as usize,
                        from: caller(edge.0),
                        to: caller(edge.1),
                    }
                }
                // Ruled out above (no repeated index after the area check).
                TopologyError::BadTriangle(t) => MeshError::Degenerate {
                    triangle: t as usize,
                },
            });
        }
        let closed = mesh
            .topology()
            .is_some_and(|t| t.half_edges.iter().all(|h| h.twin != u32::MAX));
        let rim = if closed {
            Rim::default()
        } else {
            Rim::of(mesh.indices(), mesh.vertices().len())
        };
        let aabb = mesh.local_aabb();
        let size = (aabb.maxs - aabb.mins).length();
        let near = Arc::new(Near::of(&mesh));
        let rim_lines = rim_polyline(&mesh).map(Arc::new);
        let own_rim = rim.segments(&mesh);
        Ok(Self {
            own_triangles: mesh.indices().len(),
            mesh: Arc::new(mesh),
            closed,
            rim: Arc::new(rim),
            on_surface: ON_SURFACE * size,
            near,
            rim_lines,
            own_rim: Arc::new(own_rim),
            extension: 0.0,
        })
    }

    /// Whether every edge is shared by two triangles (the mesh bounds a
    /// solid and has an inside).
    pub fn is_closed(&self) -> bool {
        self.closed
    }

    /// The vertices (duplicates merged, unused ones dropped).
    pub fn vertices(&self) -> impl ExactSizeIterator<Item = Vector3<f64>> + '_ {
        self.mesh.vertices().iter().map(|&v| to_na(v))
    }

    /// The triangles, indexing [`vertices`](Self::vertices), in the order
    /// they were given.
    pub fn triangles(&self) -> &[[u32; 3]] {
        self.mesh.indices()
    }

    /// The closest point, outward normal and signed gap of `x`.
    ///
    /// Of several triangles equally close (a point closest to an edge or a
    /// vertex they share) the one of lowest index answers, so that
    /// [`Self::project_from`] gives the same bits from any start.
    pub fn project(&self, x: &Vector3<f64>) -> Projection {
        let mut hint = u32::MAX;
        self.project_from(x, &mut hint)
    }

    /// [`Self::project`], the index of the triangle of the closest point,
    /// and whether that point is on the rim (an open edge or a vertex of
    /// one), where the gap is the distance to the rim from every side.
    pub(crate) fn locate(&self, x: &Vector3<f64>) -> (Projection, u32, bool) {
        let q = to_glam(x);
        let (tri, proj, location) = self.closest(q, u32::MAX);
        let (projection, on_rim) = self.finish(q, tri, proj, location);
        (projection, tri, on_rim)
    }

    /// [`Self::project`], searching first around the triangle `hint` (the
    /// one this point found last, or `u32::MAX`), and setting `hint` to the
    /// triangle found. The answer is the same, bit for bit, as without the
    /// hint: a point that stays near its triangle costs a few triangle
    /// tests instead of a descent of the tree (each triangle keeps a list of
    /// its near neighbours, built with the mesh).
    pub fn project_from(&self, x: &Vector3<f64>, hint: &mut u32) -> Projection {
        let q = to_glam(x);
        let (tri, proj, location) = self.closest(q, *hint);
        *hint = tri;
        self.finish(q, tri, proj, location).0
    }

    /// The closest triangle of `q`, from around `hint` when that is
    /// conclusive, else by parry's query, whose answer is then settled
    /// among the triangles equally close as from any hint.
    fn closest(&self, q: DVec3, hint: u32) -> Closest {
        if let Some(found) = self.near.search(&self.mesh, q, hint) {
            return found;
        }
        // `solid = false`: the closest point on the boundary even from
        // inside; the side comes from the pseudo-normals in `finish`.
        let (proj, (tri, location)) = self.mesh.project_local_point_and_get_location(q, false);
        self.near
            .search(&self.mesh, q, tri)
            .unwrap_or((tri, proj, location))
    }

    /// A lower bound of the distance from `x` to the rim (the open edges),
    /// infinite for a closed mesh.
    pub fn rim_distance(&self, x: &Vector3<f64>) -> f64 {
        self.rim_lines
            .as_ref()
            .map_or(f64::INFINITY, |rim| rim_distance(rim, to_glam(x)))
    }

    /// The projection of `q` from its closest point on triangle `tri`, and
    /// whether that point is on the rim.
    fn finish(
        &self,
        q: DVec3,
        tri: u32,
        proj: parry3d_f64::query::PointProjection,
        location: TrianglePointLocation,
    ) -> (Projection, bool) {
        let p = proj.point;
        let d = q - p;
        // Non-degenerate triangles were checked at construction.
        let face = self.mesh.triangle(tri).normal().unwrap_or(DVec3::Z);
        let pseudo = self
            .mesh
            .pseudo_normals()
            .map_or(face, |pn| match location {
                TrianglePointLocation::OnEdge(i, _) => {
                    pn.edges_pseudo_normal[tri as usize][i as usize]
                }
                TrianglePointLocation::OnVertex(i) => {
                    pn.vertices_pseudo_normal
                        [self.mesh.indices()[tri as usize][i as usize] as usize]
                }
                TrianglePointLocation::OnFace(..) | TrianglePointLocation::OnSolid => face,
            });
        let mut rim = false;
        let (normal, gap) = match location {
            TrianglePointLocation::OnFace(..) | TrianglePointLocation::OnSolid => {
                // Exact along the face normal, already signed.
                (face, d.dot(face))
            }
            _ => {
                let dist = d.length();
                let on_rim = !self.closed
                    && match location {
                        TrianglePointLocation::OnEdge(i, _) => {
                            self.rim.edges[tri as usize][i as usize]
                        }
                        TrianglePointLocation::OnVertex(i) => {
                            self.rim.vertices
                                [self.mesh.indices()[tri as usize][i as usize] as usize]
                        }
                        _ => false,
                    };
                rim = on_rim;
                // A rim is outside from every side; elsewhere strictly
                // behind the pseudo-normal is inside.
                let sign = if !on_rim && d.dot(pseudo) < 0.0 {
                    -1.0
                } else {
                    1.0
                };
                if dist > self.on_surface {
                    (d * (sign / dist), sign * dist)
                } else {
                    // On the surface: the direction to x is noise. A
                    // pseudo-normal can vanish where a sheet folds back on
                    // itself; the face normal then.
                    (pseudo.try_normalize().unwrap_or(face), sign * dist)
                }
            }
        };
        let projection = Projection {
            point: to_na(p),
            normal: to_na(normal),
            gap,
        };
        (projection, rim)
    }

    /// The box around the mesh's triangles.
    pub fn aabb(&self) -> Aabb {
        let b = self.mesh.local_aabb();
        Aabb {
            min: to_na(b.mins),
            max: to_na(b.maxs),
        }
    }
}

/// Compares the vertex and index buffers (after merging duplicates): the
/// derived data (tree, pseudo-normals, topology) follows from them.
impl PartialEq for MeshSurface {
    fn eq(&self, other: &Self) -> bool {
        self.mesh.vertices() == other.mesh.vertices() && self.mesh.indices() == other.mesh.indices()
    }
}

/// A summary: a mesh's buffers are too long to print.
impl std::fmt::Debug for MeshSurface {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshSurface")
            .field("vertices", &self.mesh.vertices().len())
            .field("triangles", &self.mesh.indices().len())
            .field("closed", &self.closed)
            .field("aabb", &self.aabb())
            .finish()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Surface;
    use crate::surface::tests::lipschitz;
    use std::collections::HashMap;

    /// An icosahedron subdivided `levels` times, vertices on the sphere of
    /// radius `r` about the origin, triangles counter-clockwise from outside.
    fn icosphere(r: f64, levels: usize) -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
        let t = (1.0 + 5f64.sqrt()) / 2.0;
        let mut v: Vec<Vector3<f64>> = [
            [-1.0, t, 0.0],
            [1.0, t, 0.0],
            [-1.0, -t, 0.0],
            [1.0, -t, 0.0],
            [0.0, -1.0, t],
            [0.0, 1.0, t],
            [0.0, -1.0, -t],
            [0.0, 1.0, -t],
            [t, 0.0, -1.0],
            [t, 0.0, 1.0],
            [-t, 0.0, -1.0],
            [-t, 0.0, 1.0],
        ]
        .iter()
        .map(|p| Vector3::from(*p).normalize() * r)
        .collect();
        let mut f: Vec<[u32; 3]> = vec![
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        for _ in 0..levels {
            let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
            let mut midpoint = |a: u32, b: u32, v: &mut Vec<Vector3<f64>>| {
                *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                    v.push(((v[a as usize] + v[b as usize]) / 2.0).normalize() * r);
                    (v.len() - 1) as u32
                })
            };
            let mut next = Vec::with_capacity(4 * f.len());
            for &[a, b, c] in &f {
                let ab = midpoint(a, b, &mut v);
                let bc = midpoint(b, c, &mut v);
                let ca = midpoint(c, a, &mut v);
                next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
            f = next;
        }
        (v, f)
    }

    /// Directions spread over the sphere (a Fibonacci lattice).
    fn directions(n: usize) -> impl Iterator<Item = Vector3<f64>> {
        let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
        (0..n).map(move |i| {
            let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let s = (1.0 - z * z).sqrt();
            let a = golden * i as f64;
            Vector3::new(s * a.cos(), s * a.sin(), z)
        })
    }

    #[test]
    fn icosphere_agrees_with_the_sphere_within_the_chordal_error() {
        let r = 50.0;
        let (v, f) = icosphere(r, 3);
        // Chordal error: the faces lie between the inscribed radius (the
        // nearest face plane) and r. Angular size: the largest angle between
        // a face normal and the direction to one of its corners.
        let (mut r_in, mut theta) = (f64::INFINITY, 0.0f64);
        for t in &f {
            let [a, b, c] = t.map(|i| v[i as usize]);
            let n = (b - a).cross(&(c - a)).normalize();
            assert!(n.dot(&a) > 0.0, "the generator winds outwards");
            r_in = r_in.min(n.dot(&a));
            for p in [a, b, c] {
                theta = theta.max(n.angle(&p));
            }
        }
        let sagitta = r - r_in;
        assert!(sagitta > 0.0 && sagitta < 0.01 * r);
        let mesh = Surface::triangle_mesh(v.clone(), f.clone()).unwrap();
        let Surface::Mesh(m) = &mesh else {
            unreachable!()
        };
        assert!(m.is_closed());
        // Right next to the edges and the corners, where the side is
        // decided by pseudo-normals: 1e-10·r in or out along the radius.
        for t in &f {
            for k in 0..3 {
                let (a, b) = (v[t[k] as usize], v[t[(k + 1) % 3] as usize]);
                for p in [a, (a + b) / 2.0, a * 0.9 + b * 0.1] {
                    for s in [-1.0, 1.0] {
                        let x = p + p.normalize() * (s * 1e-10 * r);
                        let q = mesh.project(&x);
                        assert_eq!(q.gap.signum(), s, "{x:?}: gap {}", q.gap);
                        assert!((q.gap - s * 1e-10 * r).abs() < 1e-11 * r);
                    }
                }
            }
        }
        let sphere = Surface::sphere(Vector3::zeros(), r).unwrap();
        let mut checked = 0;
        for d in directions(400) {
            for rho in [0.3, 0.8, 0.9, 0.97, 1.03, 1.1, 1.5, 3.0] {
                let x = d * (rho * r);
                let q = mesh.project(&x);
                let s = sphere.project(&x);
                // The polytope is between the balls of radii r_in and r, so
                // its signed distance exceeds the sphere's by 0 … sagitta.
                let excess = q.gap - s.gap;
                assert!(
                    (-1e-9..=sagitta + 1e-9).contains(&excess),
                    "|x| = {}: mesh gap {} vs sphere {} (sagitta {sagitta})",
                    rho * r,
                    q.gap,
                    s.gap
                );
                assert_eq!(q.gap < 0.0, rho < 1.0, "the side at |x| = {}", rho * r);
                assert!((q.normal.norm() - 1.0).abs() < 1e-12);
                assert!((q.gap.abs() - (x - q.point).norm()).abs() < 1e-9);
                // Normal against the radial direction: within the faces'
                // angular size outside; inside, the angle grows as the
                // point nears the centre (tan ≤ r·sin θ / depth of the face
                // plane below x), so only the outer shell is checked.
                let angle = q.normal.angle(&s.normal);
                if rho > 1.0 {
                    assert!(angle <= theta + 1e-9, "angle {angle} > {theta}");
                } else if rho >= 0.8 {
                    let depth = r_in - (r - rho * r);
                    assert!(angle <= (r * theta.sin() / depth).atan() + 1e-9);
                }
                checked += 1;
            }
        }
        assert_eq!(checked, 3200);
        // A vertex lies on the sphere: gap zero there and the normal is the
        // (normalised) vertex pseudo-normal, radial by symmetry of the
        // icosahedron's original corners.
        let corner = Vector3::new(-1.0, (1.0 + 5f64.sqrt()) / 2.0, 0.0).normalize() * r;
        let q = mesh.project(&corner);
        assert!(q.gap.abs() < 1e-12);
        assert!((q.normal - corner / r).norm() < 1e-9);
        let b = mesh.aabb();
        assert!((b.max - Vector3::repeat(r)).amax() < 0.1 * r && b.max.amax() <= r + 1e-12);
        assert!((b.min + b.max).amax() < 1e-9);
    }

    /// The box [0, 2] × [0, 3] × [0, 4], faces wound outwards.
    fn closed_box() -> Surface {
        let v = (0..8)
            .map(|i| {
                Vector3::new(
                    2.0 * (i & 1) as f64,
                    3.0 * ((i >> 1) & 1) as f64,
                    4.0 * ((i >> 2) & 1) as f64,
                )
            })
            .collect();
        // Corner i has x = bit 0, y = bit 1, z = bit 2.
        let quads = [
            [0, 2, 3, 1], // z = 0, normal −z
            [4, 5, 7, 6], // z = 4, +z
            [0, 1, 5, 4], // y = 0, −y
            [2, 6, 7, 3], // y = 3, +y
            [0, 4, 6, 2], // x = 0, −x
            [1, 3, 7, 5], // x = 2, +x
        ];
        let f = quads
            .iter()
            .flat_map(|&[a, b, c, d]| [[a, b, c], [a, c, d]])
            .collect();
        Surface::triangle_mesh(v, f).unwrap()
    }

    #[test]
    fn closed_box_has_exact_gaps_and_a_negative_inside() {
        let b = closed_box();
        let Surface::Mesh(m) = &b else { unreachable!() };
        assert!(m.is_closed());
        assert_eq!(m.triangles().len(), 12);
        // Above each face's centre (and off its diagonal, where the two
        // triangles meet).
        let cases = [
            (Vector3::new(1.2, 1.4, 4.5), 0.5, Vector3::z()),
            (Vector3::new(1.2, 1.4, -0.25), 0.25, -Vector3::z()),
            (Vector3::new(1.3, 3.75, 2.2), 0.75, Vector3::y()),
            (Vector3::new(0.5, -1.0, 2.2), 1.0, -Vector3::y()),
            (Vector3::new(2.125, 1.0, 1.0), 0.125, Vector3::x()),
            (Vector3::new(-2.0, 1.0, 3.0), 2.0, -Vector3::x()),
            // Inside: negative, to the nearest face.
            (Vector3::new(1.0, 1.5, 3.9), -0.1, Vector3::z()),
            (Vector3::new(0.3, 1.5, 2.0), -0.3, -Vector3::x()),
            (Vector3::new(1.0, 1.5, 2.0), -1.0, Vector3::x()),
            // On a face, and across a face's diagonal (shared edge).
            (Vector3::new(1.0, 1.0, 4.0), 0.0, Vector3::z()),
            (Vector3::new(1.0, 1.5, 4.0), 0.0, Vector3::z()),
        ];
        for (x, gap, normal) in cases {
            let q = b.project(&x);
            assert!((q.gap - gap).abs() < 1e-14, "{x:?}: gap {} ≠ {gap}", q.gap);
            // At the box's centre −x and +x are equally near: either.
            if x != Vector3::new(1.0, 1.5, 2.0) {
                assert!((q.normal - normal).norm() < 1e-14, "{x:?}: {:?}", q.normal);
            }
            assert!((x - q.normal * q.gap - q.point).norm() < 1e-14);
        }
        // Off a corner: the distance to it, along the diagonal.
        let q = b.project(&Vector3::new(3.0, 4.0, 5.0));
        assert!((q.gap - 3f64.sqrt()).abs() < 1e-14);
        assert!((q.normal - Vector3::repeat(1.0 / 3f64.sqrt())).norm() < 1e-14);
        assert!((q.point - Vector3::new(2.0, 3.0, 4.0)).norm() < 1e-14);
        // Off an edge.
        let q = b.project(&Vector3::new(1.0, -0.3, -0.4));
        assert!((q.gap - 0.5).abs() < 1e-14);
        assert!((q.normal - Vector3::new(0.0, -0.6, -0.8)).norm() < 1e-14);
        // On an edge and on a corner: zero gap; the normal is a face's
        // (parry places a point exactly on an edge in either triangle's
        // face) or the feature's pseudo-normal.
        let q = b.project(&Vector3::new(1.0, 0.0, 0.0));
        assert_eq!(q.gap, 0.0);
        let edge = [
            -Vector3::y(),
            -Vector3::z(),
            Vector3::new(0.0, -1.0, -1.0).normalize(),
        ];
        assert!(
            edge.iter().any(|n| (q.normal - n).norm() < 1e-14),
            "{:?}",
            q.normal
        );
        let q = b.project(&Vector3::new(2.0, 3.0, 4.0));
        assert_eq!(q.gap, 0.0);
        let corner = [
            Vector3::x(),
            Vector3::y(),
            Vector3::z(),
            Vector3::repeat(1.0 / 3f64.sqrt()),
        ];
        assert!(
            corner.iter().any(|n| (q.normal - n).norm() < 1e-14),
            "{:?}",
            q.normal
        );
        let aabb = b.aabb();
        assert_eq!(aabb.min, Vector3::zeros());
        assert_eq!(aabb.max, Vector3::new(2.0, 3.0, 4.0));
    }

    /// The exact signed distance to the box [0, 2] × [0, 3] × [0, 4].
    fn box_distance(x: &Vector3<f64>) -> f64 {
        let h = Vector3::new(1.0, 1.5, 2.0);
        let q = (x - h).abs() - h;
        q.sup(&Vector3::zeros()).norm() + q.max().min(0.0)
    }

    proptest::proptest! {
        #[test]
        fn box_gap_is_the_exact_signed_distance(
            x in -1.0f64..3.0, y in -1.0f64..4.0, z in -1.0f64..5.0,
        ) {
            let b = closed_box();
            let p = Vector3::new(x, y, z);
            let q = b.project(&p);
            proptest::prop_assert!((q.gap - box_distance(&p)).abs() < 1e-13);
            proptest::prop_assert!((p - q.normal * q.gap - q.point).norm() < 1e-13);
        }

        /// Near edges and corners the side must not flip: offsets down to
        /// 1e-11 of the box's size off an edge or a corner, in any direction.
        #[test]
        fn box_side_is_right_next_to_edges_and_corners(
            corner in 0usize..8, along in 0usize..3, t in 0.0f64..1.0,
            exponent in 1i32..12, d in proptest::array::uniform3(-1.0f64..1.0),
        ) {
            let b = closed_box();
            let size = Vector3::new(2.0, 3.0, 4.0);
            let mut base = Vector3::new(
                size.x * (corner & 1) as f64,
                size.y * ((corner >> 1) & 1) as f64,
                size.z * ((corner >> 2) & 1) as f64,
            );
            // Slide along one edge from the corner (t = 0: the corner).
            base[along] = if base[along] == 0.0 { t * size[along] } else { size[along] * (1.0 - t) };
            let d = Vector3::from(d);
            proptest::prop_assume!(d.norm() > 1e-3);
            let p = base + d.normalize() * 10f64.powi(-exponent);
            let q = b.project(&p);
            let exact = box_distance(&p);
            proptest::prop_assert!(
                (q.gap - exact).abs() < 1e-14,
                "{:?}: {} vs {}", p, q.gap, exact
            );
        }
    }

    fn plate(flipped: bool) -> Surface {
        let v = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let f = if flipped {
            vec![[0, 2, 1], [0, 3, 2]]
        } else {
            vec![[0, 1, 2], [0, 2, 3]]
        };
        Surface::triangle_mesh(v, f).unwrap()
    }

    #[test]
    fn open_plate_gap_sign_is_the_side_of_the_triangle_normal() {
        let up = plate(false);
        let Surface::Mesh(m) = &up else {
            unreachable!()
        };
        assert!(!m.is_closed());
        let q = up.project(&Vector3::new(0.3, 0.6, 0.2));
        assert!((q.gap - 0.2).abs() < 1e-15);
        assert_eq!(q.normal, Vector3::z());
        assert_eq!(q.point, Vector3::new(0.3, 0.6, 0.0));
        let q = up.project(&Vector3::new(0.3, 0.6, -0.2));
        assert!((q.gap + 0.2).abs() < 1e-15);
        assert_eq!(q.normal, Vector3::z());
        // Beyond the rim, above: the distance to the edge x = 1, along the
        // direction from it.
        let q = up.project(&Vector3::new(1.3, 0.5, 0.4));
        assert!((q.gap - 0.5).abs() < 1e-15);
        assert!((q.normal - Vector3::new(0.6, 0.0, 0.8)).norm() < 1e-15);
        // Beyond the rim, below: the rim is outside from every side.
        let q = up.project(&Vector3::new(1.3, 0.5, -0.4));
        assert!((q.gap - 0.5).abs() < 1e-15);
        assert!((q.normal - Vector3::new(0.6, 0.0, -0.8)).norm() < 1e-15);
        // Off a rim corner, below: outside too.
        let q = up.project(&Vector3::new(-0.3, 1.4, -1.2));
        assert!((q.gap - 1.3).abs() < 1e-14);
        // Behind the plate, inside its rim: inside.
        let q = up.project(&Vector3::new(0.9, 0.5, -0.4));
        assert!((q.gap + 0.4).abs() < 1e-15);
        // Level with the rim: outside.
        let q = up.project(&Vector3::new(-0.5, 0.5, 0.0));
        assert!((q.gap - 0.5).abs() < 1e-15);
        assert!((q.normal + Vector3::x()).norm() < 1e-15);
        // Wound the other way, the fabric's side is below.
        let down = plate(true);
        let q = down.project(&Vector3::new(0.3, 0.6, 0.2));
        assert!((q.gap + 0.2).abs() < 1e-15);
        assert_eq!(q.normal, -Vector3::z());
        let q = down.project(&Vector3::new(0.3, 0.6, -0.2));
        assert!((q.gap - 0.2).abs() < 1e-15);
        assert_ne!(up, down);
        assert_eq!(up, plate(false));
        assert!(format!("{up:?}").contains("triangles: 2"));
    }

    #[test]
    fn bad_meshes_are_rejected_with_the_culprit_named() {
        let tri = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
        ];
        let err = |v: Vec<Vector3<f64>>, f: Vec<[u32; 3]>| match Surface::triangle_mesh(v, f) {
            Err(SurfaceError::Mesh(e)) => e,
            other => panic!("expected a mesh error, got {other:?}"),
        };
        use crate::SurfaceError;
        assert_eq!(err(vec![], vec![[0, 1, 2]]), MeshError::NoVertices);
        assert_eq!(err(tri.clone(), vec![]), MeshError::NoTriangles);
        assert_eq!(
            err(tri.clone(), vec![[0, 1, 2], [0, 3, 1]]),
            MeshError::IndexOutOfRange {
                triangle: 1,
                index: 3,
                vertices: 3
            }
        );
        assert_eq!(
            err(tri.clone(), vec![[0, 1, 1]]),
            MeshError::Degenerate { triangle: 0 }
        );
        let mut collinear = tri.clone();
        collinear[2] = Vector3::new(0.5, 0.0, 0.0);
        assert_eq!(
            err(collinear, vec![[0, 1, 2]]),
            MeshError::Degenerate { triangle: 0 }
        );
        let mut coincident = tri.clone();
        coincident.push(Vector3::new(1.0, 0.0, 0.0));
        assert_eq!(
            err(coincident, vec![[0, 1, 2], [1, 3, 2]]),
            MeshError::Degenerate { triangle: 1 }
        );
        let mut nan = tri.clone();
        nan[1].y = f64::NAN;
        assert_eq!(
            err(nan, vec![[0, 1, 2]]),
            MeshError::NotFinite { vertex: 1 }
        );
        // The second triangle runs along 1 → 2 like the first.
        let mut quad = tri.clone();
        quad.push(Vector3::new(1.0, 1.0, 0.0));
        let e = err(quad, vec![[0, 1, 2], [1, 2, 3]]);
        assert_eq!(
            e,
            MeshError::Winding {
                first: 0,
                second: 1,
                from: 1,
                to: 2
            }
        );
        let message = SurfaceError::from(e).to_string();
        assert!(message.contains("triangles 0 and 1"), "{message}");
    }

    /// Points on every edge (midpoint and a point near one end) and every
    /// vertex of a mesh, where the side is decided by pseudo-normals.
    fn features(s: &Surface) -> Vec<Vector3<f64>> {
        let Surface::Mesh(m) = s else { unreachable!() };
        let v: Vec<_> = m.vertices().collect();
        let mut out = v.clone();
        for t in m.triangles() {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
                let (a, b) = (v[a as usize], v[b as usize]);
                out.extend([(a + b) / 2.0, a * 0.9 + b * 0.1]);
            }
        }
        out
    }

    proptest::proptest! {
        /// A closed mesh's gap is 1-Lipschitz: random pairs, and pairs
        /// straddling every edge and vertex (where a wrong pseudo-normal
        /// would flip the side).
        #[test]
        fn a_closed_meshs_gap_is_1_lipschitz(
            a in proptest::array::uniform3(-60.0f64..60.0),
            dir in proptest::array::uniform3(-1.0f64..1.0),
            log_d in -8.0f64..2.0,
            pick in 0usize..10_000,
        ) {
            let dir = Vector3::from(dir);
            proptest::prop_assume!(dir.norm() > 1e-3);
            let step = dir.normalize() * 10f64.powf(log_d);
            let a = Vector3::from(a);
            let (v, f) = icosphere(50.0, 1);
            for s in [closed_box(), Surface::triangle_mesh(v, f).unwrap()] {
                lipschitz(&s, &a, &(a + step)).map_err(proptest::test_runner::TestCaseError::fail)?;
                let feats = features(&s);
                let p = feats[pick % feats.len()];
                lipschitz(&s, &(p - step), &(p + step))
                    .map_err(proptest::test_runner::TestCaseError::fail)?;
            }
        }

        /// An open plate is 1-Lipschitz across its interior edges and
        /// wherever a pair does not cross the cut behind its rim (below
        /// z = 0, on the square's border), and beyond the rim its gap is the
        /// distance to the rim, from every side.
        #[test]
        fn an_open_plate_is_1_lipschitz_off_its_cut(
            a in proptest::array::uniform3(-1.0f64..2.0),
            dir in proptest::array::uniform3(-1.0f64..1.0),
            log_d in -8.0f64..-1.0,
            pick in 0usize..10_000,
        ) {
            let dir = Vector3::from(dir);
            proptest::prop_assume!(dir.norm() > 1e-3);
            let d = 10f64.powf(log_d);
            let step = dir.normalize() * d;
            let a = Vector3::from(a);
            let up = plate(false);
            let near_cut = |p: &Vector3<f64>| {
                p.z < 2.0 * d
                    && (0..2).any(|k| {
                        let other = 1 - k;
                        (p[k].abs() < 2.0 * d || (p[k] - 1.0).abs() < 2.0 * d)
                            && p[other] > -2.0 * d
                            && p[other] < 1.0 + 2.0 * d
                    })
            };
            if !near_cut(&a) {
                lipschitz(&up, &a, &(a + step)).map_err(proptest::test_runner::TestCaseError::fail)?;
            }
            // Interior edges and vertices, straddled (the diagonal, and
            // points of the plate away from its border).
            let p = Vector3::new(0.5, 0.5, 0.0) + Vector3::new(0.3, 0.3, 0.0) * ((pick % 7) as f64 / 3.0 - 1.0);
            lipschitz(&up, &(p - step), &(p + step)).map_err(proptest::test_runner::TestCaseError::fail)?;
            // Beside the rim (outside the square's footprint): the distance
            // to the square, positive above and below.
            let clamp = Vector3::new(a.x.clamp(0.0, 1.0), a.y.clamp(0.0, 1.0), 0.0);
            if clamp.xy() != a.xy() {
                let q = up.project(&a);
                proptest::prop_assert!((q.gap - (a - clamp).norm()).abs() < 1e-12, "{:?}: {}", a, q.gap);
            }
        }
    }
}
