//! Yarn bending: a rotation-free discrete elastica along the yarn lines of
//! the mesh, superposed on the membranes (SPEC §4 "Beyond the paper").
//!
//! # Formulation, and why
//!
//! A woven fabric's bending stiffness is its yarns': each family bends
//! about its own axis with its own rigidity B_k (N·mm, a moment per unit
//! width per unit curvature), the two hardly coupled, and the twist
//! stiffness is small. drape's blanks are meshed with lines along the
//! yarns (the trusses' lattice), so each yarn line of the mesh is a
//! discrete elastic rod: at every node `j` inside a line, between its
//! neighbours `i` and `k` along the line, one *triplet* carries
//!
//! E = ½·B_k·w·ℓ_rep·κ²,  κ = 2·tan(φ/2)/ℓ̄,
//!
//! with φ the turning angle between the edges a = xⱼ − xᵢ and b = xₖ − xⱼ,
//! ℓ̄ the mean of their reference lengths (the Voronoi length of the node
//! along the line), ℓ_rep the reference length of line the triplet stands
//! for (ℓ̄, plus the outer half-edge when `i` or `k` ends the line, so a
//! line's triplets cover its whole length), and w the width of fabric the
//! line carries (the node's lumped area over ℓ̄). 2·tan(φ/2) is the
//! curvature binormal of discrete elastic rods (Bergou et al. 2008); with
//! p = |a||b| and d = a·b it is 4·tan²(φ/2) = 4(p − d)/(p + d), a rational
//! function of the positions, smooth through the straight state, so the
//! force and tangent have no 0/0 at φ = 0 (where an atan2 would).
//!
//! Chosen over the alternatives:
//! - *Hinges on interior edges* (discrete shells): one dihedral per edge
//!   between two triangles mixes the yarn directions and needs triangles;
//!   drape's quads are warped in general, and on a fibre-aligned grid a
//!   hinge is a triplet's worse-conditioned cousin.
//! - *Discrete Kirchhoff triangles*: rotations as extra unknowns, a new
//!   element type for both triangles and quads; far more than a stiffness
//!   three orders below the membrane's needs.
//!
//! The triplet converges as O(h²) to the elastica (a cantilever under its
//! weight is the Peirce test, `cargo xtask validate --filter bending`), it
//! is objective (it reads only lengths and a dot product), it has no
//! history, and it batches like the trusses: 3 nodes, 3 slots.
//!
//! What it is not: no twist (torsion of a yarn) and no coupling of the two
//! families' curvatures; a mesh without lines along the yarns (embedded
//! fibres at an angle to the grid, most imported meshes) has no triplets,
//! which [`yarn_triplets`] reports so that a scene asking for bending there
//! is refused. Energies and forces are elastic: bending dissipation (the
//! hysteresis of dry fabrics) is not modelled.

use nalgebra::{DMatrix, Matrix3, Vector3};
use rayon::prelude::*;

use crate::{ElementError, KinematicsError, MIN_CHUNK, lowest_error};

/// A yarn-line triplet found in a mesh: nodes `[i, j, k]` consecutive
/// along one line of `family`, `j` in the middle.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct YarnTriplet {
    /// `[i, j, k]`.
    pub nodes: [u32; 3],
    /// 0 = warp, 1 = weft.
    pub family: u8,
    /// Whether `i` (resp. `k`) is the last node of its line.
    pub line_ends: [bool; 2],
}

