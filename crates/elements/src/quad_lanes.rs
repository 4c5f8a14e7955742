//! Resin-only quad membranes four elements at a time: the same arithmetic
//! as the scalar path ([`crate::MembraneBatch`]'s `point_response` and
//! `add_nodal_forces`), operation for operation, on [`f64x4`] lanes over
//! struct-of-arrays reference data.
//!
//! What it is for: the explicit force pass of the paper's representation
//! (yarns as trusses, the membrane carrying the resin only), the bulk of an
//! explicit step. What it is not: a second element. Each lane does exactly
//! the scalar path's operations in the scalar path's order, with no fused
//! multiply-add, so it gives the scalar path's results bit for bit (tested
//! on distorted, rotated and sheared elements with Prony history); anything
//! the lanes do not cover (triangles, embedded fibres, a resin with more
//! Prony terms than the batch's factor table) stays on the scalar path, and
//! so does any block with a degenerate or non-finite point, which the
//! scalar path then names.
//!
//! Instruction set: see [`crate::lanes`]; the kernel is compiled twice, for the target's baseline (two SSE2 operations per
//! lane operation on x86-64) and with AVX2 enabled (one), and
//! [`QuadLanes::block_forces`] picks the second at run time when the
//! processor has it. Neither contracts a multiply and an add into an FMA,
//! so both give the same bits.

use drape_kinematics::Vector2;

use crate::lanes::{LANES, f64x4};
use nalgebra::Vector3;

const NODES: usize = 4;
const POINTS: usize = 4;
/// As in `drape_kinematics::right_stretch`.
const DEGENERATE_DET_C: f64 = 1e-14;

/// ∂N/∂X and point areas of the batch's whole blocks of [`LANES`]
/// elements, lane k holding element `LANES·b + k`.
#[derive(Debug, Clone)]
pub(crate) struct QuadLanes {
    /// Per (block, point, node): ∂N/∂X₁ and ∂N/∂X₂.
    grad: Vec<[f64x4; 2]>,
    /// Per (block, point): the point's reference area (weight).
    area: Vec<f64x4>,
}

/// The resin's constants and the step's Prony factors.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ResinStep<'a> {
    /// Plane-stress wave modulus E/(1 − ν²).
    pub wave_modulus: f64,
    pub poisson: f64,
    pub shear_modulus: f64,
    /// 1 − Σ gₖ, summed as the scalar update sums it.
    pub long_term: f64,
    /// Resin thickness h_m.
    pub thickness: f64,
    /// (e^(−Δt/τₖ), gₖ·φₖ) per Prony term; empty for an elastic resin.
    pub prony: &'a [(f64, f64)],
}

#[inline(always)]
fn lanes(v: [f64; LANES]) -> f64x4 {
    f64x4::new(v)
}

impl QuadLanes {
    /// The lanes of `count` quads with ∂N/∂X `grad_n` (per element, point,
    /// node) and point areas `area` (per element, point); a last partial
    /// block is left to the scalar path.
    pub(crate) fn new(grad_n: &[Vector2<f64>], area: &[f64], count: usize) -> Self {
        let blocks = count / LANES;
        let mut grad = Vec::with_capacity(blocks * POINTS * NODES);
        let mut areas = Vec::with_capacity(blocks * POINTS);
        for b in 0..blocks {
            for p in 0..POINTS {
                for a in 0..NODES {
                    let g =
                        |k: usize, c: usize| grad_n[((LANES * b + k) * POINTS + p) * NODES + a][c];
                    grad.push([
                        lanes([g(0, 0), g(1, 0), g(2, 0), g(3, 0)]),
                        lanes([g(0, 1), g(1, 1), g(2, 1), g(3, 1)]),
                    ]);
                }
                let w = |k: usize| area[(LANES * b + k) * POINTS + p];
                areas.push(lanes([w(0), w(1), w(2), w(3)]));
            }
        }
        Self { grad, area: areas }
    }

