//! The pin-jointed net: its specification, the construction from the seed
//! outward, and the draped net with its shear per cell.

use drape_contact::Surface;
use drape_kinematics::shear_angle;
use drape_model::blank::BlankFrame;
use nalgebra::Vector3;

use crate::FishnetError;
use crate::mould::Mould;

/// What to drape and how to start.
#[derive(Debug, Clone, PartialEq)]
pub struct NetSpec {
    /// The flat blank: a rectangle in the plane z = `outline.center.z`,
    /// its sides along x and y. Cells whose flat centre lies inside it are
    /// draped.
    pub outline: BlankFrame,
    /// The seed: the flat point (x, y) of the blank where the net starts,
    /// the crossing (0, 0) of the lattice. It is put on the mould along
    /// `direction`.
    pub seed: [f64; 2],
    /// θ, the warp's angle from x in the blank plane (degrees); the weft is
    /// at θ + 90°, as in drape's blanks.
    pub orientation_deg: f64,
    /// Side of a cell along the warp and along the weft (mm): the length of
    /// a warp yarn between two weft yarns, and of a weft yarn between two
    /// warp yarns.
    pub spacing: [f64; 2],
    /// The unit direction in which the blank moves onto the mould (−z for
    /// a mould under the blank).
    pub direction: Vector3<f64>,
    /// The warp generator: None for the geodesic through the seed along
    /// the warp, or a polyline on (or near) the mould, in the mould's
    /// coordinates, that passes through the seed; the warp runs along it
    /// in the order of its points.
    pub warp_curve: Option<Vec<Vector3<f64>>>,
    /// The weft generator, likewise (None: the geodesic at right angles to
    /// the warp at the seed).
    pub weft_curve: Option<Vec<Vector3<f64>>>,
}

/// Why a crossing of the lattice has no place on the mould.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NodeStatus {
    /// Placed on the mould.
    Placed,
    /// Not needed by any cell of the outline.
    NotNeeded,
    /// The yarns from its neighbours do not meet on the mould: the net
    /// has reached the mould's edge (or a generator curve's end).
    OffMould,
    /// Its cell would close with the yarns on one line: sheared to 90°,
    /// the net folds.
    Folded,
    /// A crossing it is built from has no place.
    Blocked,
}

/// One draped cell of the net: the yarn segments between crossings
/// (i, j), (i+1, j), (i+1, j+1), (i, j+1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NetCell {
    /// Lattice index (i, j) of its first crossing.
    pub index: [i32; 2],
    /// Shear angle γ (radians): 90° less the angle between the cell's warp
    /// and weft directions, positive when the angle closes.
    pub shear: f64,
    /// Unit warp direction at the cell's centre (mean of its two warp
    /// segments).
    pub warp: Vector3<f64>,
    /// Unit weft direction at the cell's centre.
    pub weft: Vector3<f64>,
    /// Mean length of its warp and weft segments over the spacing: 1 up to
    /// the placement tolerance (the yarns are inextensible).
    pub stretch: [f64; 2],
    /// Current area, ½|d₁ × d₂| of its diagonals (mm²).
    pub area: f64,
    /// Current centroid (mean of the corners).
    pub centroid: Vector3<f64>,
}

/// Counts of a drape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct NetStats {
    /// Crossings placed on the mould.
    pub placed: usize,
    /// Crossings the outline needs that could not be placed.
    pub missed: usize,
    /// Cells of the outline.
    pub outline_cells: usize,
    /// Cells draped (all four crossings placed).
    pub draped_cells: usize,
    /// Closest-point queries of the mould surface.
    pub queries: usize,
}

