//! Open tool meshes as a mould comes from CAD: which side of an open
//! surface a blank lies on (so the file's normals need not point to it),
//! the surface wound the other way, a tangential extension of its open
//! rims (so that a node reaching a rim keeps a continuous gap), and where
//! on a tool a node is, for the messages of a failed run.
//!
//! What it is not: no repair of a badly wound or degenerate mesh (see
//! `mesh_repair`), no file reading.
//!
//! # Rim extension
//!
//! Behind an open surface, right at its rim, the signed gap cannot be
//! continuous (see [`MeshSurface`]): a node that slides over the rim and
//! is then pressed back under it (a ply pinched between a punch's and a
//! mould's edges) crosses the cut there, and is either thrown out through
//! the closest point or stopped as a contact fault. An extension adds a
//! strip of `length` around every open boundary: each open edge gets a
//! quad continuing its triangle's plane outward, perpendicular to the edge
//! (at a boundary vertex the two strips meet along the bisector of their
//! outward directions, mitred so that both strips keep their width, at
//! most doubled at a sharp corner). The cut moves `length` away from the
//! user's rim, and within that distance of the rim the gap is continuous
//! and 1-Lipschitz (tested). Where the rim is concave with a radius below
//! `length`, neighbouring strips overlap; the gap stays that of the nearest
//! triangle.

use std::collections::HashMap;
use std::sync::Arc;

use nalgebra::Vector3;

use crate::mesh::{MeshError, MeshSurface};

/// How the points of a blank lie about an open surface: in front (the
/// side its triangles' counter-clockwise normals point to) or behind.
/// Points whose closest surface point is on the rim (beside the surface)
/// or within the tolerance of it say nothing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Sides {
    /// Points in front.
    pub front: usize,
    /// Points behind.
    pub back: usize,
    /// The first point in front, by index.
    pub first_front: Option<usize>,
    /// The first point behind, by index.
    pub first_back: Option<usize>,
}

/// Why a rim cannot be extended.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RimError {
    /// The length is not a positive finite number.
    #[error("the rim extension must be a positive length, got {0}")]
    Length(f64),
    /// Two open boundaries touch at a vertex.
    #[error(
        "vertex at ({:.6}, {:.6}, {:.6}) starts {count} open edges: two open boundaries touch there, \
         so the rim cannot be extended around it",
        position[0], position[1], position[2]
    )]
    Pinched {
        /// Where the vertex is.
        position: [f64; 3],
        /// Open edges leaving it.
        count: usize,
    },
    /// The extended mesh is not a valid mesh.
    #[error("the extended mesh: {0}")]
    Mesh(#[from] MeshError),
}

impl MeshSurface {
    /// Which side of the surface `points` lie on (see [`Sides`]); a point
    /// within `tolerance` of the surface counts on neither side.
    pub fn sides(&self, points: &[Vector3<f64>], tolerance: f64) -> Sides {
        let mut sides = Sides::default();
        for (i, x) in points.iter().enumerate() {
            let (p, _, on_rim) = self.locate(x);
            if on_rim || p.gap.abs() <= tolerance {
                continue;
            }
            if p.gap > 0.0 {
                sides.front += 1;
                sides.first_front.get_or_insert(i);
            } else {
                sides.back += 1;
                sides.first_back.get_or_insert(i);
            }
        }
        sides
    }

    /// How many of `points` lie on the surface at the start, inside the
    /// fabric's contact band: their closest point is on it (not beside its
    /// rim) and within `tolerance`; with the first of them by index. Such
    /// a point is pushed out by the whole band in the first step.
    pub fn touching(&self, points: &[Vector3<f64>], tolerance: f64) -> (usize, Option<usize>) {
        let mut count = 0;
        let mut first = None;
        for (i, x) in points.iter().enumerate() {
            let (p, _, on_rim) = self.locate(x);
            if !on_rim && p.gap.abs() <= tolerance {
                count += 1;
                first.get_or_insert(i);
            }
        }
        (count, first)
    }

