//! Resin membranes (3-node triangle, 4-node quad) with optional embedded
//! fibres.

use drape_constitutive::Material;
use drape_kinematics::{
    FibreKinematics, KinematicsError, LocalFrame, PolarDecomposition, add_nodal_forces,
    deformation_gradient, fibre_stretch, polar_decomposition, quad_point, rotated_strain_increment,
    shear_angle, triangle_point,
};
use nalgebra::{DMatrix, Matrix2, Matrix3x2, Vector2, Vector3};
use rayon::prelude::*;

use crate::lanes::LANES;
use crate::quad_lanes::{QuadLanes, ResinStep, StepBound};
use crate::{ElementError, MIN_CHUNK, lowest_error};

mod locking;
use locking::LockingPoint;

/// Values per integration point before the resin's own history:
/// U (11, 22, 12) and τ̄ (11, 22, 12).
const KINEMATIC_HISTORY: usize = 6;
const MAX_NODES: usize = 4;
/// The reference warp and weft directions in every point's local frame,
/// which is turned onto the fibres when the batch is built.
const FIBRES: [Vector2<f64>; 2] = [Vector2::new(1.0, 0.0), Vector2::new(0.0, 1.0)];
/// 1/√3, the 2×2 Gauss abscissa.
const GAUSS: f64 = 0.577_350_269_189_625_8;
/// Prony terms whose step factors a pass computes once (a resin with more
/// computes them at every point, on the scalar path).
const PRONY_TABLE: usize = 8;
/// The most history values of an element the lanes carry: four points of
/// U, τ̄, the shear stress and [`PRONY_TABLE`] Prony terms.
const LANE_ELEMENT_HISTORY: usize = 4 * (KINEMATIC_HISTORY + 1 + PRONY_TABLE);

/// The fabric a membrane batch is made of, and whether its yarns are
/// embedded in the membrane (else trusses carry them and the membrane is
/// resin only).
#[derive(Debug, Clone, PartialEq)]
pub struct FabricSection {
    /// The fabric.
    pub material: Material,
    /// Whether the two yarn families' stress is added at each integration
    /// point (SPEC §2, "embedded").
    pub embedded_fibres: bool,
}

impl FabricSection {
    /// A section of `material`, with or without embedded fibres.
    pub fn new(material: Material, embedded_fibres: bool) -> Self {
        Self {
            material,
            embedded_fibres,
        }
    }
}

/// The resin membrane's tangent the implicit driver factorises.
///
/// A resin membrane in compression has a negative geometric stiffness
/// out of its plane: the exact tangent of a compressed region can outweigh
/// the yarns' tension and bending, and the assembled K̂ is then indefinite
/// (the condensed contact solve meets pᵀAp ≤ 0 and the increment is cut;
/// measured on the ±45 hemisphere with the physical mass: the most negative
/// eigenvector of K̂ lies on the dome's flank, out of plane, and the resin's
/// stress terms are its only negative energy). The tension-field tangent
/// drops the compressive principal stresses from those terms, as membrane
/// codes do for wrinkling: it equals the exact tangent wherever the resin
/// is in tension, and is positive semi-definite where it is not. The
/// residual stays exact, so the converged state is the same; only Newton's
/// path changes (linear instead of quadratic convergence where it acts).
///
/// Between the two, [`MembraneTangent::CompressionScaled`] keeps a fraction
/// of the compressive part (the implicit driver steps down to the tension
/// field only as far as the factorisation needs).
///
/// Not for the fibres (embedded or trusses) or the shear-locking term:
/// those stay exact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MembraneTangent {
    /// The exact derivative of the discrete update.
    Exact,
    /// The resin stress in the tangent's stress terms is its tensile part.
    TensionField,
    /// The tensile part and this fraction (in [0, 1]) of the compressive
    /// part: 1 is the exact tangent, 0 the tension field.
    CompressionScaled(f64),
}

/// The tensile part Σ max(σᵢ, 0)·nᵢ⊗nᵢ of a symmetric 2×2 stress, in
/// closed form (the eigenvalues of a 2×2 from its mean and radius).
#[inline]
fn tensile_part(tau: &Matrix2<f64>) -> Matrix2<f64> {
    let (a, b, c) = (tau[(0, 0)], tau[(1, 1)], tau[(0, 1)]);
    let mean = 0.5 * (a + b);
    let radius = (0.25 * (a - b) * (a - b) + c * c).sqrt();
    let (high, low) = (mean + radius, mean - radius);
    if low >= 0.0 {
        return *tau;
    }
    if high <= 0.0 {
        return Matrix2::zeros();
    }
    // τ = high·P + low·(I − P) with P the projector on the high direction:
    // P = (τ − low·I)/(high − low), so the tensile part is high·P.
    (tau - Matrix2::identity() * low) * (high / (high - low))
}

/// The element family of a batch.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum MembraneShape {
    /// 3 nodes, 1 integration point (M3D3-like).
    Triangle,
    /// 4 nodes, 2×2 Gauss points (M3D4-like).
    Quad,
}

impl MembraneShape {
    /// Nodes per element.
    pub const fn nodes(self) -> usize {
        match self {
            Self::Triangle => 3,
            Self::Quad => 4,
        }
    }

    /// Integration points per element.
    pub const fn points(self) -> usize {
        match self {
            Self::Triangle => 1,
            Self::Quad => 4,
        }
    }
}

/// Output fields of one membrane element, averaged over its points
/// (weighted by reference area).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct MembraneOutput {
    /// Shear angle γ between warp and weft (radians, positive closing).
    pub shear_angle: f64,
    /// Stretch λ of [warp, weft].
    pub fibre_stretch: [f64; 2],
    /// Fibre stress τ of [warp, weft] (MPa); zero when trusses carry them.
    pub fibre_stress: [f64; 2],
    /// The resin's rotated Kirchhoff stress τ̄ [11, 22, 12] in the element's
    /// rotated local frame (MPa).
    pub resin_stress: [f64; 3],
    /// Current fabric thickness h₀·λ₃ (mm).
    pub thickness: f64,
    /// Current unit directions of [warp, weft]: the area-weighted mean of
    /// the integration points' directions, normalised, then turned
    /// symmetrically about their bisector so that the angle between them is
    /// 90° − `shear_angle` (the mean of the points' shear; the plain means
    /// differ from that by a second-order amount when the shear varies
    /// over a quad).
    pub fibre_direction: [Vector3<f64>; 2],
}

