//! Membrane kinematics at one integration point: F, C, U, R, Δε̄, P and
//! nodal forces.

use nalgebra::{Matrix2, Matrix3x2, Vector2, Vector3};

use crate::KinematicsError;

/// Relative threshold under which det C counts as zero: a point squeezed to
/// a sliver this thin has no trustworthy rotation, and a NaN would follow.
/// The test is det C ≤ `DEGENERATE_DET_C`·(tr C)², i.e. λ₂/λ₁ ≲ 1e-7 for
/// the principal stretches λ₁ ≥ λ₂.
pub const DEGENERATE_DET_C: f64 = 1e-14;

/// A principal stretch above which a membrane point is "over-stretched":
/// twice its length, far beyond anything a woven fabric survives (yarns
/// break at a few percent, shear alone stretches a diagonal by at most √2).
pub const OVERSTRETCHED: f64 = 2.0;

/// What a degenerate membrane point looks like, for a failure message that
/// says what happened.
///
/// Since C = FᵀF, det C = J² ≥ 0 whatever the orientation: C cannot tell a
/// point turned over from one squeezed flat. Orientation is judged by the
/// element, which sees the point's current normal n = F·e₁ × F·e₂ and its
/// surroundings: `inverted` when n opposes the normals of the element's
/// other integration points (a quad turned inside out about a corner),
/// `folded` when it opposes the mean normal of the elements that share a
/// node with it (the element turned over onto its neighbours, through zero
/// area). `None` where nobody judged it (the kinematics alone cannot).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Degeneracy {
    /// Principal stretches λ₁ ≥ λ₂ ≥ 0 (square roots of C's eigenvalues).
    pub stretches: [f64; 2],
    /// det C/(tr C)² (at most ¼, for an equal stretch).
    pub det_ratio: f64,
    /// Turned against the element's other points (quads).
    pub inverted: Option<bool>,
    /// Turned against the elements around it.
    pub folded: Option<bool>,
}

impl Degeneracy {
    /// From det C and tr C, orientation not judged.
    pub fn from_invariants(det_c: f64, tr_c: f64) -> Self {
        // λ₁² from the larger root, λ₂² = det C/λ₁² (no cancellation).
        let disc = (tr_c * tr_c - 4.0 * det_c).max(0.0).sqrt();
        let l1 = 0.5 * (tr_c + disc);
        let l2 = if l1 > 0.0 { (det_c / l1).max(0.0) } else { 0.0 };
        Self {
            stretches: [l1.sqrt(), l2.sqrt()],
            det_ratio: det_c / (tr_c * tr_c),
            inverted: None,
            folded: None,
        }
    }

    /// Stretched beyond [`OVERSTRETCHED`] along one direction.
    pub fn over_stretched(&self) -> bool {
        self.stretches[0] > OVERSTRETCHED
    }
}

impl std::fmt::Display for Degeneracy {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [l1, l2] = self.stretches;
        write!(
            f,
            "principal stretches {l1:.4e} and {l2:.4e}, det C/(tr C)² = {:.3e} ≤ {DEGENERATE_DET_C:e} \
             (no area left for its size):",
            self.det_ratio
        )?;
        let mut what = Vec::new();
        if self.inverted == Some(true) {
            what.push("inverted (turned inside out against the element's other points)".to_owned());
        }
        if self.folded == Some(true) {
            what.push("folded (turned over against the elements around it)".to_owned());
        }
        if self.over_stretched() {
            what.push(format!(
                "over-stretched ({l1:.3e} times its length along one direction)"
            ));
        }
        if what.is_empty() {
            what.push(format!(
                "collapsed (squeezed to {l2:.3e} of its width across, {l1:.3} along)"
            ));
        }
        write!(f, " {}", what.join(", "))?;
        if self.inverted.is_none() && self.folded.is_none() {
            write!(f, " (orientation not judged)")?;
        }
        Ok(())
    }
}

