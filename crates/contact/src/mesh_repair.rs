//! Opt-in repairs of a tool's triangle mesh before it becomes a
//! [`MeshSurface`](crate::MeshSurface): dropping degenerate triangles and
//! winding every triangle consistently. Both change the user's geometry,
//! so a scene asks for them (`drop_degenerate`, `reorient`) and is told
//! what was changed; without them such a mesh is refused with the
//! triangle that is wrong.
//!
//! - **Degenerate** triangles (a repeated vertex, two vertices at one
//!   place, three on a line: the criterion of [`MeshSurface::new`]) are
//!   dropped; CAD exports leave such slivers along fillets.
//! - **Orientation**: triangles are grouped into pieces connected through
//!   edges that exactly two triangles share (vertices at the same place are
//!   one vertex, as an STL file repeats them), and within a piece every
//!   triangle is turned to run each shared edge opposite to its
//!   neighbour. A piece that closes on itself (every edge shared) is then
//!   turned so that its normals point out of the solid it bounds (positive
//!   enclosed volume), the convention of [`MeshSurface`]; an open piece
//!   keeps the orientation of the larger part of its area as given (the
//!   side the user meant, when most triangles were right). A piece that
//!   cannot be oriented (a Möbius strip) is an error.
//!
//! [`MeshSurface`]: crate::MeshSurface
//! [`MeshSurface::new`]: crate::MeshSurface::new

use std::collections::HashMap;

use nalgebra::Vector3;

use crate::mesh::DEGENERATE_SINE;

/// What to repair.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct RepairOptions {
    /// Drop degenerate triangles.
    pub drop_degenerate: bool,
    /// Wind the triangles consistently.
    pub reorient: bool,
}

/// What was repaired.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct RepairReport {
    /// Indices (as given) of the triangles dropped as degenerate.
    pub dropped: Vec<usize>,
    /// How many of the kept triangles were turned over.
    pub flipped: usize,
    /// Connected pieces, closed and open.
    pub pieces: (usize, usize),
}

/// A mesh that cannot be repaired.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RepairError {
    /// No triangle is left.
    #[error("every triangle of the mesh is degenerate")]
    NothingLeft,
    /// A triangle refers to a missing vertex.
    #[error("triangle {triangle} refers to vertex {index}, but there are only {vertices} vertices")]
    IndexOutOfRange {
        /// The triangle (as given).
        triangle: usize,
        /// The bad index.
        index: u32,
        /// Number of vertices.
        vertices: usize,
    },
    /// A piece whose triangles cannot all agree.
    #[error(
        "the triangles around triangle {triangle} cannot be wound consistently (the surface is \
         one-sided, like a Möbius strip)"
    )]
    NonOrientable {
        /// A triangle (as given) of the piece.
        triangle: usize,
    },
}

/// Whether triangle `t` of `vertices` is degenerate by the criterion of
/// [`MeshSurface::new`](crate::MeshSurface::new).
fn degenerate(vertices: &[Vector3<f64>], t: [u32; 3]) -> bool {
    let [a, b, c] = t.map(|i| vertices[i as usize]);
    let (ab, ac, bc) = (b - a, c - a, c - b);
    let longest2 = ab
        .norm_squared()
        .max(ac.norm_squared())
        .max(bc.norm_squared());
    ab.cross(&ac).norm() <= DEGENERATE_SINE * longest2
}

/// Repairs `triangles` (indices into `vertices`, counter-clockwise as
/// meant) as `options` ask; returns the triangles kept, in their order,
/// and what was done.
pub fn repair(
    vertices: &[Vector3<f64>],
    triangles: &[[u32; 3]],
    options: RepairOptions,
) -> Result<(Vec<[u32; 3]>, RepairReport), RepairError> {
    let mut report = RepairReport::default();
    for (triangle, t) in triangles.iter().enumerate() {
        if let Some(&index) = t.iter().find(|&&i| i as usize >= vertices.len()) {
            return Err(RepairError::IndexOutOfRange {
                triangle,
                index,
                vertices: vertices.len(),
            });
        }
    }
    let mut kept: Vec<(usize, [u32; 3])> = Vec::with_capacity(triangles.len());
    for (i, &t) in triangles.iter().enumerate() {
        if options.drop_degenerate && degenerate(vertices, t) {
            report.dropped.push(i);
        } else {
            kept.push((i, t));
        }
    }
    if kept.is_empty() {
        return Err(RepairError::NothingLeft);
    }
    if options.reorient {
        report.pieces = orient(vertices, &mut kept, &mut report.flipped)?;
    }
    Ok((kept.into_iter().map(|(_, t)| t).collect(), report))
}

