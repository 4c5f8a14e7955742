//! How far the plies of a laminate are inside each other, measured from
//! the positions with the same contact geometry the narrow phase enforces:
//! the check a run makes at its energy checks and at its end, and the
//! peaks per interface that `summary.json` reports.
//!
//! A ply's volume here is its mid-surface grown by the two half
//! thicknesses along the normal, ending square at the ply's free outline
//! (as the narrow phase treats it: a ply sliding past the edge of the one
//! below is not pushed sideways). A node of one ply is inside its
//! neighbour by
//! - `offset − |d|` over the face's interior and its shared edges and
//!   vertices, d from the closest point of the mid-surface (the narrow
//!   phase's gap, continuous across the kinks between faces), or the
//!   closest point's distance from the ply's free outline where that is
//!   less: a node level with the mid-plane at the end, held there by the
//!   end's row from the far side, is at the end whatever the sign that
//!   round-off gives its height;
//! - `offset − along` over a face's free-outline edge or vertex, along the
//!   face's normal (the square end);
//! - its in-plane distance from the ply's free outline when it is behind
//!   the mid-surface and that way out through the end is shorter than the
//!   way back to its side (the offset and its depth), as the narrow phase
//!   puts it out: a node held at the end plane behind the ply is at the
//!   end, within the solve's tolerance, not through the ply;
//! - `offset + |d|` when it is behind the mid-surface with its projection
//!   inside the face: through the ply (the narrow phase puts such a node
//!   back out on its stacking side, so this is what a node left there by
//!   the last step shows);
//! - `offset + |d|` as well when it is behind the nearest face that takes
//!   it, however far: through the ply. A node behind a face by more than
//!   the offset with a nearer face in front of it is over a fold of the
//!   ply (that face is the folded-back layer), not through it. The first
//!   measure left every node more than the offset behind as a fold, and
//!   so let the four-ply hemisphere (24 × 24 cells, its ±45 plies at
//!   17 × 17) end "completed" with flapping free edges through their
//!   neighbours, a `m45` corner node 1.07 mm behind `p90`'s corner face
//!   at t = 0.28 s, its own neighbours 2–6 mm above it.
//!
//! A node beside the ply (more than the offset sideways of the closest
//! point), or behind an edge or vertex, is not inside it: the first
//! measure, which took every closest point within the offset as a rounded
//! edge and gave a node behind one the whole offset more, reported a ply
//! whose edge hangs 0.15 mm beside the edge of the one below as 0.45 mm
//! inside it (the two-ply hemisphere at t = 0.30 s), where no material of
//! the two overlaps.
//!
//! Not for the contact's own solve: that is [`PlyContact::normal`].

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::narrow::{inside_end, p_of, through_end};
use super::{PlyContact, closest_on_triangle, on_outline};

/// The deepest node of one ply inside its neighbour.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PlyOverlap {
    /// How deep (mm, > 0).
    pub depth: f64,
    /// The interface (index into those [`PlyContact::new`] was given).
    pub interface: usize,
    /// The ply of the node.
    pub ply: usize,
    /// The ply it is inside.
    pub into: usize,
    /// The node.
    pub node: u32,
    /// Where the node is (mm).
    pub position: Vector3<f64>,
    /// How the face of `into` the depth was measured from bends
    /// ([`FaceBend`]); None for a degenerate face.
    pub bend: Option<FaceBend>,
}

/// How far a face's flat middle lies inside the curved ply its nodes
/// describe, where the ply bends round a tool: the node-to-face contact
/// holds the neighbour's nodes off the flat faces, so a neighbour whose
/// nodes lie on the curved surface reaches through a face by about `sag`.
/// Per edge of the face, e from node i to node j, with each node's normal
/// nᵢ the area-weighted mean of its faces': the surface through both nodes
/// with those normals lies e·(nⱼ − nᵢ)/8 off the edge's middle (to second
/// order: Phong's tessellation at α = ½, exact for a quadric), and bends
/// along the edge with the radius |e|²/(8·sag). On a cylinder of radius R
/// an edge across it of length L = 2R·sin(φ/2) gives R(1 − cos(φ/2)) to
/// second order and R exactly, and an edge along a helix the same sag. A
/// face 12.5 mm across bent over a 10 mm die fillet sags about 2 mm,
/// several times a glass ply's 0.57 mm; the hemisphere stacks' 14.6 mm
/// faces on the 120 mm punch 0.22 mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FaceBend {
    /// The largest of the edges' sags (mm).
    pub sag: f64,
    /// The sharpest of the edges' bends: its radius (mm; infinite where
    /// no edge turns), ...
    pub radius: f64,
    /// ... that edge's length (mm) ...
    pub edge: f64,
    /// ... and the angle its nodes' normals turn by (degrees).
    pub turn_deg: f64,
}