    /// ∂N/∂X of the nodes at point `p` of block `b`.
    #[inline(always)]
    fn point_grad(&self, b: usize, p: usize) -> &[[f64x4; 2]] {
        &self.grad[(b * POINTS + p) * NODES..(b * POINTS + p + 1) * NODES]
    }

    /// Whole blocks.
    pub(crate) fn blocks(&self) -> usize {
        self.area.len() / POINTS
    }

    /// Forces and new history of block `b`: `nodes` its elements' nodes
    /// (4 per element), `h` the block's history (`stride` values per
    /// point, value-major: value `i` of point `p` of lane `k` at
    /// `(p·stride + i)·4 + k`), the committed one read from `h_in`, or
    /// from `h` itself when None (advanced in place), the new one written
    /// into `h`; `slots` their nodal forces (4 per element). Returns
    /// false, having written nothing, if a point of the block is
    /// non-finite or degenerate: the caller then runs the block on the
    /// scalar path, which names the element.
    #[allow(clippy::too_many_arguments)]
    #[inline]
    pub(crate) fn block_forces(
        &self,
        b: usize,
        nodes: &[u32],
        x: &[Vector3<f64>],
        h_in: Option<&[f64]>,
        h: &mut [f64],
        stride: usize,
        resin: &ResinStep<'_>,
        slots: &mut [Vector3<f64>],
    ) -> bool {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (checked just above).
            return unsafe { self.block_forces_avx2(b, nodes, x, h_in, h, stride, resin, slots) };
        }
        self.block_forces_lanes(b, nodes, x, h_in, h, stride, resin, slots)
    }

    /// [`Self::block_forces`] compiled with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    #[allow(clippy::too_many_arguments)]
    fn block_forces_avx2(
        &self,
        b: usize,
        nodes: &[u32],
        x: &[Vector3<f64>],
        h_in: Option<&[f64]>,
        h: &mut [f64],
        stride: usize,
        resin: &ResinStep<'_>,
        slots: &mut [Vector3<f64>],
    ) -> bool {
        self.block_forces_lanes(b, nodes, x, h_in, h, stride, resin, slots)
    }

    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn block_forces_lanes(
        &self,
        b: usize,
        nodes: &[u32],
        x: &[Vector3<f64>],
        h_in: Option<&[f64]>,
        h: &mut [f64],
        stride: usize,
        resin: &ResinStep<'_>,
        slots: &mut [Vector3<f64>],
    ) -> bool {
        let eh = stride * POINTS;
        // Fixed-size views and explicit loops, no `array::from_fn`: its
        // closures are generic code compiled without this function's target
        // features, so they were not inlined and every lane crossed a call.
        let nodes: &[u32; LANES * NODES] = nodes.try_into().expect("a block's nodes");
        let slots: &mut [Vector3<f64>; LANES * NODES] =
            slots.try_into().expect("a block's force slots");
        assert!(h.len() == LANES * eh && h_in.is_none_or(|h_in| h_in.len() == LANES * eh));
        let used = if resin.prony.is_empty() {
            6
        } else {
            7 + resin.prony.len()
        };
        assert!(stride >= used);
        // Nodal positions, [node][component] across the lanes.
        let mut xe = [[f64x4::splat(0.0); 3]; NODES];
        for (a, xa) in xe.iter_mut().enumerate() {
            for k in 0..LANES {
                let p = &x[nodes[k * NODES + a] as usize];
                for (c, v) in xa.iter_mut().enumerate() {
                    v.0[k] = p[c];
                }
            }
        }
        let zero = f64x4::splat(0.0);
        let half = f64x4::splat(0.5);
        // First every point's F and C, and the block's check, so that a
        // block that goes to the scalar path has written nothing (its
        // history may be the committed one, advanced in place).
        // (Built point by point, not zeroed and filled: a memset call.)
        let points = [
            point_gradient(self.point_grad(b, 0), &xe),
            point_gradient(self.point_grad(b, 1), &xe),
            point_gradient(self.point_grad(b, 2), &xe),
            point_gradient(self.point_grad(b, 3), &xe),
        ];
        // One test stands for the scalar path's finiteness and degeneracy
        // checks: tr C is the sum of the squares of F, so a NaN in F, C or
        // det C fails the comparison, and an infinite (or overflowing)
        // entry makes its right side +∞, which nothing exceeds. Every
        // point it passes is one the scalar path accepts.
        let mut ok = true;
        for (_, [_, _, _, det_c, tr_c]) in &points {
            ok &= det_c.all_gt(f64x4::splat(DEGENERATE_DET_C) * *tr_c * *tr_c);
        }
        if !ok {
            return false;
        }
        let mut force = [[zero; 3]; NODES];
        for (p, (f, [c00, c01, c11, det_c, tr_c])) in points.iter().enumerate() {
            let grad = self.point_grad(b, p);
            let (c00, c01, c11, det_c, tr_c) = (*c00, *c01, *c11, *det_c, *tr_c);
            let det_u = det_c.sqrt();
            let s = (tr_c + f64x4::splat(2.0) * det_u).sqrt();
            let (u00, u01, u11) = ((c00 + det_u) / s, (c01 + zero) / s, (c11 + det_u) / s);
            let tr_u = u00 + u11;
            let (ui00, ui01, ui11) = (
                (tr_u - u00) / det_u,
                (zero - u01) / det_u,
                (tr_u - u11) / det_u,
            );
            // Rotated strain increment from the committed U. The block's
            // history is value-major ([point][value][lane], see
            // `MembraneBatch`'s layout), so each value of the four lanes
            // is one load; the first six as a fixed array, one bounds
            // check. Every committed value of the point is read before the
            // point's new ones are written (the same place when in place).
            let range = p * stride * LANES..(p * stride + used) * LANES;
            let (from, point) = (h_in.map(|h| &h[range.clone()]), &mut h[range]);
            let fixed: [f64; 6 * LANES] = from.unwrap_or(point)[..6 * LANES]
                .try_into()
                .expect("a point's six values");
            let un = |i: usize| {
                lanes([
                    fixed[LANES * i],
                    fixed[LANES * i + 1],
                    fixed[LANES * i + 2],
                    fixed[LANES * i + 3],
                ])
            };
            let (n00, n11, n01) = (un(0), un(1), un(2));
            let (m00, m01, m11) = ((n00 + u00) * half, (n01 + u01) * half, (n11 + u11) * half);
            let det_m = m00 * m11 - m01 * m01;
            let tr_m = m00 + m11;
            let (mi00, mi01, mi11) = (
                (tr_m - m00) / det_m,
                (zero - m01) / det_m,
                (tr_m - m11) / det_m,
            );
            let (d00, d01, d11) = (u00 - n00, u01 - n01, u11 - n11);
            let l00 = d00 * mi00 + d01 * mi01;
            let l01 = d00 * mi01 + d01 * mi11;
            let l10 = d01 * mi00 + d11 * mi01;
            let l11 = d01 * mi01 + d11 * mi11;
            let e00 = (l00 + l00) * half;
            let e11 = (l11 + l11) * half;
            let e01 = (l01 + l10) * half;
            let e10 = (l10 + l01) * half;
            // The resin: elastic normal stress, relaxing shear.
            let k = f64x4::splat(resin.wave_modulus);
            let nu = f64x4::splat(resin.poisson);
            let t00 = un(3) + k * (e00 + nu * e11);
            let t11 = un(4) + k * (nu * e00 + e11);
            let d_s0 = f64x4::splat(resin.shear_modulus) * (e01 + e10);
            let t01 = if resin.prony.is_empty() {
                un(5) + d_s0
            } else {
                // The shear stress and Prony terms, each read before its
                // new value is written over it.
                let committed = |point: &[f64], i: usize| load(from.unwrap_or(point), 6 + i);
                let s0 = committed(point, 0) + d_s0;
                let mut relaxing = zero;
                for (q, &(decay, weight)) in resin.prony.iter().enumerate() {
                    let qk =
                        f64x4::splat(decay) * committed(point, 1 + q) + f64x4::splat(weight) * d_s0;
                    relaxing += qk;
                    store(point, 7 + q, qk);
                }
                store(point, 6, s0);
                f64x4::splat(resin.long_term) * s0 + relaxing
            };
            let out_fixed: &mut [f64; 6 * LANES] = (&mut point[..6 * LANES])
                .try_into()
                .expect("a point's six values");
            for (i, v) in [u00, u11, u01, t00, t11, t01].into_iter().enumerate() {
                out_fixed[LANES * i..LANES * (i + 1)].copy_from_slice(&v.0);
            }
            // P = F·(U⁻¹·τ̄·U⁻¹)·h_m.
            let a00 = ui00 * t00 + ui01 * t01;
            let a01 = ui00 * t01 + ui01 * t11;
            let a10 = ui01 * t00 + ui11 * t01;
            let a11 = ui01 * t01 + ui11 * t11;
            let b00 = a00 * ui00 + a01 * ui01;
            let b01 = a00 * ui01 + a01 * ui11;
            let b10 = a10 * ui00 + a11 * ui01;
            let b11 = a10 * ui01 + a11 * ui11;
            let h_m = f64x4::splat(resin.thickness);
            let mut piola = [[zero; 2]; 3];
            for (pi, fi) in piola.iter_mut().zip(f) {
                *pi = [
                    (fi[0] * b00 + fi[1] * b10) * h_m,
                    (fi[0] * b01 + fi[1] * b11) * h_m,
                ];
            }
            // fₐ += (P·∇Nₐ)·A.
            let area = self.area[b * POINTS + p];
            for (fa, ga) in force.iter_mut().zip(grad) {
                for i in 0..3 {
                    fa[i] += (piola[i][0] * ga[0] + piola[i][1] * ga[1]) * area;
                }
            }
        }
        for (a, fa) in force.iter().enumerate() {
            for k in 0..LANES {
                slots[k * NODES + a] = Vector3::new(fa[0].0[k], fa[1].0[k], fa[2].0[k]);
            }
        }
        true
    }
}