/// The yarn-line triplets of a mesh with `edges`, at reference positions
/// `x0`, for the reference yarn directions `directions` ([warp, weft], in
/// the blank's plane): at each node and for each family, the neighbours
/// along +d and −d whose edges are parallel to d to within 1e-6 rad.
///
/// In node order, warp before weft, so the batch does not depend on the
/// order of `edges`.
pub fn yarn_triplets(
    x0: &[Vector3<f64>],
    edges: &[[u32; 2]],
    directions: [Vector3<f64>; 2],
) -> Vec<YarnTriplet> {
    let n = x0.len();
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
    for &[a, b] in edges {
        if a != b {
            neighbours[a as usize].push(b);
            neighbours[b as usize].push(a);
        }
    }
    // cos(1e-6) = 1 − 5e-13: parallel up to the round-off of meshing.
    let aligned = 1.0 - 5e-13;
    let along = |j: usize, d: &Vector3<f64>| -> Option<u32> {
        neighbours[j]
            .iter()
            .copied()
            .map(|k| {
                let e = x0[k as usize] - x0[j];
                (k, e.dot(d) / e.norm())
            })
            .filter(|&(_, c)| c >= aligned)
            .max_by(|a, b| a.1.total_cmp(&b.1).then(b.0.cmp(&a.0)))
            .map(|(k, _)| k)
    };
    let mut triplets = Vec::new();
    for j in 0..n {
        for (family, d) in directions.iter().enumerate() {
            let d = d.normalize();
            if let (Some(i), Some(k)) = (along(j, &-d), along(j, &d)) {
                triplets.push(YarnTriplet {
                    nodes: [i, j as u32, k],
                    family: family as u8,
                    line_ends: [
                        along(i as usize, &-d).is_none(),
                        along(k as usize, &d).is_none(),
                    ],
                });
            }
        }
    }
    triplets
}

/// A batch of yarn-bending triplets (see the module documentation).
#[derive(Debug, Clone)]
pub struct BendingBatch {
    /// `[i, j, k]` of each triplet, `j` in the middle.
    pub nodes: Vec<[u32; 3]>,
    /// The family of each triplet (0 = warp, 1 = weft).
    pub family: Vec<u8>,
    /// Bending rigidity of [warp, weft] (N·mm: moment per unit width per
    /// unit curvature).
    pub rigidity: [f64; 2],
    /// K = 2·B·w·ℓ_rep/ℓ̄² (N·mm): E = K·(p − d)/(p + d).
    stiffness: Vec<f64>,
    /// ℓ̄, the mean reference length of the two edges.
    mean_length: Vec<f64>,
    /// w, the width of fabric the line carries there.
    width: Vec<f64>,
    /// ℓ_rep, the length of line the triplet stands for.
    represented: Vec<f64>,
    /// The reference lengths [|a|, |b|].
    edge_length: Vec<[f64; 2]>,
}

/// The geometry of one triplet at current positions.
struct Hinge {
    a: Vector3<f64>,
    b: Vector3<f64>,
    la: f64,
    lb: f64,
    /// p = |a||b|.
    p: f64,
    /// d = a·b.
    d: f64,
}

impl Hinge {
    /// s = p + d = |a||b|(1 + cos φ): zero when the line folds back on itself.
    #[inline]
    fn s(&self) -> f64 {
        self.p + self.d
    }
}

impl BendingBatch {
    /// Triplets `triplets` on the reference positions `x0`, each node
    /// standing for the fabric area `nodal_area` (the lumped ∫Nⱼ dA of the
    /// membranes), with bending rigidities `rigidity` = [warp, weft].
    pub fn new(
        x0: &[Vector3<f64>],
        triplets: &[YarnTriplet],
        nodal_area: &[f64],
        rigidity: [f64; 2],
    ) -> Result<Self, ElementError> {
        let mut batch = Self {
            nodes: Vec::with_capacity(triplets.len()),
            family: Vec::with_capacity(triplets.len()),
            rigidity,
            stiffness: Vec::with_capacity(triplets.len()),
            mean_length: Vec::with_capacity(triplets.len()),
            width: Vec::with_capacity(triplets.len()),
            represented: Vec::with_capacity(triplets.len()),
            edge_length: Vec::with_capacity(triplets.len()),
        };
        for (e, t) in triplets.iter().enumerate() {
            let [i, j, k] = t.nodes.map(|n| n as usize);
            let la = (x0[j] - x0[i]).norm();
            let lb = (x0[k] - x0[j]).norm();
            let area = nodal_area[j];
            if !(la > 0.0 && lb > 0.0 && area > 0.0 && (la + lb + area).is_finite()) {
                return Err(ElementError {
                    element: e,
                    point: 0,
                    cause: KinematicsError::DegenerateReference {
                        size: la.min(lb).min(area),
                    },
                });
            }
            let mean = 0.5 * (la + lb);
            let width = area / mean;
            let mut represented = mean;
            if t.line_ends[0] {
                represented += 0.5 * la;
            }
            if t.line_ends[1] {
                represented += 0.5 * lb;
            }
            batch.nodes.push(t.nodes);
            batch.family.push(t.family);
            batch.mean_length.push(mean);
            batch.width.push(width);
            batch.represented.push(represented);
            batch.edge_length.push([la, lb]);
            batch.stiffness.push(0.0);
            batch.update_stiffness(batch.len() - 1);
        }
        Ok(batch)
    }