/// A draped net.
#[derive(Debug, Clone)]
pub struct Net {
    spec: NetSpec,
    warp0: Vector3<f64>,
    weft0: Vector3<f64>,
    origin: Vector3<f64>,
    /// Node range: i in i_min..i_min + ni, j likewise.
    i_min: i32,
    j_min: i32,
    ni: usize,
    nj: usize,
    positions: Vec<Vector3<f64>>,
    status: Vec<NodeStatus>,
    /// Draped cells of the outline, j-major then i.
    cells: Vec<NetCell>,
    /// Per lattice cell: its entry in `cells`, or `u32::MAX`.
    cell_of: Vec<u32>,
    stats: NetStats,
}

/// Tolerance of a placement, relative to the spacing: far below any
/// manufacturing tolerance, far above the surfaces' rounding.
const REL_TOLERANCE: f64 = 1e-10;

fn check(spec: &NetSpec) -> Result<(), FishnetError> {
    let bad = |field: &'static str, what: String| Err(FishnetError::Invalid { field, what });
    let o = &spec.outline;
    if !(o.width.is_finite() && o.width > 0.0 && o.height.is_finite() && o.height > 0.0) {
        return bad("outline", "width and height must be positive".into());
    }
    if !o.center.iter().all(|v| v.is_finite()) {
        return bad("outline", "the centre must be finite".into());
    }
    if !spec.spacing.iter().all(|s| s.is_finite() && *s > 0.0) {
        return bad(
            "spacing",
            format!("{:?}: expected positive lengths", spec.spacing),
        );
    }
    if !spec.orientation_deg.is_finite() {
        return bad("orientation_deg", "must be finite".into());
    }
    // Written so that a NaN component fails too.
    let unit = (spec.direction.norm() - 1.0).abs() < 1e-9;
    if !unit {
        return bad("direction", "must be a unit vector".into());
    }
    let [sx, sy] = spec.seed;
    let tol = 1e-9 * o.width.max(o.height);
    if !(sx.is_finite() && sy.is_finite())
        || (sx - o.center.x).abs() > 0.5 * o.width + tol
        || (sy - o.center.y).abs() > 0.5 * o.height + tol
    {
        return bad(
            "seed",
            format!(
                "({sx}, {sy}) must lie on the blank (centre ({}, {}), {} × {} mm)",
                o.center.x, o.center.y, o.width, o.height
            ),
        );
    }
    for (field, curve) in [
        ("warp_curve", &spec.warp_curve),
        ("weft_curve", &spec.weft_curve),
    ] {
        if let Some(c) = curve {
            if c.len() < 2 {
                return bad(field, "a generator curve needs at least two points".into());
            }
            if !c.iter().all(|p| p.iter().all(|v| v.is_finite())) {
                return bad(field, "a point is not finite".into());
            }
        }
    }
    Ok(())
}

/// A generator curve: a polyline and a position on it (segment, fraction).
struct Curve<'a> {
    points: &'a [Vector3<f64>],
}