/// F = Σₐ xₐ ⊗ ∇Nₐ at a point (from zero, node by node), and C = FᵀF's
/// C₁₁, C₁₂, C₂₂, det C, tr C as `right_stretch` forms them. A function
/// with `inline(always)`, not a closure, so that it is inlined into the
/// kernel's AVX2 build.
#[inline(always)]
fn point_gradient(grad: &[[f64x4; 2]], xe: &[[f64x4; 3]; NODES]) -> ([[f64x4; 2]; 3], [f64x4; 5]) {
    let mut f = [[f64x4::splat(0.0); 2]; 3];
    for (xa, ga) in xe.iter().zip(grad) {
        for i in 0..3 {
            for j in 0..2 {
                f[i][j] += xa[i] * ga[j];
            }
        }
    }
    let c00 = f[0][0] * f[0][0] + f[1][0] * f[1][0] + f[2][0] * f[2][0];
    let c01 = f[0][0] * f[0][1] + f[1][0] * f[1][1] + f[2][0] * f[2][1];
    let c11 = f[0][1] * f[0][1] + f[1][1] * f[1][1] + f[2][1] * f[2][1];
    let det_c = c00 * c11 - c01 * c01;
    let tr_c = c00 + c11;
    (f, [c00, c01, c11, det_c, tr_c])
}

