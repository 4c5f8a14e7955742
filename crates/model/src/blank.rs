//! Rectangular blanks: meshing a flat rectangle of fabric into membrane
//! elements, the fibre trusses along its yarn-aligned edges, and the named
//! node sets that scenes (holding springs, boundary conditions) and derived
//! measures (draw-in, profiles) refer to (SPEC §2, §8).
//!
//! Two lattices:
//!
//! - **Grid**: a structured `nx × ny` grid of the rectangle. Used for
//!   embedded fibres at any θ, and for trusses at θ = 0 or 90 (mod 180),
//!   where the grid lines follow the yarns. Trusses lie on every grid edge:
//!   horizontal edges carry the family along x (warp for θ = 0, weft for
//!   θ = 90), vertical edges the other one.
//! - **Diamond**: for trusses at θ = 45 (mod 90), the fibre-aligned lattice
//!   of SPEC §2, whose ±45° lines pass through the corners. `Cells([nx, ny])`
//!   counts cell diagonals along x and y, so the cells are square only when
//!   `width/nx == height/ny`; nodes sit at `(x_min + i·d/2, y_min + j·d/2)`
//!   with `i + j` even. Interior cells are diamonds (quads); the boundary
//!   cuts its cells into exact half-cells (triangles) whose long side, the
//!   cut diagonal, lies on the blank edge and carries no truss.
//!
//! Choices:
//!
//! - Triangles: every grid cell (or diamond) is split into two along one of
//!   its diagonals, the diagonal alternating in a checkerboard (a grid thus
//!   gets the "union jack" pattern, diagonals meeting at every other node),
//!   so that the mesh has no preferred shear direction. In the diamond
//!   lattice the checkerboard is taken in fibre coordinates: diamonds
//!   centred at even `i` are split along their vertical diagonal, odd `i`
//!   along their horizontal one. Splitting diagonals never carry trusses.
//! - Strip areas (SPEC §2, A₀ = (V_f/2)·h·s with s the yarn spacing): each
//!   element gives its area, for each family, in equal shares to its edges
//!   that carry a truss of that family. Summed per family this is exactly
//!   the blank area; on a grid an interior truss gets a cell area and a
//!   boundary truss half of it, in the diamond lattice every truss gets
//!   d²/2 (spacing d/√2 times length d/√2).
//! - θ within 1e-9° of a multiple of 45° is snapped to it: the warp is then
//!   exact (no 6e-17 components), so the trusses of a fibre-aligned lattice
//!   and the embedded fibre directions agree to the last bit.
//! - Node positions are fractions of the width and height, so the blank's
//!   edges are exact; a diamond lattice whose cells are square only to the
//!   accepted 1e-9 has its trusses off ±45° by as little.
//! - Node sets use a tolerance of 1e-9 of the larger extent. When an edge
//!   midpoint is not a node (an odd count), the two nearest nodes tie and
//!   the lower id wins (smaller y on a vertical edge, smaller x on a
//!   horizontal one).
//! - `Meshing::Size(h)`: `h` is the length of an element's edge (a yarn
//!   segment in a truss mesh), whatever the lattice, so plies of any
//!   orientation meshed at one size have elements of one size:
//!   `round(extent/h)` cells of a grid, at least one; the diamond lattice's
//!   edge runs across its cell, so it has `round(width/(h·√2))` cell
//!   diagonals along x, and the height must be a whole number of them.
//! - A mesh of more than [`MAX_ELEMENTS`] elements is refused: such a
//!   request is almost surely a unit mistake, and it would exhaust memory.

use std::collections::{BTreeMap, HashMap};

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// The largest number of membrane elements a blank may be meshed into.
pub const MAX_ELEMENTS: usize = 4_000_000;

/// Tolerance on θ (degrees) for recognising a fibre-aligned orientation.
const ANGLE_TOL_DEG: f64 = 1e-9;

/// Relative tolerance (to the blank's larger extent) for geometric tests:
/// node sets, the diamond lattice's square cells.
const REL_TOL: f64 = 1e-9;

/// The membrane element family of a blank.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ElementKind {
    /// 4-node quads (boundary half-cells of a 45° truss mesh are triangles).
    Quad,
    /// 3-node triangles.
    Triangle,
}

/// How the yarns are represented (SPEC §2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FibreRepresentation {
    /// Trusses along the yarn-aligned mesh edges (needs θ = 0, 90 or 45).
    Trusses,
    /// Fibre stress added at each membrane integration point (any θ).
    Embedded,
}

/// How finely to mesh.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Meshing {
    /// Cells along x and y.
    Cells([usize; 2]),
    /// Target element size (mm): the length of an element's edge, which
    /// in a diamond lattice (a 45° truss mesh) is its cell diagonal over √2.
    Size(f64),
}

/// A rectangular blank in a plane z = const, centred at `center`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RectangleBlank {
    /// Extent along x (mm).
    pub width: f64,
    /// Extent along y (mm).
    pub height: f64,
    /// Centre of the blank.
    pub center: Vector3<f64>,
    /// θ, warp angle from x in degrees (weft at θ + 90).
    pub orientation_deg: f64,
    /// Quads or triangles.
    pub element: ElementKind,
    /// Mesh density.
    pub meshing: Meshing,
    /// Trusses or embedded fibres.
    pub fibres: FibreRepresentation,
}

/// One fibre truss of a blank mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrussSpec {
    /// Its two nodes.
    pub nodes: [u32; 2],
    /// 0 = warp, 1 = weft.
    pub family: u8,
    /// The fabric area whose yarns of this family the truss carries.
    pub strip_area: f64,
}

/// The reference frame of a rectangular blank, for derived measures.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlankFrame {
    /// Centre.
    pub center: Vector3<f64>,
    /// Extent along x.
    pub width: f64,
    /// Extent along y.
    pub height: f64,
}

/// A meshed blank.
#[derive(Debug, Clone, Default)]
pub struct BlankMesh {
    /// Reference node positions.
    pub x0: Vec<Vector3<f64>>,
    /// Quads (counter-clockwise seen from +z).
    pub quads: Vec<[u32; 4]>,
    /// Triangles (counter-clockwise seen from +z).
    pub triangles: Vec<[u32; 3]>,
    /// The warp direction (unit, in the blank plane), the same for every element.
    pub warp: Vector3<f64>,
    /// Fibre trusses (empty for embedded fibres).
    pub trusses: Vec<TrussSpec>,
    /// Named node sets.
    pub node_sets: BTreeMap<String, Vec<u32>>,
}