impl Curve<'_> {
    fn at(&self, (k, t): (usize, f64)) -> Vector3<f64> {
        let (a, b) = (
            self.points[k],
            self.points[(k + 1).min(self.points.len() - 1)],
        );
        a + (b - a) * t
    }

    /// The closest point of the polyline to `x`: its position and distance.
    fn closest(&self, x: &Vector3<f64>) -> ((usize, f64), f64) {
        let mut best = ((0, 0.0), f64::INFINITY);
        for k in 0..self.points.len() - 1 {
            let (a, b) = (self.points[k], self.points[k + 1]);
            let ab = b - a;
            let len2 = ab.norm_squared();
            let t = if len2 > 0.0 {
                ((x - a).dot(&ab) / len2).clamp(0.0, 1.0)
            } else {
                0.0
            };
            let d = (a + ab * t - x).norm();
            if d < best.1 {
                best = ((k, t), d);
            }
        }
        best
    }

    /// The unit tangent at `pos` in the direction `sign` (+1: the order of
    /// the points).
    fn tangent(&self, (k, _): (usize, f64), sign: f64) -> Vector3<f64> {
        let (a, b) = (self.points[k], self.points[k + 1]);
        (b - a).try_normalize(0.0).unwrap_or_else(Vector3::zeros) * sign
    }

    /// Going from `pos` in the direction `sign`, the first point of the
    /// polyline at distance `d` from `x`, or None past the curve's end.
    fn reach(
        &self,
        x: &Vector3<f64>,
        pos: (usize, f64),
        sign: f64,
        d: f64,
    ) -> Option<(usize, f64)> {
        let n = self.points.len() - 1;
        let mut k = pos.0;
        let mut from = pos.1;
        loop {
            let (a, b) = (self.points[k], self.points[k + 1]);
            // The segment from its parameter `from` towards the end of travel.
            let (t0, t1) = if sign > 0.0 { (from, 1.0) } else { (from, 0.0) };
            let p0 = a + (b - a) * t0;
            let p1 = a + (b - a) * t1;
            if (p1 - x).norm() >= d {
                // |p0 + s(p1 − p0) − x|² = d², the root where the distance
                // grows through d (the larger one).
                let dir = p1 - p0;
                let w = p0 - x;
                let (qa, qb, qc) = (
                    dir.norm_squared(),
                    2.0 * dir.dot(&w),
                    w.norm_squared() - d * d,
                );
                let disc = (qb * qb - 4.0 * qa * qc).max(0.0);
                if qa > 0.0 {
                    let s = ((-qb + disc.sqrt()) / (2.0 * qa)).clamp(0.0, 1.0);
                    return Some((k, t0 + (t1 - t0) * s));
                }
            }
            if sign > 0.0 {
                if k + 1 >= n {
                    return None;
                }
                k += 1;
                from = 0.0;
            } else {
                if k == 0 {
                    return None;
                }
                k -= 1;
                from = 1.0;
            }
        }
    }
}

/// How the next crossing of a generator is aimed.
enum Aim<'a> {
    /// Straight on: the chord stays in the plane of the previous chord and
    /// the surface normal (a discrete geodesic).
    Geodesic,
    /// Towards the curve, with the position reached on it so far.
    Curve(Curve<'a>, (usize, f64), f64),
}

impl NetSpec {
    /// The lattice the net is built on: `[i_min, i_max, j_min, j_max]`,
    /// crossing indices from the seed (0, 0), covering every cell whose
    /// flat centre can lie in the outline and one more all round. Clamped
    /// (at ±2²⁹) for a spacing so small that the indices would overflow.
    pub fn lattice_bounds(&self) -> [i32; 4] {
        let (warp0, weft0) = self.fibre_axes();
        let [dw, df] = self.spacing;
        let o = &self.outline;
        let origin = Vector3::new(self.seed[0], self.seed[1], o.center.z);
        // Cells of the outline: flat centre inside the rectangle.
        let lattice = |p: &Vector3<f64>| {
            let r = p - origin;
            (r.dot(&warp0) / dw, r.dot(&weft0) / df)
        };
        let (mut xi, mut eta) = (
            [f64::INFINITY, f64::NEG_INFINITY],
            [f64::INFINITY, f64::NEG_INFINITY],
        );
        for (sx, sy) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
            let corner = o.center + Vector3::new(0.5 * sx * o.width, 0.5 * sy * o.height, 0.0);
            let (a, b) = lattice(&corner);
            xi = [xi[0].min(a), xi[1].max(a)];
            eta = [eta[0].min(b), eta[1].max(b)];
        }
        // `as i32` saturates; ±2²⁹ keeps the ± 2 below and the span
        // (i_max − i_min + 1) from overflowing i32.
        let index = |v: f64| (v as i32).clamp(-(1 << 29), 1 << 29);
        [
            (index((xi[0] - 0.5).floor()) - 1).min(0),
            (index((xi[1] - 0.5).ceil()) + 2).max(0),
            (index((eta[0] - 0.5).floor()) - 1).min(0),
            (index((eta[1] - 0.5).ceil()) + 2).max(0),
        ]
    }

    /// Crossings of the lattice ([`Self::lattice_bounds`]).
    pub fn lattice_crossings(&self) -> u64 {
        let [i_min, i_max, j_min, j_max] = self.lattice_bounds();
        let span = |a: i32, b: i32| (i64::from(b) - i64::from(a) + 1) as u64;
        span(i_min, i_max) * span(j_min, j_max)
    }

    /// The bytes [`Net::drape`] allocates for this spec at most, from the
    /// sizes of its own arrays: per crossing its position, status and
    /// `needed` flag, and per lattice cell its index into the draped cells
    /// and, if draped, the cell. The results drawn from the net
    /// ([`Net::results`]) and written from them take more; the caller adds
    /// those.
    pub fn lattice_bytes(&self) -> u64 {
        let per_crossing = std::mem::size_of::<Vector3<f64>>()
            + std::mem::size_of::<NodeStatus>()
            + std::mem::size_of::<bool>()
            + std::mem::size_of::<u32>()
            + std::mem::size_of::<NetCell>();
        self.lattice_crossings().saturating_mul(per_crossing as u64)
    }

    fn fibre_axes(&self) -> (Vector3<f64>, Vector3<f64>) {
        // Multiples of 90° exactly, as the blanks snap them: no 6e-17
        // components in a 0/90 net.
        let theta = self.orientation_deg;
        let (s, c) = if (theta / 90.0 - (theta / 90.0).round()).abs() < 1e-11 {
            match ((theta / 90.0).round() as i64).rem_euclid(4) {
                0 => (0.0, 1.0),
                1 => (1.0, 0.0),
                2 => (0.0, -1.0),
                _ => (-1.0, 0.0),
            }
        } else {
            theta.to_radians().sin_cos()
        };
        (Vector3::new(c, s, 0.0), Vector3::new(-s, c, 0.0))
    }
}