impl FaceBend {
    /// The longest face edge whose sag over this bend is at most `sag`
    /// (mm): √(8·R·sag) to first order.
    pub fn edge_for_sag(&self, sag: f64) -> f64 {
        (8.0 * self.radius * sag).sqrt()
    }
}

impl PlyContact {
    /// The deepest node of search `k`'s slave ply inside its master at
    /// `x`, over the candidates of the last broad phase.
    fn deepest_of(&self, k: usize, x: &[Vector3<f64>]) -> Option<PlyOverlap> {
        let s = &self.searches[k];
        let slave = &self.layers[s.slave];
        let faces = &self.layers[s.master].faces;
        let outline = &self.outline[s.master];
        let mut worst: Option<(PlyOverlap, u32)> = None;
        for local in 0..slave.node_count as usize {
            let node = slave.first_node + local as u32;
            let p = x[node as usize];
            let range = s.cand_ptr[local] as usize..s.cand_ptr[local + 1] as usize;
            let mut depth: f64 = 0.0;
            let mut depth_face = u32::MAX;
            // The nearest face that takes the node, and how deep the node
            // is behind it (0 when in front of it).
            let mut nearest = f64::INFINITY;
            let mut through: f64 = 0.0;
            let mut through_face = u32::MAX;
            for &f in &s.cand[range] {
                let [a, b, c] = faces[f as usize].map(|n| x[n as usize]);
                let nf = (b - a).cross(&(c - a));
                let len = nf.norm();
                if len == 0.0 {
                    continue;
                }
                let (q, w) = closest_on_triangle(&p, &a, &b, &c);
                let (d, up, bits) = (p - q, nf * (s.side / len), outline[f as usize]);
                let here = node_depth(d, up, s.offset, w, bits, [a, b, c]);
                if here > depth {
                    depth = here;
                    depth_face = f;
                }
                if let Some(t) = behind_depth(d, up, s.offset, w, bits, [a, b, c])
                    && d.norm_squared() < nearest
                {
                    nearest = d.norm_squared();
                    through = t;
                    through_face = f;
                }
            }
            let (depth, face) = if through > depth {
                (through, through_face)
            } else {
                (depth, depth_face)
            };
            if depth > 0.0 && worst.is_none_or(|w| depth > w.0.depth) {
                worst = Some((
                    PlyOverlap {
                        depth,
                        // [`Self::new`] pushes the searches in pairs, one
                        // pair per interface in order.
                        interface: k / 2,
                        ply: s.slave,
                        into: s.master,
                        node,
                        position: p,
                        bend: None,
                    },
                    face,
                ));
            }
        }
        worst.map(|(o, face)| PlyOverlap {
            bend: faces
                .get(face as usize)
                .and_then(|f| face_bend(&self.layers[s.master], *f, x)),
            ..o
        })
    }

    /// The deepest node of any ply inside a neighbour at `x`, over the
    /// candidates of the last broad phase; None when no node is inside.
    pub fn deepest_overlap(&self, x: &[Vector3<f64>]) -> Option<PlyOverlap> {
        (0..self.searches.len())
            .filter_map(|k| self.deepest_of(k, x))
            .reduce(|w, o| if o.depth > w.depth { o } else { w })
    }

    /// The largest overlap of any node of one ply into its neighbour at
    /// `x` (mm, ≥ 0): [`Self::deepest_overlap`]'s depth.
    pub fn max_overlap(&self, x: &[Vector3<f64>]) -> f64 {
        self.deepest_overlap(x).map_or(0.0, |o| o.depth)
    }

    /// [`Self::deepest_overlap`] at `x`, keeping each interface's largest
    /// so far ([`Self::overlap_peaks`]).
    pub fn record_overlap(&mut self, x: &[Vector3<f64>]) -> Option<PlyOverlap> {
        // Before the first pass (a run's start) there are no candidates yet.
        if self.reference_x.len() != x.len() {
            self.refresh(x);
        }
        let mut worst: Option<PlyOverlap> = None;
        for k in 0..self.searches.len() {
            let Some(o) = self.deepest_of(k, x) else {
                continue;
            };
            let peak = &mut self.overlap_peak[o.interface];
            *peak = peak.max(o.depth);
            if self.worst_overlap.is_none_or(|w| o.depth > w.depth) {
                self.worst_overlap = Some(o);
            }
            if worst.is_none_or(|w| o.depth > w.depth) {
                worst = Some(o);
            }
        }
        worst
    }