    fn update_stiffness(&mut self, e: usize) {
        let b = self.rigidity[self.family[e] as usize];
        let mean = self.mean_length[e];
        self.stiffness[e] = 2.0 * b * self.width[e] * self.represented[e] / (mean * mean);
    }

    /// Clamps the lines at the nodes marked `held` (fixed in place): a
    /// triplet whose middle node and one neighbour are held has a rigid
    /// half, so it bends over its free half edge only, ℓ̄ = ℓ_rep = |b|/2
    /// (or |a|/2) in place of the Voronoi length. That is the mirror
    /// ("ghost node") condition of a clamped end, second order like the
    /// interior; without it the clamp sits half an edge behind the held
    /// node and a cantilever converges only as O(h).
    pub fn clamp(&mut self, held: &[bool]) {
        for e in 0..self.len() {
            let [i, j, k] = self.nodes[e].map(|n| held[n as usize]);
            let [la, lb] = self.edge_length[e];
            let free = match (i, j, k) {
                (true, true, false) => lb,
                (false, true, true) => la,
                _ => continue,
            };
            self.mean_length[e] = 0.5 * free;
            self.represented[e] = 0.5 * free;
            self.update_stiffness(e);
        }
    }

    /// K of each triplet (N·mm): the energy is K·(p − d)/(p + d) (for a
    /// port of the force pass, e.g. drape-gpu).
    pub fn stiffnesses(&self) -> &[f64] {
        &self.stiffness
    }

    /// Number of triplets.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Whether the batch is empty.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    #[inline]
    fn hinge(&self, e: usize, x: &[Vector3<f64>]) -> Result<Hinge, ElementError> {
        let [i, j, k] = self.nodes[e].map(|n| n as usize);
        let a = x[j] - x[i];
        let b = x[k] - x[j];
        let (la, lb) = (a.norm(), b.norm());
        let fail = |cause| ElementError {
            element: e,
            point: 0,
            cause,
        };
        if !(la.is_finite() && lb.is_finite()) {
            return Err(fail(KinematicsError::NonFinite {
                what: "yarn line's node positions",
            }));
        }
        if !(la > 0.0 && lb > 0.0) {
            return Err(fail(KinematicsError::DegenerateFibre {
                length: la.min(lb),
            }));
        }
        let h = Hinge {
            p: la * lb,
            d: a.dot(&b),
            a,
            b,
            la,
            lb,
        };
        // Folded back to within 1e-6 rad of 180°: tan(φ/2) has no finite value.
        if h.s() <= 5e-13 * h.p {
            return Err(fail(KinematicsError::DegenerateFibre { length: h.s() }));
        }
        Ok(h)
    }

    /// The curvature κ = 2·tan(φ/2)/ℓ̄ of triplet `e` (1/mm, ≥ 0).
    pub fn element_curvature(&self, e: usize, x: &[Vector3<f64>]) -> Result<f64, ElementError> {
        let h = self.hinge(e, x)?;
        Ok(2.0 * h.a.cross(&h.b).norm() / h.s() / self.mean_length[e])
    }

    /// Bending energy K·(p − d)/(p + d) = ½·B·w·ℓ_rep·κ² of triplet `e`.
    pub fn element_energy(&self, e: usize, x: &[Vector3<f64>]) -> Result<f64, ElementError> {
        let h = self.hinge(e, x)?;
        // p − d = |a×b|²/(p + d) without the cancellation near straight.
        let c = h.a.cross(&h.b).norm_squared();
        let s = h.s();
        Ok(self.stiffness[e] * c / (s * s))
    }

    /// Total bending energy of the batch.
    pub fn energy(&self, x: &[Vector3<f64>]) -> Result<f64, ElementError> {
        (0..self.len()).map(|e| self.element_energy(e, x)).sum()
    }