/// A batch of membrane elements of one shape and one fabric section.
///
/// Each integration point works in a local frame whose first axis is the
/// reference warp, so τ̄ and the outputs are in fibre axes.
///
/// History per integration point ([`Self::history_stride`] values): the
/// right stretch U and the rotated stress τ̄ of the last committed state,
/// then the resin's Prony history. Build the start with
/// [`Self::initial_history`].
///
/// A batch's history is one flat array of [`Self::element_history_len`]
/// values per element, but not always element after element: in a batch
/// that runs on the lanes (resin-only quads) each whole block of four
/// elements keeps its values value-major, `[point][value][lane]`, so that
/// the kernel loads one value of four elements at once. Read an element's
/// history with [`Self::element_history`] (the point-after-point order
/// [`Self::element_force`], [`Self::element_tangent`], [`Self::element_output`]
/// and [`Self::element_energy`] take), write it with
/// [`Self::set_element_history`]; [`Self::history_to_element_major`] and
/// [`Self::history_from_element_major`] convert a whole batch's (for
/// files that must not depend on the kernels' order).
#[derive(Debug, Clone)]
pub struct MembraneBatch {
    /// The fabric.
    pub section: FabricSection,
    shape: MembraneShape,
    nodes: Vec<u32>,
    grad_n: Vec<Vector2<f64>>,
    area: Vec<f64>,
    nodal_area: Vec<f64>,
    stride: usize,
    /// The struct-of-arrays lanes of resin-only quads (none otherwise), see
    /// [`crate::quad_lanes`].
    lanes: Option<QuadLanes>,
    /// The elements whose history is in lane blocks (the first ones).
    blocked: usize,
}

/// One element's history, point after point, as [`MembraneBatch`]'s
/// element functions read it: borrowed where the batch stores it so,
/// copied out of its lane block otherwise. Dereferences to `[f64]`.
#[derive(Debug, Clone)]
pub struct ElementHistory<'h>(HistoryValues<'h>);

// The copy lives on the stack: reading an element allocates nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone)]
enum HistoryValues<'h> {
    Borrowed(&'h [f64]),
    Copied([f64; LANE_ELEMENT_HISTORY], usize),
}

impl std::ops::Deref for ElementHistory<'_> {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        match &self.0 {
            HistoryValues::Borrowed(h) => h,
            HistoryValues::Copied(values, len) => &values[..*len],
        }
    }
}

/// A step's Δt and its Prony factors (e^(−Δt/τₖ), gₖ·φ): computed once
/// per batch pass; empty to have each point compute them.
#[derive(Debug, Clone, Copy)]
struct Step<'a> {
    dt: f64,
    prony: &'a [(f64, f64)],
}

/// A point's history as [`MembraneBatch::point_response`] takes it: the
/// committed values only, or also where the new ones go (another array,
/// or over the committed ones).
enum PointHistory<'a> {
    Committed(&'a [f64]),
    Next {
        from: &'a [f64],
        to: &'a mut [f64],
    },
    InPlace(&'a mut [f64]),
    /// The committed values and the new ones the forces already wrote at
    /// the same positions: τ̄ is read, not updated again.
    Evaluated {
        from: &'a [f64],
        next: &'a [f64],
    },
}

impl PointHistory<'_> {
    /// The committed values.
    #[inline]
    fn committed(&self) -> &[f64] {
        match self {
            Self::Committed(h) | Self::Next { from: h, .. } | Self::Evaluated { from: h, .. } => h,
            Self::InPlace(h) => h,
        }
    }
}

/// What one integration point computes from a current F.
struct PointResponse {
    f: Matrix3x2<f64>,
    polar: PolarDecomposition,
    u_n: Matrix2<f64>,
    tau: Matrix2<f64>,
    fibres: [FibreKinematics; 2],
    /// (τ, E_t) of each family, zero when the fibres are not embedded.
    fibre_law: [(f64, f64); 2],
    /// Thickness-weighted first Piola stress h_m·P_resin + t_f·Σ P_fibre
    /// (+ the shear-locking law's, if any).
    p: Matrix3x2<f64>,
    /// The shear-locking law's state, when the resin has one.
    locking: Option<LockingPoint>,
}

#[inline]
fn sym_from(h: &[f64]) -> Matrix2<f64> {
    Matrix2::new(h[0], h[2], h[2], h[1])
}

#[inline]
fn sym_into(m: &Matrix2<f64>, h: &mut [f64]) {
    h[0] = m[(0, 0)];
    h[1] = m[(1, 1)];
    h[2] = m[(0, 1)];
}

impl MembraneBatch {
    /// Linear triangles on the reference positions `x0`; `warp` gives each
    /// element's reference warp direction in 3D (projected on each point's
    /// tangent plane; the weft is at 90° to it in that plane).
    pub fn triangles(
        section: FabricSection,
        x0: &[Vector3<f64>],
        nodes: Vec<[u32; 3]>,
        warp: &[Vector3<f64>],
    ) -> Result<Self, ElementError> {
        Self::build(
            section,
            MembraneShape::Triangle,
            x0,
            nodes.iter().flatten().copied().collect(),
            warp,
        )
    }

    /// Bilinear quads (nodes counter-clockwise) with 2×2 Gauss points; see
    /// [`Self::triangles`] for `warp`.
    pub fn quads(
        section: FabricSection,
        x0: &[Vector3<f64>],
        nodes: Vec<[u32; 4]>,
        warp: &[Vector3<f64>],
    ) -> Result<Self, ElementError> {
        Self::build(
            section,
            MembraneShape::Quad,
            x0,
            nodes.iter().flatten().copied().collect(),
            warp,
        )
    }