    /// The same surface with every triangle wound the other way: its
    /// normals, and the fabric's side, reversed.
    pub fn flipped(&self) -> Self {
        let vertices: Vec<Vector3<f64>> = self.vertices().collect();
        let triangles = self
            .triangles()
            .iter()
            .map(|t| [t[0], t[2], t[1]])
            .collect();
        let mut out = Self::new(vertices, triangles)
            .expect("the same triangles, wound the other way, are as valid as before");
        out.own_triangles = self.own_triangles;
        out.own_rim = Arc::clone(&self.own_rim);
        out.extension = self.extension;
        out
    }

    /// The surface with its open rims extended by `length` (see the
    /// module's docs); a closed mesh is returned as it is.
    pub fn with_rim_extension(&self, length: f64) -> Result<Self, RimError> {
        if !(length.is_finite() && length > 0.0) {
            return Err(RimError::Length(length));
        }
        if self.is_closed() {
            return Ok(self.clone());
        }
        let mut vertices: Vec<Vector3<f64>> = self.vertices().collect();
        let mut triangles = self.triangles().to_vec();
        // Open edges as wound by their triangle (a → b), with the outward
        // direction in the triangle's plane, perpendicular to the edge.
        let mut open: Vec<(u32, u32, Vector3<f64>)> = Vec::new();
        for (t, corners) in triangles.iter().enumerate() {
            let [a, b, c] = corners.map(|i| vertices[i as usize]);
            let normal = (b - a).cross(&(c - a)).normalize();
            // parry's edge numbering: ab, bc, ac (run c → a by the winding).
            for (k, (from, to)) in [(0, 1), (1, 2), (2, 0)].into_iter().enumerate() {
                if self.rim.edges[t][k] {
                    let (p, q) = (corners[from], corners[to]);
                    let along = vertices[q as usize] - vertices[p as usize];
                    open.push((p, q, along.cross(&normal).normalize()));
                }
            }
        }
        let mut leaving: HashMap<u32, usize> = HashMap::new();
        let mut arriving: HashMap<u32, usize> = HashMap::new();
        let mut starts: HashMap<u32, usize> = HashMap::new();
        for (e, &(p, q, _)) in open.iter().enumerate() {
            *starts.entry(p).or_insert(0) += 1;
            leaving.insert(p, e);
            arriving.insert(q, e);
        }
        // Deterministic order: by vertex index.
        let mut rim_vertices: Vec<u32> = leaving.keys().copied().collect();
        rim_vertices.sort_unstable();
        let mut moved: HashMap<u32, u32> = HashMap::new();
        for &v in &rim_vertices {
            let count = starts[&v];
            // The open edges of a consistently wound mesh form closed
            // loops: every vertex on them has one arriving per leaving.
            let (Some(&out_edge), Some(&in_edge)) = (leaving.get(&v), arriving.get(&v)) else {
                return Err(RimError::Pinched {
                    position: vertices[v as usize].into(),
                    count,
                });
            };
            if count != 1 {
                return Err(RimError::Pinched {
                    position: vertices[v as usize].into(),
                    count,
                });
            }
            let (o_in, o_out) = (open[in_edge].2, open[out_edge].2);
            let bisector = o_in + o_out;
            let direction = match bisector.try_normalize(1e-9) {
                // A mitre keeps both strips `length` wide, up to twice that.
                Some(d) => d * (1.0 / d.dot(&o_in).max(0.5)),
                // The rim turns back on itself: straight on, along the
                // arriving edge.
                None => {
                    let (p, q, _) = open[in_edge];
                    (vertices[q as usize] - vertices[p as usize]).normalize()
                }
            };
            moved.insert(v, vertices.len() as u32);
            vertices.push(vertices[v as usize] + direction * length);
        }
        for &(p, q, _) in &open {
            let (p2, q2) = (moved[&p], moved[&q]);
            // Run p → q the other way from the triangle inside.
            triangles.push([q, p, p2]);
            triangles.push([q, p2, q2]);
        }
        let mut out = Self::new(vertices, triangles)?;
        out.own_triangles = self.own_triangles;
        out.own_rim = Arc::clone(&self.own_rim);
        out.extension = self.extension + length;
        Ok(out)
    }