impl Net {
    /// Drapes the net of `spec` on `surface` (in the surface's own
    /// coordinates).
    ///
    /// The seed crossing is the first point of the mould on the line
    /// through the flat seed along `spec.direction`. The warp and weft
    /// leave it along the flat fibre directions projected on the tangent
    /// plane there (the weft at right angles to the warp), or along the
    /// generator curves. Crossings along the two generators come first,
    /// each one yarn segment from the last; then each quadrant fills cell
    /// by cell outward, each new crossing one warp segment from its
    /// neighbour along the warp and one weft segment from its neighbour
    /// along the weft, on the mould. Only the crossings that the outline's
    /// cells need are built; one that cannot be placed leaves the cells
    /// beyond it undraped.
    pub fn drape(surface: &Surface, spec: &NetSpec) -> Result<Self, FishnetError> {
        check(spec)?;
        let (warp0, weft0) = spec.fibre_axes();
        let [dw, df] = spec.spacing;
        let o = &spec.outline;
        let origin = Vector3::new(spec.seed[0], spec.seed[1], o.center.z);

        let [i_min, i_max, j_min, j_max] = spec.lattice_bounds();
        let (ni, nj) = ((i_max - i_min + 1) as usize, (j_max - j_min + 1) as usize);
        // Indices into the lattice are u32 (`cell_of`) and i32 (i, j): a
        // lattice past them cannot be addressed. Whether it fits the
        // machine's memory is the caller's to check, from
        // [`NetSpec::lattice_bytes`], before it asks (drape's kinematic
        // command does).
        if (ni as u64) * (nj as u64) >= u64::from(u32::MAX) {
            return Err(FishnetError::Invalid {
                field: "spacing",
                what: format!(
                    "{:?} mm on a {} × {} mm blank makes {} × {} crossings, more than a net \
                     can index (2³² − 1)",
                    spec.spacing, o.width, o.height, ni, nj
                ),
            });
        }
        let tol_flat = 1e-9 * o.width.max(o.height);
        let flat =
            |i: i32, j: i32| origin + warp0 * (f64::from(i) * dw) + weft0 * (f64::from(j) * df);
        let in_outline = |i: i32, j: i32| {
            let c =
                origin + warp0 * ((f64::from(i) + 0.5) * dw) + weft0 * ((f64::from(j) + 0.5) * df);
            (c.x - o.center.x).abs() <= 0.5 * o.width + tol_flat
                && (c.y - o.center.y).abs() <= 0.5 * o.height + tol_flat
        };

        let mut net = Self {
            spec: spec.clone(),
            warp0,
            weft0,
            origin,
            i_min,
            j_min,
            ni,
            nj,
            positions: vec![Vector3::repeat(f64::NAN); ni * nj],
            status: vec![NodeStatus::NotNeeded; ni * nj],
            cells: Vec::new(),
            cell_of: vec![u32::MAX; (ni - 1) * (nj - 1)],
            stats: NetStats::default(),
        };

        // Which crossings are needed: the corners of the outline's cells,
        // then (sweeping from the far corners in) what each is built from.
        let mut needed = vec![false; ni * nj];
        let mut outline_cells = Vec::new();
        for j in j_min..j_max {
            for i in i_min..i_max {
                if in_outline(i, j) {
                    outline_cells.push([i, j]);
                    for (a, b) in [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)] {
                        needed[net.at(a, b)] = true;
                    }
                }
            }
        }
        net.stats.outline_cells = outline_cells.len();
        let reach_i = i_max.max(-i_min);
        let reach_j = j_max.max(-j_min);
        for a in (0..=reach_i).rev() {
            for b in (0..=reach_j).rev() {
                for (si, sj) in [(1, 1), (-1, 1), (1, -1), (-1, -1)] {
                    let (i, j) = (si * a, sj * b);
                    let Some(k) = net.index(i, j) else { continue };
                    if !needed[k] {
                        continue;
                    }
                    let back_i = i - i.signum();
                    let back_j = j - j.signum();
                    for (p, q) in [(back_i, j), (i, back_j), (back_i, back_j)] {
                        if let Some(m) = net.index(p, q) {
                            needed[m] = true;
                        }
                    }
                }
            }
        }