    /// The internal nodal forces fₐ = ∂E/∂xₐ of triplet `e` ([i, j, k]),
    /// the convention of the other batches (the force on the node is −f).
    #[inline]
    pub fn element_force(
        &self,
        e: usize,
        x: &[Vector3<f64>],
    ) -> Result<[Vector3<f64>; 3], ElementError> {
        let h = self.hinge(e, x)?;
        let s = h.s();
        let k = self.stiffness[e];
        // ∂g/∂p = 2d/s², ∂g/∂d = −2p/s² for g = (p − d)/(p + d).
        let gp = 2.0 * h.d / (s * s);
        let gd = -2.0 * h.p / (s * s);
        let da = (h.a * (gp * h.lb / h.la) + h.b * gd) * k;
        let db = (h.b * (gp * h.la / h.lb) + h.a * gd) * k;
        Ok([-da, da - db, db])
    }

    /// Writes every triplet's three nodal forces into `slots` (3 per
    /// triplet, in triplet order), in parallel.
    pub fn forces_into(
        &self,
        x: &[Vector3<f64>],
        slots: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        assert_eq!(slots.len(), 3 * self.len());
        lowest_error(
            slots
                .par_chunks_mut(3)
                .with_min_len(MIN_CHUNK)
                .enumerate()
                .map(|(e, out)| {
                    out.copy_from_slice(&self.element_force(e, x)?);
                    Ok(())
                }),
        )
    }

    /// The exact 9×9 tangent ∂f/∂x of triplet `e` (node-major [i, j, k]):
    /// K·∇²g, symmetric (the energy is hyperelastic).
    pub fn element_tangent(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        k_out: &mut DMatrix<f64>,
    ) -> Result<(), ElementError> {
        let h = self.hinge(e, x)?;
        let (p, d, s) = (h.p, h.d, h.s());
        let (s2, s3) = (s * s, s * s * s);
        let (gp, gd) = (2.0 * d / s2, -2.0 * p / s2);
        let (gpp, gdd, gpd) = (-4.0 * d / s3, 4.0 * p / s3, 2.0 * (p - d) / s3);
        let (ua, ub) = (h.a / h.la, h.b / h.lb);
        // ∇p and ∇d with respect to (a, b).
        let dp = [ua * h.lb, ub * h.la];
        let dd = [h.b, h.a];
        let eye = Matrix3::identity();
        // ∇²p blocks: aa, ab (ba = abᵀ), bb.
        let paa = (eye - ua * ua.transpose()) * (h.lb / h.la);
        let pab = ua * ub.transpose();
        let pbb = (eye - ub * ub.transpose()) * (h.la / h.lb);
        let block = |u: usize, v: usize| -> Matrix3<f64> {
            let mut m = dp[u] * dp[v].transpose() * gpp
                + (dp[u] * dd[v].transpose() + dd[u] * dp[v].transpose()) * gpd
                + dd[u] * dd[v].transpose() * gdd;
            m += match (u, v) {
                (0, 0) => paa * gp,
                (0, 1) => pab * gp + eye * gd,
                (1, 0) => pab.transpose() * gp + eye * gd,
                _ => pbb * gp,
            };
            m
        };
        let hess = [[block(0, 0), block(0, 1)], [block(1, 0), block(1, 1)]];
        // a = xⱼ − xᵢ, b = xₖ − xⱼ: ∂(a, b)/∂(xᵢ, xⱼ, xₖ).
        const C: [[f64; 2]; 3] = [[-1.0, 0.0], [1.0, -1.0], [0.0, 1.0]];
        let k = self.stiffness[e];
        for (al, ca) in C.iter().enumerate() {
            for (be, cb) in C.iter().enumerate() {
                let mut m = Matrix3::zeros();
                for (u, cu) in ca.iter().enumerate() {
                    for (v, cv) in cb.iter().enumerate() {
                        if *cu != 0.0 && *cv != 0.0 {
                            m += hess[u][v] * (cu * cv);
                        }
                    }
                }
                k_out
                    .fixed_view_mut::<3, 3>(3 * al, 3 * be)
                    .copy_from(&(m * k));
            }
        }
        Ok(())
    }

    /// How many triplets of the batch touch each of `node_count` nodes.
    pub fn node_degree(&self, node_count: usize) -> Vec<u32> {
        let mut degree = vec![0; node_count];
        for t in &self.nodes {
            for &n in t {
                degree[n as usize] += 1;
            }
        }
        degree
    }

