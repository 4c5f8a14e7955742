//! Derived measures of a formed blank (SPEC §8): shear profiles, draw-in,
//! area above a locking angle, maxima.
//!
//! These are the numbers the paper compares with experiments: shear along
//! the diagonal and medians (its Figs. 7 and 12), the draw-in or
//! "shrinkage" of edge midpoints and corners (its Table 4), and the area
//! sheared past a locking angle as a wrinkle-risk indicator. They are pure
//! functions of reference and current positions and per-element shear, so
//! they can be evaluated on any frame of a result.
//!
//! Conventions:
//! - Lines and directions live in the blank's reference plane (x, y); z is
//!   dropped, so a blank drawn into a die measures its in-plane pull-in.
//! - A profile's `distance` is the signed coordinate along the line from
//!   the blank centre, positive towards +x (medians along x, diagonal) or
//!   +y (median along y).

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::blank::BlankFrame;

/// A line of the blank along which a shear profile is read.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProfileLine {
    /// From the bottom-left to the top-right corner.
    Diagonal,
    /// The median parallel to x (y = centre).
    MedianX,
    /// The median parallel to y (x = centre).
    MedianY,
}

impl ProfileLine {
    /// The unit in-plane direction (x, y) of the line on a blank `frame`.
    pub fn direction(self, frame: &BlankFrame) -> [f64; 2] {
        match self {
            ProfileLine::Diagonal => {
                let length = frame.width.hypot(frame.height);
                [frame.width / length, frame.height / length]
            }
            ProfileLine::MedianX => [1.0, 0.0],
            ProfileLine::MedianY => [0.0, 1.0],
        }
    }
}

/// One point of a shear profile.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ProfilePoint {
    /// Signed initial distance from the blank centre along the line (mm).
    pub distance: f64,
    /// Shear angle there (degrees).
    pub shear_deg: f64,
}

/// Draw-in (the paper's "shrinkage", Table 4), mm.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct DrawIn {
    /// Mean inward in-plane displacement of the midpoints of the two edges normal to x.
    pub dx: f64,
    /// The same for the edges normal to y.
    pub dy: f64,
    /// Mean inward in-plane displacement of the four corners along the diagonals.
    pub dd: f64,
}

/// The elements along `line`: every element whose reference centroid lies
/// within `band` of the line, as (element index, signed distance from the
/// centre), sorted by distance.
///
/// `band` is a perpendicular distance, inclusive up to a rounding tolerance
/// of 1e-9 of the blank's size: on a grid with an even number of rows the
/// centroids next to a median sit exactly half a cell away, and a band of
/// half a cell must take both rows, not whichever rounding favours. Equal
/// distances keep element order, so the result is deterministic.
pub fn profile_elements(
    frame: &BlankFrame,
    centroids0: &[Vector3<f64>],
    line: ProfileLine,
    band: f64,
) -> Vec<(usize, f64)> {
    let [ux, uy] = line.direction(frame);
    let reach = band + 1e-9 * frame.width.max(frame.height);
    let mut points: Vec<(usize, f64)> = centroids0
        .iter()
        .enumerate()
        .filter_map(|(e, c)| {
            let (rx, ry) = (c.x - frame.center.x, c.y - frame.center.y);
            let across = (rx * uy - ry * ux).abs();
            (across <= reach).then_some((e, rx * ux + ry * uy))
        })
        .collect();
    // Stable sort: elements at the same distance stay in element order.
    points.sort_by(|a, b| a.1.total_cmp(&b.1));
    points
}

/// The shear profile along `line`: the shear of the elements of
/// [`profile_elements`], sorted by signed distance from the centre.
pub fn shear_profile(
    frame: &BlankFrame,
    centroids0: &[Vector3<f64>],
    shear_rad: &[f64],
    line: ProfileLine,
    band: f64,
) -> Vec<ProfilePoint> {
    debug_assert_eq!(centroids0.len(), shear_rad.len());
    profile_elements(frame, centroids0, line, band)
        .into_iter()
        .map(|(e, distance)| ProfilePoint {
            distance,
            shear_deg: shear_rad[e].to_degrees(),
        })
        .collect()
}