    /// Each interface's largest overlap (mm) over the calls of
    /// [`Self::record_overlap`] so far, in the order of the interfaces
    /// [`Self::new`] was given.
    pub fn overlap_peaks(&self) -> &[f64] {
        &self.overlap_peak
    }

    /// The deepest overlap over the calls of [`Self::record_overlap`] so
    /// far (where, and how the face there bends).
    pub fn worst_overlap(&self) -> Option<&PlyOverlap> {
        self.worst_overlap.as_ref()
    }
}

/// [`FaceBend`] of the face `face` of `layer` at `x`: the largest sag
/// of its edges, and the sharpest of their bends.
fn face_bend(layer: &super::PlyLayer, face: [u32; 3], x: &[Vector3<f64>]) -> Option<FaceBend> {
    let mut normals = [Vector3::zeros(); 3];
    for f in &layer.faces {
        let [a, b, c] = f.map(|n| x[n as usize]);
        let n = (b - a).cross(&(c - a));
        for (k, node) in face.iter().enumerate() {
            if f.contains(node) {
                normals[k] += n;
            }
        }
    }
    let normals = [
        normals[0].try_normalize(0.0)?,
        normals[1].try_normalize(0.0)?,
        normals[2].try_normalize(0.0)?,
    ];
    let mut bend = FaceBend {
        sag: 0.0,
        radius: f64::INFINITY,
        edge: 0.0,
        turn_deg: 0.0,
    };
    for k in 0..3 {
        let j = (k + 1) % 3;
        let e = x[face[j] as usize] - x[face[k] as usize];
        let sag = (e.dot(&(normals[j] - normals[k])) / 8.0).abs();
        bend.sag = bend.sag.max(sag);
        let radius = if sag > 0.0 {
            e.norm_squared() / (8.0 * sag)
        } else {
            f64::INFINITY
        };
        if radius < bend.radius {
            bend.radius = radius;
            bend.edge = e.norm();
            bend.turn_deg = normals[k]
                .dot(&normals[j])
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees();
        }
    }
    Some(bend)
}

/// How deep a node at `d` from its closest point (weights `w`) on a face
/// of unit normal `up` (towards the node's ply) is inside that face's
/// ply, with `offset` the two half thicknesses and `bits` the face's
/// outline features; 0 when it is not (see the module's rules).
fn node_depth(
    d: Vector3<f64>,
    up: Vector3<f64>,
    offset: f64,
    w: [f64; 3],
    bits: u8,
    v: [Vector3<f64>; 3],
) -> f64 {
    let along = d.dot(&up);
    if (d - up * along).norm_squared() > offset * offset {
        return 0.0;
    }
    let dist = d.norm();
    let depth = if on_outline(bits, &w) {
        // Past the square end.
        return 0.0;
    } else if dist < offset
        && let Some(e) = end_depth(d, along, offset, w, bits, v)
    {
        // In the ply's thickness; deeper behind, only the nearest face
        // decides ([`behind_depth`]): behind a fold's far layer near its
        // end is not inside it.
        e
    } else if along > 0.0 {
        // In front, near the end: no deeper than the end is near. A node
        // level with the mid-plane, held at the end plane by the end's
        // row (its height's sign round-off), is at the end, not the whole
        // offset inside: read so, it stopped the two plies drawn under a
        // fixed holder at t = 0.45 s ("0.5699 mm inside") with the node
        // 7.6e-5 mm past the end.
        let through_end = inside_end(bits, v, &w).unwrap_or(f64::INFINITY);
        (offset - dist).min(through_end)
    } else if w.iter().all(|&w| w > 0.0) && dist < offset {
        offset + dist
    } else {
        return 0.0;
    };
    depth.max(0.0)
}