/// Winds the triangles of `kept` consistently (see the module's docs),
/// counting the triangles turned over; returns the numbers of closed and
/// open pieces.
fn orient(
    vertices: &[Vector3<f64>],
    kept: &mut [(usize, [u32; 3])],
    flipped: &mut usize,
) -> Result<(usize, usize), RepairError> {
    // One id per position: an STL file repeats a vertex for each triangle.
    let mut id_of: HashMap<[u64; 3], u32> = HashMap::new();
    let canonical: Vec<u32> = vertices
        .iter()
        .map(|v| {
            let key = [v.x, v.y, v.z].map(|c| (c + 0.0).to_bits());
            let next = id_of.len() as u32;
            *id_of.entry(key).or_insert(next)
        })
        .collect();
    let corners = |t: &[u32; 3]| t.map(|i| canonical[i as usize]);
    // Edge → the triangles using it and whether each runs it low → high.
    let mut edges: HashMap<(u32, u32), Vec<(usize, bool)>> = HashMap::new();
    for (k, (_, t)) in kept.iter().enumerate() {
        let c = corners(t);
        for j in 0..3 {
            let (a, b) = (c[j], c[(j + 1) % 3]);
            if a != b {
                edges
                    .entry((a.min(b), a.max(b)))
                    .or_default()
                    .push((k, a < b));
            }
        }
    }
    // Neighbours across edges two triangles share, and whether they run
    // that edge the same way (they must not).
    let n = kept.len();
    let mut neighbours: Vec<Vec<(usize, bool)>> = vec![Vec::new(); n];
    let mut open_edge = vec![false; n];
    for uses in edges.values() {
        match uses.as_slice() {
            [(u, fu), (v, fv)] => {
                neighbours[*u].push((*v, fu == fv));
                neighbours[*v].push((*u, fu == fv));
            }
            [(u, _)] => open_edge[*u] = true,
            // More than two triangles on an edge: it says nothing.
            more => more.iter().for_each(|&(u, _)| open_edge[u] = true),
        }
    }
    for list in &mut neighbours {
        list.sort_unstable();
    }
    let mut flip: Vec<Option<bool>> = vec![None; n];
    let (mut closed, mut open) = (0, 0);
    let mut stack = Vec::new();
    for seed in 0..n {
        if flip[seed].is_some() {
            continue;
        }
        flip[seed] = Some(false);
        stack.push(seed);
        let mut members = Vec::new();
        while let Some(e) = stack.pop() {
            members.push(e);
            let fe = flip[e].unwrap_or(false);
            for &(nb, same) in &neighbours[e] {
                let want = fe ^ same;
                match flip[nb] {
                    None => {
                        flip[nb] = Some(want);
                        stack.push(nb);
                    }
                    Some(f) if f != want => {
                        return Err(RepairError::NonOrientable {
                            triangle: kept[seed].0,
                        });
                    }
                    Some(_) => {}
                }
            }
        }
        // Which way the whole piece goes: outward for a closed one (the
        // enclosed volume, Σ a·(b × c)/6, positive), the larger area as
        // given for an open one.
        let is_closed = members.iter().all(|&e| !open_edge[e]);
        let turn_all = if is_closed {
            closed += 1;
            let volume: f64 = members
                .iter()
                .map(|&e| {
                    let [a, b, c] = kept[e].1.map(|i| vertices[i as usize]);
                    let v = a.dot(&b.cross(&c));
                    if flip[e] == Some(true) { -v } else { v }
                })
                .sum();
            volume < 0.0
        } else {
            open += 1;
            let (mut as_given, mut against) = (0.0, 0.0);
            for &e in &members {
                let [a, b, c] = kept[e].1.map(|i| vertices[i as usize]);
                let area = (b - a).cross(&(c - a)).norm();
                if flip[e] == Some(true) {
                    against += area;
                } else {
                    as_given += area;
                }
            }
            against > as_given
        };
        for &e in &members {
            if (flip[e] == Some(true)) != turn_all {
                let t = &mut kept[e].1;
                t.swap(1, 2);
                *flipped += 1;
            }
        }
    }
    Ok((closed, open))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::MeshSurface;

    /// A unit cube's 12 triangles, outward.
    fn cube() -> (Vec<Vector3<f64>>, Vec<[u32; 3]>) {
        let v: Vec<Vector3<f64>> = (0..8)
            .map(|i| Vector3::new(f64::from(i & 1), f64::from((i >> 1) & 1), f64::from(i >> 2)))
            .collect();
        let quads = [
            [0, 2, 3, 1],
            [4, 5, 7, 6],
            [0, 1, 5, 4],
            [2, 6, 7, 3],
            [0, 4, 6, 2],
            [1, 3, 7, 5],
        ];
        let t = quads
            .iter()
            .flat_map(|q: &[u32; 4]| [[q[0], q[1], q[2]], [q[0], q[2], q[3]]])
            .collect();
        (v, t)
    }

    #[test]
    fn a_cube_with_flipped_faces_is_turned_outward() {
        let (v, good) = cube();
        MeshSurface::new(v.clone(), good.clone()).expect("the cube is wound outward");
        // Every triangle turned over, and then three turned back: mixed.
        let mut bad: Vec<[u32; 3]> = good.iter().map(|t| [t[0], t[2], t[1]]).collect();
        for k in [1, 4, 9] {
            bad[k] = good[k];
        }
        assert!(MeshSurface::new(v.clone(), bad.clone()).is_err());
        let options = RepairOptions {
            reorient: true,
            ..RepairOptions::default()
        };
        let (fixed, report) = repair(&v, &bad, options).unwrap();
        assert_eq!(fixed, good);
        assert_eq!(report.flipped, 9);
        assert_eq!(report.pieces, (1, 0));
        let surface = MeshSurface::new(v, fixed).unwrap();
        assert!(
            surface.project(&Vector3::new(0.5, 0.5, 0.5)).gap < 0.0,
            "inside"
        );
    }

    #[test]
    fn an_open_sheet_keeps_the_side_most_of_it_had() {
        // A 3 × 1 strip of squares in z = 0, wound up (+z) but for one
        // triangle.
        let v: Vec<Vector3<f64>> = (0..8)
            .map(|i| Vector3::new(f64::from(i % 4), f64::from(i / 4), 0.0))
            .collect();
        let mut t = Vec::new();
        for i in 0..3u32 {
            t.push([i, i + 1, i + 5]);
            t.push([i, i + 5, i + 4]);
        }
        let good = t.clone();
        t[3] = [t[3][0], t[3][2], t[3][1]];
        let options = RepairOptions {
            reorient: true,
            ..RepairOptions::default()
        };
        let (fixed, report) = repair(&v, &t, options).unwrap();
        assert_eq!(fixed, good);
        assert_eq!((report.flipped, report.pieces), (1, (0, 1)));
    }

    #[test]
    fn degenerate_triangles_are_dropped_and_counted() {
        let (mut v, mut t) = cube();
        v.push(Vector3::new(0.5, 0.0, 0.0));
        // A sliver on a line and a triangle repeating a vertex.
        t.insert(3, [0, 8, 1]);
        t.push([2, 2, 3]);
        let options = RepairOptions {
            drop_degenerate: true,
            ..RepairOptions::default()
        };
        let (kept, report) = repair(&v, &t, options).unwrap();
        assert_eq!(report.dropped, vec![3, 13]);
        assert_eq!(kept, cube().1);
        assert!(
            repair(&v, &t, RepairOptions::default())
                .unwrap()
                .1
                .dropped
                .is_empty()
        );
    }

    #[test]
    fn a_moebius_strip_cannot_be_oriented() {
        // Four squares in a ring whose last one joins the first with a
        // half twist.
        let n = 4;
        let mut v = Vec::new();
        for i in 0..n {
            let a = std::f64::consts::TAU * f64::from(i) / f64::from(n);
            let twist = 0.5 * a;
            let (r, h) = (twist.cos(), twist.sin());
            v.push(Vector3::new((3.0 + r) * a.cos(), (3.0 + r) * a.sin(), h));
            v.push(Vector3::new((3.0 - r) * a.cos(), (3.0 - r) * a.sin(), -h));
        }
        let mut t = Vec::new();
        for i in 0..n as u32 {
            let (a, b) = (2 * i, 2 * i + 1);
            let (c, d) = if i + 1 == n as u32 {
                (1, 0)
            } else {
                (2 * i + 2, 2 * i + 3)
            };
            t.push([a, b, d]);
            t.push([a, d, c]);
        }
        let options = RepairOptions {
            reorient: true,
            ..RepairOptions::default()
        };
        assert!(matches!(
            repair(&v, &t, options),
            Err(RepairError::NonOrientable { .. })
        ));
    }
}
