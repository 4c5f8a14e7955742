//! The ply contact's narrow phase: each slave node's closest face of the
//! master ply among its broad-phase candidates, and what that face makes
//! of the node (its gap, normal and weights, or a node to put back on its
//! side).
//!
//! The hit is the face closest to the node among those whose rules take
//! the node ([`Master::rules`]), ties to the earliest in the candidate
//! list: what projecting the node on every candidate in order gives
//! ([`Master::closest_exhaustive`], kept for the tests). It is found with
//! less work, to the same bits: last step's face is projected first (a
//! node moves a small part of a face in a step, so it is usually the
//! closest again), and a candidate whose lower bound ([`FaceBound`]) is
//! farther than the best so far is not projected at all. Where the
//! plies' lattices coincide (in the flat blank a ±45 ply's nodes lie on the
//! 0/90 ply's vertices and diagonals) a node is as far from every face
//! round its vertex or edge, and those are all projected: the earliest
//! must win, to the bit. Over the first 0.3 s of the four-ply hemisphere
//! (12 × 12 cells) the search took about a quarter less time than
//! projecting on every candidate.
//!
//! A face's rules see the ply as its mid-surface grown by the offset,
//! ending square at the free outline: a node beside the end is not in
//! it, and a node behind the face goes out the shorter of two ways, back
//! to its own side or out through the end (the nearest point of the
//! face's outline edges and vertices). The way through the ply to the far
//! side is never taken. Through the end is what keeps a node from coming
//! round a free edge: it holds at any depth behind the ply, because past
//! the offset a node behind is otherwise left alone (a fold), and that is
//! the way a free edge came round its neighbour's.
//!
//! Not for: the candidate lists (the broad phase, [`super::PlyContact`]'s
//! refresh), the solves, or the overlap measure ([`super::overlap`]).

use nalgebra::Vector3;

use super::{Hit, on_outline};

/// How far (relative to the coordinates of the face and the node) a
/// face's bound must be beyond the best distance so far before the face
/// is passed over: far above the round-off of the bound and of a computed
/// closest point (~1e-15 of the coordinates for a well-shaped face,
/// growing with the face's L²/|n| to ~4e-11 at the limit [`FaceBound`]'s
/// guard keeps slivers out at), so a face passed over can never have been
/// the closer one.
const BOUND_SLACK: f64 = 1e-10;

/// A face's data for a lower bound on a node's distance to it, at this
/// step's positions: the distance to its plane and, where the node's
/// projection is outside the face across an edge, the distance to that
/// edge's line in the plane. On a smooth ply a node is at about the
/// offset from its face and from the neighbours, which a box of a
/// slightly tilted face contains; this bound is a neighbour's distance
/// less only the in-plane distance to its nearest point.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct FaceBound {
    /// The vertices.
    v: [Vector3<f64>; 3],
    /// The face's normal (unnormalised) and 1/|n|² (0 for a sliver,
    /// whose bound is then 0).
    n: Vector3<f64>,
    inv_n2: f64,
    /// Each edge's outward normal in the plane (edge × n, from vertex k
    /// to k + 1) and 1/|m|².
    m: [Vector3<f64>; 3],
    inv_m2: [f64; 3],
    /// The largest coordinate of the vertices (for the slack).
    scale: f64,
}

impl FaceBound {
    /// The bound of the triangle `v`.
    fn of(v: [Vector3<f64>; 3]) -> Self {
        let e = [v[1] - v[0], v[2] - v[1], v[0] - v[2]];
        let n = e[0].cross(&(v[2] - v[0]));
        let n2 = n.norm_squared();
        let longest = e.iter().map(|e| e.norm_squared()).fold(0.0, f64::max);
        let scale = v.iter().map(|v| v.amax()).fold(0.0, f64::max);
        // A sliver's normal is lost in round-off (its direction errs by
        // ~1e-16·|e|²/|n|): no bound. At 1e-4 the error is 1e-12 rad.
        if n2.is_nan() || n2 <= 1e-8 * longest * longest {
            return Self {
                v,
                scale,
                ..Self::default()
            };
        }
        let m = e.map(|e| e.cross(&n));
        Self {
            v,
            n,
            inv_n2: 1.0 / n2,
            m,
            inv_m2: m.map(|m| 1.0 / m.norm_squared()),
            scale,
        }
    }