/// Draw-in from reference `x0` and current `x` positions, given the edge
/// midpoint nodes [left, right, bottom, top] and the corner nodes
/// [bottom-left, bottom-right, top-right, top-left].
///
/// Each displacement is projected on the blank plane (z dropped) and then on
/// the inward direction: +x, −x, +y, −y for the midpoints, and the unit
/// vector from the corner's reference position towards the blank centre for
/// the corners. Positive values mean the blank was pulled in.
pub fn draw_in(
    frame: &BlankFrame,
    x0: &[Vector3<f64>],
    x: &[Vector3<f64>],
    midpoints: [u32; 4],
    corners: [u32; 4],
) -> DrawIn {
    let displacement = |n: u32| {
        let n = n as usize;
        [x[n].x - x0[n].x, x[n].y - x0[n].y]
    };
    let inward = |n: u32, [ix, iy]: [f64; 2]| {
        let [ux, uy] = displacement(n);
        ux * ix + uy * iy
    };
    let [left, right, bottom, top] = midpoints;
    let dx = 0.5 * (inward(left, [1.0, 0.0]) + inward(right, [-1.0, 0.0]));
    let dy = 0.5 * (inward(bottom, [0.0, 1.0]) + inward(top, [0.0, -1.0]));
    let dd = corners
        .iter()
        .map(|&n| {
            let p = &x0[n as usize];
            let (tx, ty) = (frame.center.x - p.x, frame.center.y - p.y);
            let length = tx.hypot(ty);
            // A corner at the centre (a degenerate blank) has no inward
            // direction; it contributes nothing rather than a NaN.
            if length > 0.0 {
                inward(n, [tx / length, ty / length])
            } else {
                0.0
            }
        })
        .sum::<f64>()
        / 4.0;
    DrawIn { dx, dy, dd }
}

/// Total reference area of the elements whose |shear| exceeds `locking_rad`.
pub fn area_above(shear_rad: &[f64], areas: &[f64], locking_rad: f64) -> f64 {
    debug_assert_eq!(shear_rad.len(), areas.len());
    shear_rad
        .iter()
        .zip(areas)
        .filter(|(gamma, _)| gamma.abs() > locking_rad)
        // A fold from +0: an empty `sum` of floats is −0, which reads oddly.
        .fold(0.0, |total, (_, a)| total + a)
}

/// Waviness above which an element counts as wrinkled (degrees) in
/// [`crate::Measures::wrinkle_area`] **\[choice\]**: about the deviation a
/// wrinkle of amplitude a and wavelength λ gives on elements of size h,
/// 2π²·a·h²/λ², for a = h on λ = 6h; far above what a smooth tool
/// curvature κ leaves (≈ (κh)² rad).
pub const WRINKLE_THRESHOLD_DEG: f64 = 5.0;

/// The wrinkle indicator of elements of `waviness` (degrees) and reference
/// `area` (mm²): the largest waviness, and the area of the elements wavier
/// than [`WRINKLE_THRESHOLD_DEG`].
pub fn wrinkle_indicator(waviness: &[f64], area: &[f64]) -> (f64, f64) {
    let largest = waviness.iter().fold(0.0, |a: f64, &w| a.max(w));
    let wavy = waviness
        .iter()
        .zip(area)
        .filter(|(w, _)| **w > WRINKLE_THRESHOLD_DEG)
        .fold(0.0, |total, (_, a)| total + a);
    (largest, wavy)
}

/// The unit normal of an element with `nodes` at positions `x` (a quad's:
/// the cross product of its diagonals), zero for a degenerate element.
pub fn element_normal(nodes: &[u32], x: &[Vector3<f64>]) -> Vector3<f64> {
    let p = |k: usize| x[nodes[k] as usize];
    let n = match nodes.len() {
        3 => (p(1) - p(0)).cross(&(p(2) - p(0))),
        _ => (p(2) - p(0)).cross(&(p(3) - p(1))),
    };
    n.try_normalize(0.0).unwrap_or_else(Vector3::zeros)
}

