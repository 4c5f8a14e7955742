//! Fibre kinematics: stretch λ, current direction n and log strain ε = ln λ
//! of an embedded fibre or a truss, and the shear angle between two families.

use nalgebra::{Matrix3x2, Vector2, Vector3};

use crate::KinematicsError;

/// Stretch, current direction and logarithmic strain of a fibre.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FibreKinematics {
    /// λ = current length / reference length.
    pub stretch: f64,
    /// Current unit direction n.
    pub direction: Vector3<f64>,
    /// ε = ln λ.
    pub log_strain: f64,
}

impl FibreKinematics {
    fn from_vector(v: Vector3<f64>, reference_length: f64) -> Result<Self, KinematicsError> {
        let length = v.norm();
        if !length.is_finite() {
            return Err(KinematicsError::NonFinite {
                what: "fibre vector",
            });
        }
        // Relative to the reference length: a fibre crushed to 1e-12 of its
        // length has no meaningful direction.
        if length <= 1e-12 * reference_length {
            return Err(KinematicsError::DegenerateFibre { length });
        }
        let stretch = length / reference_length;
        Ok(Self {
            stretch,
            direction: v / length,
            log_strain: stretch.ln(),
        })
    }
}

/// An embedded fibre of unit reference direction `n_ref` (in the point's
/// local reference frame): λ = |F·N|, n = F·N/λ.
#[inline]
pub fn fibre_stretch(
    f: &Matrix3x2<f64>,
    n_ref: &Vector2<f64>,
) -> Result<FibreKinematics, KinematicsError> {
    FibreKinematics::from_vector(f * n_ref, 1.0)
}

/// A two-node truss of reference length `reference_length`: λ = l/L,
/// n = (x₂ − x₁)/l.
#[inline]
pub fn truss_stretch(
    x1: &Vector3<f64>,
    x2: &Vector3<f64>,
    reference_length: f64,
) -> Result<FibreKinematics, KinematicsError> {
    if !(reference_length > 0.0 && reference_length.is_finite()) {
        return Err(KinematicsError::DegenerateReference {
            size: reference_length,
        });
    }
    FibreKinematics::from_vector(x2 - x1, reference_length)
}

/// The shear angle γ = θ₀ − ∠(n_w, n_f) between the current warp and weft
/// directions (unit vectors), with θ₀ the initial angle between them
/// (π/2 for an orthogonal weave). Positive when the angle closes.
#[inline]
pub fn shear_angle(n_warp: &Vector3<f64>, n_weft: &Vector3<f64>, initial_angle: f64) -> f64 {
    // atan2 of |sin| and cos keeps full precision near 0 and π, where acos
    // of a dot product loses half the digits.
    let angle = n_warp.cross(n_weft).norm().atan2(n_warp.dot(n_weft));
    initial_angle - angle
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn pure_shear_gives_its_shear_angle() {
        for deg in [0.0, 1e-6, 5.0, 30.0, 55.0, 70.0, -20.0] {
            let gamma = f64::to_radians(deg);
            // Trellising of a pin-jointed net: both families rotate by γ/2
            // towards each other, inextensibly.
            let (s, c) = (gamma / 2.0).sin_cos();
            let f = Matrix3x2::new(c, s, s, c, 0.0, 0.0);
            let warp = fibre_stretch(&f, &Vector2::x()).unwrap();
            let weft = fibre_stretch(&f, &Vector2::y()).unwrap();
            assert!((warp.stretch - 1.0).abs() < 1e-15);
            assert!(warp.log_strain.abs() < 1e-15);
            let got = shear_angle(&warp.direction, &weft.direction, FRAC_PI_2);
            assert!((got - gamma).abs() < 1e-15, "{deg}°: {got} vs {gamma}");
        }
    }

    #[test]
    fn uniaxial_stretch_gives_lambda_and_log_strain() {
        for lambda in [0.7, 1.0, 1.001, 1.3, 2.5] {
            let f = Matrix3x2::new(lambda, 0.0, 0.0, 1.0, 0.0, 0.0);
            let k = fibre_stretch(&f, &Vector2::x()).unwrap();
            assert!((k.stretch - lambda).abs() < 1e-15);
            assert!((k.log_strain - f64::ln(lambda)).abs() < 1e-15);
            assert_eq!(k.direction, Vector3::x());
            let t = truss_stretch(
                &Vector3::new(1.0, 2.0, 3.0),
                &Vector3::new(1.0, 2.0 + 3.0 * lambda, 3.0),
                3.0,
            )
            .unwrap();
            assert!((t.stretch - lambda).abs() < 1e-15);
            assert_eq!(t.direction, Vector3::y());
        }
    }

    #[test]
    fn zero_length_truss_is_a_typed_error() {
        let x = Vector3::new(1.0, 1.0, 1.0);
        assert!(matches!(
            truss_stretch(&x, &x, 2.0),
            Err(KinematicsError::DegenerateFibre { .. })
        ));
        assert!(matches!(
            truss_stretch(&x, &Vector3::zeros(), 0.0),
            Err(KinematicsError::DegenerateReference { .. })
        ));
        assert!(matches!(
            truss_stretch(&x, &Vector3::new(f64::NAN, 0.0, 0.0), 1.0),
            Err(KinematicsError::NonFinite { .. })
        ));
    }
}