/// The natural-coordinate derivatives (∂Nₐ/∂ξ, ∂Nₐ/∂η) of the 2×2 Gauss
/// points, computed as `drape_kinematics::quad_point` computes them.
fn gauss_derivatives(gauss: f64) -> [([f64; NODES], [f64; NODES]); POINTS] {
    let mut out = [([0.0; NODES], [0.0; NODES]); POINTS];
    for (o, (xi, eta)) in out
        .iter_mut()
        .zip([(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)])
    {
        let (xi, eta): (f64, f64) = (xi * gauss, eta * gauss);
        let (xm, xp, em, ep) = (1.0 - xi, 1.0 + xi, 1.0 - eta, 1.0 + eta);
        *o = (
            [-0.25 * em, 0.25 * em, 0.25 * ep, -0.25 * ep],
            [-0.25 * xm, -0.25 * xp, 0.25 * xp, 0.25 * xm],
        );
    }
    out
}

/// The constants of a resin-only quad batch's stable-step bound (see
/// `MembraneBatch::element_stable_time_step`).
#[derive(Debug, Clone, Copy)]
pub(crate) struct StepBound {
    /// The membrane stiffness κ (N/mm).
    pub kappa: f64,
    /// Areal density ρh.
    pub rho_h: f64,
    /// The 2×2 Gauss abscissa.
    pub gauss: f64,
}