    /// A lower bound on the squared distance from `p` to the face.
    fn distance_squared(&self, p: &Vector3<f64>) -> f64 {
        let h = (p - self.v[0]).dot(&self.n);
        let mut beside: f64 = 0.0;
        for k in 0..3 {
            let s = (p - self.v[k]).dot(&self.m[k]);
            if s > 0.0 {
                beside = beside.max(s * s * self.inv_m2[k]);
            }
        }
        h * h * self.inv_n2 + beside
    }
}

/// Each face's bound at `x` into `bounds` (one per face).
pub(super) fn face_bounds(faces: &[[u32; 3]], x: &[Vector3<f64>], bounds: &mut [FaceBound]) {
    for (b, f) in bounds.iter_mut().zip(faces) {
        *b = FaceBound::of(f.map(|n| x[n as usize]));
    }
}

/// A search's master ply as the narrow phase reads it in one step.
pub(super) struct Master<'a> {
    /// The master's triangles (normal up the stack).
    pub faces: &'a [[u32; 3]],
    /// Their outline features (bits as [`super::outline_of`] gives them).
    pub outline: &'a [u8],
    /// Their bounds at this step's positions ([`face_bounds`]).
    pub bounds: &'a [FaceBound],
    /// +1 when the slave ply is above the master, −1 below.
    pub side: f64,
    /// Sum of the two half thicknesses (mm).
    pub offset: f64,
    /// The largest gap a hit may have (mm).
    pub reach: f64,
}

