//! What makes a triangle-mesh tool about as cheap per contact step as an
//! analytic one: a closest-triangle search that starts from the triangle a
//! node found last (its neighbourhood, precomputed) instead of a full
//! descent of parry's tree, and the distance to the mesh's open rim, which
//! lets the contact pass skip far nodes of open meshes too (see
//! [`crate::Surface::rim_clearance`]).
//!
//! Not for the sign or the normal of a projection: those stay in
//! [`crate::MeshSurface`]; this module only picks the closest triangle, the
//! same one a full query picks.

use parry3d_f64::bounding_volume::Aabb as PAabb;
use parry3d_f64::math::Vector as DVec3;
use parry3d_f64::query::{PointProjection, PointQuery, PointQueryWithLocation};
use parry3d_f64::shape::{Polyline, TriMesh, TrianglePointLocation};

/// The closest triangle of a point and where on it.
pub(crate) type Closest = (u32, PointProjection, TrianglePointLocation);

/// Per triangle, the triangles whose boxes come within [`Near::radius`] of
/// its box, nearest box first, with that box-to-box distance.
///
/// # Why a local search finds the global closest triangle
///
/// Let `x` be at distance `d₀` from triangle `T₀` (closest point `p`). A
/// triangle `T` with a point `y` at most `d₀` from `x` has `|y − p| ≤ 2d₀`,
/// so the distance between the boxes of `T₀` and `T` is at most `2d₀`; if
/// `2d₀ ≤ radius`, `T` is in `T₀`'s list. More sharply, `dist(x, T) ≥
/// δ(T₀, T) − d₀` for the box distance δ, so the rows, sorted by δ, are
/// read only while `δ ≤ d₀ + best`: for a node resting on the mesh that is
/// the few triangles around `T₀`. The closest triangle is chosen by
/// (squared distance, index), so that a tie (a point closest to an edge two
/// triangles share) is resolved the same way from any start.
#[derive(Debug, Default)]
pub(crate) struct Near {
    /// Largest box-to-box distance kept (the mean longest edge of the
    /// triangles): a search from a triangle `d₀` away is conclusive while
    /// `2d₀ ≤ radius`.
    radius: f64,
    /// Absolute slack on every comparison (far above the round-off of a
    /// distance, far below any contact distance): a triangle whose computed
    /// distance could tie with the best is always looked at.
    slack: f64,
    /// Each triangle's box.
    boxes: Vec<[DVec3; 2]>,
    /// Row `t` is `start[t]..start[t + 1]` of `triangle` and `distance`.
    start: Vec<u32>,
    triangle: Vec<u32>,
    distance: Vec<f64>,
}

/// The distance between two boxes (0 when they overlap).
fn box_gap(a: &[DVec3; 2], b: &[DVec3; 2]) -> f64 {
    (a[0] - b[1]).max(b[0] - a[1]).max(DVec3::ZERO).length()
}

/// The squared distance from `q` to a box (0 inside).
fn box_point_gap2(b: &[DVec3; 2], q: DVec3) -> f64 {
    (b[0] - q).max(q - b[1]).max(DVec3::ZERO).length_squared()
}

impl Near {
    /// The neighbourhoods of `mesh`'s triangles.
    pub(crate) fn of(mesh: &TriMesh) -> Self {
        let n = mesh.indices().len();
        let mut boxes = Vec::with_capacity(n);
        let mut longest = 0.0;
        for t in mesh.triangles() {
            boxes.push([t.a.min(t.b).min(t.c), t.a.max(t.b).max(t.c)]);
            longest +=
                t.a.distance(t.b)
                    .max(t.b.distance(t.c))
                    .max(t.a.distance(t.c));
        }
        let radius = longest / n.max(1) as f64;
        let aabb = mesh.local_aabb();
        let scale = (aabb.maxs - aabb.mins)
            .length()
            .max(aabb.mins.abs().max(aabb.maxs.abs()).max_element());
        let mut start = Vec::with_capacity(n + 1);
        let mut triangle = Vec::new();
        let mut distance = Vec::new();
        let mut row: Vec<(f64, u32)> = Vec::new();
        start.push(0);
        for b in &boxes {
            let grown = PAabb::new(b[0] - DVec3::splat(radius), b[1] + DVec3::splat(radius));
            row.clear();
            row.extend(
                mesh.bvh()
                    .intersect_aabb(&grown)
                    .map(|j| (box_gap(b, &boxes[j as usize]), j))
                    .filter(|&(d, _)| d <= radius),
            );
            row.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            triangle.extend(row.iter().map(|&(_, j)| j));
            distance.extend(row.iter().map(|&(d, _)| d));
            start.push(triangle.len() as u32);
        }
        Self {
            radius,
            slack: 1e-9 * scale,
            boxes,
            start,
            triangle,
            distance,
        }
    }