/// A blank that cannot be meshed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MeshError {
    /// A dimension or count is not positive and finite.
    #[error("blank field `{field}` = {value}: {expected}")]
    Invalid {
        /// The field.
        field: &'static str,
        /// Its value.
        value: f64,
        /// What is allowed.
        expected: &'static str,
    },
}

impl RectangleBlank {
    /// The blank's frame.
    pub fn frame(&self) -> BlankFrame {
        BlankFrame {
            center: self.center,
            width: self.width,
            height: self.height,
        }
    }

    /// Meshes the blank.
    pub fn mesh(&self) -> Result<BlankMesh, MeshError> {
        self.validate()?;
        let layout = self.layout()?;
        let mut mesh = match layout {
            Layout::Grid {
                nx,
                ny,
                x_edge_family,
            } => self.grid_mesh(nx, ny, x_edge_family),
            Layout::Diamond { nx, ny } => self.diamond_mesh(nx, ny),
        };
        if !mesh.trusses.is_empty() {
            assign_strip_areas(&mut mesh);
        }
        mesh.node_sets = self.node_sets(&mesh.x0);
        Ok(mesh)
    }

    fn validate(&self) -> Result<(), MeshError> {
        let length = "a positive finite length (mm)";
        positive_finite("width", self.width, length)?;
        positive_finite("height", self.height, length)?;
        for c in self.center.iter() {
            if !c.is_finite() {
                return Err(invalid("center", *c, "finite coordinates (mm)"));
            }
        }
        if !self.orientation_deg.is_finite() {
            return Err(invalid(
                "orientation_deg",
                self.orientation_deg,
                "a finite angle in degrees",
            ));
        }
        match self.meshing {
            Meshing::Cells([nx, ny]) => {
                if nx == 0 || ny == 0 {
                    return Err(invalid(
                        "meshing",
                        nx.min(ny) as f64,
                        "at least 1 cell along x and along y",
                    ));
                }
            }
            Meshing::Size(h) => {
                positive_finite("meshing", h, "a positive finite element size (mm)")?;
            }
        }
        Ok(())
    }

    /// Chooses the lattice and its cell counts, refusing unsupported
    /// orientations and oversized meshes.
    fn layout(&self) -> Result<Layout, MeshError> {
        let layout = match self.fibres {
            FibreRepresentation::Embedded => {
                let (nx, ny) = self.grid_cells();
                Layout::Grid {
                    nx,
                    ny,
                    x_edge_family: None,
                }
            }
            FibreRepresentation::Trusses => match snapped_octant(self.orientation_deg) {
                Some(k) if k % 2 == 0 => {
                    let (nx, ny) = self.grid_cells();
                    // The warp runs along x for θ = 0/180, along y for 90/270.
                    let x_edge_family = if k % 4 == 0 { 0 } else { 1 };
                    Layout::Grid {
                        nx,
                        ny,
                        x_edge_family: Some(x_edge_family),
                    }
                }
                Some(_) => {
                    let (nx, ny) = self.diamond_cells()?;
                    Layout::Diamond { nx, ny }
                }
                None => {
                    return Err(invalid(
                        "orientation_deg",
                        self.orientation_deg,
                        "0, 90 or 45 for trusses (a fibre-aligned mesh); use embedded fibres for other orientations",
                    ));
                }
            },
        };
        let elements = layout.element_count(self.element);
        if elements > MAX_ELEMENTS as f64 {
            return Err(invalid(
                "meshing",
                elements,
                "at most 4 million elements (the value is the requested count)",
            ));
        }
        Ok(layout)
    }

    /// Grid cell counts as `f64`-checked integers: a huge count is caught by
    /// [`Layout::element_count`] before anything is allocated.
    fn grid_cells(&self) -> (usize, usize) {
        match self.meshing {
            Meshing::Cells([nx, ny]) => (nx, ny),
            Meshing::Size(h) => (cells_for(self.width, h), cells_for(self.height, h)),
        }
    }

    fn diamond_cells(&self) -> Result<(usize, usize), MeshError> {
        match self.meshing {
            Meshing::Cells([nx, ny]) => {
                let ratio = (self.width / nx as f64) / (self.height / ny as f64);
                if (ratio - 1.0).abs() > REL_TOL {
                    return Err(invalid(
                        "meshing",
                        ratio,
                        "a 45° truss mesh needs square cells: the blank's aspect ratio width:height must be nx:ny \
                         (the value is (width/nx)/(height/ny))",
                    ));
                }
                Ok((nx, ny))
            }
            Meshing::Size(h) => {
                // The lattice's edge is its cell's side, d/√2.
                let nx = cells_for(self.width, h * std::f64::consts::SQRT_2);
                let d = self.width / nx as f64;
                let ny = (self.height / d).round();
                if ny < 1.0 || (ny * d - self.height).abs() > REL_TOL * self.height {
                    return Err(invalid(
                        "height",
                        self.height,
                        "a 45° truss mesh needs square cells: the height must be a whole multiple of the cell \
                         diagonal width/round(width/(size·√2)) (size is the elements' edge, the cell's side)",
                    ));
                }
                // Saturating conversion; an absurd count is refused later.
                Ok((nx, ny as usize))
            }
        }
    }

    fn corner_min(&self) -> (f64, f64) {
        (
            self.center.x - 0.5 * self.width,
            self.center.y - 0.5 * self.height,
        )
    }