        let tolerance = REL_TOLERANCE * dw.min(df);
        let mut mould = Mould::new(surface, tolerance);
        let seed = mould.seed(&flat(0, 0), &spec.direction)?;
        let n0 = seed.normal;
        let tangent = |v: &Vector3<f64>| (v - n0 * v.dot(&n0)).try_normalize(1e-12);
        let warp_curve = spec.warp_curve.as_deref().map(|points| Curve { points });
        let weft_curve = spec.weft_curve.as_deref().map(|points| Curve { points });
        let start = |curve: &Option<Curve<'_>>,
                     name: &'static str|
         -> Result<Option<(usize, f64)>, FishnetError> {
            match curve {
                None => Ok(None),
                Some(c) => {
                    let (pos, distance) = c.closest(&seed.point);
                    if distance > 0.5 * dw.min(df) {
                        return Err(FishnetError::CurveOffSeed {
                            family: name,
                            distance,
                            seed: seed.point.into(),
                        });
                    }
                    Ok(Some(pos))
                }
            }
        };
        let warp_start = start(&warp_curve, "warp")?;
        let weft_start = start(&weft_curve, "weft")?;
        let t_warp = match (&warp_curve, warp_start) {
            (Some(c), Some(pos)) => tangent(&c.tangent(pos, 1.0)),
            _ => tangent(&warp0),
        }
        .ok_or(FishnetError::WarpNormalToMould)?;
        let t_weft = match (&weft_curve, weft_start) {
            (Some(c), Some(pos)) => tangent(&c.tangent(pos, 1.0)),
            _ => Some(n0.cross(&t_warp)),
        }
        .ok_or(FishnetError::WarpNormalToMould)?;