    /// The closest triangle of `q` by a search around `seed`, or `None`
    /// when `q` is too far from `seed` for the neighbourhood to be
    /// conclusive (see [`Near`]).
    pub(crate) fn search(&self, mesh: &TriMesh, q: DVec3, seed: u32) -> Option<Closest> {
        let s = seed as usize;
        if s >= self.boxes.len() {
            return None;
        }
        let (proj, location) = mesh
            .triangle(seed)
            .project_local_point_and_get_location(q, false);
        let mut best_d2 = (q - proj.point).length_squared();
        let d0 = best_d2.sqrt();
        // Written so that a NaN distance (a point not finite) also gives up.
        let conclusive = 2.0 * d0 + self.slack <= self.radius;
        if !conclusive {
            return None;
        }
        let mut best = (seed, proj, location);
        let mut best_d = d0;
        for k in self.start[s] as usize..self.start[s + 1] as usize {
            if self.distance[k] > d0 + best_d + self.slack {
                break;
            }
            let j = self.triangle[k];
            if j == seed {
                continue;
            }
            let reach = best_d + self.slack;
            if box_point_gap2(&self.boxes[j as usize], q) > reach * reach {
                continue;
            }
            let (p, l) = mesh
                .triangle(j)
                .project_local_point_and_get_location(q, false);
            let d2 = (q - p.point).length_squared();
            if d2 < best_d2 || (d2 == best_d2 && j < best.0) {
                best = (j, p, l);
                best_d2 = d2;
                best_d = d2.sqrt();
            }
        }
        Some(best)
    }
}

/// The open edges of a mesh as a polyline, for the distance to its rim
/// (`None` for a closed mesh).
pub(crate) fn rim_polyline(mesh: &TriMesh) -> Option<Polyline> {
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut count = std::collections::HashMap::new();
    for t in mesh.indices() {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[0], t[2])] {
            *count.entry(key(a, b)).or_insert(0u32) += 1;
        }
    }
    let mut edges: Vec<[u32; 2]> = count
        .into_iter()
        .filter(|&(_, c)| c == 1)
        .map(|((a, b), _)| [a, b])
        .collect();
    if edges.is_empty() {
        return None;
    }
    // The map's order is random: sorted, the tree (and nothing else) is
    // the same from run to run.
    edges.sort_unstable();
    Some(Polyline::new(mesh.vertices().to_vec(), Some(edges)))
}

/// The distance from `q` to a rim polyline.
pub(crate) fn rim_distance(rim: &Polyline, q: DVec3) -> f64 {
    let p = rim.project_local_point(q, false);
    (q - p.point).length()
}

#[cfg(test)]
pub(crate) mod tests {
    use nalgebra::Vector3;

    use crate::{ProfileSegment, Surface};

    /// An open, double-curved sheet over [−L/2, L/2]² (L = `n`·`h`),
    /// z = 3·sin(x/10)·cos(y/12), triangles counter-clockwise from above;
    /// `n` × `n` cells of two triangles.
    pub(crate) fn bumpy_sheet(n: usize, h: f64) -> Surface {
        let half = 0.5 * n as f64 * h;
        let mut v = Vec::new();
        for j in 0..=n {
            for i in 0..=n {
                let (x, y) = (i as f64 * h - half, j as f64 * h - half);
                v.push(Vector3::new(
                    x,
                    y,
                    3.0 * (x / 10.0).sin() * (y / 12.0).cos(),
                ));
            }
        }
        let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
        let mut f = Vec::new();
        for j in 0..n {
            for i in 0..n {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                // Alternating diagonals: vertices with 4 and with 8 triangles.
                if (i + j) % 2 == 0 {
                    f.extend([[a, b, c], [a, c, d]]);
                } else {
                    f.extend([[a, b, d], [b, c, d]]);
                }
            }
        }
        Surface::triangle_mesh(v, f).unwrap()
    }

    fn mesh(s: &Surface) -> &crate::MeshSurface {
        let Surface::Mesh(m) = s else { unreachable!() };
        m
    }

    /// The triangle of lowest index among the nearest to `x` by parry's
    /// per-triangle projection, by brute force, and its squared distance.
    fn brute_force(s: &Surface, x: &Vector3<f64>) -> (u32, f64) {
        use parry3d_f64::query::PointQuery;
        let m = mesh(s);
        let q = super::DVec3::new(x.x, x.y, x.z);
        let mut best = (u32::MAX, f64::INFINITY);
        for (k, t) in m.triangles().iter().enumerate() {
            let v: Vec<_> = t
                .iter()
                .map(|&i| m.vertices().nth(i as usize).unwrap())
                .map(|p| super::DVec3::new(p.x, p.y, p.z))
                .collect();
            let tri = parry3d_f64::shape::Triangle::new(v[0], v[1], v[2]);
            let d2 = (q - tri.project_local_point(q, false).point).length_squared();
            if d2 < best.1 {
                best = (k as u32, d2);
            }
        }
        best
    }