impl QuadLanes {
    /// The stable steps of a block's four quads at positions `x` (`nodes`
    /// their nodes, `nodal_area` their nodes' reference areas, 4 per
    /// element): `MembraneBatch::element_stable_time_step` lane by lane,
    /// operation for operation (`quad_point`'s frame, Jacobian and
    /// gradients at each Gauss point, the Laplacian, Gershgorin's bound),
    /// and 0 for a quad whose current shape has a degenerate or non-finite
    /// point, as there.
    #[inline]
    pub(crate) fn block_stable_steps(
        &self,
        nodes: &[u32],
        x: &[Vector3<f64>],
        nodal_area: &[f64],
        bound: StepBound,
    ) -> [f64; LANES] {
        #[cfg(target_arch = "x86_64")]
        if std::arch::is_x86_feature_detected!("avx2") {
            // SAFETY: the processor has AVX2 (checked just above).
            return unsafe { block_stable_steps_avx2(nodes, x, nodal_area, bound) };
        }
        block_stable_steps_lanes(nodes, x, nodal_area, bound)
    }
}

/// [`block_stable_steps_lanes`] compiled with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn block_stable_steps_avx2(
    nodes: &[u32],
    x: &[Vector3<f64>],
    nodal_area: &[f64],
    bound: StepBound,
) -> [f64; LANES] {
    block_stable_steps_lanes(nodes, x, nodal_area, bound)
}

/// Three components of four lanes.
type Vec3x4 = [f64x4; 3];

/// nalgebra's 3-vector dot, (a₀b₀ + a₁b₁) + a₂b₂.
#[inline(always)]
fn dot3(a: &Vec3x4, b: &Vec3x4) -> f64x4 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// nalgebra's cross product.
#[inline(always)]
fn cross3(a: &Vec3x4, b: &Vec3x4) -> Vec3x4 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

#[inline(always)]
fn divided3(a: &Vec3x4, d: f64x4) -> Vec3x4 {
    [a[0] / d, a[1] / d, a[2] / d]
}