        let k0 = net.at(0, 0);
        net.positions[k0] = seed.point;
        net.status[k0] = NodeStatus::Placed;
        // The generators: along i (warp) and j (weft), both ways.
        for (axis, t0, curve, pos0, d) in [
            (0, t_warp, &warp_curve, warp_start, dw),
            (1, t_weft, &weft_curve, weft_start, df),
        ] {
            for sign in [1i32, -1] {
                let mut aim = match (curve, pos0) {
                    (Some(c), Some(pos)) => {
                        Aim::Curve(Curve { points: c.points }, pos, f64::from(sign))
                    }
                    _ => Aim::Geodesic,
                };
                let mut previous = seed.point;
                let mut here = seed;
                let mut direction = t0 * f64::from(sign);
                let mut blocked = false;
                for a in 1.. {
                    let (i, j) = if axis == 0 {
                        (sign * a, 0)
                    } else {
                        (0, sign * a)
                    };
                    let Some(k) = net.index(i, j) else { break };
                    if !needed[k] {
                        break;
                    }
                    if blocked {
                        net.status[k] = NodeStatus::Blocked;
                        continue;
                    }
                    if a > 1 {
                        direction = here.point - previous;
                    }
                    if let Aim::Curve(c, pos, s) = &mut aim {
                        match c.reach(&here.point, *pos, *s, d) {
                            Some(next) => {
                                direction = c.at(next) - here.point;
                                *pos = next;
                            }
                            None => {
                                net.status[k] = NodeStatus::OffMould;
                                blocked = true;
                                continue;
                            }
                        }
                    }
                    let n = here.normal;
                    let placed = (direction - n * direction.dot(&n))
                        .try_normalize(1e-12)
                        .and_then(|t| mould.on_circle(&here.point, d, &t, &n));
                    match placed {
                        Some((x, p)) => {
                            previous = here.point;
                            here = drape_contact::Projection { point: x, ..p };
                            net.positions[k] = x;
                            net.status[k] = NodeStatus::Placed;
                        }
                        None => {
                            net.status[k] = NodeStatus::OffMould;
                            blocked = true;
                        }
                    }
                }
            }
        }

        // The quadrants, cell by cell outward.
        for (si, sj) in [(1, 1), (-1, 1), (-1, -1), (1, -1)] {
            for a in 1..=reach_i {
                for b in 1..=reach_j {
                    let (i, j) = (si * a, sj * b);
                    let Some(k) = net.index(i, j) else { continue };
                    if !needed[k] {
                        continue;
                    }
                    // A: along the warp from X, B: along the weft, C: opposite.
                    let (ka, kb, kc) =
                        (net.at(i - si, j), net.at(i, j - sj), net.at(i - si, j - sj));
                    let placed = |m: usize| net.status[m] == NodeStatus::Placed;
                    if !(placed(ka) && placed(kb) && placed(kc)) {
                        net.status[k] = NodeStatus::Blocked;
                        continue;
                    }
                    let (pa, pb, pc) = (net.positions[ka], net.positions[kb], net.positions[kc]);
                    net.status[k] = match close(&mut mould, &pa, &pb, &pc, dw, df) {
                        Closed::At(x) => {
                            net.positions[k] = x;
                            NodeStatus::Placed
                        }
                        Closed::Folded => NodeStatus::Folded,
                        Closed::OffMould => NodeStatus::OffMould,
                    };
                }
            }
        }