    fn grid_mesh(&self, nx: usize, ny: usize, x_edge_family: Option<u8>) -> BlankMesh {
        let (x_min, y_min) = self.corner_min();
        let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
        let mut x0 = Vec::with_capacity((nx + 1) * (ny + 1));
        for j in 0..=ny {
            for i in 0..=nx {
                // Fractions of the extent rather than repeated steps, so the
                // far edges land on the blank's edges up to one rounding.
                x0.push(Vector3::new(
                    x_min + self.width * (i as f64 / nx as f64),
                    y_min + self.height * (j as f64 / ny as f64),
                    self.center.z,
                ));
            }
        }
        let mut quads = Vec::new();
        let mut triangles = Vec::new();
        for j in 0..ny {
            for i in 0..nx {
                let (a, b, c, d) = (id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1));
                match self.element {
                    ElementKind::Quad => quads.push([a, b, c, d]),
                    ElementKind::Triangle if (i + j) % 2 == 0 => {
                        triangles.push([a, b, c]);
                        triangles.push([a, c, d]);
                    }
                    ElementKind::Triangle => {
                        triangles.push([a, b, d]);
                        triangles.push([b, c, d]);
                    }
                }
            }
        }
        let mut trusses = Vec::new();
        if let Some(fx) = x_edge_family {
            let truss = |nodes, family| TrussSpec {
                nodes,
                family,
                strip_area: 0.0,
            };
            for j in 0..=ny {
                for i in 0..nx {
                    trusses.push(truss([id(i, j), id(i + 1, j)], fx));
                }
            }
            for j in 0..ny {
                for i in 0..=nx {
                    trusses.push(truss([id(i, j), id(i, j + 1)], 1 - fx));
                }
            }
        }
        BlankMesh {
            x0,
            quads,
            triangles,
            warp: self.warp(),
            trusses,
            node_sets: BTreeMap::new(),
        }
    }

    fn diamond_mesh(&self, nx: usize, ny: usize) -> BlankMesh {
        let (x_min, y_min) = self.corner_min();
        let (ni, nj) = (2 * nx, 2 * ny);
        // Lattice (i, j) → node id; only i + j even are nodes.
        let mut ids = vec![u32::MAX; (ni + 1) * (nj + 1)];
        let slot = |i: usize, j: usize| j * (ni + 1) + i;
        let mut x0 = Vec::with_capacity((nx + 1) * (ny + 1) + nx * ny);
        for j in 0..=nj {
            for i in (j % 2..=ni).step_by(2) {
                ids[slot(i, j)] = x0.len() as u32;
                x0.push(Vector3::new(
                    x_min + self.width * (i as f64 / ni as f64),
                    y_min + self.height * (j as f64 / nj as f64),
                    self.center.z,
                ));
            }
        }
        let node = |i: isize, j: isize| -> Option<u32> {
            if i < 0 || j < 0 || i as usize > ni || j as usize > nj {
                None
            } else {
                Some(ids[slot(i as usize, j as usize)])
            }
        };
        let mut quads = Vec::new();
        let mut triangles = Vec::new();
        for j in 0..=nj {
            for i in ((j + 1) % 2..=ni).step_by(2) {
                let (ci, cj) = (i as isize, j as isize);
                // Counter-clockwise: bottom, right, top, left. Dropping the
                // vertex the boundary cuts off keeps the order counter-clockwise.
                let [b, r, t, l] = [
                    node(ci, cj - 1),
                    node(ci + 1, cj),
                    node(ci, cj + 1),
                    node(ci - 1, cj),
                ];
                match (b, r, t, l) {
                    (Some(b), Some(r), Some(t), Some(l)) => match self.element {
                        ElementKind::Quad => quads.push([b, r, t, l]),
                        ElementKind::Triangle if i % 2 == 0 => {
                            triangles.push([b, r, t]);
                            triangles.push([b, t, l]);
                        }
                        ElementKind::Triangle => {
                            triangles.push([l, b, r]);
                            triangles.push([l, r, t]);
                        }
                    },
                    _ => {
                        let half: Vec<u32> = [b, r, t, l].into_iter().flatten().collect();
                        // A lattice centre is never a corner (corners have
                        // i + j even), so a cut cell always keeps 3 vertices.
                        debug_assert_eq!(half.len(), 3);
                        triangles.push([half[0], half[1], half[2]]);
                    }
                }
            }
        }
        let warp = self.warp();
        // The lattice steps (±d/2, d/2) point along the ±45° yarns; which of
        // them is the warp depends on θ (45 vs −45/135).
        let up_is_warp = warp.x * warp.y > 0.0;
        let mut trusses = Vec::with_capacity(4 * nx * ny);
        for j in 0..=nj {
            for i in (j % 2..ni).step_by(2) {
                let (ci, cj) = (i as isize, j as isize);
                let a = ids[slot(i, j)];
                for (dj, is_up) in [(1, true), (-1, false)] {
                    if let Some(b) = node(ci + 1, cj + dj) {
                        trusses.push(TrussSpec {
                            nodes: [a, b],
                            family: if is_up == up_is_warp { 0 } else { 1 },
                            strip_area: 0.0,
                        });
                    }
                }
            }
        }
        BlankMesh {
            x0,
            quads,
            triangles,
            warp,
            trusses,
            node_sets: BTreeMap::new(),
        }
    }

    /// The warp direction; exact for multiples of 45° (within the angle
    /// tolerance), so fibre-aligned lattices and fibres agree to the last bit.
    fn warp(&self) -> Vector3<f64> {
        match snapped_octant(self.orientation_deg) {
            Some(k) => {
                let s = std::f64::consts::FRAC_1_SQRT_2;
                let (c, sn) = [
                    (1.0, 0.0),
                    (s, s),
                    (0.0, 1.0),
                    (-s, s),
                    (-1.0, 0.0),
                    (-s, -s),
                    (0.0, -1.0),
                    (s, -s),
                ][k];
                Vector3::new(c, sn, 0.0)
            }
            None => {
                let t = self.orientation_deg.to_radians();
                Vector3::new(t.cos(), t.sin(), 0.0)
            }
        }
    }

    fn node_sets(&self, x0: &[Vector3<f64>]) -> BTreeMap<String, Vec<u32>> {
        let tol = REL_TOL * self.width.max(self.height);
        let (x_min, y_min) = self.corner_min();
        let (x_max, y_max) = (x_min + self.width, y_min + self.height);
        let (cx, cy) = (self.center.x, self.center.y);
        let ids = || (0..x0.len() as u32).map(|n| (n, &x0[n as usize]));
        let select = |f: &dyn Fn(&Vector3<f64>) -> bool| -> Vec<u32> {
            ids().filter(|(_, p)| f(p)).map(|(n, _)| n).collect()
        };
        let on_left = |p: &Vector3<f64>| (p.x - x_min).abs() <= tol;
        let on_right = |p: &Vector3<f64>| (p.x - x_max).abs() <= tol;
        let on_bottom = |p: &Vector3<f64>| (p.y - y_min).abs() <= tol;
        let on_top = |p: &Vector3<f64>| (p.y - y_max).abs() <= tol;

        let left = select(&on_left);
        let right = select(&on_right);
        let bottom = select(&on_bottom);
        let top = select(&on_top);
        let boundary =
            select(&|p: &Vector3<f64>| on_left(p) || on_right(p) || on_bottom(p) || on_top(p));

        let corners = [
            (x_min, y_min),
            (x_max, y_min),
            (x_max, y_max),
            (x_min, y_max),
        ]
        .map(|(x, y)| nearest(x0, 0..x0.len() as u32, x, y, tol));
        let edge_midpoints = [
            (&left, x_min, cy),
            (&right, x_max, cy),
            (&bottom, cx, y_min),
            (&top, cx, y_max),
        ]
        .map(|(set, x, y)| nearest(x0, set.iter().copied(), x, y, tol));

        // The diagonal from the bottom-left to the top-right corner.
        let length = self.width.hypot(self.height);
        let (ux, uy) = (self.width / length, self.height / length);
        let along = |p: &Vector3<f64>| (p.x - x_min) * ux + (p.y - y_min) * uy;
        let across = |p: &Vector3<f64>| ((p.x - x_min) * uy - (p.y - y_min) * ux).abs();
        let mut diagonal = select(&|p: &Vector3<f64>| {
            let s = along(p);
            across(p) <= tol && s >= -tol && s <= length + tol
        });
        sort_by_key(&mut diagonal, x0, |p| along(p));
        let mut median_x = select(&|p: &Vector3<f64>| (p.y - cy).abs() <= tol);
        sort_by_key(&mut median_x, x0, |p| p.x);
        let mut median_y = select(&|p: &Vector3<f64>| (p.x - cx).abs() <= tol);
        sort_by_key(&mut median_y, x0, |p| p.y);

        let mut sets = BTreeMap::new();
        sets.insert("all".to_string(), (0..x0.len() as u32).collect());
        sets.insert("left".to_string(), left);
        sets.insert("right".to_string(), right);
        sets.insert("bottom".to_string(), bottom);
        sets.insert("top".to_string(), top);
        sets.insert("boundary".to_string(), boundary);
        sets.insert("corners".to_string(), corners.to_vec());
        sets.insert("edge_midpoints".to_string(), edge_midpoints.to_vec());
        sets.insert("diagonal".to_string(), diagonal);
        sets.insert("median_x".to_string(), median_x);
        sets.insert("median_y".to_string(), median_y);
        sets
    }
}