/// [`QuadLanes::block_stable_steps`] for the target's baseline.
#[inline(always)]
pub(crate) fn block_stable_steps_lanes(
    nodes: &[u32],
    x: &[Vector3<f64>],
    nodal_area: &[f64],
    bound: StepBound,
) -> [f64; LANES] {
    let nodes: &[u32; LANES * NODES] = nodes.try_into().expect("a block's nodes");
    let nodal_area: &[f64; LANES * NODES] = nodal_area.try_into().expect("a block's areas");
    let zero = f64x4::splat(0.0);
    let mut xe = [[zero; 3]; NODES];
    for (a, xa) in xe.iter_mut().enumerate() {
        for k in 0..LANES {
            let p = &x[nodes[k * NODES + a] as usize];
            for (c, v) in xa.iter_mut().enumerate() {
                v.0[k] = p[c];
            }
        }
    }
    let mut ok = [true; LANES];
    let mut lap = [[zero; NODES]; NODES];
    for (d_xi, d_eta) in gauss_derivatives(bound.gauss) {
        // reference_point: the tangents, the frame, J, ∇N and the area.
        let (mut g1, mut g2) = ([zero; 3], [zero; 3]);
        for (a, xa) in xe.iter().enumerate() {
            let (s1, s2) = (f64x4::splat(d_xi[a]), f64x4::splat(d_eta[a]));
            for c in 0..3 {
                g1[c] += xa[c] * s1;
                g2[c] += xa[c] * s2;
            }
        }
        let n = cross3(&g1, &g2);
        let size = dot3(&n, &n).sqrt();
        let (n1, n2) = (dot3(&g1, &g1).sqrt(), dot3(&g2, &g2).sqrt());
        let small = f64x4::splat(1e-12) * n1 * n2;
        for (ok, (size, small)) in ok.iter_mut().zip(size.0.into_iter().zip(small.0)) {
            // As `LocalFrame::from_tangents`: a NaN bound passes there too.
            let degenerate = size <= small;
            *ok &= size.is_finite() && !degenerate;
        }
        let normal = divided3(&n, size);
        let e1 = divided3(&g1, n1);
        let e2 = cross3(&normal, &e1);
        let (j00, j10) = (dot3(&e1, &g1), dot3(&e2, &g1));
        let (j01, j11) = (dot3(&e1, &g2), dot3(&e2, &g2));
        let det_j = j00 * j11 - j10 * j01;
        let (t00, t01, t10, t11) = (j11 / det_j, -j10 / det_j, -j01 / det_j, j00 / det_j);
        let mut grad = [[zero; 2]; NODES];
        for (a, g) in grad.iter_mut().enumerate() {
            let (s1, s2) = (f64x4::splat(d_xi[a]), f64x4::splat(d_eta[a]));
            *g = [t00 * s1 + t01 * s2, t10 * s1 + t11 * s2];
        }
        // The area is det J (weight 1). L is symmetric to the bit (the
        // products and sums commute), so its upper half is computed and
        // mirrored below.
        for a in 0..NODES {
            for b in a..NODES {
                lap[a][b] += det_j * (grad[a][0] * grad[b][0] + grad[a][1] * grad[b][1]);
            }
        }
    }
    #[allow(clippy::needless_range_loop)] // (a mirror: both orders index it)
    for a in 1..NODES {
        for b in 0..a {
            lap[a][b] = lap[b][a];
        }
    }
    let rho_h = f64x4::splat(bound.rho_h);
    let area_of = |a: usize| {
        lanes([
            nodal_area[a],
            nodal_area[NODES + a],
            nodal_area[2 * NODES + a],
            nodal_area[3 * NODES + a],
        ])
    };
    // ρh·√(mₐ·m_b), symmetric as L.
    let mut scale = [[zero; NODES]; NODES];
    #[allow(clippy::needless_range_loop)] // (a mirror: both orders index it)
    for a in 0..NODES {
        for b in a..NODES {
            scale[a][b] = rho_h * (area_of(a) * area_of(b)).sqrt();
            scale[b][a] = scale[a][b];
        }
    }
    let mut lambda = zero;
    for (row, scale) in lap.iter().zip(&scale) {
        let mut sum = zero;
        for (l, s) in row.iter().zip(scale) {
            sum += l.abs() / *s;
        }
        lambda = lambda.max(sum);
    }
    let dt = f64x4::splat(2.0) / (f64x4::splat(bound.kappa) * lambda).sqrt();
    let mut out = dt.0;
    for k in 0..LANES {
        if !ok[k] {
            out[k] = 0.0;
        }
    }
    out
}

/// Value `i` of the four lanes in a value-major run of history `h`.
#[inline(always)]
fn load(h: &[f64], i: usize) -> f64x4 {
    let v: &[f64; LANES] = h[LANES * i..LANES * (i + 1)]
        .try_into()
        .expect("four lanes");
    f64x4::new(*v)
}

/// Writes value `i` of the four lanes into a value-major run of history `h`.
#[inline(always)]
fn store(h: &mut [f64], i: usize, v: f64x4) {
    h[LANES * i..LANES * (i + 1)].copy_from_slice(&v.0);
}