        for [i, j] in outline_cells {
            let corners =
                [(i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)].map(|(a, b)| net.at(a, b));
            if corners.iter().any(|&k| net.status[k] != NodeStatus::Placed) {
                continue;
            }
            let [p00, p10, p11, p01] = corners.map(|k| net.positions[k]);
            let warp = p10 - p00 + p11 - p01;
            let weft = p01 - p00 + p11 - p10;
            let (Some(nw), Some(nf)) = (warp.try_normalize(0.0), weft.try_normalize(0.0)) else {
                continue;
            };
            let c = net.cell_index(i, j);
            net.cell_of[c] = net.cells.len() as u32;
            net.cells.push(NetCell {
                index: [i, j],
                shear: shear_angle(&nw, &nf, std::f64::consts::FRAC_PI_2),
                warp: nw,
                weft: nf,
                stretch: [
                    ((p10 - p00).norm() + (p11 - p01).norm()) / (2.0 * dw),
                    ((p01 - p00).norm() + (p11 - p10).norm()) / (2.0 * df),
                ],
                area: 0.5 * (p11 - p00).cross(&(p01 - p10)).norm(),
                centroid: (p00 + p10 + p11 + p01) / 4.0,
            });
        }
        net.stats.placed = net
            .status
            .iter()
            .filter(|s| **s == NodeStatus::Placed)
            .count();
        net.stats.missed = net
            .status
            .iter()
            .zip(&needed)
            .filter(|(s, n)| **n && **s != NodeStatus::Placed)
            .count();
        net.stats.draped_cells = net.cells.len();
        net.stats.queries = mould.queries;
        Ok(net)
    }

    fn index(&self, i: i32, j: i32) -> Option<usize> {
        let (a, b) = (i - self.i_min, j - self.j_min);
        (a >= 0 && b >= 0 && (a as usize) < self.ni && (b as usize) < self.nj)
            .then(|| a as usize + self.ni * b as usize)
    }

    fn at(&self, i: i32, j: i32) -> usize {
        self.index(i, j).expect("a crossing inside the lattice")
    }

    fn cell_index(&self, i: i32, j: i32) -> usize {
        (i - self.i_min) as usize + (self.ni - 1) * (j - self.j_min) as usize
    }

    /// The specification it was draped with.
    pub fn spec(&self) -> &NetSpec {
        &self.spec
    }

    /// The draped cells of the outline (j-major, then i).
    pub fn cells(&self) -> &[NetCell] {
        &self.cells
    }

    /// Counts of the drape.
    pub fn stats(&self) -> NetStats {
        self.stats
    }

    /// The flat warp and weft directions (unit, in the blank plane).
    pub fn fibre_axes(&self) -> (Vector3<f64>, Vector3<f64>) {
        (self.warp0, self.weft0)
    }

    /// Where crossing (i, j) was in the flat blank.
    pub fn flat(&self, i: i32, j: i32) -> Vector3<f64> {
        let [dw, df] = self.spec.spacing;
        self.origin + self.warp0 * (f64::from(i) * dw) + self.weft0 * (f64::from(j) * df)
    }

    /// Crossing (i, j) on the mould, if placed.
    pub fn node(&self, i: i32, j: i32) -> Option<Vector3<f64>> {
        let k = self.index(i, j)?;
        (self.status[k] == NodeStatus::Placed).then_some(self.positions[k])
    }

    /// What became of crossing (i, j) (None outside the lattice).
    pub fn status(&self, i: i32, j: i32) -> Option<NodeStatus> {
        self.index(i, j).map(|k| self.status[k])
    }

    /// The draped cell (i, j), if any.
    pub fn cell(&self, i: i32, j: i32) -> Option<&NetCell> {
        if i < self.i_min
            || j < self.j_min
            || i + 1 >= self.i_min + self.ni as i32
            || j + 1 >= self.j_min + self.nj as i32
        {
            return None;
        }
        let c = self.cell_of[self.cell_index(i, j)];
        (c != u32::MAX).then(|| &self.cells[c as usize])
    }

    /// Lattice coordinates (ξ, η) of a flat point: crossing (i, j) is at
    /// (i, j).
    pub fn lattice_coordinates(&self, flat: &Vector3<f64>) -> (f64, f64) {
        let r = flat - self.origin;
        (
            r.dot(&self.warp0) / self.spec.spacing[0],
            r.dot(&self.weft0) / self.spec.spacing[1],
        )
    }

    /// The draped cell holding the flat point (on a shared side, the first
    /// draped one of its neighbours) and the point's local coordinates in
    /// it, in [0, 1]².
    fn holding(&self, flat: &Vector3<f64>) -> Option<(&NetCell, f64, f64)> {
        let (xi, eta) = self.lattice_coordinates(flat);
        let eps = 1e-9;
        for i in [(xi + eps).floor(), (xi - eps).floor()] {
            for j in [(eta + eps).floor(), (eta - eps).floor()] {
                if !(i.abs() < 1e9 && j.abs() < 1e9) {
                    return None;
                }
                if let Some(c) = self.cell(i as i32, j as i32) {
                    return Some((c, (xi - i).clamp(0.0, 1.0), (eta - j).clamp(0.0, 1.0)));
                }
            }
        }
        None
    }

    /// Where the flat point lies on the mould: the bilinear interpolation
    /// of its draped cell's crossings (None off the draped net).
    pub fn position_at(&self, flat: &Vector3<f64>) -> Option<Vector3<f64>> {
        let (cell, s, t) = self.holding(flat)?;
        let [i, j] = cell.index;
        let p = |a, b| {
            self.node(a, b)
                .expect("a draped cell's crossings are placed")
        };
        Some(
            p(i, j) * ((1.0 - s) * (1.0 - t))
                + p(i + 1, j) * (s * (1.0 - t))
                + p(i + 1, j + 1) * (s * t)
                + p(i, j + 1) * ((1.0 - s) * t),
        )
    }

    /// The shear angle (radians) at a flat point: bilinear between the
    /// centres of the four draped cells around it, or the value of the
    /// draped cell holding it where a neighbour is missing (None off the
    /// draped net).
    pub fn shear_at(&self, flat: &Vector3<f64>) -> Option<f64> {
        let (xi, eta) = self.lattice_coordinates(flat);
        let (a, b) = (xi - 0.5, eta - 0.5);
        let (i0, j0) = (a.floor(), b.floor());
        if i0.abs() < 1e9 && j0.abs() < 1e9 {
            let (i0, j0) = (i0 as i32, j0 as i32);
            let (s, t) = (a - f64::from(i0), b - f64::from(j0));
            let around = [(i0, j0), (i0 + 1, j0), (i0 + 1, j0 + 1), (i0, j0 + 1)]
                .map(|(i, j)| self.cell(i, j).map(|c| c.shear));
            if let [Some(g00), Some(g10), Some(g11), Some(g01)] = around {
                return Some(
                    g00 * (1.0 - s) * (1.0 - t)
                        + g10 * s * (1.0 - t)
                        + g11 * s * t
                        + g01 * (1.0 - s) * t,
                );
            }
        }
        self.holding(flat).map(|(c, _, _)| c.shear)
    }
}