/// The lattice chosen for a blank, with its cell counts.
#[derive(Debug, Clone, Copy)]
enum Layout {
    /// Structured grid; `x_edge_family` is the truss family of the edges
    /// along x, or `None` without trusses.
    Grid {
        nx: usize,
        ny: usize,
        x_edge_family: Option<u8>,
    },
    /// The 45° diamond lattice, `nx`, `ny` cell diagonals along x and y.
    Diamond { nx: usize, ny: usize },
}

impl Layout {
    /// The number of membrane elements, in `f64` so that absurd requests
    /// are measured without overflow.
    fn element_count(&self, kind: ElementKind) -> f64 {
        let per_cell = match kind {
            ElementKind::Quad => 1.0,
            ElementKind::Triangle => 2.0,
        };
        match *self {
            Layout::Grid { nx, ny, .. } => per_cell * nx as f64 * ny as f64,
            Layout::Diamond { nx, ny } => {
                let (nx, ny) = (nx as f64, ny as f64);
                // 2·nx·ny − nx − ny full diamonds, 2·(nx + ny) half-cells.
                per_cell * (2.0 * nx * ny - nx - ny) + 2.0 * (nx + ny)
            }
        }
    }
}

fn invalid(field: &'static str, value: f64, expected: &'static str) -> MeshError {
    MeshError::Invalid {
        field,
        value,
        expected,
    }
}

fn positive_finite(
    field: &'static str,
    value: f64,
    expected: &'static str,
) -> Result<(), MeshError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(invalid(field, value, expected))
    }
}

/// Cells along an extent for a target size: `round(extent/h)`, at least 1.
/// The float-to-int cast saturates, so a huge ratio becomes a huge count
/// that the element limit refuses.
fn cells_for(extent: f64, h: f64) -> usize {
    ((extent / h).round() as usize).max(1)
}

/// `Some(k)` when θ is a multiple k·45° (mod 360) within the tolerance.
fn snapped_octant(theta_deg: f64) -> Option<usize> {
    let q = theta_deg / 45.0;
    let k = q.round();
    if ((q - k) * 45.0).abs() <= ANGLE_TOL_DEG {
        Some(k.rem_euclid(8.0) as usize)
    } else {
        None
    }
}

/// The node among `candidates` nearest to (x, y) in the plane. Distances
/// within `tol` count as ties, won by the first candidate, so that rounding
/// does not pick between symmetric nodes at random. Meshes are never empty,
/// and every node set handed in here is non-empty (each blank edge holds at
/// least its two corners).
fn nearest(
    x0: &[Vector3<f64>],
    candidates: impl IntoIterator<Item = u32>,
    x: f64,
    y: f64,
    tol: f64,
) -> u32 {
    let mut best: Option<(u32, f64)> = None;
    for n in candidates {
        let p = &x0[n as usize];
        let d = (p.x - x).hypot(p.y - y);
        if best.is_none_or(|(_, bd)| d < bd - tol) {
            best = Some((n, d));
        }
    }
    best.map(|(n, _)| n).unwrap_or(0)
}

/// Sorts node ids by a coordinate, ties by id.
fn sort_by_key(set: &mut [u32], x0: &[Vector3<f64>], key: impl Fn(&Vector3<f64>) -> f64) {
    set.sort_by(|&a, &b| {
        key(&x0[a as usize])
            .total_cmp(&key(&x0[b as usize]))
            .then(a.cmp(&b))
    });
}

/// Signed in-plane (x, y) area of a polygon, positive when counter-clockwise.
fn polygon_area(x0: &[Vector3<f64>], nodes: &[u32]) -> f64 {
    let n = nodes.len();
    let mut twice = 0.0;
    for k in 0..n {
        let p = &x0[nodes[k] as usize];
        let q = &x0[nodes[(k + 1) % n] as usize];
        twice += p.x * q.y - q.x * p.y;
    }
    0.5 * twice
}