/// The waviness of each element (degrees): the angle between its normal and
/// the mean of its edge neighbours' normals (a quad: of each pair of
/// opposite neighbours, the larger; a triangle: of its three), a measure of
/// out-of-plane waviness at the scale of the mesh. The mean of neighbours
/// on both sides cancels the first-order change of the normal across a
/// smoothly curved surface (a tool's curvature κ leaves O((κh)²)), while a
/// wrinkle whose crests are a few elements apart tilts neighbours
/// alternately and reads as its second difference. Directions with a free
/// edge on one side are not measured (0 when none is left).
///
/// `elements` are the node lists of every membrane element, consistently
/// oriented (a quad's normal is the cross product of its diagonals).
pub fn waviness(elements: &[&[u32]], x: &[Vector3<f64>]) -> Vec<f64> {
    let normals: Vec<Vector3<f64>> = elements.iter().map(|e| element_normal(e, x)).collect();
    let mut by_edge: std::collections::HashMap<(u32, u32), Vec<usize>> =
        std::collections::HashMap::new();
    for (e, nodes) in elements.iter().enumerate() {
        for k in 0..nodes.len() {
            let (a, b) = (nodes[k], nodes[(k + 1) % nodes.len()]);
            by_edge.entry((a.min(b), a.max(b))).or_default().push(e);
        }
    }
    // The neighbour across each edge of each element (the first other owner).
    let across = |e: usize, k: usize| -> Option<usize> {
        let nodes = elements[e];
        let (a, b) = (nodes[k], nodes[(k + 1) % nodes.len()]);
        by_edge[&(a.min(b), a.max(b))]
            .iter()
            .copied()
            .find(|&o| o != e)
    };
    let angle = |n: &Vector3<f64>, s: Vector3<f64>| match s.try_normalize(0.0) {
        Some(mean) => n.dot(&mean).clamp(-1.0, 1.0).acos().to_degrees(),
        None => 0.0,
    };
    (0..elements.len())
        .map(|e| {
            let n = &normals[e];
            if elements[e].len() == 4 {
                // Opposite neighbours in pairs: the mean of a pair cancels
                // a smooth curvature's first-order tilt; a pair with a
                // free edge on one side is not measured.
                [(0, 2), (1, 3)]
                    .iter()
                    .filter_map(|&(k, l)| Some(normals[across(e, k)?] + normals[across(e, l)?]))
                    .map(|s| angle(n, s))
                    .fold(0.0, f64::max)
            } else {
                // A triangle's three neighbours surround it; one on a free
                // edge is not measured.
                let all: Option<Vec<usize>> = (0..3).map(|k| across(e, k)).collect();
                all.map_or(0.0, |all| angle(n, all.iter().map(|&o| normals[o]).sum()))
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::blank::{ElementKind, FibreRepresentation, Meshing, RectangleBlank};

    fn frame() -> BlankFrame {
        BlankFrame {
            center: Vector3::new(5.0, -3.0, 2.0),
            width: 100.0,
            height: 80.0,
        }
    }

    /// Hand-made nodes: midpoints left, right, bottom, top, then corners
    /// bottom-left, bottom-right, top-right, top-left.
    fn nodes(f: &BlankFrame) -> Vec<Vector3<f64>> {
        let (c, w, h) = (f.center, 0.5 * f.width, 0.5 * f.height);
        [
            (-w, 0.0),
            (w, 0.0),
            (0.0, -h),
            (0.0, h),
            (-w, -h),
            (w, -h),
            (w, h),
            (-w, h),
        ]
        .iter()
        .map(|&(x, y)| c + Vector3::new(x, y, 0.0))
        .collect()
    }

    const MID: [u32; 4] = [0, 1, 2, 3];
    const CORNERS: [u32; 4] = [4, 5, 6, 7];

    #[test]
    fn waviness_ignores_a_smooth_cylinder_and_flags_mesh_scale_waves() {
        let (nx, ny, h) = (40usize, 6usize, 2.0);
        let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
        let quads: Vec<[u32; 4]> = (0..ny)
            .flat_map(|j| {
                (0..nx).map(move |i| [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)])
            })
            .collect();
        let elements: Vec<&[u32]> = quads.iter().map(|q| &q[..]).collect();
        let grid = |z: &dyn Fn(f64) -> Vector3<f64>| -> Vec<Vector3<f64>> {
            (0..=ny)
                .flat_map(|j| (0..=nx).map(move |i| (i, j)))
                .map(|(i, j)| z(i as f64 * h) + Vector3::new(0.0, j as f64 * h, 0.0))
                .collect()
        };
        // Rolled on R = 30 mm: κh = 0.067, neighbours differ by 3.8°, but
        // the mean of two opposite neighbours is the element's own normal.
        let r = 30.0;
        let rolled = grid(&|s| Vector3::new(r * (s / r).sin(), 0.0, r * (1.0 - (s / r).cos())));
        let smooth = waviness(&elements, &rolled);
        assert!(
            smooth.iter().all(|w| *w < 0.5),
            "{:?}",
            smooth.iter().fold(0.0f64, |a, b| a.max(*b))
        );
        // A wave of 8 mm (4 elements) and 1 mm amplitude: well above 5°.
        let waves = grid(&|s| Vector3::new(s, 0.0, (s * std::f64::consts::TAU / 8.0).sin()));
        let wavy = waviness(&elements, &waves);
        let max = wavy.iter().fold(0.0f64, |a, b| a.max(*b));
        assert!(max > 20.0, "{max}");
        // Flat: zero.
        assert!(
            waviness(&elements, &grid(&|s| Vector3::new(s, 0.0, 0.0)))
                .iter()
                .all(|w| *w == 0.0)
        );
    }

    #[test]
    fn uniform_inward_translation_of_edges() {
        let f = frame();
        let x0 = nodes(&f);
        let (dx, dy, dd) = (7.0, 4.0, 3.0);
        let (w, h) = (f.width, f.height);
        let diag = w.hypot(h);
        // Each node moves inward by its amount, plus an out-of-plane lift
        // and (for midpoints) a tangential slide that must not count.
        let moves = [
            Vector3::new(dx, 1.0, 9.0),
            Vector3::new(-dx, -2.0, 9.0),
            Vector3::new(0.5, dy, -4.0),
            Vector3::new(0.0, -dy, 30.0),
            Vector3::new(w, h, 0.0) * (dd / diag) + Vector3::new(0.0, 0.0, 12.0),
            Vector3::new(-w, h, 0.0) * (dd / diag),
            Vector3::new(-w, -h, 0.0) * (dd / diag),
            Vector3::new(w, -h, 0.0) * (dd / diag),
        ];
        let x: Vec<_> = x0.iter().zip(moves).map(|(p, m)| p + m).collect();
        let d = draw_in(&f, &x0, &x, MID, CORNERS);
        assert!((d.dx - dx).abs() < 1e-12, "{d:?}");
        assert!((d.dy - dy).abs() < 1e-12, "{d:?}");
        assert!((d.dd - dd).abs() < 1e-12, "{d:?}");
        // No motion, no draw-in; outward motion is negative.
        assert_eq!(draw_in(&f, &x0, &x0, MID, CORNERS), DrawIn::default());
        let out: Vec<_> = x0.iter().zip(&x).map(|(p, q)| p - (q - p)).collect();
        let d = draw_in(&f, &x0, &out, MID, CORNERS);
        assert!(
            (d.dx + dx).abs() < 1e-12 && (d.dy + dy).abs() < 1e-12 && (d.dd + dd).abs() < 1e-12
        );
    }

    #[test]
    fn rigid_translation_is_no_draw_in() {
        let f = frame();
        let x0 = nodes(&f);
        let x: Vec<_> = x0
            .iter()
            .map(|p| p + Vector3::new(3.0, -8.0, 50.0))
            .collect();
        let d = draw_in(&f, &x0, &x, MID, CORNERS);
        assert!(
            d.dx.abs() < 1e-12 && d.dy.abs() < 1e-12 && d.dd.abs() < 1e-12,
            "{d:?}"
        );
    }

    #[test]
    fn uniform_shrink_of_a_meshed_blank() {
        let b = RectangleBlank {
            width: 100.0,
            height: 80.0,
            center: Vector3::new(5.0, -3.0, 2.0),
            orientation_deg: 0.0,
            element: ElementKind::Quad,
            meshing: Meshing::Cells([4, 4]),
            fibres: FibreRepresentation::Trusses,
        };
        let m = b.mesh().unwrap();
        let s = 0.9;
        let x: Vec<_> = m.x0.iter().map(|p| b.center + (p - b.center) * s).collect();
        let set = |name: &str| -> [u32; 4] { m.node_sets[name].clone().try_into().unwrap() };
        let d = draw_in(&b.frame(), &m.x0, &x, set("edge_midpoints"), set("corners"));
        assert!((d.dx - 0.1 * 50.0).abs() < 1e-12, "{d:?}");
        assert!((d.dy - 0.1 * 40.0).abs() < 1e-12, "{d:?}");
        assert!((d.dd - 0.1 * 50.0f64.hypot(40.0)).abs() < 1e-12, "{d:?}");
    }

    #[test]
    fn profile_picks_the_right_elements_in_order() {
        let f = frame();
        let c = f.center;
        let at = |x: f64, y: f64| c + Vector3::new(x, y, 0.0);
        // Diagonal direction (100, 80)/|..|; a point at t along it, offset n across.
        let l = 100.0f64.hypot(80.0);
        let (ux, uy) = (100.0 / l, 80.0 / l);
        let on_diag = |t: f64, n: f64| at(t * ux - n * uy, t * uy + n * ux);
        let centroids = vec![
            on_diag(20.0, 0.5),           // 0: diagonal, +20
            at(-30.0, 0.0),               // 1: median x, −30
            on_diag(-10.0, -0.9),         // 2: diagonal, −10
            at(0.0, 25.0),                // 3: median y, +25
            on_diag(5.0, 1.5),            // 4: outside the band
            at(12.0, -0.99),              // 5: median x, +12
            at(0.2, -35.0),               // 6: median y, −35
            Vector3::new(c.x, c.y, 40.0), // 7: the centre, any z: on every line
        ];
        let shear: Vec<f64> = (0..centroids.len())
            .map(|k| (k as f64 - 3.0).to_radians())
            .collect();
        let read = |line| -> Vec<(f64, f64)> {
            shear_profile(&f, &centroids, &shear, line, 1.0)
                .iter()
                .map(|p| (p.distance, p.shear_deg))
                .collect()
        };
        let close = |got: Vec<(f64, f64)>, want: &[(f64, f64)]| {
            assert_eq!(got.len(), want.len(), "{got:?}");
            for (g, w) in got.iter().zip(want) {
                assert!(
                    (g.0 - w.0).abs() < 1e-12 && (g.1 - w.1).abs() < 1e-12,
                    "{got:?} vs {want:?}"
                );
            }
        };
        close(
            read(ProfileLine::Diagonal),
            &[(-10.0, -1.0), (0.0, 4.0), (20.0, -3.0)],
        );
        close(
            read(ProfileLine::MedianX),
            &[(-30.0, -2.0), (0.0, 4.0), (12.0, 2.0)],
        );
        close(
            read(ProfileLine::MedianY),
            &[(-35.0, 3.0), (0.0, 4.0), (25.0, 0.0)],
        );
        // A wider band reaches element 4 (1.5 off the diagonal).
        assert_eq!(
            shear_profile(&f, &centroids, &shear, ProfileLine::Diagonal, 1.5).len(),
            4
        );
        assert!(shear_profile(&f, &[], &[], ProfileLine::Diagonal, 1.0).is_empty());
    }

    #[test]
    fn band_of_half_a_cell_takes_both_rows_beside_a_median() {
        // 3 × 4 cells of 1.1 × 0.7 mm, an even number of rows: centroids at ±cell/2 of the
        // median y = centre, with values that round differently.
        let f = BlankFrame {
            center: Vector3::new(0.3, 0.1, 0.0),
            width: 3.3,
            height: 2.8,
        };
        let (dx, dy) = (1.1, 0.7);
        let mut centroids = Vec::new();
        for j in 0..4 {
            for i in 0..3 {
                centroids.push(Vector3::new(
                    f.center.x - 0.5 * f.width + (i as f64 + 0.5) * dx,
                    f.center.y - 0.5 * f.height + (j as f64 + 0.5) * dy,
                    0.0,
                ));
            }
        }
        let shear = vec![0.0; centroids.len()];
        let p = shear_profile(&f, &centroids, &shear, ProfileLine::MedianX, 0.5 * dy);
        assert_eq!(p.len(), 6, "{p:?}");
    }

    #[test]
    fn area_above_counts_both_signs_strictly() {
        let lock = 30f64.to_radians();
        let shear = [0.0, 0.6, -0.6, lock, -lock, 1.2];
        let areas = [1.0, 2.0, 4.0, 8.0, 16.0, 32.0];
        assert_eq!(area_above(&shear, &areas, lock), 2.0 + 4.0 + 32.0);
        assert_eq!(area_above(&shear, &areas, 10.0), 0.0);
        assert_eq!(area_above(&[], &[], lock), 0.0);
    }
}