    /// The stable time step 2/ω of triplet `e` on its nodes' shares `mass`
    /// of the lumped mass, from its stiffness about the straight line in
    /// the current edge lengths: E ≈ ½·(K/2)·(g·u)² for transverse
    /// displacements u, g = (1/l_a, −1/l_a − 1/l_b, 1/l_b), a rank-one
    /// stiffness per transverse direction whose one frequency is
    /// ω² = (K/2)·Σ gₐ²/mₐ. With each node's mass shared among the triplets
    /// there, the batch's ω_max is bounded by its triplets' (the element
    /// eigenvalue inequality); a bent line stiffens by O(φ²) beyond it,
    /// which the safety factor covers.
    pub fn element_stable_time_step(&self, e: usize, x: &[Vector3<f64>], mass: [f64; 3]) -> f64 {
        let [i, j, k] = self.nodes[e].map(|n| n as usize);
        let (la, lb) = ((x[j] - x[i]).norm(), (x[k] - x[j]).norm());
        let (ga, gb) = (1.0 / la, 1.0 / lb);
        let sum = ga * ga / mass[0] + (ga + gb) * (ga + gb) / mass[1] + gb * gb / mass[2];
        2.0 / (0.5 * self.stiffness[e] * sum).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_support::{assert_tangent_matches, random_rotation};
    use proptest::prelude::*;

    /// A flat nx × ny grid of cells sx × sy in the xy-plane: positions,
    /// edges and nodal areas (a quarter cell per cell corner).
    fn grid(
        nx: usize,
        ny: usize,
        sx: f64,
        sy: f64,
    ) -> (Vec<Vector3<f64>>, Vec<[u32; 2]>, Vec<f64>) {
        let id = |i: usize, j: usize| (j * (nx + 1) + i) as u32;
        let mut x0 = Vec::new();
        let mut area = vec![0.0; (nx + 1) * (ny + 1)];
        for j in 0..=ny {
            for i in 0..=nx {
                x0.push(Vector3::new(i as f64 * sx, j as f64 * sy, 0.0));
            }
        }
        let mut edges = Vec::new();
        for j in 0..=ny {
            for i in 0..=nx {
                if i < nx {
                    edges.push([id(i, j), id(i + 1, j)]);
                }
                if j < ny {
                    edges.push([id(i, j), id(i, j + 1)]);
                }
                if i < nx && j < ny {
                    for n in [id(i, j), id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)] {
                        area[n as usize] += 0.25 * sx * sy;
                    }
                }
            }
        }
        (x0, edges, area)
    }

    fn grid_batch(
        nx: usize,
        ny: usize,
        sx: f64,
        sy: f64,
        b: [f64; 2],
    ) -> (BendingBatch, Vec<Vector3<f64>>) {
        let (x0, edges, area) = grid(nx, ny, sx, sy);
        let triplets = yarn_triplets(&x0, &edges, [Vector3::x(), Vector3::y()]);
        (BendingBatch::new(&x0, &triplets, &area, b).unwrap(), x0)
    }

    /// Three nodes bent by a turning angle, then rotated and moved.
    fn bent(phi: f64, seed: u64) -> Vec<Vector3<f64>> {
        let q = random_rotation(seed);
        let t = Vector3::new(1.0, -2.0, 0.5);
        [
            Vector3::new(-3.0, 0.0, 0.0),
            Vector3::zeros(),
            Vector3::new(4.0 * phi.cos(), 4.0 * phi.sin(), 0.0),
        ]
        .map(|p| q * p + t)
        .to_vec()
    }

    fn single() -> BendingBatch {
        let x0 = vec![
            Vector3::new(-3.0, 0.0, 0.0),
            Vector3::zeros(),
            Vector3::new(4.0, 0.0, 0.0),
        ];
        let t = YarnTriplet {
            nodes: [0, 1, 2],
            family: 1,
            line_ends: [false, true],
        };
        BendingBatch::new(&x0, &[t], &[0.0, 7.0, 0.0], [5.0, 0.8]).unwrap()
    }