/// Shares each element's area, per family, equally over its edges that carry
/// a truss of that family (see the module docs).
fn assign_strip_areas(mesh: &mut BlankMesh) {
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let by_edge: HashMap<(u32, u32), usize> = mesh
        .trusses
        .iter()
        .enumerate()
        .map(|(t, s)| (key(s.nodes[0], s.nodes[1]), t))
        .collect();
    let elements = mesh
        .quads
        .iter()
        .map(|q| &q[..])
        .chain(mesh.triangles.iter().map(|t| &t[..]));
    let mut strip = vec![0.0; mesh.trusses.len()];
    for nodes in elements {
        let area = polygon_area(&mesh.x0, nodes);
        let n = nodes.len();
        let edges: Vec<usize> = (0..n)
            .filter_map(|k| by_edge.get(&key(nodes[k], nodes[(k + 1) % n])).copied())
            .collect();
        for family in 0..2u8 {
            let mine: Vec<usize> = edges
                .iter()
                .copied()
                .filter(|&t| mesh.trusses[t].family == family)
                .collect();
            // Every element of both lattices has a truss of each family;
            // otherwise its yarns would be lost from the totals.
            debug_assert!(!mine.is_empty(), "element without a family-{family} truss");
            let share = area / mine.len() as f64;
            for t in mine {
                strip[t] += share;
            }
        }
    }
    for (truss, a) in mesh.trusses.iter_mut().zip(strip) {
        truss.strip_area = a;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blank(
        width: f64,
        height: f64,
        theta: f64,
        element: ElementKind,
        meshing: Meshing,
        fibres: FibreRepresentation,
    ) -> RectangleBlank {
        RectangleBlank {
            width,
            height,
            center: Vector3::new(3.0, -2.0, 5.0),
            orientation_deg: theta,
            element,
            meshing,
            fibres,
        }
    }

    fn trusses(w: f64, h: f64, theta: f64, el: ElementKind, cells: [usize; 2]) -> RectangleBlank {
        blank(
            w,
            h,
            theta,
            el,
            Meshing::Cells(cells),
            FibreRepresentation::Trusses,
        )
    }

    fn set<'a>(m: &'a BlankMesh, name: &str) -> &'a [u32] {
        &m.node_sets[name]
    }

    fn elements(m: &BlankMesh) -> Vec<Vec<u32>> {
        m.quads
            .iter()
            .map(|q| q.to_vec())
            .chain(m.triangles.iter().map(|t| t.to_vec()))
            .collect()
    }

    fn edge_key(a: u32, b: u32) -> (u32, u32) {
        (a.min(b), a.max(b))
    }

    /// Invariants every mesh must satisfy.
    fn check(b: &RectangleBlank) -> BlankMesh {
        let m = b.mesh().unwrap();
        let area = b.width * b.height;
        let n = m.x0.len() as u32;
        assert!((m.warp.norm() - 1.0).abs() < 1e-15 && m.warp.z == 0.0);
        for p in &m.x0 {
            assert_eq!(p.z, b.center.z);
        }
        // Counter-clockwise, positive areas that tile the blank.
        let mut total = 0.0;
        let mut used = vec![false; n as usize];
        let mut edges = std::collections::HashSet::new();
        for e in elements(&m) {
            let a = polygon_area(&m.x0, &e);
            assert!(a > 0.0, "element {e:?} is not counter-clockwise");
            total += a;
            for k in 0..e.len() {
                assert!(e[k] < n);
                used[e[k] as usize] = true;
                edges.insert(edge_key(e[k], e[(k + 1) % e.len()]));
            }
        }
        assert!((total - area).abs() <= 1e-12 * area, "{total} vs {area}");
        assert!(used.iter().all(|&u| u), "a node belongs to no element");
        // Trusses: on element edges, unique, along a yarn, strip areas sum up.
        let weft = Vector3::new(-m.warp.y, m.warp.x, 0.0);
        let mut seen = std::collections::HashSet::new();
        let mut strip = [0.0; 2];
        for t in &m.trusses {
            let k = edge_key(t.nodes[0], t.nodes[1]);
            assert!(edges.contains(&k), "truss {t:?} is no element edge");
            assert!(seen.insert(k), "duplicate truss {t:?}");
            let d = (m.x0[t.nodes[1] as usize] - m.x0[t.nodes[0] as usize]).normalize();
            let fibre = if t.family == 0 { m.warp } else { weft };
            assert!(
                d.cross(&fibre).norm() < 1e-12,
                "truss {t:?} is not along its family"
            );
            assert!(t.strip_area > 0.0);
            strip[t.family as usize] += t.strip_area;
        }
        if !m.trusses.is_empty() {
            for s in strip {
                assert!((s - area).abs() <= 1e-12 * area, "strip {s} vs {area}");
            }
        }
        // Node sets are within range and (except the ordered ones) ascending.
        assert_eq!(set(&m, "all").len(), m.x0.len());
        for (name, ids) in &m.node_sets {
            assert!(ids.iter().all(|&i| i < n));
            if ![
                "corners",
                "edge_midpoints",
                "diagonal",
                "median_x",
                "median_y",
            ]
            .contains(&name.as_str())
            {
                assert!(ids.windows(2).all(|w| w[0] < w[1]), "{name} not sorted");
            }
        }
        assert_eq!(set(&m, "corners").len(), 4);
        assert_eq!(set(&m, "edge_midpoints").len(), 4);
        let (x_min, y_min) = b.corner_min();
        let corners = [
            (x_min, y_min),
            (x_min + b.width, y_min),
            (x_min + b.width, y_min + b.height),
            (x_min, y_min + b.height),
        ];
        for (&c, (x, y)) in set(&m, "corners").iter().zip(corners) {
            let p = m.x0[c as usize];
            assert!((p.x - x).abs() < 1e-9 && (p.y - y).abs() < 1e-9);
        }
        m
    }

    #[test]
    fn grid_quads_theta0_counts_and_families() {
        let m = check(&trusses(40.0, 30.0, 0.0, ElementKind::Quad, [4, 3]));
        assert_eq!((m.x0.len(), m.quads.len(), m.triangles.len()), (20, 12, 0));
        assert_eq!(m.trusses.len(), 31);
        assert_eq!(m.warp, Vector3::new(1.0, 0.0, 0.0));
        for t in &m.trusses {
            let d = m.x0[t.nodes[1] as usize] - m.x0[t.nodes[0] as usize];
            let along_x = d.y.abs() < 1e-12;
            assert_eq!(t.family, if along_x { 0 } else { 1 });
        }
        assert_eq!(m.trusses.iter().filter(|t| t.family == 0).count(), 16);
        // Interior trusses carry a cell area, boundary ones half of it.
        let cell = 10.0 * 10.0;
        let mut on_boundary = 0;
        for t in &m.trusses {
            let edge = ["left", "right", "bottom", "top"]
                .iter()
                .any(|e| t.nodes.iter().all(|n| set(&m, e).contains(n)));
            on_boundary += usize::from(edge);
            let expect = if edge { cell / 2.0 } else { cell };
            assert!((t.strip_area - expect).abs() < 1e-9, "{t:?}");
        }
        assert_eq!(on_boundary, 2 * (4 + 3));
    }

    #[test]
    fn grid_theta90_swaps_families() {
        let m = check(&trusses(40.0, 30.0, 90.0, ElementKind::Quad, [4, 3]));
        assert_eq!(m.warp, Vector3::new(0.0, 1.0, 0.0));
        for t in &m.trusses {
            let d = m.x0[t.nodes[1] as usize] - m.x0[t.nodes[0] as usize];
            assert_eq!(t.family, if d.y.abs() < 1e-12 { 1 } else { 0 });
        }
        // 180 and −90 are the same fibre-aligned meshes.
        for theta in [180.0, -90.0, 270.0 + 1e-10] {
            check(&trusses(40.0, 30.0, theta, ElementKind::Triangle, [4, 3]));
        }
    }

    #[test]
    fn grid_triangles_checkerboard_without_diagonal_trusses() {
        let m = check(&trusses(40.0, 30.0, 0.0, ElementKind::Triangle, [4, 3]));
        assert_eq!((m.x0.len(), m.quads.len(), m.triangles.len()), (20, 0, 24));
        assert_eq!(m.trusses.len(), 31);
        // Cell (0, 0) is cut from node 0 to node 6, cell (1, 0) from 2 to 6.
        let has_edge = |a: u32, b: u32| {
            m.triangles
                .iter()
                .any(|t| (0..3).any(|k| edge_key(t[k], t[(k + 1) % 3]) == edge_key(a, b)))
        };
        assert!(has_edge(0, 6) && !has_edge(1, 5));
        assert!(has_edge(2, 6) && !has_edge(1, 7));
        // Same strip areas as quads: the split moves no yarn.
        let q = trusses(40.0, 30.0, 0.0, ElementKind::Quad, [4, 3])
            .mesh()
            .unwrap();
        for (a, b) in m.trusses.iter().zip(&q.trusses) {
            assert_eq!(a.nodes, b.nodes);
            assert!((a.strip_area - b.strip_area).abs() < 1e-9);
        }
    }

    #[test]
    fn diamond_2x2_counted_by_hand() {
        // Lattice 0..=4 × 0..=4 with i + j even: 13 nodes. Centres with i + j
        // odd: 4 interior diamonds, 2 half-cells on each of the 4 edges.
        // Sides: 4·4 + 8·2 = 32 incidences, each side shared by 2 cells.
        let b = trusses(100.0, 100.0, 45.0, ElementKind::Quad, [2, 2]);
        let m = check(&b);
        assert_eq!((m.x0.len(), m.quads.len(), m.triangles.len()), (13, 4, 8));
        assert_eq!(m.trusses.len(), 16);
        let s = std::f64::consts::FRAC_1_SQRT_2;
        assert_eq!(m.warp, Vector3::new(s, s, 0.0));
        // Every truss carries d²/2 (spacing d/√2 × length d/√2), d = 50.
        for t in &m.trusses {
            assert!((t.strip_area - 1250.0).abs() < 1e-9, "{t:?}");
            let d = m.x0[t.nodes[1] as usize] - m.x0[t.nodes[0] as usize];
            assert_eq!(t.family, if d.x * d.y > 0.0 { 0 } else { 1 });
        }
        // Half-cells have their long side on the blank edge.
        let boundary = set(&m, "boundary");
        for t in &m.triangles {
            assert_eq!(t.iter().filter(|n| boundary.contains(n)).count(), 2);
        }
        let tri = check(&trusses(100.0, 100.0, 45.0, ElementKind::Triangle, [2, 2]));
        assert_eq!(
            (tri.x0.len(), tri.quads.len(), tri.triangles.len()),
            (13, 0, 16)
        );
        assert_eq!(tri.trusses.len(), 16);
        for t in &tri.trusses {
            assert!((t.strip_area - 1250.0).abs() < 1e-9, "{t:?}");
        }
    }

    #[test]
    fn diamond_counts_follow_the_formula() {
        for (w, h, nx, ny) in [
            (50.0, 50.0, 1, 1),
            (300.0, 200.0, 3, 2),
            (70.0, 350.0, 1, 5),
        ] {
            for el in [ElementKind::Quad, ElementKind::Triangle] {
                let m = check(&trusses(w, h, 45.0, el, [nx, ny]));
                let full = 2 * nx * ny - nx - ny;
                let half = 2 * (nx + ny);
                assert_eq!(m.x0.len(), (nx + 1) * (ny + 1) + nx * ny);
                assert_eq!(m.trusses.len(), 4 * nx * ny);
                match el {
                    ElementKind::Quad => {
                        assert_eq!((m.quads.len(), m.triangles.len()), (full, half))
                    }
                    ElementKind::Triangle => assert_eq!(m.triangles.len(), 2 * full + half),
                }
            }
        }
    }

    #[test]
    fn diamond_minus45_makes_the_other_diagonal_warp() {
        for theta in [-45.0, 135.0, 315.0, 225.0] {
            let m = check(&trusses(100.0, 100.0, theta, ElementKind::Quad, [2, 2]));
            assert!(m.warp.x * m.warp.y < 0.0 || theta == 225.0);
            for t in &m.trusses {
                let d = m.x0[t.nodes[1] as usize] - m.x0[t.nodes[0] as usize];
                let along_warp = d.normalize().cross(&m.warp).norm() < 1e-12;
                assert_eq!(t.family == 0, along_warp);
            }
        }
    }

    #[test]
    fn embedded_any_angle_has_no_trusses() {
        for theta in [0.0, 30.0, 45.0, -17.5] {
            for el in [ElementKind::Quad, ElementKind::Triangle] {
                let b = blank(
                    40.0,
                    30.0,
                    theta,
                    el,
                    Meshing::Cells([4, 3]),
                    FibreRepresentation::Embedded,
                );
                let m = check(&b);
                assert!(m.trusses.is_empty());
                assert_eq!(m.x0.len(), 20);
                assert_eq!(m.quads.len() + m.triangles.len() / 2, 12);
                let t = theta.to_radians();
                assert!((m.warp - Vector3::new(t.cos(), t.sin(), 0.0)).norm() < 1e-15);
            }
        }
    }

    #[test]
    fn size_meshing_rounds_cells() {
        let b = blank(
            100.0,
            50.0,
            0.0,
            ElementKind::Quad,
            Meshing::Size(9.0),
            FibreRepresentation::Trusses,
        );
        let m = check(&b);
        assert_eq!(m.quads.len(), 11 * 6);
        // A size larger than the blank still gives one cell.
        let b = blank(
            10.0,
            5.0,
            0.0,
            ElementKind::Quad,
            Meshing::Size(100.0),
            FibreRepresentation::Embedded,
        );
        assert_eq!(check(&b).quads.len(), 1);
        // Diamond: an edge of 17 is a diagonal of 24.04, so
        // d = 100/4 = 25, height 50 = 2 diagonals.
        let b = blank(
            100.0,
            50.0,
            45.0,
            ElementKind::Quad,
            Meshing::Size(17.0),
            FibreRepresentation::Trusses,
        );
        let m = check(&b);
        assert_eq!(m.x0.len(), 5 * 3 + 4 * 2);
    }

    /// One `element_size` gives the plies of a quasi-isotropic stack one
    /// yarn segment length: the 0/90 grids' cell side and the ±45 diamond
    /// lattices' (their cell diagonal over √2), each rounded to a whole
    /// number of cells.
    #[test]
    fn plies_of_any_orientation_meshed_at_one_size_have_one_segment_length() {
        for theta in [0.0, 45.0, 90.0, -45.0] {
            let b = blank(
                350.0,
                350.0,
                theta,
                ElementKind::Quad,
                Meshing::Size(14.6),
                FibreRepresentation::Trusses,
            );
            let m = check(&b);
            let (lo, hi) = m.trusses.iter().fold((f64::MAX, 0.0f64), |(lo, hi), t| {
                let l = (m.x0[t.nodes[1] as usize] - m.x0[t.nodes[0] as usize]).norm();
                (lo.min(l), hi.max(l))
            });
            // 0/90: 24 cells of 14.583 mm; ±45: 17 diagonals of
            // 20.588 mm, an edge of 14.558 mm.
            let expected = if theta == 0.0 || theta == 90.0 {
                350.0 / 24.0
            } else {
                350.0 / 17.0 / std::f64::consts::SQRT_2
            };
            assert!(
                (lo - expected).abs() < 1e-12 && (hi - expected).abs() < 1e-12,
                "θ = {theta}: segments {lo}..{hi} mm, expected {expected}"
            );
        }
    }

    #[test]
    fn node_sets_of_a_grid() {
        let m = check(&trusses(40.0, 30.0, 0.0, ElementKind::Quad, [4, 3]));
        assert_eq!(set(&m, "left"), [0, 5, 10, 15]);
        assert_eq!(set(&m, "right"), [4, 9, 14, 19]);
        assert_eq!(set(&m, "bottom"), [0, 1, 2, 3, 4]);
        assert_eq!(set(&m, "top"), [15, 16, 17, 18, 19]);
        assert_eq!(
            set(&m, "boundary"),
            [0, 1, 2, 3, 4, 5, 9, 10, 14, 15, 16, 17, 18, 19]
        );
        assert_eq!(set(&m, "corners"), [0, 4, 19, 15]);
        // ny = 3: the left/right midpoints are a tie, won by the lower node.
        assert_eq!(set(&m, "edge_midpoints"), [5, 9, 2, 17]);
        // 4×3 cells of 10×10: only the corners lie on the diagonal.
        assert_eq!(set(&m, "diagonal"), [0, 19]);
        assert!(set(&m, "median_x").is_empty());
        assert_eq!(set(&m, "median_y"), [2, 7, 12, 17]);

        let m = check(&trusses(40.0, 40.0, 0.0, ElementKind::Triangle, [4, 4]));
        assert_eq!(set(&m, "diagonal"), [0, 6, 12, 18, 24]);
        assert_eq!(set(&m, "median_x"), [10, 11, 12, 13, 14]);
        assert_eq!(set(&m, "median_y"), [2, 7, 12, 17, 22]);
        assert_eq!(set(&m, "edge_midpoints"), [10, 14, 2, 22]);
        assert_eq!(set(&m, "corners"), [0, 4, 24, 20]);
    }

    #[test]
    fn node_sets_of_a_diamond_lattice() {
        // Rows j = 0..=4 hold 3, 2, 3, 2, 3 nodes: ids 0-2, 3-4, 5-7, 8-9, 10-12.
        let m = check(&trusses(100.0, 100.0, 45.0, ElementKind::Quad, [2, 2]));
        assert_eq!(set(&m, "corners"), [0, 2, 12, 10]);
        assert_eq!(set(&m, "left"), [0, 5, 10]);
        assert_eq!(set(&m, "right"), [2, 7, 12]);
        assert_eq!(set(&m, "bottom"), [0, 1, 2]);
        assert_eq!(set(&m, "top"), [10, 11, 12]);
        assert_eq!(set(&m, "edge_midpoints"), [5, 7, 1, 11]);
        assert_eq!(set(&m, "diagonal"), [0, 3, 6, 9, 12]);
        assert_eq!(set(&m, "median_x"), [5, 6, 7]);
        assert_eq!(set(&m, "median_y"), [1, 6, 11]);
        // nx = 3, ny = 1 (300 × 100, d = 100). Row 0: i = 0, 2, 4, 6 → ids
        // 0-3; row 1: i = 1, 3, 5 → 4-6; row 2: ids 7-10. No edge midpoint is
        // a node (odd counts): the nearest edge node wins, ties to the lower id.
        let m = check(&trusses(300.0, 100.0, 45.0, ElementKind::Quad, [3, 1]));
        assert_eq!(set(&m, "bottom"), [0, 1, 2, 3]);
        assert_eq!(set(&m, "left"), [0, 7]);
        assert_eq!(set(&m, "edge_midpoints"), [0, 3, 1, 8]);
        assert_eq!(set(&m, "median_x"), [4, 5, 6]);
        assert_eq!(set(&m, "median_y"), [5]);
        // The diagonal (300, 100) meets the lattice at i = 3·j: (3, 1) = id 5.
        assert_eq!(set(&m, "diagonal"), [0, 5, 10]);
    }

    #[test]
    fn errors_name_the_field() {
        let field = |b: RectangleBlank| match b.mesh() {
            Err(MeshError::Invalid { field, .. }) => field,
            Ok(_) => panic!("accepted {b:?}"),
        };
        let ok = trusses(40.0, 30.0, 0.0, ElementKind::Quad, [4, 3]);
        assert_eq!(
            field(RectangleBlank {
                width: 0.0,
                ..ok.clone()
            }),
            "width"
        );
        assert_eq!(
            field(RectangleBlank {
                width: -1.0,
                ..ok.clone()
            }),
            "width"
        );
        assert_eq!(
            field(RectangleBlank {
                height: f64::NAN,
                ..ok.clone()
            }),
            "height"
        );
        assert_eq!(
            field(RectangleBlank {
                height: f64::INFINITY,
                ..ok.clone()
            }),
            "height"
        );
        assert_eq!(
            field(RectangleBlank {
                center: Vector3::new(0.0, f64::NAN, 0.0),
                ..ok.clone()
            }),
            "center"
        );
        assert_eq!(
            field(RectangleBlank {
                orientation_deg: f64::NAN,
                ..ok.clone()
            }),
            "orientation_deg"
        );
        assert_eq!(
            field(RectangleBlank {
                meshing: Meshing::Cells([0, 3]),
                ..ok.clone()
            }),
            "meshing"
        );
        assert_eq!(
            field(RectangleBlank {
                meshing: Meshing::Cells([3, 0]),
                ..ok.clone()
            }),
            "meshing"
        );
        assert_eq!(
            field(RectangleBlank {
                meshing: Meshing::Size(0.0),
                ..ok.clone()
            }),
            "meshing"
        );
        assert_eq!(
            field(RectangleBlank {
                meshing: Meshing::Size(-2.0),
                ..ok.clone()
            }),
            "meshing"
        );
        assert_eq!(
            field(RectangleBlank {
                meshing: Meshing::Size(f64::NAN),
                ..ok.clone()
            }),
            "meshing"
        );
        // Too many elements, including counts that would overflow.
        assert_eq!(
            field(RectangleBlank {
                meshing: Meshing::Size(1e-3),
                ..ok.clone()
            }),
            "meshing"
        );
        assert_eq!(
            field(RectangleBlank {
                meshing: Meshing::Size(1e-300),
                ..ok.clone()
            }),
            "meshing"
        );
        assert_eq!(
            field(RectangleBlank {
                meshing: Meshing::Cells([usize::MAX, usize::MAX]),
                ..ok.clone()
            }),
            "meshing"
        );
        assert_eq!(
            field(RectangleBlank {
                meshing: Meshing::Cells([2000, 2001]),
                element: ElementKind::Triangle,
                ..ok.clone()
            }),
            "meshing"
        );
        // Exactly at the limit is allowed (checked without building it).
        assert!(
            RectangleBlank {
                meshing: Meshing::Cells([2000, 2000]),
                ..ok.clone()
            }
            .layout()
            .is_ok()
        );
        // Unsupported orientation with trusses: a message that says what to do.
        let err = RectangleBlank {
            orientation_deg: 30.0,
            ..ok.clone()
        }
        .mesh()
        .unwrap_err();
        assert_eq!(
            err,
            MeshError::Invalid {
                field: "orientation_deg",
                value: 30.0,
                expected: "0, 90 or 45 for trusses (a fibre-aligned mesh); use embedded fibres for other orientations",
            }
        );
        assert_eq!(
            field(RectangleBlank {
                orientation_deg: 45.0 + 1e-6,
                ..ok.clone()
            }),
            "orientation_deg"
        );
        // Diamond cells must be square.
        let err = trusses(100.0, 90.0, 45.0, ElementKind::Quad, [2, 2])
            .mesh()
            .unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("meshing") && msg.contains("nx:ny"), "{msg}");
        let b = blank(
            100.0,
            60.0,
            45.0,
            ElementKind::Quad,
            Meshing::Size(25.0),
            FibreRepresentation::Trusses,
        );
        assert_eq!(field(b), "height");
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]

        /// The invariants of `check` on random grids of any aspect ratio.
        #[test]
        fn random_grids_are_consistent(
            w in 1.0f64..500.0,
            h in 1.0f64..500.0,
            nx in 1usize..12,
            ny in 1usize..12,
            quarter in 0i32..4,
            tri in proptest::bool::ANY,
        ) {
            let el = if tri { ElementKind::Triangle } else { ElementKind::Quad };
            let m = check(&trusses(w, h, 90.0 * quarter as f64, el, [nx, ny]));
            proptest::prop_assert_eq!(m.trusses.len(), nx * (ny + 1) + (nx + 1) * ny);
        }

        /// The same on random square-celled diamond lattices.
        #[test]
        fn random_diamonds_are_consistent(
            d in 1.0f64..100.0,
            nx in 1usize..8,
            ny in 1usize..8,
            octant in 0i32..4,
            tri in proptest::bool::ANY,
        ) {
            let el = if tri { ElementKind::Triangle } else { ElementKind::Quad };
            let theta = 45.0 + 90.0 * octant as f64;
            let m = check(&trusses(d * nx as f64, d * ny as f64, theta, el, [nx, ny]));
            proptest::prop_assert_eq!(m.trusses.len(), 4 * nx * ny);
            for t in &m.trusses {
                proptest::prop_assert!((t.strip_area - 0.5 * d * d).abs() < 1e-9 * d * d);
            }
        }
    }
}