/// The outcome of closing a cell.
enum Closed {
    At(Vector3<f64>),
    Folded,
    OffMould,
}

/// The crossing X that closes the cell with corners C (opposite X), A (one
/// warp segment `dw` from X) and B (one weft segment `df` from X): on the
/// circle where the spheres |X − A| = dw and |X − B| = df meet, on the
/// mould, nearest the flat parallelogram's corner A + B − C.
fn close(
    mould: &mut Mould<'_>,
    a: &Vector3<f64>,
    b: &Vector3<f64>,
    c: &Vector3<f64>,
    dw: f64,
    df: f64,
) -> Closed {
    let ab = b - a;
    let l = ab.norm();
    if l <= 1e-12 * dw.max(df) {
        return Closed::Folded;
    }
    let u = ab / l;
    let s = (l * l + dw * dw - df * df) / (2.0 * l);
    let rho2 = dw * dw - s * s;
    if rho2 <= 1e-12 * dw * dw {
        return Closed::Folded;
    }
    let centre = a + u * s;
    let guess = a + b - c - centre;
    let Some(e1) = (guess - u * guess.dot(&u)).try_normalize(1e-12 * dw) else {
        return Closed::Folded;
    };
    let e2 = u.cross(&e1);
    match mould.on_circle(&centre, rho2.sqrt(), &e1, &e2) {
        Some((x, _)) => Closed::At(x),
        None => Closed::OffMould,
    }
}