impl Master<'_> {
    /// The closest hit of the node at `p` among the candidate faces
    /// `cand`, `first` the face to project first (last step's hit; any
    /// face not among the candidates is ignored): the same hit as
    /// [`Self::closest_exhaustive`], bit for bit.
    pub(super) fn closest(
        &self,
        p: &Vector3<f64>,
        x: &[Vector3<f64>],
        cand: &[u32],
        first: u32,
    ) -> Hit {
        let mut best = f64::INFINITY;
        let mut best_k = usize::MAX;
        let mut hit = Hit::NONE;
        let p_scale = p.amax();
        let mut visit = |k: usize, best: &mut f64| {
            let f = cand[k];
            let tri = self.faces[f as usize];
            let [a, b, c] = tri.map(|n| x[n as usize]);
            let (q, w) = closest_on_triangle(p, &a, &b, &c);
            let d = p - q;
            let dist = d.norm_squared();
            // The exhaustive order keeps the earlier of two faces at the
            // same distance.
            if dist > *best || (dist == *best && k > best_k) {
                return;
            }
            if let Some(h) = self.rules(f, tri, [a, b, c], d, dist, w) {
                *best = dist;
                best_k = k;
                hit = h;
            }
        };
        let warm = cand.iter().position(|&f| f == first);
        if let Some(k) = warm {
            visit(k, &mut best);
        }
        for (k, &f) in cand.iter().enumerate() {
            if Some(k) == warm {
                continue;
            }
            let bound = &self.bounds[f as usize];
            let reach = best.sqrt() + BOUND_SLACK * (bound.scale + p_scale);
            if bound.distance_squared(p) > reach * reach {
                continue;
            }
            visit(k, &mut best);
        }
        hit
    }

    /// The closest hit of the node at `p` projecting it on every face of
    /// `cand` in order: the definition [`Self::closest`] keeps to.
    #[cfg(test)]
    pub(super) fn closest_exhaustive(
        &self,
        p: &Vector3<f64>,
        x: &[Vector3<f64>],
        cand: &[u32],
    ) -> Hit {
        let mut best = f64::INFINITY;
        let mut hit = Hit::NONE;
        for &f in cand {
            let tri = self.faces[f as usize];
            let [a, b, c] = tri.map(|n| x[n as usize]);
            let (q, w) = closest_on_triangle(p, &a, &b, &c);
            let d = p - q;
            let dist = d.norm_squared();
            if dist >= best {
                continue;
            }
            if let Some(h) = self.rules(f, tri, [a, b, c], d, dist, w) {
                best = dist;
                hit = h;
            }
        }
        hit
    }

    /// Face `f` (nodes `tri` at `abc`) as the node's hit, from `d` the
    /// node less its closest point (`dist` = |d|², weights `w`); None
    /// where the face does not take the node.
    fn rules(
        &self,
        f: u32,
        tri: [u32; 3],
        [a, b, c]: [Vector3<f64>; 3],
        d: Vector3<f64>,
        dist: f64,
        w: [f64; 3],
    ) -> Option<Hit> {
        let offset = self.offset;
        let nf = (b - a).cross(&(c - a));
        let len = nf.norm();
        if len == 0.0 || dist == 0.0 {
            return None;
        }
        let up = nf * (self.side / len);
        let along = d.dot(&up);
        // A node beside the face (past the ply's free edge, its offset
        // mostly sideways) is not on it.
        if (d - up * along).norm_squared() > offset * offset {
            return None;
        }
        let bits = self.outline[f as usize];
        let r = dist.sqrt();
        if on_outline(bits, &w) {
            if along <= 0.0 {
                // Beside the square end of the ply on its far side: not
                // in it (the end rule below keeps it from going in).
                return None;
            }
            // The face's normal: the ply ends there square, not rounded,
            // so a ply sliding past the edge of the one below is not
            // pushed sideways. Up to the offset beside the end, so that
            // plies whose edges lie on each other (equal blanks) rest on
            // each other's edges; a node that comes up into it from the
            // far side beside the end starts inside by up to the offset,
            // which goes as a shift of position ([`super::PlyContact::normal`]).
            let gap = along - offset;
            return (gap <= self.reach).then_some(Hit {
                gap,
                normal: up,
                nodes: tri,
                w,
                face: f,
                found: true,
                recover: false,
                end: false,
            });
        }
        // On the far side, the way out through the ply's square end where
        // that is shorter than the way back to the node's own side (the
        // offset and its depth): what a node that crossed the end plane
        // in a step (by its motion, or the end's coming over it) has to
        // go back, at any depth. Such a node is round the end, and
        // farther in no memoryless rule tells it from a fold of the ply;
        // nothing else stops a free edge from coming round a neighbour's
        // (the four-ply hemisphere's `p45` node 1017 came round `p90`'s
        // edge 0.5 mm beside it and crossed the end plane 2 mm behind it).
        if let Some((q, wc, m)) = through_end(bits, [a, b, c], &w, offset, along) {
            let gap = (q + d - p_of(&[a, b, c], &wc)).dot(&m);
            return (gap <= self.reach).then_some(Hit {
                gap,
                normal: m,
                nodes: tri,
                w: wc,
                face: f,
                found: true,
                recover: false,
                end: true,
            });
        }
        let (normal, gap, recover) = if along > 0.0 {
            // The distance to the closest point and its direction:
            // continuous across the kinks between faces (a face's own
            // normal would turn by the kink as the node passes a vertex
            // and push it each time), the face's normal inside a face.
            (d / r, r - offset, false)
        } else if r < offset {
            // Inside the ply beyond its mid-surface: it came round the
            // ply's free edge or a fold (no step moves a node that deep),
            // and goes back out on its own side, not the nearer one, which
            // would put it through the ply.
            (up, along - offset, true)
        } else {
            // Clear of the ply on its far side: another part of it (a
            // fold), not this one's neighbour.
            return None;
        };
        if gap > self.reach {
            return None;
        }
        Some(Hit {
            gap,
            normal,
            nodes: tri,
            w,
            face: f,
            found: true,
            recover,
            end: false,
        })
    }
}

/// Where a node behind face `v` (`along` ≤ 0 from its mid-surface, its
/// closest point at the weights `w`, `bits` the face's outline features)
/// goes out of the ply through its free end, that way being shorter than
/// the way back to its own side (the offset and its depth): its closest
/// point, the weights of the nearest point of the end, and the direction
/// out; None where the node is in front, or nearer its own side.
pub(super) fn through_end(
    bits: u8,
    v: [Vector3<f64>; 3],
    w: &[f64; 3],
    offset: f64,
    along: f64,
) -> Option<(Vector3<f64>, [f64; 3], Vector3<f64>)> {
    if along > 0.0 || bits == 0 {
        return None;
    }
    let q = p_of(&v, w);
    let (e, wc, m) = nearest_outline(bits, v, &q)?;
    (e < offset - along).then_some((q, wc, m))
}