    #[test]
    fn triplets_follow_the_grid_lines() {
        let (x0, edges, _) = grid(3, 2, 1.0, 2.0);
        let t = yarn_triplets(&x0, &edges, [Vector3::x(), Vector3::y()]);
        // Warp lines: 3 rows of 2 interior nodes; weft: 4 columns of 1.
        assert_eq!(t.iter().filter(|t| t.family == 0).count(), 6);
        assert_eq!(t.iter().filter(|t| t.family == 1).count(), 4);
        assert_eq!(
            t[0],
            YarnTriplet {
                nodes: [0, 1, 2],
                family: 0,
                line_ends: [true, false]
            }
        );
        // No line along a direction the grid does not have.
        let diagonal = Vector3::new(1.0, 1.0, 0.0).normalize();
        assert!(yarn_triplets(&x0, &edges, [diagonal, diagonal]).is_empty());
    }

    #[test]
    fn energy_is_half_b_w_l_kappa_squared() {
        // φ = 0.3: κ = 2·tan(0.15)/3.5, w = 7/3.5, ℓ_rep = 3.5 + 2 (k ends the line).
        let t = single();
        let x = bent(0.3, 3);
        let kappa = 2.0 * 0.15f64.tan() / 3.5;
        let expected = 0.5 * 0.8 * 2.0 * 5.5 * kappa * kappa;
        let e = t.element_energy(0, &x).unwrap();
        assert!((e - expected).abs() < 1e-14 * expected, "{e} vs {expected}");
        assert!((t.element_curvature(0, &x).unwrap() - kappa).abs() < 1e-15);
    }

    #[test]
    fn a_clamp_bends_the_free_half_edge_only() {
        // i and j held: ℓ̄ = ℓ_rep = |b|/2 = 2, w stays 7/3.5.
        let mut t = single();
        t.clamp(&[true, true, false]);
        let x = bent(0.3, 3);
        let kappa = 2.0 * 0.15f64.tan() / 2.0;
        let expected = 0.5 * 0.8 * 2.0 * 2.0 * kappa * kappa;
        let e = t.element_energy(0, &x).unwrap();
        assert!((e - expected).abs() < 1e-14 * expected, "{e} vs {expected}");
        // Only the middle node and one neighbour held: nothing changes.
        let mut u = single();
        u.clamp(&[true, false, true]);
        assert_eq!(u.element_energy(0, &x), single().element_energy(0, &x));
    }

    #[test]
    fn force_is_the_gradient_and_tangent_the_derivative_of_the_force() {
        let t = single();
        for (phi, seed) in [(0.0, 1), (1e-4, 2), (0.3, 3), (1.2, 4), (2.5, 5)] {
            let mut x = bent(phi, seed);
            x[2] += Vector3::new(0.1, -0.2, 0.3) * phi;
            let f = t.element_force(0, &x).unwrap();
            let h = 1e-6;
            let scale = f.iter().map(|v| v.amax()).fold(1e-3, f64::max);
            for n in 0..3 {
                for c in 0..3 {
                    let (mut xp, mut xm) = (x.clone(), x.clone());
                    xp[n][c] += h;
                    xm[n][c] -= h;
                    let fd = (t.element_energy(0, &xp).unwrap()
                        - t.element_energy(0, &xm).unwrap())
                        / (2.0 * h);
                    assert!(
                        (fd - f[n][c]).abs() <= 1e-7 * scale,
                        "φ = {phi}: node {n} comp {c}: {fd} vs {}",
                        f[n][c]
                    );
                }
            }
            let mut k = DMatrix::zeros(9, 9);
            t.element_tangent(0, &x, &mut k).unwrap();
            assert!((&k - k.transpose()).amax() <= 1e-12 * k.amax());
            assert_tangent_matches(
                &k,
                &x,
                |x| t.element_force(0, x).unwrap().to_vec(),
                &[0, 1, 2],
            );
        }
    }

    #[test]
    fn a_folded_or_collapsed_line_is_an_error_not_a_nan() {
        let t = single();
        let mut x = bent(0.0, 1);
        x[2] = x[1] - (x[2] - x[1]);
        let err = t.element_force(0, &x).unwrap_err();
        assert!(matches!(err.cause, KinematicsError::DegenerateFibre { .. }));
        x[2] = x[1];
        assert!(t.element_energy(0, &x).is_err());
        x[2] = Vector3::new(f64::NAN, 0.0, 0.0);
        assert!(t.element_energy(0, &x).is_err());
    }