/// How deep a node is through a face's ply when that face is the
/// nearest to take it, from the same arguments as [`node_depth`]:
/// `offset + |d|` when it is behind the mid-surface, however far (behind
/// an edge or vertex the ply's faces share counts, as in the narrow
/// phase's rules), 0 in front of it; None when the face does not take the
/// node (beside it, or behind its square end), so that a farther face
/// decides.
fn behind_depth(
    d: Vector3<f64>,
    up: Vector3<f64>,
    offset: f64,
    w: [f64; 3],
    bits: u8,
    v: [Vector3<f64>; 3],
) -> Option<f64> {
    let along = d.dot(&up);
    if (d - up * along).norm_squared() > offset * offset {
        None
    } else if along > 0.0 {
        Some(0.0)
    } else if on_outline(bits, &w) {
        None
    } else if let Some(e) = end_depth(d, along, offset, w, bits, v) {
        Some(e)
    } else {
        Some(offset + d.norm())
    }
}

/// How far a node behind a face is inside the ply through its free end,
/// where the narrow phase puts it back out that way ([`through_end`]):
/// its depth past the end, not through the ply.
fn end_depth(
    d: Vector3<f64>,
    along: f64,
    offset: f64,
    w: [f64; 3],
    bits: u8,
    v: [Vector3<f64>; 3],
) -> Option<f64> {
    let (q, wc, m) = through_end(bits, v, &w, offset, along)?;
    Some((-(q + d - p_of(&v, &wc)).dot(&m)).max(0.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{PlyInterface, PlyLayer};

    /// A layer of the two triangles of the quad `first`..`first + 3`,
    /// 0.15 mm half thick.
    fn layer(first: u32) -> PlyLayer {
        crate::plies::fixtures::square_layer(first, 0.15)
    }

    /// The lower ply a 10 mm square in z = 0 (normal +z), the upper one
    /// the quad `upper`, wound so its normal points along `up`.
    fn contact(upper: [Vector3<f64>; 4]) -> (Vec<Vector3<f64>>, PlyContact) {
        crate::plies::fixtures::on_square(upper)
    }

    /// The upper ply a 4 mm square at height `z` over the middle of the
    /// lower one (its nodes over the lower faces' insides).
    fn flat(z: f64) -> [Vector3<f64>; 4] {
        [[3.0, 3.0], [7.0, 3.0], [7.0, 7.0], [3.0, 7.0]].map(|[a, b]| Vector3::new(a, b, z))
    }

    /// The upper ply hanging in the plane x = `x0` from z = `top` down
    /// 10 mm, 6 mm wide, beside the lower ply's free edge x = 10 (its
    /// normal +x).
    fn hanging(x0: f64, top: f64) -> [Vector3<f64>; 4] {
        [[2.0, top], [2.0, top - 10.0], [8.0, top - 10.0], [8.0, top]]
            .map(|[y, z]| Vector3::new(x0, y, z))
    }

    #[test]
    fn a_ply_beside_the_free_edge_of_its_neighbour_is_not_inside_it() {
        // The two-ply hemisphere at t = 0.30 s: the upper ply's edge hangs
        // 0.15 mm beside the lower ply's free edge, 0.008 mm below its
        // mid-plane. The first measure took the edge as rounded with the
        // 0.3 mm offset and, the node being behind the face's plane, gave
        // it the whole offset more: 0.15 + 0.3 = 0.45 mm. No material of
        // the two overlaps (the lower ply ends square at x = 10, the
        // upper one's sheet is 0.15 mm thick about x = 10.15).
        let (x, mut c) = contact(hanging(10.15, -0.008));
        assert_eq!(c.record_overlap(&x), None);
        assert_eq!(c.max_overlap(&x), 0.0);
        // Moved 0.2 mm in, over the lower ply: its top node is inside the
        // lower ply's material, 0.008 mm behind the mid-surface and
        // 0.05 mm in from the end: the way out through the end (the
        // contact's) is the shorter, 0.05 mm. 2 mm in, the way back to
        // its own side is: the offset and 0.008.
        for (at, depth) in [(9.95, 0.05), (8.0, 0.308)] {
            let (x, mut c) = contact(hanging(at, -0.008));
            let o = c.record_overlap(&x).expect("inside");
            assert!((o.depth - depth).abs() < 1e-12, "{o:?}");
            assert_eq!((o.ply, o.into, o.interface), (1, 0, 0));
            assert!(o.node == 4 || o.node == 7, "{o:?}");
            assert_eq!(o.position, x[o.node as usize]);
            assert!((c.overlap_peaks()[0] - depth).abs() < 1e-12);
        }
    }

    #[test]
    fn the_depth_over_a_face_is_the_offset_less_the_distance_and_more_behind_it() {
        for (z, depth) in [
            (0.4, 0.0),
            (0.3, 0.0),
            (0.25, 0.05),
            (0.1, 0.2),
            (-0.1, 0.4),
            (-0.25, 0.55),
            // Beyond the offset behind, the lower ply's faces the nearest:
            // through it, however far.
            (-0.35, 0.65),
            (-1.0, 1.3),
        ] {
            let (x, mut c) = contact(flat(z));
            let found = c.record_overlap(&x).map_or(0.0, |o| o.depth);
            assert!(
                (found - depth).abs() < 1e-12,
                "z = {z}: {found} against {depth}"
            );
        }
        // The peak is kept: the last configuration measured nothing.
        let (x, mut c) = contact(flat(0.1));
        c.record_overlap(&x);
        let (y, _) = contact(flat(0.4));
        assert_eq!(c.record_overlap(&y), None);
        assert!((c.overlap_peaks()[0] - 0.2).abs() < 1e-12);
    }

    #[test]
    fn a_flapping_edge_node_behind_its_neighbour_is_through_it() {
        // The four-ply hemisphere at t = 0.28 s (24 × 24 cells, ±45 plies
        // at 17 × 17): a corner node of `m45` 1.07 mm behind the
        // mid-surface of `p90`'s corner face, its neighbours 2–6 mm above
        // it. The first measure took every node more than the offset
        // behind a face for a fold and reported nothing.
        let mut upper = flat(4.0);
        upper[0].z = 2.0;
        upper[2].z = 6.0;
        upper[3].z = -1.07;
        let (x, mut c) = contact(upper);
        let o = c.record_overlap(&x).expect("through");
        assert!((o.depth - (0.3 + 1.07)).abs() < 1e-12, "{o:?}");
        assert_eq!((o.ply, o.into, o.node), (1, 0, 7));
        assert_eq!(o.position, x[7]);
    }

    #[test]
    fn over_a_fold_the_nearest_layer_decides() {
        // The lower ply folded twice under the upper one (a Z): layers in
        // z = 0 (normal +z), −0.6 (folded back, normal −z) and −1.2. A
        // node of the upper ply over the top layer is behind the middle
        // one by more than the offset, which is not through the ply: the
        // top layer, nearer, has it in front.
        let square = |z: f64| {
            [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]].map(|[a, b]| Vector3::new(a, b, z))
        };
        let mut x: Vec<Vector3<f64>> = [0.0, -0.6, -1.2].iter().flat_map(|&z| square(z)).collect();
        let folded = PlyLayer {
            first_node: 0,
            node_count: 12,
            faces: vec![
                [0, 1, 2],
                [0, 2, 3],
                [4, 6, 5],
                [4, 7, 6],
                [8, 9, 10],
                [8, 10, 11],
            ],
            half_thickness: 0.15,
        };
        let interface = PlyInterface {
            lower: 0,
            upper: 1,
            friction: 0.0,
        };
        for (z, depth) in [(0.35, 0.0), (0.25, 0.05)] {
            x.truncate(12);
            x.extend(flat(z));
            let mut c = PlyContact::new(
                vec![folded.clone(), layer(12)],
                &[interface],
                vec![1.0; 16],
                1.0,
            );
            let found = c.record_overlap(&x).map_or(0.0, |o| o.depth);
            assert!((found - depth).abs() < 1e-12, "z = {z}: {found}");
        }
    }

    #[test]
    fn near_a_fold_s_end_only_the_nearest_layer_decides() {
        // The lower ply folded back under itself: layers in z = 0 (normal
        // +z) and −0.6 (folded back, normal −z), both ending at x = 10.
        // The upper ply rests on the top layer at the offset, 0.1 mm in
        // from the end: behind the folded-back layer by 0.9 mm there, and
        // 0.1 mm in from its end, which is the shorter way out of that
        // layer. The top layer, nearer, has the node in front: not inside.
        let square = |z: f64| {
            [[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]].map(|[a, b]| Vector3::new(a, b, z))
        };
        let mut x: Vec<Vector3<f64>> = [0.0, -0.6].iter().flat_map(|&z| square(z)).collect();
        x.extend(
            [[5.9, 3.0], [9.9, 3.0], [9.9, 7.0], [5.9, 7.0]].map(|[a, b]| Vector3::new(a, b, 0.3)),
        );
        let folded = PlyLayer {
            first_node: 0,
            node_count: 8,
            faces: vec![[0, 1, 2], [0, 2, 3], [4, 6, 5], [4, 7, 6]],
            half_thickness: 0.15,
        };
        let interface = PlyInterface {
            lower: 0,
            upper: 1,
            friction: 0.0,
        };
        let mut c = PlyContact::new(vec![folded, layer(8)], &[interface], vec![1.0; 12], 1.0);
        assert_eq!(c.record_overlap(&x), None);
    }

    #[test]
    fn over_a_kink_the_depth_is_from_the_rounded_mid_surface() {
        // The lower ply a ridge: its corners 1 and 3 lowered 5 mm, the
        // diagonal 0–2 the crest. A node above the crest's middle is over
        // the edge the two faces share, and its distance to the edge is
        // what counts (the narrow phase's gap there).
        let (mut x, mut c) = contact(flat(50.0));
        x[1].z = -5.0;
        x[3].z = -5.0;
        // Over the middle of the crest 0–2, 0.2 mm up: inside by 0.1.
        x[4] = Vector3::new(5.0, 5.0, 0.2);
        let o = c.record_overlap(&x).expect("inside");
        assert!((o.depth - 0.1).abs() < 1e-12, "{o:?}");
        assert_eq!(o.node, 4);
    }

    /// A strip of 12.5 mm faces wrapped round a cylinder of radius 10 mm
    /// (a die's fillet) about the y axis, five nodes across and two
    /// along, its quads' diagonals in a zigzag so that every node has as
    /// many triangles on either side (its normal exactly radial inside):
    /// a face inside bends with the cylinder's radius, its edges across
    /// turning φ = 2·asin(L/2R), and sags R·sin²(φ/2)/2 = L²/8R, its
    /// diagonal as much as the edge across it.
    #[test]
    fn a_face_wrapped_round_a_fillet_sags_by_its_chord() {
        let (r, l): (f64, f64) = (10.0, 12.5);
        let phi = 2.0 * (l / (2.0 * r)).asin();
        let node = |i: u32, j: u32| j * 5 + i;
        let x: Vec<Vector3<f64>> = (0..2)
            .flat_map(|j| {
                (0..5).map(move |i| {
                    let t = f64::from(i) * phi;
                    Vector3::new(r * t.sin(), 8.0 * f64::from(j), r * t.cos())
                })
            })
            .collect();
        let mut faces = Vec::new();
        for i in 0..4 {
            let [a, b, c, d] = [node(i, 0), node(i + 1, 0), node(i + 1, 1), node(i, 1)];
            // Wound with the normal outward (+z at the top).
            if i % 2 == 0 {
                faces.extend([[a, b, d], [b, c, d]]);
            } else {
                faces.extend([[a, b, c], [a, c, d]]);
            }
        }
        let layer = PlyLayer {
            first_node: 0,
            node_count: 10,
            faces,
            half_thickness: 0.285,
        };
        for f in &layer.faces {
            let [a, b, c] = f.map(|n| x[n as usize]);
            let mid = (a + b + c) / 3.0;
            assert!(
                (b - a)
                    .cross(&(c - a))
                    .dot(&Vector3::new(mid.x, 0.0, mid.z))
                    > 0.0
            );
        }
        // The faces of the quad between the second and third columns.
        for face in [layer.faces[2], layer.faces[3]] {
            let bend = face_bend(&layer, face, &x).expect("a face");
            let sag = r * (0.5 * phi).sin().powi(2) / 2.0;
            assert!((sag - l * l / (8.0 * r)).abs() < 1e-12);
            assert!((bend.sag - sag).abs() < 1e-12, "{bend:?} against {sag}");
            assert!((bend.radius - r).abs() < 1e-12, "{bend:?}");
            assert!((bend.edge - l).abs() < 1e-12, "{bend:?}");
            assert!((bend.turn_deg - phi.to_degrees()).abs() < 1e-9, "{bend:?}");
            // Faces of √(8·R·s) sag s.
            assert!((bend.edge_for_sag(sag) - l).abs() < 1e-12);
        }
        // Flat: no sag, no bend.
        let flat: Vec<Vector3<f64>> = x.iter().map(|p| Vector3::new(p.x, p.y, 0.0)).collect();
        let bend = face_bend(&layer, layer.faces[2], &flat).expect("a face");
        assert_eq!((bend.sag, bend.radius), (0.0, f64::INFINITY));
    }
}