/// The membrane deformation gradient F = Σₐ xₐ ⊗ ∂Nₐ/∂X (3×2).
///
/// `x` are the current nodal positions and `grad_n` the reference
/// shape-function gradients ∂Nₐ/∂X in the point's local reference frame
/// (see [`crate::reference`]). Both slices have one entry per node.
#[inline]
pub fn deformation_gradient(x: &[Vector3<f64>], grad_n: &[Vector2<f64>]) -> Matrix3x2<f64> {
    debug_assert_eq!(x.len(), grad_n.len());
    let mut f = Matrix3x2::zeros();
    for (xa, ga) in x.iter().zip(grad_n) {
        f += xa * ga.transpose();
    }
    f
}

/// The right Cauchy–Green tensor C = FᵀF (2×2, symmetric).
#[inline]
pub fn right_cauchy_green(f: &Matrix3x2<f64>) -> Matrix2<f64> {
    f.tr_mul(f)
}

/// The right stretch U = √C and its inverse U⁻¹, in closed form
/// (SPEC §3): √C = (C + √det C·I)/√(tr C + 2√det C).
///
/// Errors when det C ≤ [`DEGENERATE_DET_C`]·(tr C)², i.e. the point has no
/// area left for its size (see [`Degeneracy`]).
#[inline]
pub fn right_stretch(c: &Matrix2<f64>) -> Result<(Matrix2<f64>, Matrix2<f64>), KinematicsError> {
    let det_c = c[(0, 0)] * c[(1, 1)] - c[(0, 1)] * c[(1, 0)];
    let tr_c = c[(0, 0)] + c[(1, 1)];
    if !(det_c.is_finite() && tr_c.is_finite()) {
        return Err(KinematicsError::NonFinite {
            what: "right Cauchy–Green tensor C",
        });
    }
    if det_c <= DEGENERATE_DET_C * tr_c * tr_c {
        return Err(KinematicsError::DegenerateMembrane(
            Degeneracy::from_invariants(det_c, tr_c),
        ));
    }
    let det_u = det_c.sqrt();
    let u = (c + Matrix2::identity() * det_u) / (tr_c + 2.0 * det_u).sqrt();
    // For a 2×2 matrix adj(U) = tr(U)·I − U, and det U = √det C.
    let u_inv = (Matrix2::identity() * (u[(0, 0)] + u[(1, 1)]) - u) / det_u;
    Ok((u, u_inv))
}

/// The Green–Naghdi decomposition F = R·U of a 3×2 membrane gradient.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PolarDecomposition {
    /// The rotation: a 3×2 matrix with orthonormal columns, the current
    /// images of the reference local axes (the rotated frame).
    pub r: Matrix3x2<f64>,
    /// The right stretch U = √(FᵀF), symmetric positive definite.
    pub u: Matrix2<f64>,
    /// U⁻¹.
    pub u_inv: Matrix2<f64>,
}

impl PolarDecomposition {
    /// The area stretch det U = J of the membrane's mid-surface.
    #[inline]
    pub fn area_stretch(&self) -> f64 {
        self.u.determinant()
    }

    /// The current unit normal of the membrane, r₁ × r₂.
    #[inline]
    pub fn normal(&self) -> Vector3<f64> {
        self.r.column(0).cross(&self.r.column(1))
    }
}

/// The polar decomposition F = R·U with the closed-form √C (SPEC §3).
///
/// Unlike nalgebra's `polar()` this is the right decomposition of a
/// rectangular F and never returns a reflection.
#[inline]
pub fn polar_decomposition(f: &Matrix3x2<f64>) -> Result<PolarDecomposition, KinematicsError> {
    if !f.iter().all(|v| v.is_finite()) {
        return Err(KinematicsError::NonFinite {
            what: "deformation gradient F",
        });
    }
    let (u, u_inv) = right_stretch(&right_cauchy_green(f))?;
    Ok(PolarDecomposition {
        r: f * u_inv,
        u,
        u_inv,
    })
}