    /// Points at a grid's vertices and edge midpoints (where triangles tie)
    /// and off them, at heights from behind to well in front.
    fn probes() -> Vec<Vector3<f64>> {
        let mut out = Vec::new();
        for (k, z) in [-2.0, -0.3, -1e-9, 0.0, 0.15, 0.5, 1.7, 4.0, 40.0]
            .into_iter()
            .enumerate()
        {
            for j in 0..9 {
                for i in 0..9 {
                    // Steps of 2.5 = half a cell: vertices and midpoints,
                    // and past the rim at ±15 … ±20.
                    let (x, y) = (-20.0 + 5.0 * i as f64, -20.0 + 2.5 * (j + k) as f64);
                    let s = 3.0 * (x / 10.0f64).sin() * (y / 12.0f64).cos();
                    out.push(Vector3::new(x, y, s + z));
                    out.push(Vector3::new(x + 0.37, y - 0.81, s + z));
                }
            }
        }
        out
    }

    /// From any start the warm-started projection gives the full query's
    /// bits, and the triangle it settles on is the nearest by brute force
    /// (the lowest index among equals) wherever the neighbourhood decides.
    #[test]
    fn a_warm_start_gives_the_full_querys_bits_and_the_nearest_triangle() {
        let s = bumpy_sheet(6, 5.0);
        let m = mesh(&s);
        let n = m.triangles().len() as u32;
        let mut decided = 0;
        for x in probes() {
            let full = s.project(&x);
            let mut found = u32::MAX;
            assert_eq!(m.project_from(&x, &mut found), full);
            let (nearest, d2) = brute_force(&s, &x);
            assert!(
                (full.gap.abs() - d2.sqrt()).abs() <= 1e-12 * (1.0 + d2.sqrt()),
                "{x:?}: |gap| {} against {}",
                full.gap.abs(),
                d2.sqrt()
            );
            if 2.0 * d2.sqrt() < 0.99 * m.near.radius {
                assert_eq!(found, nearest, "{x:?}");
                decided += 1;
            }
            for start in [0, n / 3, n / 2, n - 1, found, nearest, u32::MAX, n + 5] {
                let mut hint = start;
                let p = s.project_from(&x, &mut hint);
                assert_eq!(p, full, "{x:?} from triangle {start}");
                assert_eq!(hint, found, "{x:?} from triangle {start}");
            }
        }
        assert!(decided > 500, "{decided}");
    }

    /// The rim's distance: the square's border for an open sheet, the free
    /// end's circle for an open profile, none for closed surfaces.
    #[test]
    fn rim_clearance_is_the_distance_to_the_open_edges() {
        let s = bumpy_sheet(6, 5.0);
        let z = |x: f64, y: f64| 3.0 * (x / 10.0).sin() * (y / 12.0).cos();
        // The border's vertices, round the square.
        let mut border = Vec::new();
        for k in 0..24 {
            let t = -15.0 + 5.0 * (k % 6) as f64;
            let (a, b) = match k / 6 {
                0 => (t, -15.0),
                1 => (15.0, t),
                2 => (-t, 15.0),
                _ => (-15.0, -t),
            };
            border.push(Vector3::new(a, b, z(a, b)));
        }
        for x in probes() {
            let d = (0..24)
                .map(|k| {
                    let (a, b) = (border[k], border[(k + 1) % 24]);
                    let t = ((x - a).dot(&(b - a)) / (b - a).norm_squared()).clamp(0.0, 1.0);
                    (x - a - (b - a) * t).norm()
                })
                .fold(f64::INFINITY, f64::min);
            let r = s.rim_clearance(&x);
            assert!((r - d).abs() < 1e-12 * (1.0 + d), "{x:?}: {r} against {d}");
        }
        let ring = Surface::revolution(
            Vector3::new(1.0, 2.0, 3.0),
            vec![ProfileSegment::Line {
                from: [250.0, 0.0],
                to: [95.0, 0.0],
            }],
        )
        .unwrap();
        let x = Vector3::new(1.0 + 60.0, 2.0 + 80.0, 3.0 - 4.0);
        assert!((ring.rim_clearance(&x) - (5.0f64.powi(2) + 16.0).sqrt()).abs() < 1e-12);
        let closed = [
            Surface::sphere(Vector3::zeros(), 1.0).unwrap(),
            Surface::plane(Vector3::zeros(), Vector3::z()).unwrap(),
            Surface::hemispherical_punch(Vector3::zeros(), 50.0, 20.0).unwrap(),
        ];
        for c in closed {
            assert_eq!(c.rim_clearance(&x), f64::INFINITY, "{c:?}");
        }
    }
}