    /// A strip L × W rolled without stretch onto a cylinder of radius R
    /// (warp lines along its circumference): E = B·L·W/(2R²) up to the
    /// O((ℓ/R)²) of 2·tan(φ/2) against φ, and the error falls as h².
    #[test]
    fn strip_rolled_onto_a_cylinder_stores_b_l_w_over_2r2() {
        let (l, w, r, b) = (100.0, 20.0, 40.0, 0.37);
        let error = |nx: usize| {
            let (t, x0) = grid_batch(nx, 4, l / nx as f64, w / 4.0, [b, 55.0]);
            let x: Vec<_> = x0
                .iter()
                .map(|p| {
                    let a = p.x / r;
                    Vector3::new(r * a.sin(), p.y, r * (1.0 - a.cos()))
                })
                .collect();
            let exact = b * l * w / (2.0 * r * r);
            (t.energy(&x).unwrap() - exact) / exact
        };
        let (coarse, fine) = (error(20), error(40));
        assert!(
            coarse.abs() < 1e-2 && fine.abs() < 3e-3,
            "{coarse:e}, {fine:e}"
        );
        // 2·tan(φ/2)/φ − 1 ≈ φ²/12 squared into the energy: ratio 4.
        assert!((coarse / fine - 4.0).abs() < 0.05, "{coarse:e}, {fine:e}");
    }

    #[test]
    fn stable_step_is_the_rank_one_frequency() {
        // Equal edges ℓ and masses m: ω² = (K/2)·6/(ℓ²m), the exact highest
        // frequency of the assembled 9×9 tangent at the straight state.
        let x0 = vec![
            Vector3::zeros(),
            Vector3::new(2.0, 0.0, 0.0),
            Vector3::new(4.0, 0.0, 0.0),
        ];
        let tr = YarnTriplet {
            nodes: [0, 1, 2],
            family: 0,
            line_ends: [false, false],
        };
        let t = BendingBatch::new(&x0, &[tr], &[0.0, 3.0, 0.0], [0.5, 0.5]).unwrap();
        let m = 1e-9;
        let dt = t.element_stable_time_step(0, &x0, [m; 3]);
        let mut k = DMatrix::zeros(9, 9);
        t.element_tangent(0, &x0, &mut k).unwrap();
        let omega2 = (k / m).symmetric_eigenvalues().max();
        assert!(
            (dt - 2.0 / omega2.sqrt()).abs() < 1e-9 * dt,
            "{dt:e} vs {:e}",
            2.0 / omega2.sqrt()
        );
        assert_eq!(t.node_degree(4), vec![1, 1, 1, 0]);
    }

    proptest! {
        /// Energy and forces are objective: a rigid motion of a bent grid
        /// leaves the energy and rotates the forces; a rigid motion of the
        /// flat grid stores nothing.
        #[test]
        fn objective_under_rigid_motion(
            seed in 0u64..1000,
            amp in 0.01f64..0.5,
            tx in -50.0f64..50.0,
            ty in -50.0f64..50.0,
        ) {
            let (t, x0) = grid_batch(4, 3, 2.0, 3.0, [0.4, 1.3]);
            let q = random_rotation(seed);
            let shift = Vector3::new(tx, ty, 0.3 * tx);
            let flat: Vec<_> = x0.iter().map(|p| q * p + shift).collect();
            prop_assert!(t.energy(&flat).unwrap().abs() < 1e-25);
            let bent: Vec<_> = x0
                .iter()
                .map(|p| Vector3::new(p.x, p.y, amp * (p.x * 0.7).sin() * (1.0 + 0.2 * p.y)))
                .collect();
            let moved: Vec<_> = bent.iter().map(|p| q * p + shift).collect();
            let (e0, e1) = (t.energy(&bent).unwrap(), t.energy(&moved).unwrap());
            prop_assert!((e0 - e1).abs() <= 1e-11 * e0.max(1e-12), "{} vs {}", e0, e1);
            for e in 0..t.len() {
                let f0 = t.element_force(e, &bent).unwrap();
                let f1 = t.element_force(e, &moved).unwrap();
                for (a, b) in f0.iter().zip(&f1) {
                    prop_assert!((q * a - b).norm() <= 1e-9 * a.norm() + 1e-14);
                }
            }
        }
    }
}