/// The rotated (Green–Naghdi) strain increment with the midpoint rule,
/// Δε̄ = sym((Uₙ₊₁ − Uₙ)·Uₙ₊½⁻¹), Uₙ₊½ = ½(Uₙ + Uₙ₊₁).
///
/// Symmetric, written in the reference local frame. Zero for any rigid motion
/// between the two states, whatever the rotation.
#[inline]
pub fn rotated_strain_increment(u_n: &Matrix2<f64>, u_next: &Matrix2<f64>) -> Matrix2<f64> {
    let mid = (u_n + u_next) * 0.5;
    // U_n and U_{n+1} are s.p.d., so their mean is too: the inverse exists.
    let det = mid[(0, 0)] * mid[(1, 1)] - mid[(0, 1)] * mid[(1, 0)];
    let mid_inv = (Matrix2::identity() * (mid[(0, 0)] + mid[(1, 1)]) - mid) / det;
    let l = (u_next - u_n) * mid_inv;
    (l + l.transpose()) * 0.5
}

/// The first Piola stress P = R·τ̄·U⁻¹ from the rotated Kirchhoff stress τ̄.
#[inline]
pub fn first_piola(
    r: &Matrix3x2<f64>,
    tau_bar: &Matrix2<f64>,
    u_inv: &Matrix2<f64>,
) -> Matrix3x2<f64> {
    r * (tau_bar * u_inv)
}