    fn build(
        section: FabricSection,
        shape: MembraneShape,
        x0: &[Vector3<f64>],
        nodes: Vec<u32>,
        warp: &[Vector3<f64>],
    ) -> Result<Self, ElementError> {
        let (nn, np) = (shape.nodes(), shape.points());
        let count = nodes.len() / nn;
        assert_eq!(warp.len(), count, "one warp direction per element");
        let mut grad_n = Vec::with_capacity(count * np * nn);
        let mut area = Vec::with_capacity(count * np);
        let mut nodal_area = vec![0.0; count * nn];
        for e in 0..count {
            let xe: Vec<Vector3<f64>> = nodes[e * nn..(e + 1) * nn]
                .iter()
                .map(|&i| x0[i as usize])
                .collect();
            for p in 0..np {
                let err = |cause| ElementError {
                    element: e,
                    point: p,
                    cause,
                };
                let (grads, shape_values, frame, a): (
                    Vec<Vector2<f64>>,
                    Vec<f64>,
                    LocalFrame,
                    f64,
                ) = match shape {
                    MembraneShape::Triangle => {
                        let rp = triangle_point(&[xe[0], xe[1], xe[2]]).map_err(err)?;
                        (rp.grad_n.to_vec(), rp.shape.to_vec(), rp.frame, rp.area)
                    }
                    MembraneShape::Quad => {
                        let (xi, eta) = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)][p];
                        let rp =
                            quad_point(&[xe[0], xe[1], xe[2], xe[3]], xi * GAUSS, eta * GAUSS, 1.0)
                                .map_err(err)?;
                        (rp.grad_n.to_vec(), rp.shape.to_vec(), rp.frame, rp.area)
                    }
                };
                let w = frame.local(&warp[e]);
                if w.norm().is_nan() || w.norm() <= 1e-6 * warp[e].norm() {
                    return Err(err(KinematicsError::DegenerateFibre { length: w.norm() }));
                }
                let w = w.normalize();
                // Turn the local frame onto the fibres: ∂N/∂X transforms as a vector.
                grad_n.extend(
                    grads
                        .iter()
                        .map(|g| Vector2::new(w.x * g.x + w.y * g.y, -w.y * g.x + w.x * g.y)),
                );
                area.push(a);
                for (na, sv) in nodal_area[e * nn..(e + 1) * nn]
                    .iter_mut()
                    .zip(&shape_values)
                {
                    *na += sv * a;
                }
            }
        }
        let stride = KINEMATIC_HISTORY + section.material.resin.history_len();
        // The lanes carry the paper's resin only: a shear-locking law (an
        // option beyond the paper) keeps its quads on the scalar path, and
        // so does a resin with more Prony terms than a pass's factor table.
        let lanes = (shape == MembraneShape::Quad
            && !section.embedded_fibres
            && section.material.resin.shear_locking.is_none()
            && section.material.resin.prony.len() <= PRONY_TABLE)
            .then(|| QuadLanes::new(&grad_n, &area, count));
        let blocked = lanes.as_ref().map_or(0, |l| l.blocks() * LANES);
        Ok(Self {
            section,
            shape,
            nodes,
            grad_n,
            area,
            nodal_area,
            stride,
            lanes,
            blocked,
        })
    }

    /// Number of elements.
    pub fn len(&self) -> usize {
        self.nodes.len() / self.shape.nodes()
    }

    /// Whether the batch is empty.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// Triangle or quad.
    pub fn shape(&self) -> MembraneShape {
        self.shape
    }

    /// The nodes of element `e`.
    pub fn element_nodes(&self, e: usize) -> &[u32] {
        let n = self.shape.nodes();
        &self.nodes[e * n..(e + 1) * n]
    }

    /// Renumbers the batch's nodes by `by`, for a batch built on its own
    /// nodes and then placed behind others' in one model (a laminate's
    /// plies): the reference data are relative to the nodes, so nothing
    /// else changes.
    pub fn shift_nodes(&mut self, by: u32) {
        for n in &mut self.nodes {
            *n += by;
        }
    }

    /// The reference area each node of element `e` represents (∫Nₐ dA), for
    /// lumping mass and loads.
    pub fn nodal_areas(&self, e: usize) -> &[f64] {
        let n = self.shape.nodes();
        &self.nodal_area[e * n..(e + 1) * n]
    }

    /// Reference area of element `e`.
    pub fn element_area(&self, e: usize) -> f64 {
        self.nodal_areas(e).iter().sum()
    }

    /// History values per integration point.
    pub fn history_stride(&self) -> usize {
        self.stride
    }

    /// History values per element.
    pub fn element_history_len(&self) -> usize {
        self.stride * self.shape.points()
    }

    /// The undeformed, stress-free history of the whole batch (U = I, τ̄ = 0).
    pub fn initial_history(&self) -> Vec<f64> {
        let mut h = vec![0.0; self.len() * self.element_history_len()];
        for e in 0..self.len() {
            for p in 0..self.shape.points() {
                h[self.history_index(e, p, 0)] = 1.0;
                h[self.history_index(e, p, 1)] = 1.0;
            }
        }
        h
    }

    /// Where value `i` of point `p` of element `e` is in the batch's
    /// history (see the layout in [`MembraneBatch`]).
    #[inline]
    fn history_index(&self, e: usize, p: usize, i: usize) -> usize {
        let at = p * self.stride + i;
        if e < self.blocked {
            (e / LANES) * LANES * self.element_history_len() + at * LANES + e % LANES
        } else {
            e * self.element_history_len() + at
        }
    }

    /// Element `e`'s history, point after point, from the batch's history
    /// `h` (whatever order the batch keeps it in).
    pub fn element_history<'h>(&self, h: &'h [f64], e: usize) -> ElementHistory<'h> {
        let eh = self.element_history_len();
        if e >= self.blocked {
            return ElementHistory(HistoryValues::Borrowed(&h[e * eh..(e + 1) * eh]));
        }
        let block = &h[(e / LANES) * LANES * eh..(e / LANES + 1) * LANES * eh];
        let mut values = [0.0; LANE_ELEMENT_HISTORY];
        for (j, v) in values[..eh].iter_mut().enumerate() {
            *v = block[j * LANES + e % LANES];
        }
        ElementHistory(HistoryValues::Copied(values, eh))
    }

    /// Writes element `e`'s history `values` (point after point, as
    /// [`Self::element_history`] gives it) into the batch's history `h`.
    pub fn set_element_history(&self, h: &mut [f64], e: usize, values: &[f64]) {
        let eh = self.element_history_len();
        assert_eq!(values.len(), eh, "one element's history");
        if e >= self.blocked {
            h[e * eh..(e + 1) * eh].copy_from_slice(values);
            return;
        }
        let block = &mut h[(e / LANES) * LANES * eh..(e / LANES + 1) * LANES * eh];
        for (j, v) in values.iter().enumerate() {
            block[j * LANES + e % LANES] = *v;
        }
    }

    /// The batch's history `h` element after element (each as
    /// [`Self::element_history`] gives it).
    pub fn history_to_element_major(&self, h: &[f64]) -> Vec<f64> {
        assert_eq!(h.len(), self.len() * self.element_history_len());
        (0..self.len())
            .flat_map(|e| self.element_history(h, e).to_vec())
            .collect()
    }

    /// The batch's history from `h` element after element: the inverse of
    /// [`Self::history_to_element_major`].
    pub fn history_from_element_major(&self, h: &[f64]) -> Vec<f64> {
        let eh = self.element_history_len();
        assert_eq!(h.len(), self.len() * eh);
        let mut out = vec![0.0; h.len()];
        for (e, values) in h.chunks_exact(eh.max(1)).enumerate() {
            self.set_element_history(&mut out, e, values);
        }
        out
    }

    #[inline]
    fn gather(&self, e: usize, x: &[Vector3<f64>]) -> [Vector3<f64>; MAX_NODES] {
        let mut xe = [Vector3::zeros(); MAX_NODES];
        for (slot, &i) in xe.iter_mut().zip(self.element_nodes(e)) {
            *slot = x[i as usize];
        }
        xe
    }

    /// ∂Nₐ/∂X of point `p` of element `e`, one per node, in the point's
    /// local frame turned onto the fibres: what the force pass multiplies
    /// the nodal positions by (for a port of the pass, e.g. drape-gpu).
    pub fn point_gradients(&self, e: usize, p: usize) -> &[Vector2<f64>] {
        self.point_grad(e, p)
    }

    /// The reference area (integration weight) of point `p` of element `e`.
    pub fn point_weight(&self, e: usize, p: usize) -> f64 {
        self.area[e * self.shape.points() + p]
    }

    #[inline]
    fn point_grad(&self, e: usize, p: usize) -> &[Vector2<f64>] {
        let (nn, np) = (self.shape.nodes(), self.shape.points());
        let start = (e * np + p) * nn;
        &self.grad_n[start..start + nn]
    }

    /// The resin's stress update of one point from τ̄ₙ over `d_eps`, its
    /// own history updated where it lies in `out` (a copy of step n's);
    /// writes U and τ̄ of step n+1 into `out` and returns τ̄.
    #[inline]
    fn update_point(
        &self,
        out: &mut [f64],
        u: &Matrix2<f64>,
        tau_n: Matrix2<f64>,
        d_eps: &Matrix2<f64>,
        step: Step<'_>,
    ) -> Matrix2<f64> {
        let resin = &self.section.material.resin;
        let mut tau = tau_n;
        if step.prony.len() == resin.prony.len() {
            resin.update_stress_with(&mut tau, &mut out[KINEMATIC_HISTORY..], d_eps, step.prony);
        } else {
            resin.update_stress(&mut tau, &mut out[KINEMATIC_HISTORY..], d_eps, step.dt);
        }
        sym_into(u, &mut out[0..3]);
        sym_into(&tau, &mut out[3..6]);
        tau
    }

    /// The response of point `p` of element `e` at positions `xe`, from the
    /// point history `history` (which also says whether and where the new
    /// history goes).
    #[inline]
    fn point_response(
        &self,
        e: usize,
        p: usize,
        xe: &[Vector3<f64>],
        history: PointHistory<'_>,
        step: Step<'_>,
    ) -> Result<PointResponse, KinematicsError> {
        let m = &self.section.material;
        let f = deformation_gradient(xe, self.point_grad(e, p));
        let polar = polar_decomposition(&f)?;
        let h_in = history.committed();
        let u_n = sym_from(&h_in[0..3]);
        let tau_n = sym_from(&h_in[3..6]);
        let d_eps = || rotated_strain_increment(&u_n, &polar.u);
        // Updating in place, U and τ̄ of step n are read above before
        // anything is written, and the resin updates its own history where
        // it lies: both ways give the same bits.
        let tau = match history {
            PointHistory::Committed(h) => {
                m.resin
                    .stress_after(&tau_n, &h[KINEMATIC_HISTORY..], &d_eps(), step.dt)
            }
            PointHistory::Next { from, to } => {
                to[KINEMATIC_HISTORY..].copy_from_slice(&from[KINEMATIC_HISTORY..]);
                self.update_point(to, &polar.u, tau_n, &d_eps(), step)
            }
            PointHistory::InPlace(h) => self.update_point(h, &polar.u, tau_n, &d_eps(), step),
            PointHistory::Evaluated { next, .. } => sym_from(&next[3..6]),
        };
        let fibres = if self.section.embedded_fibres {
            [
                fibre_stretch(&f, &FIBRES[0])?,
                fibre_stretch(&f, &FIBRES[1])?,
            ]
        } else {
            [FibreKinematics {
                stretch: 1.0,
                direction: Vector3::zeros(),
                log_strain: 0.0,
            }; 2]
        };
        let mut p_eff = f * (polar.u_inv * tau * polar.u_inv) * m.resin_thickness();
        let mut fibre_law = [(0.0, 0.0); 2];
        if self.section.embedded_fibres {
            let t_f = m.family_thickness();
            for (k, fib) in fibres.iter().enumerate() {
                let (s, e_t) = m.fibre.stress_and_tangent(fib.log_strain);
                fibre_law[k] = (s, e_t);
                // P_fibre = τ/λ·n ⊗ N with N the k-th local axis.
                let mut column = p_eff.column_mut(k);
                column += fib.direction * (t_f * s / fib.stretch);
            }
        }
        let locking = match &m.resin.shear_locking {
            Some(law) => {
                let point = LockingPoint::new(law, m.thickness, &f)?;
                point.add_stress(&mut p_eff);
                Some(point)
            }
            None => None,
        };
        Ok(PointResponse {
            f,
            polar,
            u_n,
            tau,
            fibres,
            fibre_law,
            p: p_eff,
            locking,
        })
    }

    /// The internal nodal forces fₐ = ∂W/∂xₐ of element `e` at positions
    /// `x`, from its history `h_in` (one element's worth); writes the new
    /// history into `h_out`. `forces` has one entry per node.
    #[inline]
    pub fn element_force(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        h_in: &[f64],
        h_out: &mut [f64],
        dt: f64,
        forces: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        self.element_force_with(e, x, Some(h_in), h_out, Step { dt, prony: &[] }, forces)
    }

    /// [`Self::element_force`] with the step's Prony factors; `h_in` the
    /// committed history, or None to update `h` in place (on an error the
    /// points before the failing one are then already updated).
    #[inline]
    fn element_force_with(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        h_in: Option<&[f64]>,
        h: &mut [f64],
        step: Step<'_>,
        forces: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        let nn = self.shape.nodes();
        let xe = self.gather(e, x);
        forces.fill(Vector3::zeros());
        for p in 0..self.shape.points() {
            let range = p * self.stride..(p + 1) * self.stride;
            let history = match h_in {
                Some(from) => PointHistory::Next {
                    from: &from[range.clone()],
                    to: &mut h[range],
                },
                None => PointHistory::InPlace(&mut h[range]),
            };
            let r = self
                .point_response(e, p, &xe[..nn], history, step)
                .map_err(|cause| ElementError {
                    element: e,
                    point: p,
                    cause,
                })?;
            let ip = e * self.shape.points() + p;
            add_nodal_forces(&r.p, self.point_grad(e, p), self.area[ip], forces);
        }
        Ok(())
    }

    /// The current normal of point `p` of element `e`, F·e₁ × F·e₂, times
    /// the point's reference area (so its length is the current area).
    fn weighted_normal(&self, e: usize, p: usize, x: &[Vector3<f64>]) -> Vector3<f64> {
        let xe = self.gather(e, x);
        let f = deformation_gradient(&xe[..self.shape.nodes()], self.point_grad(e, p));
        f.column(0).cross(&f.column(1)) * self.area[e * self.shape.points() + p]
    }

    /// Judges the orientation of a degenerate membrane point at positions
    /// `x` (see [`Degeneracy`](drape_kinematics::Degeneracy)): `inverted` when the point's normal opposes
    /// the summed normals of its element's other points (quads; a triangle
    /// has one point), `folded` when it opposes the summed normals of the
    /// elements sharing a node with it. Normals are compared as the mesh
    /// orients them, which is consistent for drape's blanks and for imported
    /// meshes (checked on import). Any other error is returned unchanged.
    ///
    /// A cold path (it scans the batch for neighbours): for failure
    /// messages.
    pub fn diagnose(&self, error: ElementError, x: &[Vector3<f64>]) -> ElementError {
        let KinematicsError::DegenerateMembrane(mut d) = error.cause else {
            return error;
        };
        let (e, p) = (error.element, error.point);
        if e >= self.len() || p >= self.shape.points() {
            return error;
        }
        let n = self.weighted_normal(e, p, x);
        let own: Vector3<f64> = (0..self.shape.points())
            .filter(|&q| q != p)
            .map(|q| self.weighted_normal(e, q, x))
            .sum();
        if self.shape.points() > 1 {
            d.inverted = Some(n.dot(&own) < 0.0);
        }
        let mine = self.element_nodes(e);
        let around: Vector3<f64> = (0..self.len())
            .filter(|&o| o != e && self.element_nodes(o).iter().any(|i| mine.contains(i)))
            .flat_map(|o| (0..self.shape.points()).map(move |q| (o, q)))
            .map(|(o, q)| self.weighted_normal(o, q, x))
            .sum();
        if around != Vector3::zeros() {
            d.folded = Some(n.dot(&around) < 0.0);
        }
        ElementError {
            cause: KinematicsError::DegenerateMembrane(d),
            ..error
        }
    }

    /// Writes every element's nodal forces into `slots` (nodes-per-element
    /// entries per element, in element order) and the new history into
    /// `h_out`, in parallel. A degenerate point's error is
    /// [diagnosed](Self::diagnose).
    pub fn forces_into(
        &self,
        x: &[Vector3<f64>],
        h_in: &[f64],
        h_out: &mut [f64],
        dt: f64,
        slots: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        assert_eq!(h_in.len(), self.element_history_len() * self.len());
        self.forces(x, Some(h_in), h_out, dt, slots)
    }

    /// [`Self::forces_into`] with the history `h` updated where it lies:
    /// the same forces and the same new history, bit for bit, with one
    /// history array read and written instead of one read and another
    /// written (the explicit step's largest memory stream).
    ///
    /// On an error `h` is partly updated (the elements and points before
    /// the failing one, in any order): the caller must keep a copy of the
    /// committed history to go back to (the explicit driver's guard keeps
    /// the last good state). A driver that evaluates trial states from one
    /// committed history (Newton iterations) uses [`Self::forces_into`].
    pub fn forces_in_place(
        &self,
        x: &[Vector3<f64>],
        h: &mut [f64],
        dt: f64,
        slots: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        self.forces(x, None, h, dt, slots)
    }

    /// [`Self::forces_into`] from `h_in`, or in place when None.
    fn forces(
        &self,
        x: &[Vector3<f64>],
        h_in: Option<&[f64]>,
        h: &mut [f64],
        dt: f64,
        slots: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        let (nn, eh) = (self.shape.nodes(), self.element_history_len());
        assert_eq!(slots.len(), nn * self.len());
        assert_eq!(h.len(), eh * self.len());
        let resin = &self.section.material.resin;
        let mut table = [(0.0, 0.0); PRONY_TABLE];
        let factors: &[(f64, f64)] = if resin.prony.len() <= table.len() {
            resin.prony_factors(dt, &mut table);
            &table[..resin.prony.len()]
        } else {
            &[]
        };
        let step = Step { dt, prony: factors };
        if let Some(lanes) = &self.lanes {
            // (A lane batch's Prony terms fit the table.)
            return self
                .forces_into_lanes(lanes, x, h_in, h, step, slots)
                .map_err(|error| self.diagnose(error, x));
        }
        lowest_error(
            slots
                .par_chunks_mut(nn)
                .zip(h.par_chunks_mut(eh))
                .with_min_len(MIN_CHUNK)
                .enumerate()
                .map(|(e, (f, out))| {
                    let from = h_in.map(|h| &h[e * eh..(e + 1) * eh]);
                    self.element_force_with(e, x, from, out, step, f)
                }),
        )
        .map_err(|error| self.diagnose(error, x))
    }

    /// [`Self::forces`] of a resin-only quad batch: whole blocks of
    /// [`LANES`] elements on the lanes (a block with a failing point again
    /// on the scalar path, which names it), the rest on the scalar path.
    fn forces_into_lanes(
        &self,
        lanes: &QuadLanes,
        x: &[Vector3<f64>],
        h_in: Option<&[f64]>,
        h: &mut [f64],
        step: Step<'_>,
        slots: &mut [Vector3<f64>],
    ) -> Result<(), ElementError> {
        let (nn, eh) = (self.shape.nodes(), self.element_history_len());
        let m = &self.section.material;
        let mut long_term = 1.0;
        for p in &m.resin.prony {
            long_term -= p.g;
        }
        let resin = ResinStep {
            wave_modulus: m.resin.wave_modulus(),
            poisson: m.resin.poisson,
            shear_modulus: m.resin.shear_modulus(),
            long_term,
            thickness: m.resin_thickness(),
            prony: step.prony,
        };
        let split = lanes.blocks() * LANES;
        let (block_slots, tail_slots) = slots.split_at_mut(split * nn);
        let (block_h, tail_h) = h.split_at_mut(split * eh);
        lowest_error(
            block_slots
                .par_chunks_mut(LANES * nn)
                .zip(block_h.par_chunks_mut(LANES * eh))
                .with_min_len(MIN_CHUNK / LANES)
                .enumerate()
                .map(|(b, (f, out))| {
                    let e0 = b * LANES;
                    let nodes = &self.nodes[e0 * nn..(e0 + LANES) * nn];
                    let from = h_in.map(|h| &h[e0 * eh..(e0 + LANES) * eh]);
                    if lanes.block_forces(b, nodes, x, from, out, self.stride, &resin, f) {
                        return Ok(());
                    }
                    // The cold path (the kernel wrote nothing): each
                    // lane's history out of the block and back (value `j`
                    // of lane `k` at `j·LANES + k`, see `history_index`).
                    let (mut prev, mut next) =
                        ([0.0; LANE_ELEMENT_HISTORY], [0.0; LANE_ELEMENT_HISTORY]);
                    for k in 0..LANES {
                        let committed = from.unwrap_or(out);
                        for (j, v) in prev[..eh].iter_mut().enumerate() {
                            *v = committed[j * LANES + k];
                        }
                        self.element_force_with(
                            e0 + k,
                            x,
                            Some(&prev[..eh]),
                            &mut next[..eh],
                            step,
                            &mut f[k * nn..(k + 1) * nn],
                        )?;
                        for (j, v) in next[..eh].iter().enumerate() {
                            out[j * LANES + k] = *v;
                        }
                    }
                    Ok(())
                }),
        )?;
        for (k, (f, out)) in tail_slots
            .chunks_mut(nn)
            .zip(tail_h.chunks_mut(eh))
            .enumerate()
        {
            let e = split + k;
            let from = h_in.map(|h| &h[e * eh..(e + 1) * eh]);
            self.element_force_with(e, x, from, out, step, f)?;
        }
        Ok(())
    }

    /// The tangent ∂f/∂x of element `e` (3n × 3n, node-major) at positions
    /// `x` from history `h_in` over a step `dt`: the exact derivative of the
    /// discrete update, material and geometric parts together.
    ///
    /// The resin is hypo-elastic, so the tangent is not symmetric in general
    /// (its τ̄ depends on the path through Uₙ); it is consistent, so Newton
    /// converges quadratically with it. The fibre part is symmetric.
    pub fn element_tangent(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        h_in: &[f64],
        dt: f64,
        k_out: &mut DMatrix<f64>,
    ) -> Result<(), ElementError> {
        self.element_tangent_with(e, x, h_in, dt, MembraneTangent::Exact, k_out)
    }

    /// [`Self::element_tangent`] with the resin's stress terms as `kind`
    /// says: [`MembraneTangent::TensionField`] replaces the resin stress τ̄
    /// by its tensile part wherever the tangent multiplies it (the
    /// geometric stiffness and the stress terms of dS), and leaves
    /// everything else exact; [`MembraneTangent::CompressionScaled`] adds
    /// back that fraction of the compressive part. The fibres' and the
    /// shear-locking terms are exact in all.
    pub fn element_tangent_with(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        h_in: &[f64],
        dt: f64,
        kind: MembraneTangent,
        k_out: &mut DMatrix<f64>,
    ) -> Result<(), ElementError> {
        self.tangent(e, x, h_in, None, dt, kind, k_out)
    }

    /// [`Self::element_tangent_with`] at positions `x` where the forces have
    /// already been evaluated from `h_in` over `dt` into the new history
    /// `h_next` (one element's worth of each; the batch's forces write it):
    /// the resin's stress τ̄ is read from `h_next` instead of being updated
    /// a second time, which is most of a point's response (the
    /// viscoelastic update's exponentials). The same matrix bit for bit,
    /// since the forces made the same update; an `h_next` from other
    /// positions gives a tangent that is not theirs.
    #[allow(clippy::too_many_arguments)]
    pub fn element_tangent_after_forces(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        h_in: &[f64],
        h_next: &[f64],
        dt: f64,
        kind: MembraneTangent,
        k_out: &mut DMatrix<f64>,
    ) -> Result<(), ElementError> {
        self.tangent(e, x, h_in, Some(h_next), dt, kind, k_out)
    }

    #[allow(clippy::too_many_arguments)]
    fn tangent(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        h_in: &[f64],
        h_next: Option<&[f64]>,
        dt: f64,
        kind: MembraneTangent,
        k_out: &mut DMatrix<f64>,
    ) -> Result<(), ElementError> {
        let nn = self.shape.nodes();
        let m = &self.section.material;
        let (h_m, t_f) = (m.resin_thickness(), m.family_thickness());
        let c_alg = m.resin.algorithmic_matrix(dt);
        let xe = self.gather(e, x);
        // Summed on the stack, column-major as `k_out`, and copied once:
        // no checked indexing of the heap matrix inside the loops.
        let d = 3 * nn;
        let mut k = [0.0; 9 * MAX_NODES * MAX_NODES];
        for p in 0..self.shape.points() {
            let range = p * self.stride..(p + 1) * self.stride;
            let h = &h_in[range.clone()];
            let history = match h_next {
                Some(next) => PointHistory::Evaluated {
                    from: h,
                    next: &next[range],
                },
                None => PointHistory::Committed(h),
            };
            let r = self
                .point_response(e, p, &xe[..nn], history, Step { dt, prony: &[] })
                .map_err(|cause| ElementError {
                    element: e,
                    point: p,
                    cause,
                })?;
            let ip = e * self.shape.points() + p;
            let grads = self.point_grad(e, p);
            let (u, u_inv) = (r.polar.u, r.polar.u_inv);
            let (det_u, tr_u) = (u.determinant(), u.trace());
            let mid = (r.u_n + u) * 0.5;
            let mid_inv = mid.try_inverse().expect("mean of two s.p.d. stretches");
            let l = (u - r.u_n) * mid_inv;
            let tau_t = match kind {
                MembraneTangent::Exact => r.tau,
                MembraneTangent::TensionField => tensile_part(&r.tau),
                MembraneTangent::CompressionScaled(kept) => {
                    let tension = tensile_part(&r.tau);
                    tension + (r.tau - tension) * kept
                }
            };
            let s = u_inv * tau_t * u_inv;
            // dP is linear in dF, and node b's component i moves F by
            // e_i ⊗ ∇N_b = Σ_c ∇N_b[c]·E_ic: dP of the six unit gradients
            // E_ic, combined per node, costs half of evaluating it for the
            // 3n columns. The resin's part, through dS, depends on dF only
            // through dC = dFᵀF + FᵀdF (symmetric 2×2): dS of the three
            // unit dC, combined per E_ic, halves that chain once more.
            let d_s_unit: [Matrix2<f64>; 3] = std::array::from_fn(|k| {
                let d_c = match k {
                    0 => Matrix2::new(1.0, 0.0, 0.0, 0.0),
                    1 => Matrix2::new(0.0, 0.0, 0.0, 1.0),
                    _ => Matrix2::new(0.0, 1.0, 1.0, 0.0),
                };
                // dU solves U·dU + dU·U = dC; for 2×2 in closed form.
                let d_u = (d_c + u_inv * d_c * u_inv * det_u) / (2.0 * tr_u);
                let d_u_inv = -u_inv * d_u * u_inv;
                let d_l = (d_u - l * d_u * 0.5) * mid_inv;
                let d_eps = (d_l + d_l.transpose()) * 0.5;
                let d_tau_v = c_alg
                    * nalgebra::Vector3::new(d_eps[(0, 0)], d_eps[(1, 1)], 2.0 * d_eps[(0, 1)]);
                let d_tau = Matrix2::new(d_tau_v[0], d_tau_v[2], d_tau_v[2], d_tau_v[1]);
                d_u_inv * tau_t * u_inv + u_inv * d_tau * u_inv + u_inv * tau_t * d_u_inv
            });
            let mut d_p_unit = [Matrix3x2::<f64>::zeros(); 6];
            for (ic, d_p_out) in d_p_unit.iter_mut().enumerate() {
                let (i, c) = (ic / 2, ic % 2);
                let mut d_f = Matrix3x2::zeros();
                d_f[(i, c)] = 1.0;
                // dC = E_icᵀ·F + Fᵀ·E_ic: row and column c get F's row i,
                // so dS takes two of the three unit dC, and dF·S is S's
                // row c in row i. Written out, these skip only products
                // and sums with exact zeros: the same bits as the general
                // products, with a fraction of the work.
                let d_s = if c == 0 {
                    d_s_unit[0] * (r.f[(i, 0)] + r.f[(i, 0)]) + d_s_unit[2] * r.f[(i, 1)]
                } else {
                    d_s_unit[1] * (r.f[(i, 1)] + r.f[(i, 1)]) + d_s_unit[2] * r.f[(i, 0)]
                };
                let mut d_p = r.f * d_s;
                for j in 0..2 {
                    d_p[(i, j)] += s[(c, j)];
                }
                let mut d_p = d_p * h_m;
                if self.section.embedded_fibres {
                    for (k, fib) in r.fibres.iter().enumerate() {
                        let (tau_f, e_t) = r.fibre_law[k];
                        let n_ref = &FIBRES[k];
                        let d_fn = d_f * n_ref;
                        let l2 = fib.stretch * fib.stretch;
                        let d_dir = fib.direction
                            * ((e_t - 2.0 * tau_f) / l2 * fib.direction.dot(&d_fn))
                            + d_fn * (tau_f / l2);
                        d_p += d_dir * n_ref.transpose() * t_f;
                    }
                }
                if let Some(point) = &r.locking {
                    point.add_stress_derivative(&d_f, &mut d_p);
                }
                *d_p_out = d_p * self.area[ip];
            }
            for (a, ga) in grads.iter().enumerate() {
                // (dP of E_ic)·∇N_a, for every i, c.
                let towards_a: [Vector3<f64>; 6] = std::array::from_fn(|ic| d_p_unit[ic] * ga);
                for (b, gb) in grads.iter().enumerate() {
                    for i in 0..3 {
                        let col = towards_a[2 * i] * gb[0] + towards_a[2 * i + 1] * gb[1];
                        let out = &mut k[(3 * b + i) * d + 3 * a..][..3];
                        for (o, v) in out.iter_mut().zip(col.iter()) {
                            *o += v;
                        }
                    }
                }
            }
        }
        k_out.copy_from_slice(&k[..d * d]);
        Ok(())
    }

    /// Strain energy of element `e`: the resin's stored energy (from the
    /// committed history `h`) and the fibres' (from positions `x`).
    pub fn element_energy(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        h: &[f64],
    ) -> Result<f64, ElementError> {
        let m = &self.section.material;
        let nn = self.shape.nodes();
        let xe = self.gather(e, x);
        let mut energy = 0.0;
        for p in 0..self.shape.points() {
            let ip = e * self.shape.points() + p;
            let hp = &h[p * self.stride..(p + 1) * self.stride];
            let mut w = m.resin_thickness()
                * m.resin
                    .stored_energy(&sym_from(&hp[3..6]), &hp[KINEMATIC_HISTORY..]);
            if self.section.embedded_fibres {
                let f = deformation_gradient(&xe[..nn], self.point_grad(e, p));
                for n_ref in &FIBRES {
                    let fib = fibre_stretch(&f, n_ref).map_err(|cause| ElementError {
                        element: e,
                        point: p,
                        cause,
                    })?;
                    w += m.family_thickness() * m.fibre.energy(fib.log_strain);
                }
            }
            if let Some(law) = &m.resin.shear_locking {
                let f = deformation_gradient(&xe[..nn], self.point_grad(e, p));
                let gamma = locking::shear_angle(&f).map_err(|cause| ElementError {
                    element: e,
                    point: p,
                    cause,
                })?;
                w += m.thickness * law.energy(gamma);
            }
            energy += w * self.area[ip];
        }
        Ok(energy)
    }

    /// Total strain energy of the batch with history `h`.
    pub fn energy(&self, x: &[Vector3<f64>], h: &[f64]) -> Result<f64, ElementError> {
        (0..self.len())
            .map(|e| self.element_energy(e, x, &self.element_history(h, e)))
            .sum()
    }

    /// The membrane stiffness κ (N/mm) that bounds the section's energy:
    /// ε:C:ε·h ≤ κ·|∇u|², κ = E_m·h_m/(1 − ν) (+ E_f·t_f if embedded). The
    /// plane-stress bound uses (tr ε)² ≤ 2|ε|²; the two fibre families load
    /// orthogonal strain components.
    pub fn stiffness_bound(&self) -> f64 {
        let m = &self.section.material;
        let mut kappa = m.resin.young / (1.0 - m.resin.poisson) * m.resin_thickness();
        if self.section.embedded_fibres {
            kappa += m.fibre.wave_modulus() * m.family_thickness();
        }
        kappa
    }

    /// The stable time step 2/ω of element `e` in its current shape, with a
    /// bound of its highest frequency on its own lumped masses (which bounds
    /// the mesh's, by the element eigenvalue inequality):
    /// ω² ≤ κ·λ_max(M^(−½)·L·M^(−½)), L = Σₚ Aₚ·∇Nₐ·∇N_b the element's
    /// Laplacian in the current shape, λ_max bounded by Gershgorin's circles.
    /// Within a factor of about 1.5 of the exact element step.
    pub fn element_stable_time_step(&self, e: usize, x: &[Vector3<f64>]) -> f64 {
        let nn = self.shape.nodes();
        let xe = self.gather(e, x);
        let mut lap = [[0.0; MAX_NODES]; MAX_NODES];
        let mut add = |grads: &[Vector2<f64>], area: f64| {
            for a in 0..nn {
                for b in 0..nn {
                    lap[a][b] += area * grads[a].dot(&grads[b]);
                }
            }
        };
        match self.shape {
            MembraneShape::Triangle => match triangle_point(&[xe[0], xe[1], xe[2]]) {
                Ok(p) => add(&p.grad_n, p.area),
                Err(_) => return 0.0,
            },
            MembraneShape::Quad => {
                for (xi, eta) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                    match quad_point(&[xe[0], xe[1], xe[2], xe[3]], xi * GAUSS, eta * GAUSS, 1.0) {
                        Ok(p) => add(&p.grad_n, p.area),
                        Err(_) => return 0.0,
                    }
                }
            }
        }
        let mut kappa = self.stiffness_bound();
        if let Some(law) = &self.section.material.resin.shear_locking {
            // ½·h·τ_s'·δγ² ≤ ½·(2h·τ_s')·|∇u|² at the element's current
            // shear angle (δγ² ≤ 2|∇u|²); a stiffening law's stress term
            // τ_s is below τ_s'·γ and inside the safety factor.
            let worst = (0..self.shape.points())
                .map(|p| {
                    let f = deformation_gradient(&xe[..nn], self.point_grad(e, p));
                    locking::shear_angle(&f).map_or(f64::INFINITY, |g| law.tangent(g.abs()))
                })
                .fold(0.0, f64::max);
            kappa += 2.0 * self.section.material.thickness * worst;
        }
        let rho_h = self.section.material.areal_density();
        let mass = self.nodal_areas(e);
        let lambda = (0..nn)
            .map(|a| {
                (0..nn)
                    .map(|b| lap[a][b].abs() / (rho_h * (mass[a] * mass[b]).sqrt()))
                    .sum::<f64>()
            })
            .fold(0.0, f64::max);
        2.0 / (kappa * lambda).sqrt()
    }

    /// The smallest stable time step of the batch (∞ when empty).
    pub fn stable_time_step(&self, x: &[Vector3<f64>]) -> f64 {
        (0..self.len())
            .into_par_iter()
            .with_min_len(MIN_CHUNK)
            .map(|e| self.element_stable_time_step(e, x))
            .reduce(|| f64::INFINITY, f64::min)
    }

    /// The smallest of [`Self::element_stable_time_step`] times `scale[e]`
    /// over the batch (∞ when empty), in parallel: what the explicit
    /// driver's stable-step estimate takes of a batch (`scale` its √(mass
    /// scale) per element). A resin-only quad batch computes its whole
    /// blocks on the lanes, with the same bits as element by element
    /// (tested); the minimum does not depend on the split.
    pub fn min_scaled_stable_time_step(&self, x: &[Vector3<f64>], scale: &[f64]) -> f64 {
        assert_eq!(scale.len(), self.len());
        let scalar = |e: usize| self.element_stable_time_step(e, x) * scale[e];
        let Some(lanes) = &self.lanes else {
            return (0..self.len())
                .into_par_iter()
                .with_min_len(MIN_CHUNK / 4)
                .map(scalar)
                .reduce(|| f64::INFINITY, f64::min);
        };
        let bound = StepBound {
            kappa: self.stiffness_bound(),
            rho_h: self.section.material.areal_density(),
            gauss: GAUSS,
        };
        let nn = self.shape.nodes();
        let blocks = (0..lanes.blocks())
            .into_par_iter()
            .with_min_len(MIN_CHUNK / LANES)
            .map(|b| {
                let (e0, e1) = (b * LANES * nn, (b + 1) * LANES * nn);
                let dt = lanes.block_stable_steps(
                    &self.nodes[e0..e1],
                    x,
                    &self.nodal_area[e0..e1],
                    bound,
                );
                let s = &scale[b * LANES..(b + 1) * LANES];
                (dt[0] * s[0])
                    .min(dt[1] * s[1])
                    .min(dt[2] * s[2])
                    .min(dt[3] * s[3])
            })
            .reduce(|| f64::INFINITY, f64::min);
        (self.blocked..self.len())
            .map(scalar)
            .fold(blocks, f64::min)
    }

    /// Output fields of element `e` at positions `x` with its committed
    /// history `h`.
    pub fn element_output(
        &self,
        e: usize,
        x: &[Vector3<f64>],
        h: &[f64],
    ) -> Result<MembraneOutput, ElementError> {
        let m = &self.section.material;
        let nn = self.shape.nodes();
        let xe = self.gather(e, x);
        let mut out = MembraneOutput::default();
        let total: f64 = (0..self.shape.points())
            .map(|p| self.area[e * self.shape.points() + p])
            .sum();
        for p in 0..self.shape.points() {
            let ip = e * self.shape.points() + p;
            let w = self.area[ip] / total;
            let err = |cause| ElementError {
                element: e,
                point: p,
                cause,
            };
            let f = deformation_gradient(&xe[..nn], self.point_grad(e, p));
            let polar = polar_decomposition(&f).map_err(err)?;
            let warp = fibre_stretch(&f, &FIBRES[0]).map_err(err)?;
            let weft = fibre_stretch(&f, &FIBRES[1]).map_err(err)?;
            out.shear_angle += w * shear_angle(
                &warp.direction,
                &weft.direction,
                std::f64::consts::FRAC_PI_2,
            );
            for (k, fib) in [warp, weft].iter().enumerate() {
                out.fibre_stretch[k] += w * fib.stretch;
                out.fibre_direction[k] += fib.direction * w;
                if self.section.embedded_fibres {
                    out.fibre_stress[k] += w * m.fibre.stress(fib.log_strain);
                }
            }
            let hp = &h[p * self.stride..(p + 1) * self.stride];
            for (o, v) in out.resin_stress.iter_mut().zip(&hp[3..6]) {
                *o += w * v;
            }
            out.thickness += w * m.thickness * m.resin.thickness_stretch(polar.area_stretch());
        }
        for d in &mut out.fibre_direction {
            // A mean of unit vectors within one element: never near zero
            // unless the element is folded, where any unit vector will do.
            *d = d.try_normalize(0.0).unwrap_or_else(Vector3::x);
        }
        // The angle between the mean directions is not 90° − (the mean
        // shear) when the shear varies over a quad (by a second-order
        // amount: up to 0.5° on the hemisphere's corner elements pulled by
        // springs). Turn both symmetrically about their bisector, in their
        // plane, to the angle 90° − γ: the directions written with the
        // element then show the shear written with it.
        let [w, f] = out.fibre_direction;
        if let (Some(bisector), Some(across)) =
            ((w + f).try_normalize(1e-12), (w - f).try_normalize(1e-12))
        {
            let half = 0.5 * (std::f64::consts::FRAC_PI_2 - out.shear_angle);
            let (s, c) = half.sin_cos();
            out.fibre_direction = [bisector * c + across * s, bisector * c - across * s];
        }
        Ok(out)
    }
}

#[cfg(test)]
mod tests;
