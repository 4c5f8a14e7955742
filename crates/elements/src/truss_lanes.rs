//! Trusses four at a time: [`crate::TrussBatch::element_force`]'s
//! arithmetic, operation for operation, on [`f64x4`] lanes.
//!
//! What it is for: the truss pass of the explicit step (the paper's yarns),
//! a third of the hemisphere step before it. What it is not: a second
//! truss. Each lane does the scalar path's operations in its order (no
//! fused multiply-add), and the logarithm ε = ln λ and e^(−x) − 1 are the
//! same `f64::ln`/`f64::exp_m1` calls per lane, so the forces equal the
//! scalar path's bit for bit (tested over the law's branches). The crimp
//! law's branches (compression, Taylor series near ε = 0, closed form,
//! uncrimped) are evaluated for every lane and selected lane by lane; the
//! closed form's `exp_m1` is only called for the lanes that use it. A
//! block with a non-finite or collapsed truss is left to the scalar path,
//! which names it. A confined yarn's compressed lanes call the scalar
//! `FibreLaw::confined_stress` per lane (its walls are rare and its
//! branches many; the same bits by construction).
//!
//! Instruction set: see [`crate::lanes`]; compiled for the baseline and
//! with AVX2, picked at run time.

use drape_constitutive::FibreLaw;
use nalgebra::Vector3;

use crate::lanes::{LANES, f64x4};

/// The forces [f₁, f₂] = [−N·n, N·n] of the block of [`LANES`] trusses
/// `nodes` (reference lengths `length`, sections `section`) into `slots`
/// (2 per truss). Returns false, having written nothing meaningful, if a
/// truss of the block is non-finite or collapsed (the caller then runs the
/// block on the scalar path, which names it).
#[inline]
pub(crate) fn block_forces(
    law: &FibreLaw,
    nodes: &[[u32; 2]],
    length: &[f64],
    section: &[f64],
    clearance: Option<&[f64]>,
    x: &[Vector3<f64>],
    slots: &mut [Vector3<f64>],
) -> bool {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx2") {
        // SAFETY: the processor has AVX2 (checked just above).
        return unsafe { block_forces_avx2(law, nodes, length, section, clearance, x, slots) };
    }
    block_forces_lanes(law, nodes, length, section, clearance, x, slots)
}

/// [`block_forces`] compiled with AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn block_forces_avx2(
    law: &FibreLaw,
    nodes: &[[u32; 2]],
    length: &[f64],
    section: &[f64],
    clearance: Option<&[f64]>,
    x: &[Vector3<f64>],
    slots: &mut [Vector3<f64>],
) -> bool {
    block_forces_lanes(law, nodes, length, section, clearance, x, slots)
}

/// [`block_forces`] for the target's baseline instruction set.
#[inline(always)]
pub(crate) fn block_forces_lanes(
    law: &FibreLaw,
    nodes: &[[u32; 2]],
    length: &[f64],
    section: &[f64],
    clearance: Option<&[f64]>,
    x: &[Vector3<f64>],
    slots: &mut [Vector3<f64>],
) -> bool {
    let nodes: &[[u32; 2]; LANES] = nodes.try_into().expect("a block's trusses");
    let clearance: Option<&[f64; LANES]> =
        clearance.map(|c| c.try_into().expect("a block's clearances"));
    let length: &[f64; LANES] = length.try_into().expect("a block's lengths");
    let section: &[f64; LANES] = section.try_into().expect("a block's sections");
    let slots: &mut [Vector3<f64>; 2 * LANES] = slots.try_into().expect("a block's slots");
    // d = x₂ − x₁, across the lanes.
    let mut d = [f64x4::splat(0.0); 3];
    for (k, &[i, j]) in nodes.iter().enumerate() {
        let (p, q) = (&x[i as usize], &x[j as usize]);
        for (c, dc) in d.iter_mut().enumerate() {
            dc.0[k] = q[c] - p[c];
        }
    }
    // `truss_stretch`: l = |d| (summed as nalgebra's norm sums), checks,
    // λ = l/L₀, n = d/l.
    let l = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    let reference = f64x4::new(*length);
    let mut ok = l.all_finite();
    for k in 0..LANES {
        let (l, r) = (l.0[k], reference.0[k]);
        ok &= r > 0.0 && r.is_finite() && l > 1e-12 * r;
    }
    if !ok {
        return false;
    }
    let stretch = l / reference;
    let n = [d[0] / l, d[1] / l, d[2] / l];
    let s = stretch.0;
    let eps = f64x4::new([s[0].ln(), s[1].ln(), s[2].ln(), s[3].ln()]);
    let tau = stress(law, eps, clearance);
    // N = A₀·τ/λ, f₂ = −f₁ = N·n.
    let force = f64x4::new(*section) * tau / stretch;
    for k in 0..LANES {
        let f = Vector3::new(
            n[0].0[k] * force.0[k],
            n[1].0[k] * force.0[k],
            n[2].0[k] * force.0[k],
        );
        slots[2 * k] = -f;
        slots[2 * k + 1] = f;
    }
    true
}

/// `FibreLaw::stress` lane by lane: every branch in the scalar law's
/// operations, the lane's own branch selected.
#[inline(always)]
fn stress(law: &FibreLaw, eps: f64x4, clearance: Option<&[f64; LANES]>) -> f64x4 {
    let e = law.modulus;
    let zero = f64x4::splat(0.0);
    let compressed = eps.le(zero);
    let mut compression = f64x4::splat(law.compression_factor * e) * eps;
    if law.buckling_stress > 0.0 {
        // The buckled column's square roots, only in the compressed lanes,
        // by the scalar law's own function (the same bits); confined by
        // the lane's clearance when there is one.
        for (k, ((out, &eps), &squeezed)) in compression
            .0
            .iter_mut()
            .zip(&eps.0)
            .zip(&compressed)
            .enumerate()
        {
            *out = match (squeezed, clearance) {
                (false, _) => 0.0,
                (true, Some(c)) => law.confined_stress(eps, c[k]),
                (true, None) => law.buckled_stress_and_tangent(eps).0,
            };
        }
    }
    let sh = law.crimp_strain;
    if sh == 0.0 {
        return f64x4::select(compressed, compression, f64x4::splat(e) * eps);
    }
    let x = eps / f64x4::splat(sh);
    let series = x.lt(f64x4::splat(FibreLaw::TENSION_SERIES_BELOW));
    // x − (1 − e^(−x)) = x²/2 − x³/6 + x⁴/24 − …, as the scalar law writes it.
    let poly = f64x4::splat(0.5)
        - x * (f64x4::splat(1.0 / 6.0) - x * (f64x4::splat(1.0 / 24.0) - x / f64x4::splat(120.0)));
    let near_zero = f64x4::splat(e * sh) * x * x * poly;
    // 1 − e^(−x), only where the closed form is used.
    let mut straightened = zero;
    for k in 0..LANES {
        if !compressed[k] && !series[k] {
            straightened.0[k] = -(-x.0[k]).exp_m1();
        }
    }
    let closed = f64x4::splat(e) * (eps - f64x4::splat(sh) * straightened);
    f64x4::select(
        compressed,
        compression,
        f64x4::select(series, near_zero, closed),
    )
}