/// Adds the nodal internal forces fₐ += V₀·P·∂Nₐ/∂X of one integration point
/// of reference volume `volume` (area × thickness × weight) into `forces`.
#[inline]
pub fn add_nodal_forces(
    p: &Matrix3x2<f64>,
    grad_n: &[Vector2<f64>],
    volume: f64,
    forces: &mut [Vector3<f64>],
) {
    debug_assert_eq!(grad_n.len(), forces.len());
    for (fa, ga) in forces.iter_mut().zip(grad_n) {
        *fa += (p * ga) * volume;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, Unit};
    use proptest::prelude::*;

    fn rel(a: f64, scale: f64) -> f64 {
        a / scale.max(1e-300)
    }

    /// A well-conditioned F: a rotation of a stretch with principal stretches
    /// in [0.5, 2] along a random direction, plus an in-plane shear.
    fn well_conditioned_f() -> impl Strategy<Value = Matrix3x2<f64>> {
        (
            0.5f64..2.0,
            0.5f64..2.0,
            -3.2f64..3.2,
            -0.5f64..0.5,
            prop::array::uniform3(-1.0f64..1.0),
            -3.2f64..3.2,
        )
            .prop_filter_map("axis", |(l1, l2, phi, shear, axis, angle)| {
                let axis = Vector3::from(axis);
                if axis.norm() < 1e-3 {
                    return None;
                }
                let (s, c) = phi.sin_cos();
                let q = Matrix2::new(c, -s, s, c);
                let u = q * Matrix2::new(l1, 0.0, 0.0, l2) * q.transpose()
                    + Matrix2::new(0.0, shear, 0.0, 0.0);
                let rot = Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle);
                let embed = Matrix3x2::new(1.0, 0.0, 0.0, 1.0, 0.0, 0.0);
                Some(rot.matrix() * embed * u)
            })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        #[test]
        fn polar_reproduces_f_with_orthonormal_r_and_spd_u(f in well_conditioned_f()) {
            let p = polar_decomposition(&f).unwrap();
            prop_assert!(rel((p.r * p.u - f).norm(), f.norm()) < 1e-12);
            prop_assert!((p.r.tr_mul(&p.r) - Matrix2::identity()).norm() < 1e-12);
            prop_assert!((p.u - p.u.transpose()).norm() < 1e-14 * p.u.norm());
            let eig = p.u.symmetric_eigenvalues();
            prop_assert!(eig.min() > 0.0);
            prop_assert!((p.u * p.u_inv - Matrix2::identity()).norm() < 1e-12);
        }

        #[test]
        fn polar_agrees_with_svd(f in well_conditioned_f()) {
            let p = polar_decomposition(&f).unwrap();
            let svd = f.svd(true, true);
            let (w, vt) = (svd.u.unwrap(), svd.v_t.unwrap());
            let sigma = Matrix2::from_diagonal(&svd.singular_values);
            let r_svd = w * vt;
            let u_svd = vt.transpose() * sigma * vt;
            // nalgebra's SVD is not backward stable to round-off: on these
            // F its W·Σ·Vᵀ misses F by up to 1e-9 (1 in 250 000 draws past
            // 1e-11; polar_decomposition's R·U misses by 3e-16). Its W·Vᵀ
            // is the polar factor of F + E, E its misfit (with W, V's loss
            // of orthonormality), and the polar factor of a full-rank 3×2
            // matrix moves by a small multiple of |E|/σ_min (2.1 at most
            // over 3 000 000 draws; 3 taken), U = √(FᵀF) by at most √2·|E|.
            // So the comparison is as tight as the reference: 16·ε beyond.
            let misfit = (w * sigma * vt - f).norm()
                + (w.tr_mul(&w) - Matrix2::identity()).norm()
                + (vt * vt.transpose() - Matrix2::identity()).norm();
            let r_tol = 16.0 * f64::EPSILON + 3.0 * misfit / svd.singular_values.min();
            let u_tol = 16.0 * f64::EPSILON * u_svd.norm() + 2.0 * misfit;
            prop_assert!(
                (p.r - r_svd).norm() <= r_tol,
                "R {} vs {} (tolerance {:e})", p.r, r_svd, r_tol
            );
            prop_assert!(
                (p.u - u_svd).norm() <= u_tol,
                "U {} vs {} (tolerance {:e})", p.u, u_svd, u_tol
            );
        }

        #[test]
        fn rigid_rotation_gives_zero_increment_and_objective_piola(
            f in well_conditioned_f(),
            axis in prop::array::uniform3(-1.0f64..1.0),
            angle in -3.2f64..3.2,
            t11 in -10.0f64..10.0, t22 in -10.0f64..10.0, t12 in -10.0f64..10.0,
        ) {
            let axis = Vector3::from(axis);
            prop_assume!(axis.norm() > 1e-3);
            let q = *Rotation3::from_axis_angle(&Unit::new_normalize(axis), angle).matrix();
            let before = polar_decomposition(&f).unwrap();
            let after = polar_decomposition(&(q * f)).unwrap();
            // U is unchanged by the rotation, so the strain increment vanishes.
            prop_assert!((after.u - before.u).norm() < 1e-12 * before.u.norm());
            let d_eps = rotated_strain_increment(&before.u, &after.u);
            prop_assert!(d_eps.norm() < 1e-12);
            // The same τ̄ gives a P that rotates with the body.
            let tau = Matrix2::new(t11, t12, t12, t22);
            let p0 = first_piola(&before.r, &tau, &before.u_inv);
            let p1 = first_piola(&after.r, &tau, &after.u_inv);
            prop_assert!((p1 - q * p0).norm() < 1e-11 * (1.0 + p0.norm()));
            prop_assert!((after.r - q * before.r).norm() < 1e-12);
        }
    }

    #[test]
    fn pure_rotation_gives_identity_stretch() {
        let q = Rotation3::from_euler_angles(0.3, -1.2, 2.0);
        let f = q.matrix() * Matrix3x2::new(1.0, 0.0, 0.0, 1.0, 0.0, 0.0);
        let p = polar_decomposition(&f).unwrap();
        assert!((p.u - Matrix2::identity()).norm() < 1e-15);
        assert!((p.area_stretch() - 1.0).abs() < 1e-15);
        assert!((p.normal() - q * Vector3::z()).norm() < 1e-15);
    }

    #[test]
    fn strain_increment_of_uniaxial_stretch_integrates_to_log_strain() {
        // Summing midpoint increments of a monotone uniaxial stretch converges
        // to ln λ with second order in the increment size.
        let lambda = 1.5f64;
        let error = |n: usize| {
            let mut sum = 0.0;
            let mut u_n = Matrix2::identity();
            for k in 1..=n {
                let l = 1.0 + (lambda - 1.0) * k as f64 / n as f64;
                let u = Matrix2::new(l, 0.0, 0.0, 1.0);
                sum += rotated_strain_increment(&u_n, &u)[(0, 0)];
                u_n = u;
            }
            (sum - lambda.ln()).abs()
        };
        let (e1, e2) = (error(50), error(100));
        assert!(e2 < 1e-5);
        let order = (e1 / e2).log2();
        assert!((order - 2.0).abs() < 0.05, "observed order {order}");
    }

    #[test]
    fn a_degenerate_point_reports_its_principal_stretches() {
        // Stretched 1.4e4 times along x, squeezed to 1e-3 across (rotated):
        // det C/(tr C)² ≈ 5e-15.
        let (s, c) = 0.4f64.sin_cos();
        let f = Matrix3x2::new(1.4e4 * c, -1e-3 * s, 1.4e4 * s, 1e-3 * c, 0.0, 0.0);
        let Err(KinematicsError::DegenerateMembrane(d)) = polar_decomposition(&f) else {
            panic!("not degenerate")
        };
        assert!(
            (d.stretches[0] / 1.4e4 - 1.0).abs() < 1e-12,
            "{:?}",
            d.stretches
        );
        assert!(
            (d.stretches[1] / 1e-3 - 1.0).abs() < 1e-6,
            "{:?}",
            d.stretches
        );
        assert!(
            (d.det_ratio - (1.4e4f64 * 1e-3).powi(2) / (1.4e4f64.powi(2) + 1e-6).powi(2)).abs()
                < 1e-25
        );
        assert!(d.over_stretched());
        let m = KinematicsError::DegenerateMembrane(d).to_string();
        for part in [
            "principal stretches 1.4000e4 and 1.0000e-3",
            "det C/(tr C)²",
            "over-stretched",
        ] {
            assert!(m.contains(part), "{m}");
        }
        // Squeezed flat without stretching: collapsed.
        let f = Matrix3x2::new(0.9, 0.0, 0.0, 1e-8, 0.0, 0.0);
        let Err(KinematicsError::DegenerateMembrane(d)) = polar_decomposition(&f) else {
            panic!("not degenerate")
        };
        assert!(!d.over_stretched());
        let m = d.to_string();
        assert!(m.contains("collapsed") && m.contains("not judged"), "{m}");
        let judged = Degeneracy {
            folded: Some(true),
            inverted: Some(false),
            ..d
        };
        let m = judged.to_string();
        assert!(
            m.contains("folded") && !m.contains("collapsed") && !m.contains("judged"),
            "{m}"
        );
    }

    #[test]
    fn collapsed_point_is_a_typed_error() {
        let f = Matrix3x2::new(1.0, 2.0, 0.0, 0.0, 1.0, 2.0);
        assert!(matches!(
            polar_decomposition(&f),
            Err(KinematicsError::DegenerateMembrane(_))
        ));
        let f = Matrix3x2::new(f64::NAN, 0.0, 0.0, 1.0, 0.0, 0.0);
        assert!(matches!(
            polar_decomposition(&f),
            Err(KinematicsError::NonFinite { .. })
        ));
    }

    #[test]
    fn nodal_forces_of_constant_stress_sum_to_zero() {
        let grad = [
            Vector2::new(-1.0, -1.0),
            Vector2::new(1.0, 0.0),
            Vector2::new(0.0, 1.0),
        ];
        let p = Matrix3x2::new(3.0, 1.0, -2.0, 0.5, 0.7, 4.0);
        let mut f = [Vector3::zeros(); 3];
        add_nodal_forces(&p, &grad, 0.5, &mut f);
        assert!((f[0] + f[1] + f[2]).norm() < 1e-15);
        assert_eq!(f[1], Vector3::new(1.5, -1.0, 0.35));
    }

    #[test]
    fn deformation_gradient_of_affine_map_is_exact() {
        let a = Matrix3x2::new(1.2, 0.1, -0.3, 0.9, 0.2, 0.05);
        let b = Vector3::new(3.0, -1.0, 2.0);
        let xs = [
            Vector2::new(0.0, 0.0),
            Vector2::new(2.0, 0.0),
            Vector2::new(0.0, 1.0),
        ];
        // Linear triangle gradients for that reference triangle (area 1).
        let grad = [
            Vector2::new(-0.5, -1.0),
            Vector2::new(0.5, 0.0),
            Vector2::new(0.0, 1.0),
        ];
        let x: Vec<_> = xs.iter().map(|p| a * p + b).collect();
        assert!((deformation_gradient(&x, &grad) - a).norm() < 1e-15);
    }
}