/// How far a node in front of face `v` (its closest point at the weights
/// `w`, `bits` the face's outline features) is inside the ply's square
/// free end: the distance from its closest point to the nearest point of
/// the end (None where the face has no outline feature).
pub(super) fn inside_end(bits: u8, v: [Vector3<f64>; 3], w: &[f64; 3]) -> Option<f64> {
    nearest_outline(bits, v, &p_of(&v, w)).map(|(e, _, _)| e)
}

/// The point of the face `v` at the barycentric weights `w`.
pub(super) fn p_of(v: &[Vector3<f64>; 3], w: &[f64; 3]) -> Vector3<f64> {
    v[0] * w[0] + v[1] * w[1] + v[2] * w[2]
}

/// The point of the face `v`'s free-outline features (`bits` as
/// [`super::outline_of`] gives them) nearest its point `q`: the distance,
/// that point's weights, and the unit direction from `q` to it (out of
/// the ply through its end); None where the face has no outline feature
/// or `q` is on it.
fn nearest_outline(
    bits: u8,
    v: [Vector3<f64>; 3],
    q: &Vector3<f64>,
) -> Option<(f64, [f64; 3], Vector3<f64>)> {
    if bits == 0 {
        return None;
    }
    let mut best: Option<(f64, [f64; 3], Vector3<f64>)> = None;
    let mut keep = |w: [f64; 3], to: Vector3<f64>| {
        let d2 = to.norm_squared();
        if best.is_none_or(|b| d2 < b.0) {
            best = Some((d2, w, to));
        }
    };
    for k in 0..3 {
        let j = (k + 1) % 3;
        if bits & (1 << k) != 0 {
            let e = v[j] - v[k];
            let e2 = e.norm_squared();
            let t = if e2 > 0.0 {
                ((q - v[k]).dot(&e) / e2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let mut w = [0.0; 3];
            w[k] = 1.0 - t;
            w[j] = t;
            keep(w, v[k] + e * t - q);
        }
        if bits & (1 << (3 + k)) != 0 {
            let mut w = [0.0; 3];
            w[k] = 1.0;
            keep(w, v[k] - q);
        }
    }
    let (d2, w, to) = best?;
    let e = d2.sqrt();
    (e > 0.0).then(|| (e, w, to / e))
}

/// The closest point of triangle abc to p and its barycentric weights
/// (Ericson, Real-Time Collision Detection, §5.1.5).
pub(super) fn closest_on_triangle(
    p: &Vector3<f64>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
) -> (Vector3<f64>, [f64; 3]) {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return (*a, [1.0, 0.0, 0.0]);
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return (*b, [0.0, 1.0, 0.0]);
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let t = d1 / (d1 - d3);
        return (a + ab * t, [1.0 - t, t, 0.0]);
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return (*c, [0.0, 0.0, 1.0]);
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let t = d2 / (d2 - d6);
        return (a + ac * t, [1.0 - t, 0.0, t]);
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let t = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return (b + (c - b) * t, [0.0, 1.0 - t, t]);
    }
    let denom = 1.0 / (va + vb + vc);
    let (s, t) = (vb * denom, vc * denom);
    (a + ab * s + ac * t, [1.0 - s - t, s, t])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plies::outline_of;
    use proptest::prelude::*;

    /// A small generator, so a proptest seed makes a whole mesh.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f64 {
            // xorshift64*
            self.0 ^= self.0 >> 12;
            self.0 ^= self.0 << 25;
            self.0 ^= self.0 >> 27;
            (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
        }
        fn below(&mut self, n: usize) -> usize {
            ((self.next() * n as f64) as usize).min(n - 1)
        }
    }

    fn same(a: &Hit, b: &Hit) -> bool {
        let bits = |v: &Vector3<f64>| v.map(f64::to_bits);
        a.found == b.found
            && a.face == b.face
            && a.nodes == b.nodes
            && a.w.map(f64::to_bits) == b.w.map(f64::to_bits)
            && a.gap.to_bits() == b.gap.to_bits()
            && bits(&a.normal) == bits(&b.normal)
            && a.recover == b.recover
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(200))]

        /// The bound never exceeds the distance to the triangle (beyond
        /// round-off: 16 ε of the coordinates times 1 + L²/|n|, the
        /// face's longest edge squared over twice its area, which the
        /// error of its normal's direction grows with; a node 2e-3 from a
        /// face 30 from the origin errs by 1e-12 of the distance, a node
        /// by a face with L²/|n| = 1871 by 87 ε of the coordinates, and
        /// `BOUND_SLACK` is 1e-10 of them, above the round-off of any face
        /// the guard keeps, L²/|n| ≤ 1e4), and is the distance
        /// where the node is over the face (then only the height counts)
        /// or beside one edge's middle (height and that edge's distance):
        /// loose nowhere a smooth ply's neighbour faces are.
        #[test]
        fn the_bound_is_below_the_distance_and_tight_over_the_face(seed in any::<u64>()) {
            let mut rng = Rng(seed | 1);
            let mut point = |s: f64| Vector3::new(s * (rng.next() - 0.5), s * (rng.next() - 0.5), s * (rng.next() - 0.5));
            let v = [point(20.0), point(20.0), point(20.0)];
            let bound = FaceBound::of(v);
            let distance = |p: &Vector3<f64>| (p - closest_on_triangle(p, &v[0], &v[1], &v[2]).0).norm_squared();
            // L²/|n|: the normal's components err by ~ε·L², its direction
            // by ε·L²/|n|, a height over the face by that times the
            // node's distance (a sliver's bound is 0: nothing to err).
            let longest = [v[1] - v[0], v[2] - v[1], v[0] - v[2]].iter().map(|e| e.norm_squared()).fold(0.0, f64::max);
            let shape = longest * bound.inv_n2.sqrt();
            for _ in 0..50 {
                let p = point(60.0);
                let d = distance(&p);
                let scale = v.iter().chain([&p]).map(|v| v.amax()).fold(0.0, f64::max);
                let round_off = 16.0 * f64::EPSILON * scale * (1.0 + shape);
                prop_assert!(bound.distance_squared(&p).sqrt() <= d.sqrt() + round_off, "{} > {d}", bound.distance_squared(&p));
                prop_assert!(round_off < BOUND_SLACK * scale);
            }
            if bound.inv_n2 > 0.0 {
                let n = bound.n.normalize();
                let mut w = [rng.next(), rng.next(), rng.next()];
                let sum: f64 = w.iter().sum();
                w.iter_mut().for_each(|w| *w /= sum);
                let h = 5.0 * (rng.next() - 0.5);
                // Over the face.
                let over = v[0] * w[0] + v[1] * w[1] + v[2] * w[2] + n * h;
                let d = distance(&over);
                prop_assert!((bound.distance_squared(&over) - d).abs() <= 1e-9 * (1.0 + d), "over: {} against {d}", bound.distance_squared(&over));
                // Beside the middle of edge 0–1, out in the plane.
                let mid = (v[0] + v[1]) * 0.5;
                let out = (v[1] - v[0]).cross(&n).normalize();
                let e = 3.0 * rng.next();
                let beside = mid + out * e + n * h;
                let d = distance(&beside);
                // Only where that edge's middle is the closest point (an
                // obtuse corner can put another edge nearer).
                if ((d - e * e - h * h) / (1.0 + d)).abs() < 1e-9 {
                    prop_assert!((bound.distance_squared(&beside) - d).abs() <= 1e-9 * (1.0 + d), "beside: {} against {d}", bound.distance_squared(&beside));
                }
            }
        }

        /// On a wavy, jittered grid of triangles (a ply's mid-surface,
        /// some of it folded steeply), nodes above, below and beside it,
        /// some exactly over a vertex (where several faces tie), with
        /// candidate lists in any order and any face (or none) first: the
        /// pruned search finds the exhaustive one's hit, bit for bit.
        #[test]
        fn the_pruned_search_finds_the_exhaustive_hit(seed in any::<u64>(), side in prop::bool::ANY) {
            let mut rng = Rng(seed | 1);
            let n = 2 + rng.below(5);
            let cell = 1.0 + 9.0 * rng.next();
            let wave = cell * rng.next();
            let mut x = Vec::new();
            for j in 0..=n {
                for i in 0..=n {
                    let jitter = if rng.next() < 0.5 { 0.0 } else { 0.3 * cell };
                    x.push(Vector3::new(
                        i as f64 * cell + jitter * (rng.next() - 0.5),
                        j as f64 * cell + jitter * (rng.next() - 0.5),
                        wave * (rng.next() - 0.5),
                    ));
                }
            }
            let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
            let mut faces = Vec::new();
            for j in 0..n {
                for i in 0..n {
                    let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                    if rng.next() < 0.5 {
                        faces.extend([[a, b, c], [a, c, d]]);
                    } else {
                        faces.extend([[a, b, d], [b, c, d]]);
                    }
                }
            }
            let outline = outline_of(&faces);
            let mut bounds = vec![FaceBound::default(); faces.len()];
            face_bounds(&faces, &x, &mut bounds);
            let offset = 0.05 + cell * 0.2 * rng.next();
            let master = Master {
                faces: &faces,
                outline: &outline,
                bounds: &bounds,
                side: if side { 1.0 } else { -1.0 },
                offset,
                reach: offset + cell * rng.next(),
            };
            let vertices = x.len();
            for _ in 0..60 {
                let p = if rng.next() < 0.3 {
                    // Exactly over (or under) a vertex.
                    x[rng.below(vertices)] + Vector3::new(0.0, 0.0, 2.0 * offset * (rng.next() - 0.5))
                } else {
                    Vector3::new(
                        (n as f64 + 1.0) * cell * rng.next() - 0.5 * cell,
                        (n as f64 + 1.0) * cell * rng.next() - 0.5 * cell,
                        (wave + 3.0 * offset) * (rng.next() - 0.5),
                    )
                };
                let mut cand: Vec<u32> = (0..faces.len() as u32)
                    .filter(|_| rng.next() < 0.8)
                    .collect();
                for k in (1..cand.len()).rev() {
                    cand.swap(k, rng.below(k + 1));
                }
                let first = match rng.below(3) {
                    0 => u32::MAX,
                    _ => rng.below(faces.len()) as u32,
                };
                let exhaustive = master.closest_exhaustive(&p, &x, &cand);
                let pruned = master.closest(&p, &x, &cand, first);
                prop_assert!(
                    same(&pruned, &exhaustive),
                    "p = {p:?}, first {first}: {pruned:?} against {exhaustive:?}"
                );
            }
        }
    }

    /// The way out through a free end: to the nearest point of the face's
    /// outline edges and vertices (an edge's foot or a vertex, not an
    /// interior edge), and only behind the face where that way is shorter
    /// than the offset and the depth.
    #[test]
    fn the_way_out_through_the_end_is_to_the_nearest_outline_point_behind_the_face() {
        let v = [
            Vector3::new(0.0, 0.0, 0.0),
            Vector3::new(4.0, 0.0, 0.0),
            Vector3::new(0.0, 4.0, 0.0),
        ];
        let q = Vector3::new(1.0, 0.5, 0.0);
        let close = |a: f64, b: f64| (a - b).abs() < 1e-14;
        // Edge ab free (with its vertices): straight across to it.
        let (e, w, m) = nearest_outline(0b01_1001, v, &q).expect("ab");
        assert!(close(e, 0.5) && close(w[0], 0.75) && close(w[1], 0.25) && w[2] == 0.0);
        assert!((m + Vector3::y()).norm() < 1e-14, "{m}");
        // Edge bc free: its foot, at 0.4375 of the way from b.
        let (e, w, m) = nearest_outline(0b00_0010, v, &q).expect("bc");
        assert!(close(e, 2.5 / 2f64.sqrt()), "{e}");
        assert!(
            w[0] == 0.0 && close(w[1], 0.5625) && close(w[2], 0.4375),
            "{w:?}"
        );
        assert!((m - Vector3::new(1.0, 1.0, 0.0) / 2f64.sqrt()).norm() < 1e-14);
        // Only vertex c on the outline (its edges interior): to it.
        let (e, w, _) = nearest_outline(0b10_0000, v, &q).expect("c");
        assert!(close(e, (1.0f64 + 3.5 * 3.5).sqrt()) && w == [0.0, 0.0, 1.0]);
        // No outline, or the point on it: none.
        assert!(nearest_outline(0, v, &q).is_none());
        assert!(nearest_outline(0b01_1001, v, &Vector3::new(1.0, 0.0, 0.0)).is_none());
        // Behind the face, 0.5 from the free edge ab with the offset 0.3:
        // out through the end from 0.2 deep on, never in front.
        let w = [0.625, 0.25, 0.125];
        for (along, out) in [
            (0.1, false),
            (0.0, false),
            (-0.19, false),
            (-0.21, true),
            (-3.0, true),
        ] {
            let found = through_end(0b01_1001, v, &w, 0.3, along).is_some();
            assert_eq!(found, out, "along {along}");
        }
    }
}