    /// The width of the rim extension (mm; 0 without one).
    pub fn rim_extension(&self) -> f64 {
        self.extension
    }

    /// How many of the triangles are the user's (the rest extend its rims).
    pub fn own_triangles(&self) -> usize {
        self.own_triangles
    }

    /// How far beyond the open rim `points` reach: the largest distance
    /// to the surface of a point whose closest point is on the rim (0 when
    /// none is, and for a closed mesh). A blank cut larger than the mould's
    /// trimmed surface overhangs its rim by about this much.
    pub fn overhang(&self, points: &[Vector3<f64>]) -> f64 {
        points
            .iter()
            .map(|x| self.locate(x))
            .filter(|(_, _, on_rim)| *on_rim)
            .map(|(p, _, _)| p.gap.abs())
            .fold(0.0, f64::max)
    }

    /// Whether the closest point of `x` lies on the rim extension rather
    /// than on the user's own triangles (false without an extension): the
    /// part of a tool that is drape's, not the user's mould.
    pub fn on_rim_extension(&self, x: &Vector3<f64>) -> bool {
        self.locate(x).1 as usize >= self.own_triangles
    }

    /// Where `x` is on this surface: the projection, the distance of the
    /// closest point from the user's own open rim (none for a closed mesh)
    /// and whether the closest point is on the rim extension.
    pub(crate) fn rim_place(&self, x: &Vector3<f64>) -> (crate::Projection, Option<f64>, bool) {
        let (p, tri, _) = self.locate(x);
        let rim = (!self.own_rim.is_empty()).then(|| {
            self.own_rim
                .iter()
                .map(|[a, b]| segment_distance(&p.point, a, b))
                .fold(f64::INFINITY, f64::min)
        });
        (p, rim, tri as usize >= self.own_triangles)
    }
}

