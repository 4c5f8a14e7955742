//! The shear-locking law at a membrane point: the fabric's energy
//! h·w(γ) per unit reference area, γ = asin(u₁·u₂) the shear angle between
//! the current fibre directions uₖ = F·Nₖ/|F·Nₖ| (Nₖ the point's local
//! axes, which are the reference fibres), its first Piola stress and the
//! stress's derivative for the tangent. Kept apart from the hypo-elastic
//! resin, so a membrane without the law runs exactly as before.

use drape_constitutive::ShearLocking;
use drape_kinematics::KinematicsError;
use nalgebra::{Matrix3x2, Vector3};

/// The law's state at one point for one F.
pub(super) struct LockingPoint {
    /// Current unit fibre directions u₁, u₂.
    u: [Vector3<f64>; 2],
    /// |F·Nₖ|.
    len: [f64; 2],
    /// c = u₁·u₂ = sin γ.
    c: f64,
    /// ∂c/∂aₖ = (u_other − c·uₖ)/|aₖ|.
    g: [Vector3<f64>; 2],
    /// cos γ.
    cos: f64,
    /// φ = h·τ_s(γ)/cos γ, so that ∂W/∂aₖ = φ·gₖ.
    phi: f64,
    /// dφ/dγ.
    dphi: f64,
}

/// Unit directions, lengths and the cosine u₁·u₂ of the two fibres.
type FibrePair = ([Vector3<f64>; 2], [f64; 2], f64);

/// The fibres' kinematics at F; an error when a fibre has collapsed or the
/// two families have closed to within 1e-6 rad of each other.
fn kinematics(f: &Matrix3x2<f64>) -> Result<FibrePair, KinematicsError> {
    let a = [f.column(0).into_owned(), f.column(1).into_owned()];
    let len = [a[0].norm(), a[1].norm()];
    if len[0].is_nan() || len[1].is_nan() || len[0] <= 0.0 || len[1] <= 0.0 {
        return Err(KinematicsError::DegenerateFibre {
            length: len[0].min(len[1]),
        });
    }
    let u = [a[0] / len[0], a[1] / len[1]];
    let c = u[0].dot(&u[1]);
    if c.is_nan() || c.abs() >= 1.0 - 5e-13 {
        return Err(KinematicsError::NonFinite {
            what: "shear-locking law (the yarn families have closed onto each other)",
        });
    }
    Ok((u, len, c))
}

/// The shear angle γ = asin(u₁·u₂) at F.
pub(super) fn shear_angle(f: &Matrix3x2<f64>) -> Result<f64, KinematicsError> {
    Ok(kinematics(f)?.2.asin())
}

impl LockingPoint {
    /// The law `law` on a fabric of thickness `h` at F.
    pub(super) fn new(
        law: &ShearLocking,
        h: f64,
        f: &Matrix3x2<f64>,
    ) -> Result<Self, KinematicsError> {
        let (u, len, c) = kinematics(f)?;
        let gamma = c.asin();
        let cos = (1.0 - c * c).sqrt();
        let (tau, tangent) = (law.stress(gamma), law.tangent(gamma));
        Ok(Self {
            g: [(u[1] - u[0] * c) / len[0], (u[0] - u[1] * c) / len[1]],
            u,
            len,
            c,
            cos,
            phi: h * tau / cos,
            dphi: h * (tangent * cos + tau * c) / (cos * cos),
        })
    }

    /// Adds ∂W/∂F (per unit reference area) to `p`.
    #[inline]
    pub(super) fn add_stress(&self, p: &mut Matrix3x2<f64>) {
        for k in 0..2 {
            let mut column = p.column_mut(k);
            column += self.g[k] * self.phi;
        }
    }

    /// Adds the derivative of [`Self::add_stress`]'s term in the direction
    /// `d_f` to `d_p`.
    pub(super) fn add_stress_derivative(&self, d_f: &Matrix3x2<f64>, d_p: &mut Matrix3x2<f64>) {
        let da = [d_f.column(0).into_owned(), d_f.column(1).into_owned()];
        let dc = self.g[0].dot(&da[0]) + self.g[1].dot(&da[1]);
        let d_gamma = dc / self.cos;
        let du: [Vector3<f64>; 2] =
            std::array::from_fn(|k| (da[k] - self.u[k] * self.u[k].dot(&da[k])) / self.len[k]);
        for k in 0..2 {
            let o = 1 - k;
            let dg = (du[o] - self.u[k] * dc - du[k] * self.c) / self.len[k]
                - self.g[k] * (self.u[k].dot(&da[k]) / self.len[k]);
            let mut column = d_p.column_mut(k);
            column += self.g[k] * (self.dphi * d_gamma) + dg * self.phi;
        }
    }
}