/// The distance from `x` to the segment from `a` to `b`.
fn segment_distance(x: &Vector3<f64>, a: &Vector3<f64>, b: &Vector3<f64>) -> f64 {
    let ab = b - a;
    let s = ((x - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    (x - (a + ab * s)).norm()
}

/// Where on a tool a point is, for the messages of a failed run.
#[derive(Debug, Clone, PartialEq)]
pub struct ToolPlace {
    /// The tool's name.
    pub tool: String,
    /// The point whose place this is (mm, world frame).
    pub from: Vector3<f64>,
    /// The closest point on the tool (mm, world frame).
    pub point: Vector3<f64>,
    /// The point's signed gap to the tool (mm, the surface's own).
    pub gap: f64,
    /// For an open tool: how far the closest point is from the tool's own
    /// open rim (mm).
    pub rim_distance: Option<f64>,
    /// Whether the closest point is on the tool's rim extension.
    pub on_extension: bool,
    /// The width of the tool's rim extension (mm; 0 without one).
    pub extension: f64,
}

impl std::fmt::Display for ToolPlace {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let p = self.point;
        write!(
            f,
            "tool `{}` at ({:.2}, {:.2}, {:.2}) mm (gap {:.3e} mm)",
            self.tool, p.x, p.y, p.z, self.gap
        )?;
        match self.rim_distance {
            Some(d) if self.on_extension => write!(
                f,
                ", on its rim extension ({:.2} mm wide) {d:.2} mm beyond its open rim: near the open rim",
                self.extension
            ),
            // Within a micron: on the rim.
            Some(d) if d < 1e-3 => write!(f, ", on its open rim"),
            Some(d) => write!(f, ", {d:.2} mm from its open rim"),
            None => write!(f, " (a closed tool, no rim)"),
        }
    }
}

impl ToolPlace {
    /// Where `x` is on `tool` displaced by `displacement` along its axis.
    pub fn of(tool: &crate::Tool, x: &Vector3<f64>, displacement: f64) -> Self {
        let shift = tool.motion.direction() * displacement;
        let local = x - shift;
        let (p, rim_distance, on_extension, extension) = match &tool.surface {
            crate::Surface::Mesh(m) => {
                let (p, rim, on) = m.rim_place(&local);
                (p, rim, on, m.rim_extension())
            }
            s => {
                let p = s.project(&local);
                (p, s.free_end_distance(&p.point), false, 0.0)
            }
        };
        Self {
            tool: tool.name.clone(),
            from: *x,
            point: p.point + shift,
            gap: p.gap,
            rim_distance,
            on_extension,
            extension,
        }
    }

    /// The place on the nearest of `tools` (by |gap|, each at its
    /// displacement), none without tools.
    pub fn nearest(tools: &[crate::Tool], displacement: &[f64], x: &Vector3<f64>) -> Option<Self> {
        tools
            .iter()
            .zip(displacement)
            .map(|(t, &u)| Self::of(t, x, u))
            .min_by(|a, b| a.gap.abs().total_cmp(&b.gap.abs()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::surface::tests::lipschitz;
    use crate::{Surface, Tool, ToolMotion};

    /// Curvature radius, half sizes and cells of the trough.
    const R: f64 = 50.0;
    const HALF: f64 = 20.0;
    const CELLS: u32 = 8;

    /// An open trough z = x²/(2R) over [−HALF, HALF]², its normals up
    /// (into the trough) or down.
    fn trough(up: bool) -> MeshSurface {
        let n = CELLS;
        let mut v = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let x = -HALF + 2.0 * HALF * f64::from(i) / f64::from(n);
                let y = -HALF + 2.0 * HALF * f64::from(j) / f64::from(n);
                v.push(Vector3::new(x, y, x * x / (2.0 * R)));
            }
        }
        let id = |i: u32, j: u32| j * (n + 1) + i;
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                if up {
                    t.extend([[a, b, c], [a, c, d]]);
                } else {
                    t.extend([[a, c, b], [a, d, c]]);
                }
            }
        }
        MeshSurface::new(v, t).unwrap()
    }

    /// The trough's surface point over (x, y) and its upward unit normal.
    fn on_trough(x: f64, y: f64) -> (Vector3<f64>, Vector3<f64>) {
        let p = Vector3::new(x, y, x * x / (2.0 * R));
        (p, Vector3::new(-x / R, 0.0, 1.0).normalize())
    }

    #[test]
    fn the_side_of_a_blank_is_found_whichever_way_the_file_winds() {
        // A blank 3 mm above the trough, and reaching 10 mm beyond its rim
        // (those nodes' closest points are on the rim: they say nothing).
        let blank: Vec<Vector3<f64>> = (0..=12)
            .flat_map(|i| (0..=12).map(move |j| (i, j)))
            .map(|(i, j)| {
                let (x, y) = (-30.0 + 5.0 * f64::from(i), -30.0 + 5.0 * f64::from(j));
                Vector3::new(x, y, 3.0 + HALF * HALF / (2.0 * R))
            })
            .collect();
        let up = trough(true).sides(&blank, 0.1);
        let down = trough(false).sides(&blank, 0.1);
        assert!(up.front > 0 && up.back == 0, "{up:?}");
        assert_eq!((down.front, down.back), (up.back, up.front));
        assert_eq!(down.first_back, up.first_front);
        // Mirrored below the trough, wound up: behind.
        let mirrored: Vec<_> = blank.iter().map(|p| Vector3::new(p.x, p.y, -p.z)).collect();
        let s = trough(true).sides(&mirrored, 0.1);
        assert!(s.front == 0 && s.back > 0, "{s:?}");
        // Within the tolerance of the surface: neither side.
        let (p, _) = on_trough(5.0, 5.0);
        let s = trough(true).sides(&[p + Vector3::z() * 0.05, p - Vector3::z() * 0.05], 0.1);
        assert_eq!((s.front, s.back), (0, 0));
        // A blank through the trough: both sides, first nodes named.
        let s = trough(true).sides(&[p + Vector3::z(), p - Vector3::z()], 0.1);
        assert_eq!((s.first_front, s.first_back), (Some(0), Some(1)));
    }

    #[test]
    fn a_flipped_mesh_has_the_opposite_gap_and_normal() {
        let (up, down) = (trough(true), trough(false));
        assert_eq!(up.flipped(), down);
        for x in [
            Vector3::new(1.0, 2.0, 3.0),
            Vector3::new(-7.0, 5.0, -1.0),
            Vector3::new(19.0, -19.5, 4.5),
        ] {
            let (a, b) = (up.flipped().project(&x), up.project(&x));
            assert_eq!(a.gap, -b.gap);
            assert_eq!(a.normal, -b.normal);
        }
    }

    #[test]
    fn the_extension_continues_each_rim_triangles_plane_by_its_length() {
        let length = 4.0;
        let m = trough(true).with_rim_extension(length).unwrap();
        assert_eq!(m.own_triangles(), 2 * 64);
        // One quad (two triangles) per open edge: 4 sides of 8 edges.
        assert_eq!(m.triangles().len(), 2 * 64 + 2 * 32);
        assert_eq!(m.rim_extension(), length);
        // Beyond the edge x = HALF, along the rim triangle's plane: on the
        // extension, at zero gap; its slope is the last cell's chord.
        let (rim, _) = on_trough(HALF, 0.0);
        let (inner, _) = on_trough(HALF - 2.0 * HALF / f64::from(CELLS), 0.0);
        let along = (rim - inner).normalize();
        let beyond = rim + along * (0.5 * length);
        let q = m.project(&beyond);
        assert!(q.gap.abs() < 1e-12, "{}", q.gap);
        let chord_normal = Vector3::new(-along.z, 0.0, along.x);
        // Under it: inside (negative), where without the extension the rim
        // is outside from every side.
        let under = beyond - chord_normal;
        assert!((m.project(&under).gap + 1.0).abs() < 1e-12);
        assert!((trough(true).project(&under).gap - (under - rim).norm()).abs() < 1e-12);
        // A corner's vertex is mitred: its strips keep their width.
        // Its two rim edges' outward directions are perpendicular, so the
        // corner moves by √2 times the length.
        let corner = Vector3::new(HALF, HALF, HALF * HALF / (2.0 * R));
        let moved: Vec<_> = m
            .vertices()
            .filter(|v| v.x > HALF + 1e-9 && v.y > HALF + 1e-9)
            .collect();
        assert_eq!(moved.len(), 1);
        assert!(((moved[0] - corner).norm() - 2f64.sqrt() * length).abs() < 1e-12);
        // The winding of the strips agrees with the mesh's (checked by
        // `MeshSurface::new`), and flipping keeps the extension.
        assert_eq!(m.flipped().rim_extension(), length);
        assert!(matches!(
            trough(true).with_rim_extension(0.0),
            Err(RimError::Length(_))
        ));
    }

    #[test]
    fn a_rim_that_touches_itself_cannot_be_extended() {
        // Two squares sharing one corner only.
        let v = vec![
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(1.0, 0.0, 0.0),
            Vector3::new(1.0, 1.0, 0.0),
            Vector3::new(0.0, 1.0, 0.0),
            Vector3::new(2.0, 1.0, 0.0),
            Vector3::new(2.0, 2.0, 0.0),
            Vector3::new(1.0, 2.0, 0.0),
        ];
        let t = vec![[0, 1, 2], [0, 2, 3], [2, 4, 5], [2, 5, 6]];
        let m = MeshSurface::new(v, t).unwrap();
        let e = m.with_rim_extension(0.5).unwrap_err();
        assert!(
            matches!(e, RimError::Pinched { position, count: 2 } if position == [1.0, 1.0, 0.0]),
            "{e}"
        );
    }

    #[test]
    fn behind_the_rim_the_gap_jumps_without_an_extension_and_not_with_one() {
        // The rim triangle's plane: the last cell's chord.
        let (rim, _) = on_trough(HALF, 5.0);
        let (inner, _) = on_trough(HALF - 2.0 * HALF / f64::from(CELLS), 5.0);
        let tangent = (rim - inner).normalize();
        let n = Vector3::new(-tangent.z, 0.0, tangent.x);
        let behind = rim - n * 0.5;
        let (a, b) = (behind - tangent * 1e-3, behind + tangent * 1e-3);
        let open = Surface::Mesh(trough(true));
        assert!(lipschitz(&open, &a, &b).is_err());
        let extended = Surface::Mesh(trough(true).with_rim_extension(4.0).unwrap());
        lipschitz(&extended, &a, &b).unwrap();
    }

    #[test]
    fn a_place_says_how_far_from_the_open_rim() {
        let tool = |s: MeshSurface| Tool {
            name: "mould".into(),
            surface: Surface::Mesh(s),
            motion: ToolMotion::Displacement {
                direction: Vector3::z(),
                distance: 1.0,
                amplitude: crate::Amplitude::Constant,
            },
            friction: 0.0,
        };
        let plain = tool(trough(true));
        // Under the trough's centre line (the ridge of its facets seen
        // from behind), the tool raised by 2 mm.
        let p = ToolPlace::of(&plain, &Vector3::new(0.0, 10.0, -1.0), 2.0);
        assert!((p.gap + 3.0).abs() < 1e-12, "{}", p.gap);
        assert!((p.point - Vector3::new(0.0, 10.0, 2.0)).norm() < 1e-12);
        assert!((p.rim_distance.unwrap() - 10.0).abs() < 1e-12);
        assert!(!p.on_extension);
        let text = p.to_string();
        assert!(text.contains("`mould` at (0.00, 10.00, 2.00) mm"), "{text}");
        assert!(text.contains("10.00 mm from its open rim"), "{text}");
        // Beside the rim: on it.
        let p = ToolPlace::of(&plain, &Vector3::new(0.0, 25.0, 0.0), 0.0);
        assert!(p.to_string().ends_with("on its open rim"), "{p}");
        // On the extension: how far beyond the own rim.
        let extended = tool(trough(true).with_rim_extension(4.0).unwrap());
        let p = ToolPlace::of(&extended, &Vector3::new(0.0, 22.5, 1.0), 0.0);
        assert!(p.on_extension && (p.rim_distance.unwrap() - 2.5).abs() < 1e-12);
        assert!(
            p.to_string()
                .contains("on its rim extension (4.00 mm wide) 2.50 mm beyond its open rim"),
            "{p}"
        );
        // The nearest of two tools.
        let other = Tool {
            name: "far".into(),
            ..plain.clone()
        };
        let near = ToolPlace::nearest(&[other, plain], &[50.0, 0.0], &Vector3::new(0.0, 0.0, 1.0));
        assert_eq!(near.unwrap().tool, "mould");
    }

    proptest::proptest! {
        /// Near the rim of an extended open mesh, front and back, the gap
        /// is 1-Lipschitz: points within a quarter of the extension of the
        /// user's rim, pairs from 1e-7 mm to 1 mm apart (so every closest
        /// point is on the mesh or its extension, never on the new rim).
        #[test]
        fn an_extended_rims_gap_is_1_lipschitz_near_the_rim(
            side in 0usize..4, s in -1.0f64..1.0,
            offset in proptest::array::uniform3(-1.0f64..1.0),
            dir in proptest::array::uniform3(-1.0f64..1.0),
            log_d in -7.0f64..0.0,
        ) {
            let length = 6.0;
            let extended = Surface::Mesh(trough(true).with_rim_extension(length).unwrap());
            let (x, y) = match side {
                0 => (HALF, s * HALF),
                1 => (-HALF, s * HALF),
                2 => (s * HALF, HALF),
                _ => (s * HALF, -HALF),
            };
            let (rim, _) = on_trough(x, y);
            let offset = Vector3::from(offset);
            proptest::prop_assume!(offset.norm() <= 1.0);
            let a = rim + offset * (length / 4.0);
            let dir = Vector3::from(dir);
            proptest::prop_assume!(dir.norm() > 1e-3);
            let b = a + dir.normalize() * 10f64.powf(log_d);
            lipschitz(&extended, &a, &b).map_err(proptest::test_runner::TestCaseError::fail)?;
        }
    }
}
